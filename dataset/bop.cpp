// BOP encoding: the options' checks, images (colour, grey, depth, masks), visibility and the
// ground-truth statistics, BopSceneWriter's frames and scene files, the splits. The rest of
// dataset/bop.h is defined by concern: bop_fragment.cpp (the scene's journal: fragments and the
// resume half), bop_rig.cpp (rigs, multi-view targets), bop_classes.cpp (object classes),
// models.cpp (the models/ folder), coco.cpp (the merged COCO).
#include "dataset/bop.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <set>
#include <system_error>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "cad/core/error.h"
#include "cad/core/random.h"
#include "dataset/bop_fragment.h"
#include "dataset/bop_internal.h"
#include "dataset/bop_read.h"
#include "dataset/coco.h"
#include "dataset/file_io.h"
#include "dataset/image_mat.h"
#include "dataset/mask_png.h"

namespace cadsynth {

using bop_internal::DistCoeffs;
using bop_internal::Fragment;
using bop_internal::FragmentText;
using bop_internal::Json;
using bop_internal::ReadFragment;
using bop_internal::RowMajor;
using bop_internal::Vec;
using bop_internal::WriteJson;

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
  if (archive_samples < 1 || archive_samples > 1000000 || archive_megabytes < 1 ||
      archive_megabytes > 1048576) {
    *why = "archive_samples must be 1 to 1,000,000 and archive_megabytes 1 to 1,048,576";
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

std::string EncodePng(const cv::Mat& image, const std::filesystem::path& where) {
  return image_mat::Png(image, where.string());
}

}  // namespace

std::string EncodeImagePng(const void* pixels, int width, int height, int channels, int bits) {
  if (width <= 0 || height <= 0 || (channels != 1 && channels != 3) || (bits != 8 && bits != 16))
    throw Error("PNG: an image must be 1 or 3 channels of 8 or 16 bits, " + std::to_string(width) +
                " x " + std::to_string(height) + " x " + std::to_string(channels) + " x " +
                std::to_string(bits) + " bits given");
  ImageView view;
  view.pixels = pixels;
  view.width = width;
  view.height = height;
  view.channels = channels;
  view.bits = bits;
  return EncodePng(view);
}

namespace {

// An alpha channel dropped: grey and alpha to grey, RGBA to RGB.
DecodedImage WithoutAlpha(DecodedImage image) {
  if (image.channels != 2 && image.channels != 4) return image;
  const size_t size = static_cast<size_t>(image.bits / 8);
  const size_t from = image.channels * size, to = (image.channels - 1) * size;
  const size_t count = static_cast<size_t>(image.width) * image.height;
  for (size_t i = 0; i < count; ++i)
    std::memmove(image.bytes.data() + i * to, image.bytes.data() + i * from, to);
  image.bytes.resize(count * to);
  image.channels -= 1;
  return image;
}

}  // namespace

DecodedImage ReadImageFile(const std::filesystem::path& path) {
  return WithoutAlpha(ReadImageBytesFile(path));
}

DecodedImage DecodeImage(std::string_view bytes, const std::string& origin) {
  return WithoutAlpha(DecodeImageBytes(bytes, origin));
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
  image_ids_ = bop_internal::FragmentIds(Folder(".fragments"));
}

namespace {

// Where WriteFrame's helpers write one frame's files: the folder of each kind of image (with the
// sensor's suffix, BopSceneWriter::Folder), the image's file stem and the frame's manifest entry.
struct FrameOut {
  std::function<std::filesystem::path(const std::string&)> folder;
  std::string im;  // Id6(image_id)
  FileLog* files;
};

// The camera's image: colour, or grey (8 or 16 bits) for a grey camera. Returns its path.
std::filesystem::path WriteCameraImage(const Frame& frame, const BopOptions& options,
                                       const FrameOut& out) {
  const int w = frame.width(), h = frame.height();
  cv::Mat grey;
  ImageView image;
  if (options.gray_bits > 0) {
    if (frame.gray.size() != static_cast<size_t>(w) * h)
      throw Error("bop: a grey camera's frame has no grey image");
    const bool deep = options.gray_bits == 16;
    grey.create(h, w, deep ? CV_16UC1 : CV_8UC1);
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) {
        const uint16_t value =
            EncodeGray(frame.gray[static_cast<size_t>(v) * w + u], options.gray_bits);
        if (deep) {
          grey.at<uint16_t>(v, u) = value;
        } else {
          grey.at<uint8_t>(v, u) = static_cast<uint8_t>(value);
        }
      }
    }
    image = image_mat::ViewOf(grey);
  } else {
    image.pixels = frame.rgb.data();
    image.width = w;
    image.height = h;
    image.channels = 3;
  }
  const std::filesystem::path rgb_path =
      out.folder(options.ImageFolder()) / (out.im + options.RgbExtension());
  try {
    out.files->Write(rgb_path, options.jpeg_quality > 0 ? EncodeJpeg(image, options.jpeg_quality)
                                                        : EncodePng(image));
  } catch (const Error& e) {
    throw Error(rgb_path.string() + ": " + e.what());
  }
  return rgb_path;
}

// depth/: what the sensor returns; with a depth model other than ideal, depth_gt/ holds the
// exact depth every label comes from.
void WriteDepthImages(const Frame& frame, const BopOptions& options, const FrameOut& out) {
  const int w = frame.width(), h = frame.height();
  const auto write_depth = [&](const std::vector<float>& values, const char* folder) {
    cv::Mat depth(h, w, CV_16UC1);
    for (int v = 0; v < h; ++v) {
      auto* row = depth.ptr<uint16_t>(v);
      for (int u = 0; u < w; ++u) {
        row[u] = EncodeDepth(values[static_cast<size_t>(v) * w + u], options.depth_scale);
      }
    }
    const std::filesystem::path depth_path = out.folder(folder) / (out.im + ".png");
    out.files->Write(depth_path, EncodePng(depth, depth_path));
  };
  if (frame.sensor_depth.empty()) {
    write_depth(frame.depth, "depth");
  } else {
    CreateFolder(out.folder("depth_gt"));
    write_depth(frame.sensor_depth, "depth");
    write_depth(frame.depth, "depth_gt");
  }
}

// The images a frame has only with some cameras and render settings: ir/, normal/, rgb_hdr/.
void WriteExtraImages(const Frame& frame, const BopOptions& options, const FrameOut& out) {
  const int w = frame.width(), h = frame.height();
  // ir/: the IR camera's image (active_stereo's left IR image, the projector's dots in it).
  if (options.infrared && !frame.infrared.empty()) {
    if (frame.infrared.size() != static_cast<size_t>(w) * h)
      throw Error("bop: the frame's IR image has the wrong size");
    CreateFolder(out.folder("ir"));
    const cv::Mat ir(h, w, CV_8UC1, const_cast<uint8_t*>(frame.infrared.data()));
    const std::filesystem::path ir_path = out.folder("ir") / (out.im + ".png");
    out.files->Write(ir_path, EncodePng(ir, ir_path));
  }

  // Camera-frame normals as 8-bit RGB: (n + 1) / 2 * 255; (0, 0, 0) = none.
  if (!frame.normals.empty()) {
    CreateFolder(out.folder("normal"));
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
    const std::filesystem::path normal_path = out.folder("normal") / (out.im + ".png");
    out.files->Write(normal_path, EncodePng(normals, normal_path));
  }

  if (!frame.radiance.empty()) {  // pbr with hdr: linear radiance as 32-bit float EXR
    CreateFolder(out.folder("rgb_hdr"));
    ImageView radiance;
    radiance.pixels = frame.radiance.data();
    radiance.width = w;
    radiance.height = h;
    radiance.channels = 3;
    radiance.bits = 32;
    const std::filesystem::path hdr_path = out.folder("rgb_hdr") / (out.im + ".exr");
    try {
      out.files->Write(hdr_path, EncodeExr(radiance));
    } catch (const Error& e) {
      throw Error(hdr_path.string() + ": " + e.what());
    }
  }
}

// The frame's scene_camera.json entry.
Json CameraEntry(const Frame& frame, const BopOptions& options) {
  Json camera_entry;
  const Eigen::Isometry3d cam_from_world = frame.camera.world_from_cam.inverse();
  Json k = Json::array();
  const Eigen::Matrix3d kmat = frame.camera.intrinsics.K();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) k.push_back(kmat(r, c));
  }
  camera_entry = {{"cam_K", k},
                  {"depth_scale", options.depth_scale},
                  {"cam_R_w2c", RowMajor(cam_from_world.linear())},
                  {"cam_t_w2c", Vec(cam_from_world.translation())}};
  // Beside cam_K, in OpenCV's order; only for a camera with lens distortion (BOP's images have
  // none: its readers ignore the key).
  if (frame.camera.intrinsics.distortion.active())
    camera_entry["cam_dist_coeffs"] = DistCoeffs(frame.camera.intrinsics.distortion);
  return camera_entry;
}

// Writes instance i's mask/ and mask_visib/ images (IMID_GTID.png) through `mask`, an all-zero
// image that is zero again on return, and returns the in-image box of its full silhouette
// (inclusive; {w, h, -1, -1} when it has no pixel in the image): COCO's amodal box.
std::array<int, 4> WriteMasks(const Frame& frame, size_t i, const GtInfo& info,
                              const VisibleMasks& visible, const FrameOut& out, cv::Mat* mask) {
  const int w = frame.width(), h = frame.height();
  const Frame::InstanceTruth& truth = frame.instances[i];
  const std::string name = out.im + "_" + Id6(static_cast<int>(i)) + ".png";
  // Masks are zero outside the full silhouette's rectangle: fill only inside.
  const auto [r0, r1, r2, r3] = truth.Roi(w, h);
  std::array<int, 4> full = {w, h, -1, -1};
  for (int v = r1; v < r3 && !truth.amodal_mask.empty(); ++v) {
    auto* row = mask->ptr<uint8_t>(v);
    const uint8_t* in = &truth.amodal_mask[static_cast<size_t>(v - r1) * (r2 - r0)];
    for (int u = r0; u < r2; ++u) {
      if (in[u - r0] == 0) continue;
      row[u] = 255;
      full[0] = std::min(full[0], u), full[1] = std::min(full[1], v);
      full[2] = std::max(full[2], u), full[3] = std::max(full[3], v);
    }
  }
  out.files->Write(out.folder("mask") / name, EncodeMaskPng(mask->data, mask->step, w, h, r1, r3));
  const int* b = info.bbox_visib;  // inclusive: [b0, b0 + b2] x [b1, b1 + b3]
  const int visib_end = info.px_count_visib > 0 ? b[1] + b[3] + 1 : b[1];
  for (int v = r1; v < r3; ++v) std::memset(mask->ptr<uint8_t>(v), 0, w);
  for (int v = b[1]; v < visib_end; ++v) {
    auto* row = mask->ptr<uint8_t>(v);
    for (int u = b[0]; u <= b[0] + b[2]; ++u) row[u] = visible(i, u, v) ? 255 : 0;
  }
  out.files->Write(out.folder("mask_visib") / name,
                   EncodeMaskPng(mask->data, mask->step, w, h, b[1], visib_end));
  for (int v = b[1]; v < visib_end; ++v) std::memset(mask->ptr<uint8_t>(v), 0, w);
  return full;
}

// A frame's per-instance entries of scene_gt.json, scene_gt_info.json and scene_gt_coco.json.
struct InstanceEntries {
  Json gt = Json::array(), gt_info = Json::array(), coco = Json::array();
};

// Writes every instance's masks, in instance order, and returns its entries.
InstanceEntries WriteInstances(const Frame& frame, const BopOptions& options,
                               const std::vector<int>& obj_ids, const FrameOut& out) {
  const int w = frame.width(), h = frame.height();
  InstanceEntries entries;
  const VisibleMasks visible(frame, options);
  const std::vector<GtInfo> infos = ComputeGtInfos(frame, options, visible);
  // Each instance's masks are written into the rows they cover and cleared after: the rest of
  // the image stays zero, and only the band of rows that may not be is compressed.
  cv::Mat mask = cv::Mat::zeros(h, w, CV_8UC1);
  for (size_t i = 0; i < frame.instances.size(); ++i) {
    const Frame::InstanceTruth& truth = frame.instances[i];
    entries.gt.push_back({{"cam_R_m2c", RowMajor(truth.cam_from_model.linear())},
                          {"cam_t_m2c", Vec(truth.cam_from_model.translation())},
                          {"obj_id", obj_ids[i]}});
    const GtInfo& info = infos[i];
    entries.gt_info.push_back(
        {{"bbox_obj", {info.bbox_obj[0], info.bbox_obj[1], info.bbox_obj[2], info.bbox_obj[3]}},
         {"bbox_visib",
          {info.bbox_visib[0], info.bbox_visib[1], info.bbox_visib[2], info.bbox_visib[3]}},
         {"px_count_all", info.px_count_all},
         {"px_count_valid", info.px_count_valid},
         {"px_count_visib", info.px_count_visib},
         {"visib_fract", info.visib_fract}});

    const std::array<int, 4> full = WriteMasks(frame, i, info, visible, out, &mask);

    // COCO, as bop_toolkit's calc_gt_coco.py: every instance with a visible pixel, its visible
    // mask as compressed RLE, the amodal (or modal) box with COCO's width max - min + 1, and
    // "ignore" below 10% visibility.
    if (!options.coco || info.px_count_visib == 0 || (options.coco_amodal_bbox && full[2] < 0))
      continue;
    const int* b = info.bbox_visib;
    const RleMask rle = EncodeRle(w, h, b[0], b[1], b[0] + b[2] + 1, b[1] + b[3] + 1,
                                  [&](size_t p) { return visible.AtPixel(i, p); });
    const Json coco_box = options.coco_amodal_bbox
                              ? Json{full[0], full[1], full[2] - full[0] + 1, full[3] - full[1] + 1}
                              : Json{b[0], b[1], b[2] + 1, b[3] + 1};
    entries.coco.push_back({{"inst_id", i},
                            {"obj_id", obj_ids[i]},
                            {"area", info.px_count_visib},
                            {"bbox", coco_box},
                            {"ignore", info.visib_fract < 0.1},
                            {"counts", CompressRleCounts(rle.counts)}});
  }
  return entries;
}

}  // namespace

void BopSceneWriter::WriteFrame(int image_id, const Frame& frame,
                                const std::vector<const FrameWriter*>& formats) {
  if (frame.instances.size() != obj_ids_.size()) {
    throw Error("bop: frame has " + std::to_string(frame.instances.size()) +
                " instances, the scene " + std::to_string(obj_ids_.size()));
  }
  FileLog files(root_);
  const FrameOut out{[this](const std::string& name) { return Folder(name); }, Id6(image_id),
                     &files};
  const std::filesystem::path rgb_path = WriteCameraImage(frame, options_, out);
  WriteDepthImages(frame, options_, out);
  WriteExtraImages(frame, options_, out);
  const Json camera_entry = CameraEntry(frame, options_);
  const InstanceEntries entries = WriteInstances(frame, options_, obj_ids_, out);
  const BopFrameFiles bop{rgb_path, Folder("depth") / (out.im + ".png")};
  for (const FrameWriter* format : formats) format->WriteFrame(image_id, frame, bop, &files);
  // One fragment per frame, written last (dataset/bop_fragment.h): five lines of compact JSON
  // read back in order by Finish(), the manifest entry among them (every file the frame wrote
  // with size and CRC-32).
  WriteFileAtomic(FragmentPath(image_id),
                  FragmentText(camera_entry, entries.gt, entries.gt_info, frame.width(),
                               frame.height(), entries.coco, files.records(), frame.randomization));
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

void BopSceneWriter::WriteSequence(const SequenceStep& step) {
  if (step.instance_ids.size() != obj_ids_.size() || step.freed.size() != obj_ids_.size() ||
      step.moved_mm.size() != obj_ids_.size())
    throw Error("bop: a sequence step for a different number of instances");
  Json instances = Json::array();
  for (size_t i = 0; i < obj_ids_.size(); ++i) {
    instances.push_back({{"inst_id", step.instance_ids[i]},
                         {"obj_id", obj_ids_[i]},
                         {"freed", static_cast<bool>(step.freed[i])},
                         {"moved_mm", step.moved_mm[i]}});
  }
  Json pick = nullptr;
  if (step.picked_id >= 0) {
    Json grasps = Json::array();
    for (const SequenceStep::Grasp& g : step.grasps) {
      grasps.push_back({{"kind", g.kind},
                        {"index", g.index},
                        {"quality", g.quality},
                        {"world_R_t2w", RowMajor(g.world_from_tool.linear())},
                        {"world_t_t2w", Vec(g.world_from_tool.translation())}});
    }
    pick = {{"inst_id", step.picked_id},
            {"obj_id", step.picked_obj_id},
            {"world_R_m2w", RowMajor(step.picked_world_from_model.linear())},
            {"world_t_m2w", Vec(step.picked_world_from_model.translation())},
            {"grasps", grasps},
            {"settle_seconds", step.settle_seconds},
            {"restless", step.restless}};
  }
  WriteJson(scene_dir_ / "scene_sequence.json", Json{{"first_scene_id", step.first_scene},
                                                     {"step", step.step},
                                                     {"picks", step.picks},
                                                     {"rule", step.rule},
                                                     {"pick", pick},
                                                     {"instances", instances}});
}

void BopSceneWriter::WriteRest(const SceneRest& rest) {
  for (const std::vector<int>* ids : {&rest.restless, &rest.outside}) {
    for (int id : *ids) {
      if (id < 0 || static_cast<size_t>(id) >= obj_ids_.size())
        throw Error("bop: a rest record naming instance " + std::to_string(id) + " of " +
                    std::to_string(obj_ids_.size()));
    }
  }
  Json shapes = Json::array();
  for (const SceneRest::Shape& shape : rest.shapes) {
    shapes.push_back({{"obj_id", shape.obj_id},
                      {"pieces", shape.pieces},
                      {"decomposed", shape.decomposed},
                      {"volume_ratio", shape.volume_ratio},
                      {"timed_out", shape.timed_out}});
  }
  WriteJson(scene_dir_ / "scene_physics.json",
            Json{{"kind", rest.kind},
                 {"at_rest", rest.restless.empty()},
                 {"settle_seconds", rest.settle_seconds},
                 {"settle_time", rest.settle_time},
                 {"restless", rest.restless},
                 {"parts_dropped", rest.dropped},
                 {"removed_outside", rest.removed_outside},
                 {"kept_outside", rest.outside},
                 {"distractors", rest.distractors},
                 {"restless_distractors", rest.restless_distractors},
                 {"collision_shapes", shapes}});
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
