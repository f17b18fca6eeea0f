// Grasp-detector input: an object's points seen by the depth camera, as NumPy arrays; the
// `grasp` output format (dataset/output_formats.h) writes them per visible instance:
//
//   ROOT/grasp/SCENEID/IMID_INST.npy      visible points of each instance, camera frame, m
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "render/frame.h"

namespace cadsynth {

// The pixels where `instance` is visible and the written depth image (at `depth_scale` mm per
// unit) has a value, back-projected through the pixel centre into the camera frame, in metres:
// z = depth, x = (u + 0.5 - cx) z / fx, y = (v + 0.5 - cy) z / fy (with lens distortion, x and y
// of the pixel centre's ray, Intrinsics::Unproject, times z). Row-major pixel order.
std::vector<Eigen::Vector3f> BackProjectInstance(const Frame& frame, int instance,
                                                 double depth_scale);

// A NumPy .npy file (format 1.0) holding `points` as a little-endian float32 array (N, 3).
std::string EncodeNpy(const std::vector<Eigen::Vector3f>& points);
// A NumPy .npy file (format 1.0) holding `rows` x `cols` little-endian float32 values (row-major).
std::string EncodeNpy(const float* values, size_t rows, size_t cols);
// The values of a 2-D little-endian float32 .npy file (C order), its shape in *rows, *cols. Throws
// Error naming `origin` for anything else.
std::vector<float> DecodeNpy(const std::string& bytes, const std::string& origin, size_t* rows,
                             size_t* cols);

}  // namespace cadsynth
