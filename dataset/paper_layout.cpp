#include "dataset/paper_layout.h"

#include <matio.h>

#include <algorithm>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "cad/core/error.h"
#include "dataset/file_io.h"
#include "dataset/image_mat.h"
#include "dataset/output_formats.h"

namespace cadsynth {
namespace {

nlohmann::ordered_json Matrix4(const Eigen::Isometry3d& t) {
  nlohmann::ordered_json rows = nlohmann::ordered_json::array();
  for (int r = 0; r < 4; ++r)
    rows.push_back({t.matrix()(r, 0), t.matrix()(r, 1), t.matrix()(r, 2), t.matrix()(r, 3)});
  return rows;
}

// One MATLAB double array, column-major `data` with `dims`.
void WriteMatDouble(mat_t* mat, const char* name, std::vector<size_t> dims,
                    std::vector<double> data, const std::filesystem::path& path) {
  matvar_t* var = Mat_VarCreate(name, MAT_C_DOUBLE, MAT_T_DOUBLE, static_cast<int>(dims.size()),
                                dims.data(), data.data(), 0);
  if (var == nullptr) throw Error(path.string() + ": cannot create MATLAB variable " + name);
  const int status = Mat_VarWrite(mat, var, MAT_COMPRESSION_NONE);
  Mat_VarFree(var);
  if (status != 0) throw Error(path.string() + ": cannot write MATLAB variable " + name);
}

}  // namespace

void WritePvn3dMeta(const std::filesystem::path& path, const Frame& frame,
                    const std::vector<int>& cls_of_instance, double depth_scale) {
  std::vector<size_t> shown;
  for (size_t i = 0; i < frame.instances.size(); ++i) {
    if (frame.instances[i].px_count_visib > 0) shown.push_back(i);
  }
  const size_t n = shown.size();
  std::vector<double> cls(n), poses(12 * n), center(2 * n);
  const Intrinsics& k = frame.camera.intrinsics;
  for (size_t j = 0; j < n; ++j) {
    const Eigen::Isometry3d& m2c = frame.instances[shown[j]].cam_from_model;
    cls[j] = cls_of_instance.at(shown[j]);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) poses[r + 3 * c + 12 * j] = m2c.linear()(r, c);
      poses[r + 3 * 3 + 12 * j] = m2c.translation()(r) / 1000.0;
    }
    // With the lens's distortion; a centre beyond its fold radius (outside the imaged field) keeps
    // the pinhole's point, which lies outside the image as well.
    Eigen::Vector2d uv;
    if (!k.Project(m2c.translation(), &uv)) {
      const Eigen::Vector3d t = m2c.translation();
      uv = Eigen::Vector2d(k.fx * t.x() / t.z() + k.cx, k.fy * t.y() / t.z() + k.cy);
    }
    center[j] = uv.x();      // column 0: u
    center[j + n] = uv.y();  // column 1: v
  }
  std::vector<double> kmat(9), w2c(12);
  const Eigen::Matrix3d kk = k.K();
  const Eigen::Isometry3d cam_from_world = frame.camera.world_from_cam.inverse();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      kmat[r + 3 * c] = kk(r, c);
      w2c[r + 3 * c] = cam_from_world.linear()(r, c);
    }
    w2c[r + 9] = cam_from_world.translation()(r) / 1000.0;
  }

  const std::string temporary = path.string() + ".tmp";
  // A fixed header: matio's default one carries the creation time, and the same run must give
  // the same bytes (resumed runs, shards).
  mat_t* mat =
      Mat_CreateVer(temporary.c_str(), "MATLAB 5.0 MAT-file, written by cadsynth", MAT_FT_MAT5);
  if (mat == nullptr) throw Error(path.string() + ": cannot create MATLAB file");
  try {
    WriteMatDouble(mat, "cls_indexes", {n, 1}, cls, path);
    WriteMatDouble(mat, "poses", {3, 4, n}, poses, path);
    WriteMatDouble(mat, "intrinsic_matrix", {3, 3}, kmat, path);
    WriteMatDouble(mat, "factor_depth", {1, 1}, {1000.0 / depth_scale}, path);
    WriteMatDouble(mat, "center", {n, 2}, center, path);
    WriteMatDouble(mat, "rotation_translation_matrix", {3, 4}, w2c, path);
  } catch (...) {
    Mat_Close(mat);
    std::filesystem::remove(temporary);
    throw;
  }
  if (Mat_Close(mat) != 0) {
    std::filesystem::remove(temporary);
    throw Error(path.string() + ": cannot write MATLAB file (disk full?)");
  }
  std::error_code ec;
  std::filesystem::rename(temporary, path, ec);
  if (ec) throw Error(path.string() + ": cannot move file into place: " + ec.message());
}

namespace {

// Each instance's obj_id: its grey value in the paper's mask and its PVN3D class index.
std::vector<int> ObjIds(const std::vector<FormatInstance>& instances) {
  std::vector<int> labels;
  for (const FormatInstance& p : instances) labels.push_back(p.obj_id);
  return labels;
}

void CheckInstances(const Frame& frame, const std::vector<FormatInstance>& instances) {
  if (frame.instances.size() != instances.size()) {
    throw Error("paper layout: frame has " + std::to_string(frame.instances.size()) +
                " instances, the scene " + std::to_string(instances.size()));
  }
}

class PaperLayoutWriter : public FrameWriter {
 public:
  explicit PaperLayoutWriter(const FormatScene& scene)
      : root_(scene.root),
        paper_dir_(scene.root / "paper" / Id6(scene.scene_id)),
        options_(scene.options),
        instances_(scene.instances) {
    for (const char* sub : {"rgb", "depth", "mask", "meta"}) CreateFolder(paper_dir_ / sub);
  }

  void WriteFrame(int image_id, const Frame& frame, const BopFrameFiles& bop,
                  FileLog* files_or_null) const override {
    FileLog own(root_);
    FileLog& files = files_or_null != nullptr ? *files_or_null : own;
    CheckInstances(frame, instances_);
    const std::string im = Id6(image_id);
    const std::vector<int> labels = ObjIds(instances_);
    const std::string rgb = im + options_.RgbExtension();
    files.Link(bop.image, paper_dir_ / "rgb" / rgb);
    files.Link(bop.depth, paper_dir_ / "depth" / (im + ".png"));
    // The mask: each visible pixel gets its object's obj_id as grey value (8 or 16 bit).
    const int w = frame.width(), h = frame.height();
    const bool wide = !labels.empty() && *std::max_element(labels.begin(), labels.end()) > 255;
    cv::Mat mask(h, w, wide ? CV_16UC1 : CV_8UC1, cv::Scalar(0));
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) {
        const uint16_t id = frame.instance[static_cast<size_t>(v) * w + u];
        if (id == 0) continue;
        if (wide) {
          mask.at<uint16_t>(v, u) = static_cast<uint16_t>(labels[id - 1]);
        } else {
          mask.at<uint8_t>(v, u) = static_cast<uint8_t>(labels[id - 1]);
        }
      }
    }
    const std::filesystem::path mask_path = paper_dir_ / "mask" / (im + ".png");
    files.Write(mask_path, image_mat::Png(mask, mask_path.string()));
    files.Write(paper_dir_ / "meta" / (im + ".json"), Meta(frame).dump(2) + "\n");
  }

 private:
  nlohmann::ordered_json Meta(const Frame& frame) const {
    nlohmann::ordered_json objects = nlohmann::ordered_json::array();
    for (size_t i = 0; i < instances_.size(); ++i) {
      const FormatInstance& p = instances_[i];
      objects.push_back({{"inst_id", i},
                         {"obj_id", p.obj_id},
                         {"class_id", p.object_class.id},
                         {"class_name", p.object_class.name},
                         {"name", p.name},
                         {"grey", p.obj_id},
                         {"px_count_visib", frame.instances[i].px_count_visib},
                         {"T_O_C", Matrix4(frame.instances[i].cam_from_model)},
                         {"T_O_W", Matrix4(p.world_from_model)}});
    }
    const Eigen::Matrix3d k = frame.camera.intrinsics.K();
    nlohmann::ordered_json meta = {
        {"K",
         {{k(0, 0), k(0, 1), k(0, 2)}, {k(1, 0), k(1, 1), k(1, 2)}, {k(2, 0), k(2, 1), k(2, 2)}}},
        {"depth_scale", options_.depth_scale},
        {"width", frame.width()},
        {"height", frame.height()},
        {"T_C_W", Matrix4(frame.camera.world_from_cam)},
        {"objects", objects}};
    const Distortion& d = frame.camera.intrinsics.distortion;
    if (d.active()) meta["dist_coeffs"] = {d.k1, d.k2, d.p1, d.p2, d.k3};  // OpenCV's order
    return meta;
  }

  std::filesystem::path root_, paper_dir_;
  BopOptions options_;
  std::vector<FormatInstance> instances_;
};

// Runs after PaperLayoutWriter (OutputFormats() order), whose meta/ folder it writes into.
class Pvn3dWriter : public FrameWriter {
 public:
  explicit Pvn3dWriter(const FormatScene& scene)
      : root_(scene.root),
        meta_dir_(scene.root / "paper" / Id6(scene.scene_id) / "meta"),
        depth_scale_(scene.options.depth_scale),
        instances_(scene.instances) {
    CreateFolder(meta_dir_);
  }

  void WriteFrame(int image_id, const Frame& frame, const BopFrameFiles&,
                  FileLog* files_or_null) const override {
    FileLog own(root_);
    FileLog& files = files_or_null != nullptr ? *files_or_null : own;
    CheckInstances(frame, instances_);
    const std::filesystem::path mat = meta_dir_ / (Id6(image_id) + "-meta.mat");
    WritePvn3dMeta(mat, frame, ObjIds(instances_), depth_scale_);
    files.Add(mat);
  }

 private:
  std::filesystem::path root_, meta_dir_;
  double depth_scale_;
  std::vector<FormatInstance> instances_;
};

}  // namespace

std::unique_ptr<FrameWriter> MakePaperLayoutWriter(const FormatScene& scene) {
  return std::make_unique<PaperLayoutWriter>(scene);
}

std::unique_ptr<FrameWriter> MakePvn3dWriter(const FormatScene& scene) {
  return std::make_unique<Pvn3dWriter>(scene);
}

}  // namespace cadsynth
