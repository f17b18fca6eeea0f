#include "dataset/models.h"

#include <algorithm>
#include <cstring>
#include <functional>
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
  // The farthest pair of hull vertices, exactly, without trying every pair (a finely tessellated
  // round part has most of its vertices on the hull): a k-d tree of the vertices, and for each
  // vertex a search that skips every node whose farthest corner is no farther than the best
  // pair found so far. The bound only skips pairs that cannot be longer, so the result is the
  // maximum over all pairs whatever the order of work.
  struct Node {
    Eigen::AlignedBox3d box;
    uint32_t begin, end, left = 0, right = 0;  // children 0: a leaf of points [begin, end)
  };
  std::vector<Node> nodes;
  const std::function<uint32_t(uint32_t, uint32_t)> build = [&](uint32_t begin,
                                                                uint32_t end) -> uint32_t {
    const uint32_t id = static_cast<uint32_t>(nodes.size());
    nodes.push_back(Node{Eigen::AlignedBox3d(), begin, end});
    Eigen::AlignedBox3d box;
    for (uint32_t i = begin; i < end; ++i) box.extend(hull[i]);
    nodes[id].box = box;
    if (end - begin > 16) {
      int axis = 0;
      box.sizes().maxCoeff(&axis);
      const uint32_t mid = begin + (end - begin) / 2;
      std::nth_element(
          hull.begin() + begin, hull.begin() + mid, hull.begin() + end,
          [axis](const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return a[axis] < b[axis]; });
      const uint32_t left = build(begin, mid);
      const uint32_t right = build(mid, end);
      nodes[id].left = left;
      nodes[id].right = right;
    }
    return id;
  };
  build(0, static_cast<uint32_t>(hull.size()));
  // A first bound: the farthest pair among the extremes along the axes.
  double bound = 0.0;
  {
    std::vector<size_t> extremes;
    for (int axis = 0; axis < 3; ++axis) {
      size_t lo = 0, hi = 0;
      for (size_t i = 0; i < hull.size(); ++i) {
        if (hull[i][axis] < hull[lo][axis]) lo = i;
        if (hull[i][axis] > hull[hi][axis]) hi = i;
      }
      extremes.insert(extremes.end(), {lo, hi});
    }
    for (size_t a : extremes) {
      for (size_t b : extremes) bound = std::max(bound, (hull[a] - hull[b]).squaredNorm());
    }
  }
  const auto farthest_corner = [](const Eigen::AlignedBox3d& box, const Eigen::Vector3d& p) {
    const Eigen::Vector3d d = (box.min() - p).cwiseAbs().cwiseMax((box.max() - p).cwiseAbs());
    return d.squaredNorm();
  };
  const double max_sq = tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, hull.size(), 256), bound,
      [&](const tbb::blocked_range<size_t>& range, double best) {
        std::vector<uint32_t> stack;
        for (size_t i = range.begin(); i < range.end(); ++i) {
          const Eigen::Vector3d& p = hull[i];
          stack.assign(1, 0);
          while (!stack.empty()) {
            const Node& node = nodes[stack.back()];
            stack.pop_back();
            if (farthest_corner(node.box, p) <= best) continue;
            if (node.left == 0) {
              for (uint32_t j = node.begin; j < node.end; ++j)
                best = std::max(best, (hull[j] - p).squaredNorm());
            } else {
              stack.push_back(node.left);
              stack.push_back(node.right);
            }
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
