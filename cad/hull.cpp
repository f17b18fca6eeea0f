#include "cad/hull.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include "cad/core/error.h"

namespace cadsynth {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using HullMesh = CGAL::Surface_mesh<Point>;

bool Less(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
}

}  // namespace

ConvexHull ComputeConvexHull(std::vector<Eigen::Vector3d> points, bool diameter) {
  // Meshes repeat a vertex once per smoothing group (per flat face on faceted parts): hull each
  // position once.
  std::sort(points.begin(), points.end(), Less);
  points.erase(std::unique(points.begin(), points.end()), points.end());
  for (const Eigen::Vector3d& p : points) {
    if (!p.allFinite()) throw Error("convex hull: a vertex is not a finite number");
  }
  if (points.size() < 4) throw Error("convex hull: fewer than 4 distinct points (no volume)");
  std::vector<Point> input;
  input.reserve(points.size());
  for (const auto& p : points) input.emplace_back(p.x(), p.y(), p.z());
  // All in one plane: CGAL would return a polygon, not a solid.
  {
    const Point& a = input[0];
    size_t b = 1;
    while (b < input.size() && input[b] == a) ++b;
    size_t c = b + 1;
    while (c < input.size() && CGAL::collinear(a, input[b], input[c])) ++c;
    size_t d = c + 1;
    while (d < input.size() && CGAL::coplanar(a, input[b], input[c], input[d])) ++d;
    if (c >= input.size() || d >= input.size())
      throw Error("convex hull: the points are flat (no volume)");
  }
  HullMesh hull;
  CGAL::convex_hull_3(input.begin(), input.end(), hull);
  if (hull.number_of_faces() < 4) throw Error("convex hull: the points are flat (no volume)");

  // Vertices by position (their rank is their id), triangles by their vertices' ranks.
  std::vector<HullMesh::Vertex_index> by_position(hull.vertices().begin(), hull.vertices().end());
  const auto position = [&](HullMesh::Vertex_index v) {
    const Point& p = hull.point(v);
    return Eigen::Vector3d(p.x(), p.y(), p.z());
  };
  std::sort(by_position.begin(), by_position.end(),
            [&](HullMesh::Vertex_index a, HullMesh::Vertex_index b) {
              return Less(position(a), position(b));
            });
  std::vector<int> rank(hull.number_of_vertices() + hull.number_of_removed_vertices(), -1);
  ConvexHull out;
  out.vertices.reserve(by_position.size());
  for (size_t r = 0; r < by_position.size(); ++r) {
    rank[by_position[r].idx()] = static_cast<int>(r);
    out.vertices.push_back(position(by_position[r]));
  }
  out.triangles.reserve(hull.number_of_faces());
  for (HullMesh::Face_index f : hull.faces()) {
    std::array<int, 3> c;
    int k = 0;
    for (auto v : CGAL::vertices_around_face(hull.halfedge(f), hull)) {
      if (k == 3) throw Error("convex hull: CGAL returned a face that is not a triangle");
      c[k++] = rank[v.idx()];
    }
    if (k != 3) throw Error("convex hull: CGAL returned a face that is not a triangle");
    std::rotate(c.begin(), std::min_element(c.begin(), c.end()), c.end());  // keeps the winding
    out.triangles.push_back(c);
  }
  std::sort(out.triangles.begin(), out.triangles.end());
  if (diameter) out.diameter = PointSetDiameter(out.vertices);
  return out;
}

ConvexHull ComputeConvexHull(const Mesh& mesh) {
  std::vector<Eigen::Vector3d> points;
  points.reserve(mesh.positions.size());
  for (const Eigen::Vector3f& p : mesh.positions) points.push_back(p.cast<double>());
  return ComputeConvexHull(std::move(points));
}

ConvexHull TransformedHull(const ConvexHull& hull, const Eigen::Isometry3d& transform) {
  if (transform.linear().determinant() <= 0)
    throw Error("convex hull: a transform that mirrors would turn the triangles inside out");
  std::vector<Eigen::Vector3d> moved(hull.vertices.size());
  for (size_t i = 0; i < moved.size(); ++i) moved[i] = transform * hull.vertices[i];
  std::vector<int> order(moved.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return Less(moved[a], moved[b]); });
  ConvexHull out;
  out.diameter = hull.diameter;
  std::vector<int> rank(order.size());
  for (size_t r = 0; r < order.size(); ++r) {
    if (r > 0 && moved[order[r]] == moved[order[r - 1]])
      throw Error("convex hull: two corners moved onto one point");
    rank[order[r]] = static_cast<int>(r);
    out.vertices.push_back(moved[order[r]]);
  }
  out.triangles.reserve(hull.triangles.size());
  for (const auto& t : hull.triangles) {
    std::array<int, 3> c = {rank[t[0]], rank[t[1]], rank[t[2]]};
    std::rotate(c.begin(), std::min_element(c.begin(), c.end()), c.end());
    out.triangles.push_back(c);
  }
  std::sort(out.triangles.begin(), out.triangles.end());
  return out;
}

double PointSetDiameter(std::vector<Eigen::Vector3d> hull) {
  if (hull.size() < 2) return 0.0;
  // The farthest pair, exactly, without trying every pair (a finely tessellated round part has
  // most of its vertices on the hull): a k-d tree of the points, and for each point a search that
  // skips every node whose farthest corner is no farther than the best pair found so far. The
  // bound only skips pairs that cannot be longer, so the result is the maximum over all pairs
  // whatever the order of work.
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

}  // namespace cadsynth
