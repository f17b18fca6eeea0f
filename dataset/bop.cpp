#include "dataset/bop.h"

#include <fnmatch.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <set>
#include <system_error>

#include <tbb/parallel_for.h>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "cad/core/error.h"
#include "cad/core/random.h"
#include "cad/core/util.h"
#include "dataset/bop_read.h"
#include "dataset/coco.h"
#include "dataset/file_io.h"
#include "dataset/mask_png.h"
#include "dataset/models.h"
#include "dataset/point_cloud.h"

namespace cadsynth {

using Json = nlohmann::ordered_json;

bool BopOptions::Check(std::string* why) const {
  if (!(depth_scale > 0.0) || !std::isfinite(depth_scale)) {
    *why = "depth_scale must be positive";
    return false;
  }
  if (jpeg_quality < 0 || jpeg_quality > 100) {
    *why = "jpeg_quality must be 1 to 100 (0: PNG)";
    return false;
  }
  if (gray_bits != 0 && gray_bits != 8 && gray_bits != 16) {
    *why = "gray_bits must be 0 (colour), 8 or 16";
    return false;
  }
  if (gray_bits == 16 && jpeg_quality > 0) {
    *why = "16-bit grey images cannot be JPEG (rgb: png)";
    return false;
  }
  if (model_points < 0 || model_points > 10000000) {
    *why = "model_points must be 0 to 10,000,000";
    return false;
  }
  if (test_every < 0 || !(test_fraction >= 0 && test_fraction <= 1) ||
      !(target_min_visib_fract >= 0 && target_min_visib_fract <= 1)) {
    *why = "test_every must not be negative; test_fraction and target_min_visib_fract lie in 0..1";
    return false;
  }
  if (!(visib_delta_mm >= 0.0) || !std::isfinite(visib_delta_mm)) {
    *why = "the visibility delta must be a length of 0 mm or more";
    return false;
  }
  // A folder name every tool can take, and JSON text as it is (not escapes of raw bytes).
  const bool plain =
      !split.empty() && split.size() <= 64 && split != "." && split != ".." &&
      std::all_of(split.begin(), split.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.';
      });
  if (!plain) {
    *why = "split must be a plain folder name: up to 64 letters, digits, '_', '-' or '.'";
    return false;
  }
  return true;
}

bool BopOptions::IsTest(int index, int count) const {
  if (test_every > 0) return index % test_every == test_every - 1;
  // Each image is a test image with probability test_fraction, drawn from (seed, its index).
  (void)count;
  return UniformDraw(split_seed, streams::kTestImage, static_cast<uint64_t>(index)) < test_fraction;
}

namespace {

// OpenCV's distortion coefficients in its order: [k1, k2, p1, p2, k3].
Json DistCoeffs(const Distortion& d) { return Json::array({d.k1, d.k2, d.p1, d.p2, d.k3}); }

Json RowMajor(const Eigen::Matrix3d& r) {
  Json out = Json::array();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) out.push_back(r(i, j));
  }
  return out;
}

Json Vec(const Eigen::Vector3d& t) { return Json::array({t.x(), t.y(), t.z()}); }

void WriteJson(const std::filesystem::path& path, const Json& json) {
  WriteFileAtomic(path, json.dump(2) + "\n");
}

std::string EncodePng(const cv::Mat& image, const std::filesystem::path& where) {
  std::vector<uchar> bytes;
  if (!cv::imencode(".png", image, bytes)) throw Error(where.string() + ": PNG encoding failed");
  return std::string(bytes.begin(), bytes.end());
}

}  // namespace

std::string EncodeImagePng(const void* pixels, int width, int height, int channels, int bits) {
  if (width <= 0 || height <= 0 || (channels != 1 && channels != 3) || (bits != 8 && bits != 16))
    throw Error("PNG: an image must be 1 or 3 channels of 8 or 16 bits, " + std::to_string(width) +
                " x " + std::to_string(height) + " x " + std::to_string(channels) + " x " +
                std::to_string(bits) + " bits given");
  const int type = CV_MAKETYPE(bits == 16 ? CV_16U : CV_8U, channels);
  const cv::Mat image(height, width, type, const_cast<void*>(pixels));
  if (channels == 1) return EncodePng(image, "image");
  cv::Mat bgr;
  cv::cvtColor(image, bgr, cv::COLOR_RGB2BGR);
  return EncodePng(bgr, "image");
}

DecodedImage ReadImageFile(const std::filesystem::path& path) {
  const cv::Mat image = cv::imread(path.string(), cv::IMREAD_UNCHANGED);
  if (image.empty()) throw Error(path.string() + ": not an image OpenCV can read");
  const int depth = image.depth();
  if ((depth != CV_8U && depth != CV_16U) || (image.channels() != 1 && image.channels() != 3))
    throw Error(path.string() + ": not an 8- or 16-bit grey or colour image");
  cv::Mat rgb = image;
  if (image.channels() == 3) cv::cvtColor(image, rgb, cv::COLOR_BGR2RGB);
  DecodedImage out;
  out.width = rgb.cols;
  out.height = rgb.rows;
  out.channels = rgb.channels();
  out.bits = depth == CV_16U ? 16 : 8;
  const size_t row = static_cast<size_t>(rgb.cols) * rgb.elemSize();
  out.bytes.resize(row * static_cast<size_t>(rgb.rows));
  for (int v = 0; v < rgb.rows; ++v)
    std::memcpy(out.bytes.data() + row * static_cast<size_t>(v), rgb.ptr(v), row);
  return out;
}

uint16_t EncodeDepth(float depth_mm, double depth_scale) {
  if (!(depth_mm > 0.0f)) return 0;
  const double units = depth_mm / depth_scale + 0.5;  // round half up (depths are positive)
  if (units >= std::numeric_limits<uint16_t>::max() + 1.0) return 0;
  return static_cast<uint16_t>(units);
}

VisibleMasks::VisibleMasks(const Frame& frame, const BopOptions& options)
    : frame_(frame), exact_(options.visibility == BopOptions::Visibility::kExact) {
  if (exact_) return;
  // bop_toolkit's visibility.estimate_visib_mask_gt, visib_mode "bop19": visible where the model
  // rendered alone is hit and its distance minus the scene's is at most delta, or the scene's
  // (written) depth is 0. Distances as misc.depth_im_to_dist_im_fast makes them: depth times
  // |((u - cx) / fx, (v - cy) / fy, 1)| at the pixel index (u, v). With lens distortion, which
  // bop_toolkit does not know, the length of the pixel centre's own ray.
  const Intrinsics& k = frame.camera.intrinsics;
  const int w = frame.width();
  masks_.resize(frame.instances.size());
  for (size_t i = 0; i < frame.instances.size(); ++i) {
    const Frame::InstanceTruth& truth = frame.instances[i];
    const int u0 = std::max(0, truth.roi[0]), v0 = std::max(0, truth.roi[1]);
    const int u1 = std::min(w, truth.roi[2]), v1 = std::min(frame.height(), truth.roi[3]);
    const size_t area = static_cast<size_t>(std::max(0, u1 - u0)) * std::max(0, v1 - v0);
    if (truth.amodal_depth.size() != area) {
      throw Error(
          "bop: the bop19 visibility rule needs each instance's depth rendered alone (amodal "
          "depth)");
    }
    std::vector<uint8_t>& mask = masks_[i];
    mask.assign(area, 0);
    for (int v = v0; v < v1; ++v) {
      const double y = (v - k.cy) / k.fy;
      for (int u = u0; u < u1; ++u) {
        const size_t q = static_cast<size_t>(v - v0) * (u1 - u0) + (u - u0);
        const float model = truth.amodal_depth[q];
        if (!(model > 0.0f)) continue;
        Eigen::Vector2d ray((u - k.cx) / k.fx, y);
        if (k.distortion.active() && !k.Unproject(u + 0.5, v + 0.5, &ray)) continue;
        const double scene =
            EncodeDepth(frame.depth[static_cast<size_t>(v) * w + u], options.depth_scale) *
            options.depth_scale;
        const double stretch = std::sqrt(ray.squaredNorm() + 1.0);
        mask[q] = scene == 0.0 || (model - scene) * stretch <= options.visib_delta_mm;
      }
    }
  }
}

bool VisibleMasks::operator()(size_t i, int u, int v) const {
  if (exact_) return frame_.instance[static_cast<size_t>(v) * frame_.width() + u] == i + 1;
  const int* roi = frame_.instances[i].roi;
  const int u0 = std::max(0, roi[0]), v0 = std::max(0, roi[1]);
  const int u1 = std::min(frame_.width(), roi[2]), v1 = std::min(frame_.height(), roi[3]);
  if (u < u0 || u >= u1 || v < v0 || v >= v1) return false;
  return masks_[i][static_cast<size_t>(v - v0) * (u1 - u0) + (u - u0)] != 0;
}

namespace {

// A frame's fragment (.fragments/NNNNNN.json, written by WriteFrame): five lines of JSON, the
// scene_camera, scene_gt and scene_gt_info entries, the COCO entry and the manifest, and a sixth
// with the frame's randomisation record when it has one. Every line's shape is checked here, so
// Finish and CheckFrame never meet a value of the wrong type in a damaged or hand-edited fragment.
struct Fragment {
  Json camera, gt, gt_info, coco;
  std::vector<FileRecord> files;
  Json randomization;  // null when the frame has none
};

Fragment ParseFragmentText(const std::string& text, const std::string& origin) {
  std::vector<std::string> lines;
  size_t start = 0;
  while (start < text.size() && lines.size() < 6) {
    const size_t end = text.find('\n', start);
    if (end == std::string::npos) break;
    lines.push_back(text.substr(start, end - start));
    start = end + 1;
  }
  if (lines.size() < 5)
    throw Error(origin + ": incomplete fragment (" + std::to_string(lines.size()) + " of 5 lines)");
  Json parsed[5];
  for (int i = 0; i < 5; ++i) {
    try {
      parsed[i] = Json::parse(lines[i]);
    } catch (const Json::exception&) {
      throw Error(origin + ":" + std::to_string(i + 1) + ": not valid JSON");
    }
  }
  const auto fail = [&](int line, const std::string& what) {
    throw Error(origin + ":" + std::to_string(line) + ": " + what);
  };
  const auto is_id = [](const Json& v) {
    return v.is_number_integer() && v.get<int64_t>() >= 0 && v.get<int64_t>() <= 2147483647;
  };
  Fragment f;
  f.camera = std::move(parsed[0]);
  if (!f.camera.is_object()) fail(1, "the camera entry is not an object");
  f.gt = std::move(parsed[1]);
  if (!f.gt.is_array()) fail(2, "the ground-truth entry is not a list");
  for (const Json& g : f.gt) {
    if (!g.is_object() || !g.contains("obj_id") || !is_id(g["obj_id"]))
      fail(2, "an instance without an obj_id");
  }
  f.gt_info = std::move(parsed[2]);
  if (!f.gt_info.is_array()) fail(3, "the visibility entry is not a list");
  for (const Json& g : f.gt_info) {
    if (!g.is_object() || !g.contains("visib_fract") || !g["visib_fract"].is_number())
      fail(3, "an instance without a visib_fract number");
  }
  f.coco = std::move(parsed[3]);
  if (!f.coco.is_object() || !f.coco.contains("width") || !is_id(f.coco["width"]) ||
      !f.coco.contains("height") || !is_id(f.coco["height"]) || !f.coco.contains("annotations") ||
      !f.coco["annotations"].is_array()) {
    fail(4, "the COCO entry lacks width, height or annotations");
  }
  for (const Json& a : f.coco["annotations"]) {
    if (!a.is_object()) fail(4, "an annotation is not an object");
    for (const char* key : {"inst_id", "obj_id", "area"}) {
      if (!a.contains(key) || !is_id(a[key])) fail(4, std::string("an annotation without ") + key);
    }
    if (!a.contains("bbox") || !a["bbox"].is_array() || !a.contains("ignore") ||
        !a["ignore"].is_boolean() || !a.contains("counts") || !a["counts"].is_string()) {
      fail(4, "an annotation without bbox, ignore or counts");
    }
  }
  const Json& manifest = parsed[4];
  if (!manifest.is_object() || !manifest.contains("files") || !manifest["files"].is_array())
    fail(5, "the manifest has no file list");
  for (const Json& file : manifest["files"]) {
    if (!file.is_array() || file.size() != 3 || !file[0].is_string() ||
        !file[1].is_number_unsigned() || !file[2].is_number_unsigned() ||
        file[2].get<uint64_t>() > 0xffffffffu) {
      fail(5, "a manifest record is not [path, size, crc32]");
    }
    const std::string path = file[0].get<std::string>();
    if (path.empty() || path[0] == '/' || path.find("..") != std::string::npos)
      fail(5, "a manifest path leaves the dataset: " + path.substr(0, 80));
    f.files.push_back({path, file[1].get<uint64_t>(), file[2].get<uint32_t>()});
  }
  if (lines.size() == 6) {
    try {
      f.randomization = Json::parse(lines[5]);
    } catch (const Json::exception&) {
      fail(6, "not valid JSON");
    }
    if (!f.randomization.is_object()) fail(6, "the randomisation record is not an object");
  }
  return f;
}

Fragment ReadFragment(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path.string() + ": cannot open");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return ParseFragmentText(text, path.string());
}

}  // namespace

void CheckFragmentText(const std::string& text, const std::string& origin) {
  ParseFragmentText(text, origin);
}

namespace {

std::vector<GtInfo> ComputeGtInfos(const Frame& frame, const BopOptions& options,
                                   const VisibleMasks& visible) {
  const int w = frame.width(), h = frame.height();
  const size_t n = frame.instances.size();
  std::vector<GtInfo> infos(n);
  // Visible pixels: their count and inclusive bounds.
  std::vector<int> u0(n, w), v0(n, h), u1(n, -1), v1(n, -1);
  const auto see = [&](size_t i, int u, int v) {
    ++infos[i].px_count_visib;
    u0[i] = std::min(u0[i], u);
    u1[i] = std::max(u1[i], u);
    v0[i] = std::min(v0[i], v);
    v1[i] = std::max(v1[i], v);
  };
  if (options.visibility == BopOptions::Visibility::kExact) {  // one pass over the instance ids
    for (int v = 0; v < h; ++v) {
      const uint16_t* row = &frame.instance[static_cast<size_t>(v) * w];
      for (int u = 0; u < w; ++u) {
        if (row[u] != 0) see(row[u] - 1u, u, v);
      }
    }
  } else {  // visible pixels lie inside the full silhouette's rectangle
    for (size_t i = 0; i < n; ++i) {
      const int* roi = frame.instances[i].roi;
      for (int v = std::max(0, roi[1]); v < std::min(h, roi[3]); ++v) {
        for (int u = std::max(0, roi[0]); u < std::min(w, roi[2]); ++u) {
          if (visible(i, u, v)) see(i, u, v);
        }
      }
    }
  }
  // bop_toolkit's misc.calc_2d_bbox: width = max - min.
  const auto box = [](int a0, int b0, int a1, int b1, int out[4]) {
    out[0] = a0;
    out[1] = b0;
    out[2] = a1 - a0;
    out[3] = b1 - b0;
  };
  for (size_t i = 0; i < n; ++i) {
    GtInfo& info = infos[i];
    // Full silhouette: only inside the rectangle the renderer traced.
    const Frame::InstanceTruth& truth = frame.instances[i];
    int a0 = w, b0 = h, a1 = -1, b1 = -1;
    if (!truth.amodal_mask.empty()) {
      const std::array<int, 4> r = truth.Roi(w, h);
      if (truth.amodal_mask.size() != static_cast<size_t>(r[2] - r[0]) * (r[3] - r[1]))
        throw Error("bop: an instance's full silhouette does not cover its rectangle (roi)");
      for (int v = r[1]; v < r[3]; ++v) {
        const uint8_t* row = &truth.amodal_mask[static_cast<size_t>(v - r[1]) * (r[2] - r[0])];
        for (int u = r[0]; u < r[2]; ++u) {
          if (row[u - r[0]] == 0) continue;
          const size_t p = static_cast<size_t>(v) * w + u;
          ++info.px_count_all;
          // Valid: the written depth (the sensor's, where it has a model) has a value.
          const float written = frame.sensor_depth.empty() ? frame.depth[p] : frame.sensor_depth[p];
          if (EncodeDepth(written, options.depth_scale) != 0) ++info.px_count_valid;
          a0 = std::min(a0, u);
          a1 = std::max(a1, u);
          b0 = std::min(b0, v);
          b1 = std::max(b1, v);
        }
      }
    }
    // As bop_toolkit: count and box on the 3x canvas, so truncated parts count (bbox_obj may
    // reach outside the image). Hand-made frames without the canvas keep the in-image values.
    if (truth.px_count_canvas > 0) {
      info.px_count_all = truth.px_count_canvas;
      const int* c = truth.bbox_canvas;  // may lie wholly left of or above the image
      a0 = c[0], b0 = c[1], a1 = c[2], b1 = c[3];
    }
    // Both boxes only for instances that show (bop_toolkit: [-1, -1, -1, -1] otherwise).
    if (info.px_count_visib > 0) {
      box(u0[i], v0[i], u1[i], v1[i], info.bbox_visib);
      box(a0, b0, a1, b1, info.bbox_obj);
    }
    info.visib_fract =
        info.px_count_all > 0 ? static_cast<double>(info.px_count_visib) / info.px_count_all : 0.0;
  }
  return infos;
}

}  // namespace

std::vector<GtInfo> ComputeGtInfos(const Frame& frame, const BopOptions& options) {
  return ComputeGtInfos(frame, options, VisibleMasks(frame, options));
}

GtInfo ComputeGtInfo(const Frame& frame, int instance, const BopOptions& options) {
  return ComputeGtInfos(frame, options).at(static_cast<size_t>(instance));
}

std::vector<ObjectClass> AssignClasses(
    const std::vector<std::string>& part_names, const std::vector<std::string>& labels,
    const std::vector<std::pair<std::string, std::vector<std::string>>>& groups,
    std::vector<std::string>* empty_groups) {
  std::vector<ObjectClass> classes(part_names.size());
  std::vector<bool> used(groups.size(), false);
  int next_id = static_cast<int>(groups.size()) + 1;
  std::map<std::string, int> label_ids;
  for (size_t i = 0; i < part_names.size(); ++i) {
    if (i < labels.size() && !labels[i].empty()) {
      auto [it, inserted] = label_ids.emplace(labels[i], next_id);
      if (inserted) ++next_id;
      classes[i] = {it->second, labels[i]};
      continue;
    }
    for (size_t g = 0; g < groups.size() && classes[i].id == 0; ++g) {
      for (const std::string& pattern : groups[g].second) {
        if (fnmatch(pattern.c_str(), part_names[i].c_str(), FNM_CASEFOLD) == 0) {
          classes[i] = {static_cast<int>(g) + 1, groups[g].first};
          used[g] = true;
          break;
        }
      }
    }
    if (classes[i].id == 0) classes[i] = {next_id++, part_names[i]};
  }
  empty_groups->clear();
  for (size_t g = 0; g < groups.size(); ++g) {
    if (!used[g]) empty_groups->push_back(groups[g].first);
  }
  return classes;
}

void WriteBopModels(const std::filesystem::path& root, const std::vector<Part>& parts,
                    const std::vector<ObjectClass>& classes) {
  if (!classes.empty() && classes.size() != parts.size()) {
    throw Error("bop: " + std::to_string(classes.size()) + " classes for " +
                std::to_string(parts.size()) + " parts");
  }
  const std::filesystem::path dir = root / "models";
  CreateFolder(dir);
  std::vector<double> diameters(parts.size());
  tbb::parallel_for(size_t{0}, parts.size(), [&](size_t i) {
    diameters[i] = PartDiameter(parts[i]);
    WriteFileAtomic(dir / ("obj_" + Id6(static_cast<int>(i) + 1) + ".ply"),
                    EncodePly(parts[i].mesh));
  });
  Json info = Json::object();
  Json cad = Json::object();
  for (size_t i = 0; i < parts.size(); ++i) {
    const Eigen::AlignedBox3d box = parts[i].mesh.Bounds();
    const std::string key = std::to_string(i + 1);
    info[key] = {{"diameter", diameters[i]},  {"min_x", box.min().x()},
                 {"min_y", box.min().y()},    {"min_z", box.min().z()},
                 {"size_x", box.sizes().x()}, {"size_y", box.sizes().y()},
                 {"size_z", box.sizes().z()}};
    // Symmetries as bop_toolkit reads them: 4x4 row-major transforms, and axes with offsets.
    const Symmetries& sym = parts[i].symmetries;
    if (!sym.discrete.empty()) {
      Json discrete = Json::array();
      for (const Eigen::Isometry3d& t : sym.discrete) {
        Json m = Json::array();
        for (int r = 0; r < 4; ++r) {
          for (int c = 0; c < 4; ++c)
            m.push_back(std::abs(t.matrix()(r, c)) < 1e-12 ? 0.0 : t.matrix()(r, c));
        }
        discrete.push_back(m);
      }
      info[key]["symmetries_discrete"] = discrete;
    }
    if (!sym.continuous.empty()) {
      Json continuous = Json::array();
      for (const Symmetries::Axis& a : sym.continuous) {
        continuous.push_back({{"axis", Vec(a.direction)}, {"offset", Vec(a.offset)}});
      }
      info[key]["symmetries_continuous"] = continuous;
    }
    Json cad_from_model = Json::array();
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) cad_from_model.push_back(parts[i].cad_from_model.matrix()(r, c));
    }
    const ObjectClass object_class =
        classes.empty() ? ObjectClass{static_cast<int>(i) + 1, parts[i].name} : classes[i];
    cad[key] = {{"name", parts[i].name},
                {"class_id", object_class.id},
                {"class_name", object_class.name},
                {"cad_from_model", cad_from_model},
                {"volume_mm3", parts[i].mass.volume_mm3},
                {"center_of_mass", Vec(parts[i].mass.center_of_mass)},
                {"mass_from_brep", parts[i].mass_from_brep},
                {"triangles", parts[i].mesh.num_triangles()}};
  }
  WriteJson(dir / "models_info.json", info);
  WriteJson(dir / "models_cad.json", cad);
}

void WriteModelPoints(const std::filesystem::path& root, const std::vector<Part>& parts,
                      const BopOptions& options) {
  if (options.model_points <= 0) return;
  CreateFolder(root / "models" / "points");
  std::vector<Keypoints> keypoints(parts.size());
  tbb::parallel_for(size_t{0}, parts.size(), [&](size_t i) {
    const std::vector<Eigen::Vector3f> points =
        options.even_points
            ? SampleEvenly(parts[i].mesh, options.model_points, options.point_seed + i)
            : SampleSurface(parts[i].mesh, options.model_points, options.point_seed + i);
    WriteFileAtomic(root / "models" / "points" / ("obj_" + Id6(static_cast<int>(i) + 1) + ".ply"),
                    EncodePointPly(points));
    keypoints[i] = ComputeKeypoints(parts[i].mesh, points);
  });
  const auto list = [](const auto& points) {
    Json out = Json::array();
    for (const Eigen::Vector3f& p : points) out.push_back({p.x(), p.y(), p.z()});
    return out;
  };
  Json all = Json::object();
  for (size_t i = 0; i < parts.size(); ++i) {
    const Keypoints& k = keypoints[i];
    all[std::to_string(i + 1)] = {{"fps8", list(k.fps8)},
                                  {"fps16", list(k.fps16)},
                                  {"center", {k.center.x(), k.center.y(), k.center.z()}},
                                  {"corners", list(k.corners)}};
  }
  WriteJson(root / "models" / "keypoints.json", all);
}

void WriteBopCamera(const std::filesystem::path& root, const Intrinsics& k,
                    const BopOptions& options, const std::string& sensor) {
  CreateFolder(root);
  const std::string name = sensor.empty() ? "camera.json" : "camera_" + sensor + ".json";
  Json camera{{"cx", k.cx},      {"cy", k.cy}, {"depth_scale", options.depth_scale},
              {"fx", k.fx},      {"fy", k.fy}, {"height", k.height},
              {"width", k.width}};
  if (k.distortion.active()) camera["dist_coeffs"] = DistCoeffs(k.distortion);
  WriteJson(root / name, camera);
}

BopSceneWriter::BopSceneWriter(const std::filesystem::path& root, int scene_id,
                               const BopOptions& options, std::vector<int> obj_id_of_instance,
                               const BopSensor& sensor)
    : root_(root),
      scene_dir_(root / options.split / Id6(scene_id)),
      options_(options),
      sensor_(sensor),
      obj_ids_(std::move(obj_id_of_instance)) {
  if (!sensor.name.empty()) options_.gray_bits = sensor.gray_bits;
  std::string why;
  if (!options_.Check(&why)) throw Error("bop: " + why);
  for (const std::string& sub : {options_.ImageFolder(), std::string("depth"), std::string("mask"),
                                 std::string("mask_visib"), std::string(".fragments")})
    CreateFolder(Folder(sub));
  // Frames of an interrupted run: complete where the fragment (written last) exists.
  for (const auto& entry : std::filesystem::directory_iterator(Folder(".fragments"))) {
    const std::string name = entry.path().filename().string();
    if (name.size() != 11 || name.substr(6) != ".json") continue;
    if (const auto id = ParseBopId(name.substr(0, 6))) image_ids_.push_back(*id);
  }
}

std::filesystem::path BopSceneWriter::FragmentPath(int image_id) const {
  return Folder(".fragments") / (Id6(image_id) + ".json");
}

bool BopSceneWriter::HasFrame(int image_id) const {
  return std::filesystem::exists(FragmentPath(image_id));
}

std::vector<int> BopSceneWriter::WrittenFrames() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<int> ids = image_ids_;
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  return ids;
}

std::string BopSceneWriter::CheckFrame(int image_id) const {
  const std::filesystem::path path = FragmentPath(image_id);
  Fragment fragment;
  try {
    fragment = ReadFragment(path);
  } catch (const Error& e) {
    return e.what();
  }
  for (const FileRecord& record : fragment.files) {
    const std::string problem = CheckFile(root_, record);
    if (!problem.empty()) return (root_ / record.path).string() + ": " + problem;
  }
  return {};
}

void BopSceneWriter::ForgetFrame(int image_id) {
  std::error_code ec;
  std::filesystem::remove(FragmentPath(image_id), ec);
  if (ec)
    throw Error(Folder(".fragments").string() + ": cannot remove the record of image " +
                std::to_string(image_id) + ": " + ec.message());
  std::lock_guard<std::mutex> lock(mutex_);
  image_ids_.erase(std::remove(image_ids_.begin(), image_ids_.end(), image_id), image_ids_.end());
}

void BopSceneWriter::RemoveFragments() {
  std::error_code ec;
  std::filesystem::remove_all(Folder(".fragments"), ec);
}

void BopSceneWriter::WriteFrame(int image_id, const Frame& frame,
                                const std::vector<const FrameWriter*>& formats) {
  if (frame.instances.size() != obj_ids_.size()) {
    throw Error("bop: frame has " + std::to_string(frame.instances.size()) +
                " instances, the scene " + std::to_string(obj_ids_.size()));
  }
  const int w = frame.width(), h = frame.height();
  const std::string im = Id6(image_id);
  FileLog files(root_);

  // The camera's image: colour, or grey (8 or 16 bits) for a grey camera.
  cv::Mat image;
  if (options_.gray_bits > 0) {
    if (frame.gray.size() != static_cast<size_t>(w) * h)
      throw Error("bop: a grey camera's frame has no grey image");
    const bool deep = options_.gray_bits == 16;
    image.create(h, w, deep ? CV_16UC1 : CV_8UC1);
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) {
        const uint16_t value =
            EncodeGray(frame.gray[static_cast<size_t>(v) * w + u], options_.gray_bits);
        if (deep) {
          image.at<uint16_t>(v, u) = value;
        } else {
          image.at<uint8_t>(v, u) = static_cast<uint8_t>(value);
        }
      }
    }
  } else {
    cv::Mat rgb(h, w, CV_8UC3, const_cast<uint8_t*>(frame.rgb.data()));
    cv::cvtColor(rgb, image, cv::COLOR_RGB2BGR);
  }
  const std::filesystem::path rgb_path =
      Folder(options_.ImageFolder()) / (im + options_.RgbExtension());
  if (options_.jpeg_quality > 0) {
    std::vector<uchar> bytes;
    if (!cv::imencode(".jpg", image, bytes, {cv::IMWRITE_JPEG_QUALITY, options_.jpeg_quality})) {
      throw Error(rgb_path.string() + ": JPEG encoding failed");
    }
    files.Write(rgb_path,
                std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
  } else {
    files.Write(rgb_path, EncodePng(image, rgb_path));
  }

  // depth/: what the sensor returns; with a depth model other than ideal, depth_gt/ holds the
  // exact depth every label comes from.
  const auto write_depth = [&](const std::vector<float>& values, const char* folder) {
    cv::Mat depth(h, w, CV_16UC1);
    for (int v = 0; v < h; ++v) {
      auto* row = depth.ptr<uint16_t>(v);
      for (int u = 0; u < w; ++u) {
        row[u] = EncodeDepth(values[static_cast<size_t>(v) * w + u], options_.depth_scale);
      }
    }
    const std::filesystem::path depth_path = Folder(folder) / (im + ".png");
    files.Write(depth_path, EncodePng(depth, depth_path));
  };
  if (frame.sensor_depth.empty()) {
    write_depth(frame.depth, "depth");
  } else {
    CreateFolder(Folder("depth_gt"));
    write_depth(frame.sensor_depth, "depth");
    write_depth(frame.depth, "depth_gt");
  }

  // ir/: the IR camera's image (active_stereo's left IR image, the projector's dots in it).
  if (options_.infrared && !frame.infrared.empty()) {
    if (frame.infrared.size() != static_cast<size_t>(w) * h)
      throw Error("bop: the frame's IR image has the wrong size");
    CreateFolder(Folder("ir"));
    const cv::Mat ir(h, w, CV_8UC1, const_cast<uint8_t*>(frame.infrared.data()));
    const std::filesystem::path ir_path = Folder("ir") / (im + ".png");
    files.Write(ir_path, EncodePng(ir, ir_path));
  }

  if (!frame.normals
           .empty()) {  // camera-frame normals as 8-bit RGB: (n + 1) / 2 * 255; (0, 0, 0) = none
    CreateFolder(Folder("normal"));
    cv::Mat normals(h, w, CV_8UC3, cv::Scalar(0, 0, 0));
    for (int v = 0; v < h; ++v) {
      auto* row = normals.ptr<cv::Vec3b>(v);
      for (int u = 0; u < w; ++u) {
        const Eigen::Vector3f& n = frame.normals[static_cast<size_t>(v) * w + u];
        if (n.isZero()) continue;
        for (int c = 0; c < 3; ++c) {
          row[u][2 - c] =
              static_cast<uint8_t>(std::clamp((n[c] + 1.0f) * 127.5f + 0.5f, 0.0f, 255.0f));  // BGR
        }
      }
    }
    const std::filesystem::path normal_path = Folder("normal") / (im + ".png");
    files.Write(normal_path, EncodePng(normals, normal_path));
  }

  if (!frame.radiance.empty()) {  // pbr with hdr: linear radiance as 32-bit float EXR
    CreateFolder(Folder("rgb_hdr"));
    cv::Mat radiance(h, w, CV_32FC3);
    for (int v = 0; v < h; ++v) {
      auto* row = radiance.ptr<cv::Vec3f>(v);
      for (int u = 0; u < w; ++u) {
        const float* c = &frame.radiance[3 * (static_cast<size_t>(v) * w + u)];
        row[u] = cv::Vec3f(c[2], c[1], c[0]);  // BGR
      }
    }
    const std::filesystem::path hdr_path = Folder("rgb_hdr") / (im + ".exr");
    std::vector<uchar> bytes;
    if (!cv::imencode(".exr", radiance, bytes, {cv::IMWRITE_EXR_TYPE, cv::IMWRITE_EXR_TYPE_FLOAT}))
      throw Error(hdr_path.string() + ": EXR encoding failed");
    files.Write(hdr_path,
                std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
  }

  Json camera_entry, gt_entry = Json::array(), gt_info_entry = Json::array();
  const Eigen::Isometry3d cam_from_world = frame.camera.world_from_cam.inverse();
  Json k = Json::array();
  const Eigen::Matrix3d kmat = frame.camera.intrinsics.K();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) k.push_back(kmat(r, c));
  }
  camera_entry = {{"cam_K", k},
                  {"depth_scale", options_.depth_scale},
                  {"cam_R_w2c", RowMajor(cam_from_world.linear())},
                  {"cam_t_w2c", Vec(cam_from_world.translation())}};
  // Beside cam_K, in OpenCV's order; only for a camera with lens distortion (BOP's images have
  // none: its readers ignore the key).
  if (frame.camera.intrinsics.distortion.active())
    camera_entry["cam_dist_coeffs"] = DistCoeffs(frame.camera.intrinsics.distortion);

  const VisibleMasks visible(frame, options_);
  const std::vector<GtInfo> infos = ComputeGtInfos(frame, options_, visible);
  // Each instance's masks are written into the rows they cover and cleared after: the rest of
  // the image stays zero, and only the band of rows that may not be is compressed.
  cv::Mat mask = cv::Mat::zeros(h, w, CV_8UC1);
  Json coco_entry = Json::array();
  for (size_t i = 0; i < frame.instances.size(); ++i) {
    const Frame::InstanceTruth& truth = frame.instances[i];
    gt_entry.push_back({{"cam_R_m2c", RowMajor(truth.cam_from_model.linear())},
                        {"cam_t_m2c", Vec(truth.cam_from_model.translation())},
                        {"obj_id", obj_ids_[i]}});
    const GtInfo& info = infos[i];
    gt_info_entry.push_back(
        {{"bbox_obj", {info.bbox_obj[0], info.bbox_obj[1], info.bbox_obj[2], info.bbox_obj[3]}},
         {"bbox_visib",
          {info.bbox_visib[0], info.bbox_visib[1], info.bbox_visib[2], info.bbox_visib[3]}},
         {"px_count_all", info.px_count_all},
         {"px_count_valid", info.px_count_valid},
         {"px_count_visib", info.px_count_visib},
         {"visib_fract", info.visib_fract}});

    const std::string name = im + "_" + Id6(static_cast<int>(i)) + ".png";
    // Masks are zero outside the full silhouette's rectangle: fill only inside. The in-image box
    // of the full silhouette (inclusive) is COCO's amodal box.
    const auto [r0, r1, r2, r3] = truth.Roi(w, h);
    int full[4] = {w, h, -1, -1};
    for (int v = r1; v < r3 && !truth.amodal_mask.empty(); ++v) {
      auto* out = mask.ptr<uint8_t>(v);
      const uint8_t* in = &truth.amodal_mask[static_cast<size_t>(v - r1) * (r2 - r0)];
      for (int u = r0; u < r2; ++u) {
        if (in[u - r0] == 0) continue;
        out[u] = 255;
        full[0] = std::min(full[0], u), full[1] = std::min(full[1], v);
        full[2] = std::max(full[2], u), full[3] = std::max(full[3], v);
      }
    }
    files.Write(Folder("mask") / name, EncodeMaskPng(mask.data, mask.step, w, h, r1, r3));
    const int* b = info.bbox_visib;  // inclusive: [b0, b0 + b2] x [b1, b1 + b3]
    const int visib_end = info.px_count_visib > 0 ? b[1] + b[3] + 1 : b[1];
    for (int v = r1; v < r3; ++v) std::memset(mask.ptr<uint8_t>(v), 0, w);
    for (int v = b[1]; v < visib_end; ++v) {
      auto* out = mask.ptr<uint8_t>(v);
      for (int u = b[0]; u <= b[0] + b[2]; ++u) out[u] = visible(i, u, v) ? 255 : 0;
    }
    files.Write(Folder("mask_visib") / name,
                EncodeMaskPng(mask.data, mask.step, w, h, b[1], visib_end));
    for (int v = b[1]; v < visib_end; ++v) std::memset(mask.ptr<uint8_t>(v), 0, w);

    // COCO, as bop_toolkit's calc_gt_coco.py: every instance with a visible pixel, its visible
    // mask as compressed RLE, the amodal (or modal) box with COCO's width max - min + 1, and
    // "ignore" below 10% visibility.
    if (!options_.coco || info.px_count_visib == 0 || (options_.coco_amodal_bbox && full[2] < 0))
      continue;
    const RleMask rle = EncodeRle(w, h, b[0], b[1], b[0] + b[2] + 1, b[1] + b[3] + 1,
                                  [&](size_t p) { return visible.AtPixel(i, p); });
    const Json coco_box = options_.coco_amodal_bbox
                              ? Json{full[0], full[1], full[2] - full[0] + 1, full[3] - full[1] + 1}
                              : Json{b[0], b[1], b[2] + 1, b[3] + 1};
    coco_entry.push_back({{"inst_id", i},
                          {"obj_id", obj_ids_[i]},
                          {"area", info.px_count_visib},
                          {"bbox", coco_box},
                          {"ignore", info.visib_fract < 0.1},
                          {"counts", CompressRleCounts(rle.counts)}});
  }
  const BopFrameFiles bop{rgb_path, Folder("depth") / (im + ".png")};
  for (const FrameWriter* format : formats) format->WriteFrame(image_id, frame, bop, &files);
  // One fragment per frame, written last: four lines of compact JSON read back in order by
  // Finish(), and the frame's manifest entry: every file it wrote with size and CRC-32.
  Json manifest = Json::array();
  for (const FileRecord& r : files.records()) manifest.push_back({r.path, r.size, r.crc32});
  WriteFileAtomic(
      FragmentPath(image_id),
      camera_entry.dump() + "\n" + gt_entry.dump() + "\n" + gt_info_entry.dump() + "\n" +
          Json{{"width", w}, {"height", h}, {"annotations", coco_entry}}.dump() + "\n" +
          Json{{"files", manifest}}.dump() + "\n" +
          (frame.randomization.empty() ? std::string()
                                       : Json::parse(frame.randomization).dump() + "\n"));
  std::lock_guard<std::mutex> lock(mutex_);
  image_ids_.push_back(image_id);
}

void BopSceneWriter::WriteWorldPoses(const std::vector<Instance>& instances) {
  if (instances.size() != obj_ids_.size())
    throw Error("bop: world poses for a different number of instances");
  Json list = Json::array();
  for (size_t i = 0; i < instances.size(); ++i) {
    list.push_back({{"obj_id", obj_ids_[i]},
                    {"world_R_m2w", RowMajor(instances[i].world_from_model.linear())},
                    {"world_t_m2w", Vec(instances[i].world_from_model.translation())},
                    {"name", instances[i].name}});
  }
  WriteJson(scene_dir_ / "scene_gt_world.json", list);
}

SceneSplit BopSceneWriter::Finish() {
  std::lock_guard<std::mutex> lock(mutex_);
  SceneSplit split;
  std::sort(image_ids_.begin(), image_ids_.end());
  image_ids_.erase(std::unique(image_ids_.begin(), image_ids_.end()), image_ids_.end());
  // Stream the three files: {"id": entry, ...}, each entry indented as json.dump(2) would.
  const std::string sfx = sensor_.Suffix();
  const std::string names[3] = {"scene_camera" + sfx + ".json", "scene_gt" + sfx + ".json",
                                "scene_gt_info" + sfx + ".json"};
  std::ofstream out[3];
  for (int f = 0; f < 3; ++f) {
    out[f].open(scene_dir_ / (names[f] + ".tmp"), std::ios::binary);
    if (!out[f]) throw Error((scene_dir_ / names[f]).string() + ": cannot create file");
    out[f] << "{";
  }
  const auto indent = [](const std::string& text) {
    std::string result;
    for (char c : text) {
      result += c;
      if (c == '\n') result += "  ";
    }
    return result;
  };
  // scene_gt_coco.json: annotations streamed, the (small) image list kept for the end.
  const std::filesystem::path coco_path = scene_dir_ / ("scene_gt_coco" + sfx + ".json");
  std::ofstream coco;
  Json coco_images = Json::array();
  int annotation_id = 0;
  if (options_.coco) {
    coco.open(coco_path.string() + ".tmp", std::ios::binary);
    if (!coco) throw Error(coco_path.string() + ": cannot create file");
    coco << "{\n  \"annotations\": [";
  }
  // scene_randomization.json: the frames' randomisation records, when they have them.
  std::string randomization;
  for (size_t n = 0; n < image_ids_.size(); ++n) {
    const Fragment fragment = ReadFragment(FragmentPath(image_ids_[n]));
    const bool test = options_.IsTest(static_cast<int>(n), static_cast<int>(image_ids_.size()));
    (test ? split.test : split.train).push_back(image_ids_[n]);
    const Json* entries[3] = {&fragment.camera, &fragment.gt, &fragment.gt_info};
    for (int f = 0; f < 3; ++f) {
      out[f] << (n == 0 ? "\n  \"" : ",\n  \"") << image_ids_[n]
             << "\": " << indent(entries[f]->dump(2));
    }
    if (!fragment.randomization.is_null()) {
      randomization += (randomization.empty() ? "{\n  \"" : ",\n  \"") +
                       std::to_string(image_ids_[n]) +
                       "\": " + indent(fragment.randomization.dump(2));
    }
    if (test) {  // gt_info: count the instances visible enough, per object
      std::map<int, int> counts;
      const Json& info = fragment.gt_info;
      for (size_t i = 0; i < info.size() && i < obj_ids_.size(); ++i) {
        if (info[i]["visib_fract"].get<double>() >= options_.target_min_visib_fract)
          ++counts[obj_ids_[i]];
      }
      for (const auto& [obj, count] : counts) split.targets.push_back({image_ids_[n], obj, count});
    }
    if (!options_.coco) continue;
    const Json& entry = fragment.coco;
    const int w = entry["width"], h = entry["height"];
    coco_images.push_back({{"id", image_ids_[n]},
                           {"file_name", options_.ImageFolder() + sfx + "/" + Id6(image_ids_[n]) +
                                             options_.RgbExtension()},
                           {"width", w},
                           {"height", h}});
    for (const Json& a : entry["annotations"]) {
      const Json annotation = {{"id", ++annotation_id},
                               {"image_id", image_ids_[n]},
                               {"category_id", a["obj_id"]},
                               {"iscrowd", 0},
                               {"area", a["area"]},
                               {"bbox", a["bbox"]},
                               {"segmentation", {{"size", {h, w}}, {"counts", a["counts"]}}},
                               {"width", w},
                               {"height", h},
                               {"ignore", a["ignore"]},
                               {"inst_id", a["inst_id"]}};
      coco << (annotation_id == 1 ? "\n    " : ",\n    ") << annotation.dump();
    }
  }
  if (options_.coco) {
    Json categories = Json::array();
    std::vector<int> ids = obj_ids_;
    std::sort(ids.begin(), ids.end());
    ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
    for (int id : ids) {
      Json c = {{"id", id}, {"name", std::to_string(id)}, {"supercategory", "cadsynth"}};
      for (const CocoCategory& known : categories_) {
        if (known.id == id)
          c = {{"id", id}, {"name", known.name}, {"supercategory", known.supercategory}};
      }
      categories.push_back(c);
    }
    coco << (annotation_id ? "\n  ],\n" : "],\n") << "  \"categories\": " << categories.dump()
         << ",\n  \"images\": " << coco_images.dump() << ",\n  \"info\": "
         << Json{{"description", "cadsynth scene " + scene_dir_.filename().string()}}.dump()
         << ",\n  \"licenses\": []\n}\n";
    coco.close();
    if (!coco) throw Error(coco_path.string() + ": cannot write file (disk full?)");
    std::error_code ec;
    std::filesystem::rename(coco_path.string() + ".tmp", coco_path, ec);
    if (ec) throw Error(coco_path.string() + ": cannot move file into place: " + ec.message());
  }
  for (int f = 0; f < 3; ++f) {
    out[f] << (image_ids_.empty() ? "}\n" : "\n}\n");
    out[f].close();
    if (!out[f]) throw Error((scene_dir_ / names[f]).string() + ": cannot write file (disk full?)");
    std::error_code ec;
    std::filesystem::rename(scene_dir_ / (names[f] + ".tmp"), scene_dir_ / names[f], ec);
    if (ec)
      throw Error((scene_dir_ / names[f]).string() +
                  ": cannot move file into place: " + ec.message());
  }
  if (!randomization.empty())
    WriteFileAtomic(scene_dir_ / ("scene_randomization" + sfx + ".json"), randomization + "\n}\n");
  return split;
}

void WriteSplits(const std::filesystem::path& root, const std::vector<SceneSplit>& scenes) {
  CreateFolder(root / "splits");
  std::string train, test;
  Json targets = Json::array();
  for (size_t s = 0; s < scenes.size(); ++s) {
    for (int im : scenes[s].train) train += Id6(static_cast<int>(s)) + " " + Id6(im) + "\n";
    for (int im : scenes[s].test) test += Id6(static_cast<int>(s)) + " " + Id6(im) + "\n";
    for (const SceneSplit::Target& t : scenes[s].targets) {
      targets.push_back({{"im_id", t.im_id},
                         {"inst_count", t.inst_count},
                         {"obj_id", t.obj_id},
                         {"scene_id", s}});
    }
  }
  WriteFileAtomic(root / "splits" / "train.txt", train);
  WriteFileAtomic(root / "splits" / "test.txt", test);
  WriteFileAtomic(root / "test_targets_bop19.json", targets.dump(2) + "\n");
}

void WriteMergedCoco(const std::filesystem::path& root, const BopOptions& options,
                     const std::vector<SceneSplit>& scenes, const std::vector<ObjectClass>& classes,
                     const BopSensor& sensor) {
  if (!options.coco) return;
  const std::string sfx = sensor.Suffix();
  CreateFolder(root / "coco");
  Json categories = Json::array();
  std::map<int, std::string> class_names;
  for (const ObjectClass& c : classes) class_names[c.id] = c.name;
  for (const auto& [id, name] : class_names)
    categories.push_back({{"id", id}, {"name", name}, {"supercategory", "cadsynth"}});
  // Streamed, so that memory does not grow with the dataset: the scene files are read as
  // Finish() writes them (one annotation per line, the image list on one line), annotations in
  // a first pass over the scenes and images in a second. Images are numbered from 1 in scene
  // order, then image order; an image's number is its rank in its scene's (sorted) split list.
  const auto scene_file = [&](size_t s) {
    return root / options.split / Id6(static_cast<int>(s)) / ("scene_gt_coco" + sfx + ".json");
  };
  const auto strip = [](std::string line) {  // "    {...}," -> "{...}"
    const size_t begin = line.find_first_not_of(' ');
    while (!line.empty() && (line.back() == ',' || line.back() == '\r')) line.pop_back();
    return begin == std::string::npos ? std::string() : line.substr(begin);
  };
  for (const bool test : {false, true}) {
    const std::filesystem::path path =
        root / "coco" / (std::string(test ? "test" : "train") + sfx + ".json");
    const std::string temporary = path.string() + ".tmp";
    std::ofstream out(temporary, std::ios::binary);
    if (!out) throw Error(path.string() + ": cannot create file");
    out << "{\"annotations\":[";
    size_t annotation_count = 0, image_base = 0;
    for (size_t s = 0; s < scenes.size(); ++s) {
      const std::vector<int>& wanted = test ? scenes[s].test : scenes[s].train;
      if (wanted.empty()) continue;
      std::ifstream in(scene_file(s), std::ios::binary);
      if (!in) throw Error(scene_file(s).string() + ": cannot open");
      std::string line;
      bool in_annotations = false;
      while (std::getline(in, line)) {
        if (line.rfind("  \"annotations\": [", 0) == 0) {
          in_annotations = true;
          continue;
        }
        if (!in_annotations) continue;
        if (line.rfind("  ]", 0) == 0 || line.rfind("  \"", 0) == 0) break;
        const std::string text = strip(line);
        if (text.empty()) continue;
        Json a;
        try {
          a = Json::parse(text);
        } catch (const Json::exception& e) {
          throw Error(scene_file(s).string() + ": unreadable annotation: " + e.what());
        }
        const int im = a["image_id"];
        const auto found = std::lower_bound(wanted.begin(), wanted.end(), im);
        if (found == wanted.end() || *found != im) continue;
        const int obj = a["category_id"];
        a["id"] = static_cast<int>(++annotation_count);
        a["image_id"] = static_cast<int>(image_base + (found - wanted.begin()) + 1);
        a["category_id"] =
            obj >= 1 && obj <= static_cast<int>(classes.size()) ? classes[obj - 1].id : obj;
        a["obj_id"] = obj;
        a["scene_id"] = s;
        a["im_id"] = im;
        out << (annotation_count == 1 ? "" : ",") << a.dump();
      }
      image_base += wanted.size();
    }
    out << "],\"categories\":" << categories.dump() << ",\"images\":[";
    size_t image_count = 0;
    for (size_t s = 0; s < scenes.size(); ++s) {
      const std::vector<int>& wanted = test ? scenes[s].test : scenes[s].train;
      if (wanted.empty()) continue;
      std::ifstream in(scene_file(s), std::ios::binary);
      std::string line;
      Json images;
      while (std::getline(in, line)) {
        if (line.rfind("  \"images\": ", 0) != 0) continue;
        images = Json::parse(strip(line.substr(12)), nullptr, false);
        break;
      }
      if (!images.is_array()) throw Error(scene_file(s).string() + ": no readable image list");
      const std::string scene_folder = options.split + "/" + Id6(static_cast<int>(s));
      size_t listed = 0;
      for (const Json& image : images) {
        const int im = image["id"];
        if (!std::binary_search(wanted.begin(), wanted.end(), im)) continue;
        ++listed;
        out << (image_count++ == 0 ? "" : ",")
            << Json{{"id", image_count},
                    {"file_name", scene_folder + "/" + image["file_name"].get<std::string>()},
                    {"width", image["width"]},
                    {"height", image["height"]},
                    {"scene_id", s},
                    {"im_id", im}}
                   .dump();
      }
      if (listed != wanted.size()) {
        throw Error(scene_file(s).string() + ": lists " + std::to_string(listed) + " of the " +
                    std::to_string(wanted.size()) + " images of its split");
      }
    }
    out << "],\"info\":"
        << Json{{"description", test ? "cadsynth test split" : "cadsynth train split"}}.dump()
        << ",\"licenses\":[]}\n";
    out.close();
    if (!out) throw Error(path.string() + ": cannot write file (disk full?)");
    std::error_code ec;
    std::filesystem::rename(temporary, path, ec);
    if (ec) throw Error(path.string() + ": cannot move file into place: " + ec.message());
  }
}

RigSceneWriter::RigSceneWriter(const std::filesystem::path& root, int scene_id,
                               const BopOptions& options,
                               const std::vector<int>& obj_id_of_instance,
                               const std::vector<BopSensor>& sensors) {
  if (sensors.empty()) throw Error("bop: a rig needs at least one sensor");
  for (const BopSensor& sensor : sensors) {
    if (sensors.size() > 1 && sensor.name.empty()) throw Error("bop: a rig's sensors need names");
    sensors_.push_back(
        std::make_unique<BopSceneWriter>(root, scene_id, options, obj_id_of_instance, sensor));
  }
}

void RigSceneWriter::WriteFrame(int image_id, const std::vector<const Frame*>& frames,
                                const std::vector<const FrameWriter*>& formats) {
  if (frames.size() != sensors_.size()) {
    throw Error("bop: " + std::to_string(frames.size()) + " frames for a rig of " +
                std::to_string(sensors_.size()) + " sensors");
  }
  for (size_t k = 0; k < sensors_.size(); ++k) {
    sensors_[k]->WriteFrame(image_id, *frames[k],
                            k == 0 ? formats : std::vector<const FrameWriter*>{});
  }
}

bool RigSceneWriter::HasFrame(int image_id) const {
  for (const auto& sensor : sensors_) {
    if (!sensor->HasFrame(image_id)) return false;
  }
  return true;
}

std::vector<int> RigSceneWriter::WrittenFrames() const {
  std::vector<int> ids = sensors_[0]->WrittenFrames();
  for (size_t k = 1; k < sensors_.size(); ++k) {
    const std::vector<int> other = sensors_[k]->WrittenFrames();
    std::vector<int> both;
    std::set_intersection(ids.begin(), ids.end(), other.begin(), other.end(),
                          std::back_inserter(both));
    ids = std::move(both);
  }
  return ids;
}

std::string RigSceneWriter::CheckFrame(int image_id) const {
  for (const auto& sensor : sensors_) {
    std::string problem = sensor->CheckFrame(image_id);
    if (!problem.empty()) return problem;
  }
  return {};
}

void RigSceneWriter::ForgetFrame(int image_id) {
  for (const auto& sensor : sensors_) sensor->ForgetFrame(image_id);
}

std::vector<SceneSplit> RigSceneWriter::Finish() {
  // A frame one sensor wrote and another did not (a run stopped between them) is not complete:
  // it is rendered again before any finish, so here every sensor holds the same frames.
  const std::vector<int> complete = WrittenFrames();
  std::vector<SceneSplit> splits;
  for (const auto& sensor : sensors_) {
    if (sensor->WrittenFrames() != complete) {
      throw Error(sensor->scene_dir().string() + ": sensor '" + sensor->sensor().name +
                  "' holds frames the rig's other sensors lack");
    }
    splits.push_back(sensor->Finish());
  }
  return splits;
}

void RigSceneWriter::RemoveFragments() {
  for (const auto& sensor : sensors_) sensor->RemoveFragments();
}

void RigSceneWriter::WriteWorldPoses(const std::vector<Instance>& instances) {
  sensors_[0]->WriteWorldPoses(instances);
}

void RigSceneWriter::SetCocoCategories(
    const std::vector<BopSceneWriter::CocoCategory>& categories) {
  for (const auto& sensor : sensors_) sensor->SetCocoCategories(categories);
}

void WriteMultiviewTargets(const std::filesystem::path& root, const std::vector<SceneSplit>& scenes,
                           const std::vector<BopSensor>& sensors) {
  Json targets = Json::array();
  for (size_t s = 0; s < scenes.size(); ++s) {
    for (int im : scenes[s].test) {
      Json views = Json::array();
      for (const BopSensor& sensor : sensors) views.push_back(Json::array({sensor.name, im}));
      targets.push_back({{"scene_id", s}, {"im_id", views}});
    }
  }
  WriteFileAtomic(root / "test_targets_multiview_bop25.json", targets.dump(2) + "\n");
}

std::filesystem::path FindSceneFolder(const std::filesystem::path& dataset,
                                      const std::string& sensor) {
  if (!std::filesystem::is_directory(dataset))
    throw Error(dataset.string() + ": no such dataset folder");
  const std::string wanted = "scene_gt" + BopSensor{sensor}.Suffix() + ".json";
  std::vector<std::filesystem::path> roots;
  std::set<std::string> sensors;  // of a multi-sensor dataset: scene_gt_NAME.json
  for (const auto& entry : std::filesystem::directory_iterator(dataset)) {
    if (!entry.is_directory()) continue;
    for (const auto& scene : std::filesystem::directory_iterator(entry.path())) {
      if (std::filesystem::exists(scene.path() / wanted)) {
        roots.push_back(entry.path());
        break;
      }
      if (!scene.is_directory() || !ParseBopId(scene.path().filename().string())) continue;
      for (const auto& file : std::filesystem::directory_iterator(scene.path())) {
        const std::string name = file.path().filename().string();
        if (name.rfind("scene_gt_", 0) == 0 && name.size() > 14 &&
            name.compare(name.size() - 5, 5, ".json") == 0 && name.rfind("scene_gt_info", 0) != 0 &&
            name.rfind("scene_gt_coco", 0) != 0 && name.rfind("scene_gt_world", 0) != 0)
          sensors.insert(name.substr(9, name.size() - 14));
      }
    }
  }
  if (roots.size() != 1) {
    std::string names;
    for (const std::string& name : sensors) names += (names.empty() ? "" : ", ") + name;
    if (roots.empty() && !sensors.empty()) {
      throw Error(dataset.string() + ": " +
                  (sensor.empty() ? "a multi-sensor dataset" : "has no sensor '" + sensor + "'") +
                  " (sensors: " + names + "): choose one with --sensor NAME");
    }
    throw Error(dataset.string() + ": expected one folder of scenes with " + wanted + ", found " +
                std::to_string(roots.size()));
  }
  return roots[0];
}

}  // namespace cadsynth
