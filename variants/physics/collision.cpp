#include "variants/physics/collision.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <set>

#include <HACD/hacdHACD.h>

#include "cad/core/error.h"
#include "cad/hull.h"
#include "cad/part_cache.h"

namespace cadsynth {

bool CollisionOptions::Check(std::string* why) const {
  if (!(convex_fraction > 0 && convex_fraction <= 1)) {
    *why = "convex_fraction must lie in (0, 1]";
  } else if (!(concavity > 0 && concavity < 1)) {
    *why = "concavity must lie in (0, 1) (a fraction of the part's size)";
  } else if (max_pieces < 1 || max_pieces > 256) {
    *why = "max_pieces must be 1 to 256";
  } else if (max_triangles < 100) {
    *why = "max_triangles must be at least 100";
  } else if (max_corners < 8 || max_corners > 4096) {
    *why = "max_corners must be 8 to 4096";
  } else if (!(tolerance_mm >= 0)) {
    *why = "tolerance_mm must not be negative";
  } else {
    return true;
  }
  return false;
}

namespace {

double HullVolume(const ConvexHull& hull) {
  const Eigen::Vector3d o = hull.vertices.empty() ? Eigen::Vector3d::Zero() : hull.vertices[0];
  double v = 0;
  for (const auto& t : hull.triangles) {
    v += (hull.vertices[t[0]] - o).dot((hull.vertices[t[1]] - o).cross(hull.vertices[t[2]] - o));
  }
  return v / 6.0;
}

// Vertex clustering on a grid of `cell` mm: each vertex goes to its cell's representative (the
// mean of the cell's vertices); triangles that collapse are dropped. `cluster_of` maps each input
// vertex to its output vertex.
struct Simplified {
  std::vector<Eigen::Vector3d> points;
  std::vector<std::array<long, 3>> triangles;
  std::vector<long> cluster_of;
};

Simplified Cluster(const Mesh& mesh, double cell) {
  Simplified s;
  std::map<std::array<int64_t, 3>, long> cells;
  std::vector<int> counts;
  s.cluster_of.resize(mesh.positions.size());
  for (size_t v = 0; v < mesh.positions.size(); ++v) {
    const Eigen::Vector3d p = mesh.positions[v].cast<double>();
    const std::array<int64_t, 3> key = {static_cast<int64_t>(std::floor(p.x() / cell)),
                                        static_cast<int64_t>(std::floor(p.y() / cell)),
                                        static_cast<int64_t>(std::floor(p.z() / cell))};
    const auto [it, added] = cells.emplace(key, static_cast<long>(s.points.size()));
    if (added) {
      s.points.push_back(Eigen::Vector3d::Zero());
      counts.push_back(0);
    }
    s.points[it->second] += p;
    ++counts[it->second];
    s.cluster_of[v] = it->second;
  }
  for (size_t i = 0; i < s.points.size(); ++i) s.points[i] /= counts[i];
  std::set<std::array<long, 3>> seen;
  for (const auto& t : mesh.triangles) {
    const std::array<long, 3> c = {s.cluster_of[t[0]], s.cluster_of[t[1]], s.cluster_of[t[2]]};
    if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) continue;
    // The same triangle twice (either winding) would be a non-manifold sliver: keep one.
    std::array<long, 3> sorted = c;
    std::sort(sorted.begin(), sorted.end());
    if (!seen.insert(sorted).second) continue;
    s.triangles.push_back(c);
  }
  return s;
}

// The hull of a subset of `points`' hull corners, at most `max_vertices`, as close as `tolerance`
// (mm) allows: no corner left out lies more than `tolerance` outside it (where the cap allows).
// Greedy: start from the extremes along 13 directions, then repeatedly add, for each face, the
// corner farthest outside it. Contacts test every corner of a piece (GJK's support search), so a
// round part's thousand corners cost a thousand times a box's.
std::vector<Eigen::Vector3d> SimplifiedCorners(const std::vector<Eigen::Vector3d>& corners,
                                               double tolerance, int max_vertices) {
  if (corners.size() <= static_cast<size_t>(max_vertices)) return corners;
  std::vector<char> taken(corners.size(), 0);
  std::vector<Eigen::Vector3d> chosen;
  const auto take = [&](size_t i) {
    if (!taken[i]) {
      taken[i] = 1;
      chosen.push_back(corners[i]);
    }
  };
  const Eigen::Vector3d directions[13] = {{1, 0, 0},  {0, 1, 0},  {0, 0, 1}, {1, 1, 0},  {1, -1, 0},
                                          {1, 0, 1},  {1, 0, -1}, {0, 1, 1}, {0, 1, -1}, {1, 1, 1},
                                          {1, 1, -1}, {1, -1, 1}, {-1, 1, 1}};
  for (const Eigen::Vector3d& d : directions) {
    size_t lo = 0, hi = 0;
    for (size_t i = 1; i < corners.size(); ++i) {
      if (corners[i].dot(d) < corners[lo].dot(d)) lo = i;
      if (corners[i].dot(d) > corners[hi].dot(d)) hi = i;
    }
    take(lo);
    take(hi);
  }
  while (chosen.size() < static_cast<size_t>(max_vertices)) {
    ConvexHull hull;
    try {
      hull = ComputeConvexHull(chosen, false);
    } catch (const Error&) {  // still flat: add the corner farthest from the first
      size_t far = 0;
      for (size_t i = 0; i < corners.size(); ++i) {
        if ((corners[i] - chosen[0]).squaredNorm() > (corners[far] - chosen[0]).squaredNorm() &&
            !taken[i])
          far = i;
      }
      if (taken[far]) break;
      take(far);
      continue;
    }
    // For each face, the corner farthest outside it.
    std::vector<std::pair<double, size_t>> best(hull.triangles.size(), {tolerance, SIZE_MAX});
    for (size_t f = 0; f < hull.triangles.size(); ++f) {
      const auto& t = hull.triangles[f];
      const Eigen::Vector3d a = hull.vertices[t[0]];
      Eigen::Vector3d n = (hull.vertices[t[1]] - a).cross(hull.vertices[t[2]] - a);
      if (!(n.norm() > 0)) continue;
      n.normalize();
      for (size_t i = 0; i < corners.size(); ++i) {
        if (taken[i]) continue;
        const double d = (corners[i] - a).dot(n);
        if (d > best[f].first) best[f] = {d, i};
      }
    }
    std::sort(best.begin(), best.end(), std::greater<>());
    size_t added = 0;
    for (const auto& [d, i] : best) {
      if (i == SIZE_MAX || chosen.size() >= static_cast<size_t>(max_vertices)) break;
      if (!taken[i]) {
        take(i);
        ++added;
      }
    }
    if (added == 0) break;  // every corner within the tolerance
  }
  return chosen;
}

}  // namespace

CollisionShape MakeCollisionShape(const Part& part, const CollisionOptions& options) {
  std::string why;
  if (!options.Check(&why)) throw Error("collision options: " + why);
  ConvexHull hull;
  try {
    hull = part.hull ? *part.hull : ComputeConvexHull(part.mesh);
  } catch (const Error& e) {
    throw Error("part '" + part.name + "': no collision shape: " + e.what());
  }
  const double hull_volume = HullVolume(hull);
  if (!(hull_volume > 0)) throw Error("part '" + part.name + "': no volume to collide with");
  CollisionShape shape;
  const double volume = part.watertight ? part.mass.volume_mm3 : 0.0;
  shape.pieces = {SimplifiedCorners(hull.vertices, options.tolerance_mm, options.max_corners)};
  shape.volume_ratio = volume > 0 ? hull_volume / volume : 0.0;
  // Open meshes have no inside to decompose; nearly convex parts are their hull.
  if (!(volume > 0) || volume >= options.convex_fraction * hull_volume) return shape;

  // Simplify to about max_triangles (coarser cells until it fits), weld by position.
  const double diameter = (hull.vertices.empty() ? 0.0 : part.mesh.Bounds().sizes().norm());
  double cell = diameter / 256;
  Simplified s = Cluster(part.mesh, cell);
  while (s.triangles.size() > static_cast<size_t>(options.max_triangles)) {
    cell *= 1.4;
    s = Cluster(part.mesh, cell);
  }
  if (s.triangles.size() < 4)
    throw Error("part '" + part.name + "': too few triangles to decompose");

  std::vector<HACD::Vec3<HACD::Real>> points;
  for (const Eigen::Vector3d& p : s.points) points.emplace_back(p.x(), p.y(), p.z());
  std::vector<HACD::Vec3<long>> triangles;
  for (const auto& t : s.triangles) triangles.emplace_back(t[0], t[1], t[2]);
  HACD::HACD hacd;
  hacd.SetPoints(points.data());
  hacd.SetNPoints(points.size());
  hacd.SetTriangles(triangles.data());
  hacd.SetNTriangles(triangles.size());
  hacd.SetCompacityWeight(0.1);
  hacd.SetVolumeWeight(0.0);
  hacd.SetNClusters(1);
  hacd.SetNVerticesPerCH(64);
  // HACD measures concavity after scaling the mesh to `scale` across.
  hacd.SetScaleFactor(1000.0);
  hacd.SetConcavity(options.concavity * 1000.0);
  hacd.SetAddExtraDistPoints(true);
  hacd.SetAddNeighboursDistPoints(false);
  hacd.SetAddFacesPoints(true);
  if (!hacd.Compute()) throw Error("part '" + part.name + "': the convex decomposition failed");
  const long* partition = hacd.GetPartition();
  const size_t n_clusters = hacd.GetNClusters();
  if (n_clusters == 0 || partition == nullptr)
    throw Error("part '" + part.name + "': the convex decomposition found no pieces");

  // Each piece: the hull of the original vertices its triangles cover (exact surface points, not
  // the simplified ones).
  std::vector<std::vector<long>> clusters_of(s.points.size());
  for (size_t t = 0; t < s.triangles.size(); ++t) {
    const long c = partition[t];
    if (c < 0 || static_cast<size_t>(c) >= n_clusters) continue;
    for (long v : s.triangles[t]) {
      std::vector<long>& list = clusters_of[static_cast<size_t>(v)];
      if (std::find(list.begin(), list.end(), c) == list.end()) list.push_back(c);
    }
  }
  std::vector<std::vector<Eigen::Vector3d>> members(n_clusters);
  for (size_t v = 0; v < part.mesh.positions.size(); ++v) {
    for (long c : clusters_of[static_cast<size_t>(s.cluster_of[v])])
      members[static_cast<size_t>(c)].push_back(part.mesh.positions[v].cast<double>());
  }
  std::vector<std::pair<double, std::vector<Eigen::Vector3d>>> pieces;
  double pieces_volume = 0;
  for (size_t c = 0; c < n_clusters; ++c) {
    if (members[c].size() < 4) continue;
    try {
      const ConvexHull piece = ComputeConvexHull(members[c], false);
      const double v = HullVolume(piece);
      pieces.emplace_back(
          v, SimplifiedCorners(piece.vertices, options.tolerance_mm, options.max_corners));
      pieces_volume += v;
    } catch (const Error&) {
      continue;  // a flat cluster: its neighbours' hulls cover it
    }
  }
  if (pieces.empty())
    throw Error("part '" + part.name + "': the convex decomposition found no solid pieces");
  // At most max_pieces: the smallest piece merges with the piece whose centre is nearest (the
  // hull of both), until few enough remain. Merging only ever covers more, never opens a hole.
  const auto centre = [](const std::vector<Eigen::Vector3d>& corners) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d& p : corners) c += p;
    return Eigen::Vector3d(c / static_cast<double>(corners.size()));
  };
  while (pieces.size() > static_cast<size_t>(options.max_pieces)) {
    size_t smallest = 0;
    for (size_t k = 1; k < pieces.size(); ++k) {
      if (pieces[k].first < pieces[smallest].first) smallest = k;
    }
    const Eigen::Vector3d c = centre(pieces[smallest].second);
    size_t nearest = smallest == 0 ? 1 : 0;
    for (size_t k = 0; k < pieces.size(); ++k) {
      if (k != smallest && (centre(pieces[k].second) - c).squaredNorm() <
                               (centre(pieces[nearest].second) - c).squaredNorm())
        nearest = k;
    }
    std::vector<Eigen::Vector3d> both = pieces[nearest].second;
    both.insert(both.end(), pieces[smallest].second.begin(), pieces[smallest].second.end());
    const ConvexHull merged = ComputeConvexHull(both, false);
    pieces[nearest] = {HullVolume(merged), SimplifiedCorners(merged.vertices, options.tolerance_mm,
                                                             options.max_corners)};
    pieces.erase(pieces.begin() + static_cast<std::ptrdiff_t>(smallest));
  }
  pieces_volume = 0;
  for (const auto& piece : pieces) pieces_volume += piece.first;
  shape.pieces.clear();
  for (auto& [v, corners] : pieces) shape.pieces.push_back(std::move(corners));
  shape.decomposed = true;
  shape.volume_ratio = pieces_volume / volume;
  return shape;
}

std::string EncodeCollisionShape(const CollisionShape& shape) {
  ByteWriter out;
  out.Put<uint8_t>(shape.decomposed);
  out.Put<double>(shape.volume_ratio);
  out.Put<uint64_t>(shape.pieces.size());
  for (const auto& piece : shape.pieces) out.PutArray(piece);
  return std::move(out.bytes());
}

CollisionShape DecodeCollisionShape(const std::string& bytes) {
  ByteReader in(bytes);
  CollisionShape shape;
  shape.decomposed = in.Get<uint8_t>() != 0;
  shape.volume_ratio = in.Get<double>();
  const uint64_t n = in.Get<uint64_t>();
  if (n == 0 || n > 4096) throw Error("part cache: a collision shape has no pieces");
  for (uint64_t k = 0; k < n; ++k) {
    shape.pieces.push_back(in.GetArray<Eigen::Vector3d>());
    if (shape.pieces.back().size() < 4) throw Error("part cache: a collision piece is flat");
  }
  if (!in.done()) throw Error("part cache: trailing bytes after a collision shape");
  return shape;
}

}  // namespace cadsynth
