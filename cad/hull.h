// Convex hulls of point sets, as plain data in an order of the geometry alone.
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "cad/mesh.h"

namespace cadsynth {

// The convex hull of a point set (mm). Vertices are the hull's corners, each position once, sorted
// lexicographically by (x, y, z); triangles wind counter-clockwise seen from outside, start at
// their lowest vertex index and are sorted. The corners and their order are a function of the
// point set alone (CGAL's own output order depends on memory addresses). A planar facet of more
// than three corners is split into triangles in a way that can differ from call to call; its
// outline cannot, and that is what the stable poses use.
struct ConvexHull {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<int, 3>> triangles;
  double diameter = 0;  // the largest distance between two corners (PointSetDiameter), mm
  bool empty() const { return triangles.empty(); }
};

// The hull of `points`. Throws Error when the points span no volume (fewer than 4, or all in one
// plane): a flat mesh has no hull to rest on.
// `diameter`: false leaves ConvexHull::diameter 0 (its exact search can cost as much as the hull
// on round parts; the stable poses of a group do not need it).
ConvexHull ComputeConvexHull(std::vector<Eigen::Vector3d> points, bool diameter = true);
// The hull of a mesh's vertex positions.
ConvexHull ComputeConvexHull(const Mesh& mesh);

// The same hull after a rigid motion (no mirror), in the canonical order again: the hull of the
// moved points without computing it again (the diameter is kept).
ConvexHull TransformedHull(const ConvexHull& hull, const Eigen::Isometry3d& transform);

// The largest distance between two of `points` (0 for fewer than two), exactly: the hull's
// vertices are enough, as the farthest pair of a set is always a pair of hull corners.
double PointSetDiameter(std::vector<Eigen::Vector3d> points);

}  // namespace cadsynth
