// What the BOP writers' sources share (dataset/bop.cpp, bop_fragment.cpp, bop_rig.cpp, models.cpp,
// coco.cpp), so that every file writes numbers, poses and JSON layout alike. Internal to
// dataset/: it brings in nlohmann-json, which the public headers keep out.
#pragma once

#include <filesystem>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "dataset/file_io.h"
#include "render/camera.h"

namespace cadsynth::bop_internal {

// Keys in the order they are written (BOP's files list them in the writers' order).
using Json = nlohmann::ordered_json;

// OpenCV's distortion coefficients in its order: [k1, k2, p1, p2, k3].
inline Json DistCoeffs(const Distortion& d) { return Json::array({d.k1, d.k2, d.p1, d.p2, d.k3}); }

inline Json RowMajor(const Eigen::Matrix3d& r) {
  Json out = Json::array();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) out.push_back(r(i, j));
  }
  return out;
}

inline Json Vec(const Eigen::Vector3d& t) { return Json::array({t.x(), t.y(), t.z()}); }

inline void WriteJson(const std::filesystem::path& path, const Json& json) {
  WriteFileAtomic(path, json.dump(2) + "\n");
}

}  // namespace cadsynth::bop_internal
