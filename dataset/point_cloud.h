// Points on a model's surface and keypoints, as pose estimators (PVN3D, the reference paper) use.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "cad/mesh.h"

namespace cadsynth {

// `count` points uniformly distributed over the surface by area: each triangle gets its share by
// a seeded draw, each point a seeded position inside it (model frame, mm).
std::vector<Eigen::Vector3f> SampleSurface(const Mesh& mesh, int count, uint64_t seed);

// `count` evenly spaced surface points (blue noise): farthest-point thinning of 10 x count
// area-uniform candidates, so that no two points are much closer than the typical spacing.
std::vector<Eigen::Vector3f> SampleEvenly(const Mesh& mesh, int count, uint64_t seed);

// Indices of `k` points chosen by farthest-point sampling, starting from the point farthest from
// the points' centroid (deterministic).
std::vector<int> FarthestPoints(const std::vector<Eigen::Vector3f>& points, int k);

struct Keypoints {
  std::vector<Eigen::Vector3f> fps8, fps16;  // farthest-point keypoints on the surface
  Eigen::Vector3f center;                    // the model origin: the bounding-box centre
  std::array<Eigen::Vector3f, 8> corners;    // bounding-box corners
};
Keypoints ComputeKeypoints(const Mesh& mesh, const std::vector<Eigen::Vector3f>& surface_points);

// ASCII PLY with x, y, z (mm).
std::string EncodePointPly(const std::vector<Eigen::Vector3f>& points);
// Reads what EncodePointPly writes (ASCII PLY whose first three vertex properties are x, y, z).
// `origin` names the file in the Error thrown on anything else.
std::vector<Eigen::Vector3f> DecodePointPly(const std::string& text, const std::string& origin);

}  // namespace cadsynth
