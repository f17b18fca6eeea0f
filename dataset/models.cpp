#include "dataset/models.h"

#include <algorithm>
#include <cstring>
#include <functional>
#include <iterator>
#include <vector>

#include "cad/core/error.h"
#include "cad/hull.h"

namespace cadsynth {

double MeshDiameter(const Mesh& mesh) {
  std::vector<Eigen::Vector3d> points;
  points.reserve(mesh.positions.size());
  for (const Eigen::Vector3f& p : mesh.positions) points.push_back(p.cast<double>());
  try {
    return ComputeConvexHull(std::move(points)).diameter;
  } catch (const Error&) {  // flat or collinear: every vertex
    std::vector<Eigen::Vector3d> all;
    all.reserve(mesh.positions.size());
    for (const Eigen::Vector3f& p : mesh.positions) all.push_back(p.cast<double>());
    return PointSetDiameter(std::move(all));
  }
}

double PartDiameter(const Part& part) {
  return part.hull ? part.hull->diameter : MeshDiameter(part.mesh);
}

namespace {

template <typename T>
void Put(std::string* out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));  // x86-64 and aarch64 are little-endian
  out->append(bytes, sizeof(T));
}

}  // namespace

std::string EncodePly(const Mesh& mesh) {
  std::string out =
      "ply\nformat binary_little_endian 1.0\ncomment cadsynth model, units: mm\n"
      "element vertex " +
      std::to_string(mesh.num_vertices()) +
      "\nproperty float x\nproperty float y\nproperty float z\n"
      "property float nx\nproperty float ny\nproperty float nz\n"
      "element face " +
      std::to_string(mesh.num_triangles()) +
      "\nproperty list uchar int vertex_indices\nend_header\n";
  out.reserve(out.size() + mesh.num_vertices() * 24 + mesh.num_triangles() * 13);
  const bool has_normals = mesh.normals.size() == mesh.positions.size();
  for (size_t i = 0; i < mesh.num_vertices(); ++i) {
    for (int c = 0; c < 3; ++c) Put<float>(&out, mesh.positions[i][c]);
    for (int c = 0; c < 3; ++c) Put<float>(&out, has_normals ? mesh.normals[i][c] : 0.0f);
  }
  for (const auto& t : mesh.triangles) {
    Put<uint8_t>(&out, 3);
    for (int c = 0; c < 3; ++c) Put<int32_t>(&out, static_cast<int32_t>(t[c]));
  }
  return out;
}

}  // namespace cadsynth
