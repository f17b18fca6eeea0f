#include "dataset/models.h"

#include <algorithm>
#include <cstring>
#include <iterator>
#include <vector>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/convex_hull_3.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

namespace cadsynth {

double MeshDiameter(const Mesh& mesh) {
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  using Point = Kernel::Point_3;
  if (mesh.positions.size() < 2) return 0.0;
  std::vector<Point> points;
  points.reserve(mesh.positions.size());
  for (const Eigen::Vector3f& p : mesh.positions) points.emplace_back(p.x(), p.y(), p.z());
  std::vector<Point> extreme;
  CGAL::extreme_points_3(points, std::back_inserter(extreme));
  if (extreme.size() < 2) extreme = points;  // degenerate (flat or collinear) input

  std::vector<Eigen::Vector3d> hull;
  hull.reserve(extreme.size());
  for (const Point& p : extreme) hull.emplace_back(p.x(), p.y(), p.z());
  const double max_sq = tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, hull.size(), 64), 0.0,
      [&](const tbb::blocked_range<size_t>& range, double best) {
        for (size_t i = range.begin(); i < range.end(); ++i) {
          for (size_t j = i + 1; j < hull.size(); ++j) {
            best = std::max(best, (hull[i] - hull[j]).squaredNorm());
          }
        }
        return best;
      },
      [](double a, double b) { return std::max(a, b); });
  return std::sqrt(max_sq);
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
