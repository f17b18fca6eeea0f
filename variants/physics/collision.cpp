#include "variants/physics/collision.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <functional>
#include <iomanip>
#include <limits>
#include <map>
#include <set>
#include <sstream>

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
  } else if (!(merge_volume >= 0 && merge_volume < 1)) {
    *why = "merge_volume must lie in [0, 1) (a fraction of the part's volume)";
  } else if (max_triangles < 100) {
    *why = "max_triangles must be at least 100";
  } else if (max_corners < 8 || max_corners > 4096) {
    *why = "max_corners must be 8 to 4096";
  } else if (!(tolerance_mm >= 0)) {
    *why = "tolerance must not be negative";
  } else if (!(time_limit_s >= 0) || !std::isfinite(time_limit_s)) {
    *why = "time_limit must be a number of seconds, 0 or more (0: no limit)";
  } else {
    return true;
  }
  return false;
}

namespace {

// HACD (Bullet's extras) has no way to stop a decomposition: its progress callback's answer is
// ignored and its cancel flag is read only before the merging starts. The callback, called between
// two merge steps (about every 1 % of the progress, every step near the end), throws this instead
// once the deadline has passed. HACD's state is whole there, and its containers and its
// destructor free what it holds. The callback takes no user data: the deadline is this thread's
// (one decomposition runs on a thread from start to end, with no TBB work in between).
struct OutOfTime {};
thread_local std::chrono::steady_clock::time_point tls_deadline;

bool StopWhenLate(const char*, double, double, size_t) {
  if (std::chrono::steady_clock::now() > tls_deadline) throw OutOfTime{};
  return true;
}

double HullVolume(const ConvexHull& hull) {
  const Eigen::Vector3d o = hull.vertices.empty() ? Eigen::Vector3d::Zero() : hull.vertices[0];
  double v = 0;
  for (const auto& t : hull.triangles) {
    v += (hull.vertices[t[0]] - o).dot((hull.vertices[t[1]] - o).cross(hull.vertices[t[2]] - o));
  }
  return v / 6.0;
}

// A convex piece as the solid it bounds: its corners, its faces' planes (n . x <= d inside) and
// its box, for inside tests on a grid (the volume the pieces cover together).
struct Solid {
  std::vector<Eigen::Vector3d> corners;
  std::vector<Eigen::Vector4d> planes;
  Eigen::AlignedBox3d box;
  double volume = 0;  // of its hull
};

Solid MakeSolid(const std::vector<Eigen::Vector3d>& points) {
  const ConvexHull hull = ComputeConvexHull(points, false);
  Solid solid;
  solid.volume = HullVolume(hull);
  solid.corners = hull.vertices;
  for (const Eigen::Vector3d& p : hull.vertices) solid.box.extend(p);
  for (const auto& t : hull.triangles) {
    const Eigen::Vector3d a = hull.vertices[t[0]];
    const Eigen::Vector3d n = (hull.vertices[t[1]] - a).cross(hull.vertices[t[2]] - a);
    if (!(n.norm() > 0)) continue;
    const Eigen::Vector3d u = n.normalized();
    solid.planes.emplace_back(u.x(), u.y(), u.z(), u.dot(a));
  }
  return solid;
}

bool Inside(const Solid& solid, const Eigen::Vector3d& p) {
  if (!solid.box.contains(p)) return false;
  for (const Eigen::Vector4d& plane : solid.planes) {
    if (plane.head<3>().dot(p) > plane.w()) return false;
  }
  return true;
}

// The volume (mm^3) of the points of `box` inside `inside`, sampled at the centres of a grid of
// about `cells` cubic cells: deterministic, and within a cell's layer of the surface.
template <typename InsideTest>
double GridVolume(const Eigen::AlignedBox3d& box, double cells, InsideTest&& inside) {
  const Eigen::Vector3d size = box.sizes();
  const double cell = std::cbrt(std::max(size.prod(), 1e-12) / cells);
  const Eigen::Vector3i n = (size / cell).array().ceil().cast<int>().max(1);
  const Eigen::Vector3d step = size.cwiseQuotient(n.cast<double>());
  double count = 0;
  for (int i = 0; i < n.x(); ++i) {
    for (int j = 0; j < n.y(); ++j) {
      for (int k = 0; k < n.z(); ++k) {
        const Eigen::Vector3d p =
            box.min() + step.cwiseProduct(Eigen::Vector3d(i + 0.5, j + 0.5, k + 0.5));
        if (inside(p)) ++count;
      }
    }
  }
  return count * step.prod();
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

// HACD's clusters are patches of the surface: a patch on one side of a wall (a casing's outer
// face) is flat, and its hull would be a sheet or nothing, leaving the wall uncovered (the
// casing's pieces held at most 74 % of its volume). So each thin patch also takes its triangles'
// corners pushed into the part by the wall's thickness behind the triangle: the least distance,
// along the inward normal, to the part's far side from four points of the triangle (its centre
// and a point near each corner; inside the triangle, so a ray never grazes an edge and crosses an
// open pocket instead).
void AddWallsBehindThinPatches(const Simplified& s, const long* partition, size_t n_clusters,
                               double diameter,
                               std::vector<std::vector<Eigen::Vector3d>>* members) {
  const auto depth_along = [&](const Eigen::Vector3d& o, const Eigen::Vector3d& d, size_t self) {
    double nearest = std::numeric_limits<double>::infinity();
    bool leaves = false;
    for (size_t k = 0; k < s.triangles.size(); ++k) {  // Moeller-Trumbore
      if (k == self) continue;
      const auto& t = s.triangles[k];
      const Eigen::Vector3d e1 = s.points[t[1]] - s.points[t[0]];
      const Eigen::Vector3d e2 = s.points[t[2]] - s.points[t[0]];
      const Eigen::Vector3d p = d.cross(e2);
      const double det = e1.dot(p);
      if (std::abs(det) < 1e-12) continue;
      const Eigen::Vector3d q = o - s.points[t[0]];
      const double u = q.dot(p) / det;
      if (u < 0 || u > 1) continue;
      const Eigen::Vector3d r = q.cross(e1);
      const double w = d.dot(r) / det;
      if (w < 0 || u + w > 1) continue;
      const double hit = e2.dot(r) / det;
      if (hit > 1e-6 * diameter && hit < nearest) {
        nearest = hit;
        leaves = e1.cross(e2).dot(d) > 0;
      }
    }
    // The first surface met must be one the ray leaves the part through; one it enters by means
    // the ray left through a gap of the simplified mesh (its clustering drops triangles) and
    // crossed empty space: no depth there.
    return leaves ? nearest : std::numeric_limits<double>::infinity();
  };
  // Only thin patches: a pushed corner is a corner of the piece, and each piece keeps only
  // max_corners (a bolt's shank pushed through its head lost the corners that keep its round
  // within 0.1 mm). Thin: the hull's volume under 5 % of the part's size times half the patch's
  // area (a slab of thickness t and area A has about A / 2 on each side).
  std::vector<double> area(n_clusters, 0.0);
  for (size_t k = 0; k < s.triangles.size(); ++k) {
    const long c = partition[k];
    if (c < 0 || static_cast<size_t>(c) >= n_clusters) continue;
    const auto& t = s.triangles[k];
    area[static_cast<size_t>(c)] +=
        0.5 * (s.points[t[1]] - s.points[t[0]]).cross(s.points[t[2]] - s.points[t[0]]).norm();
  }
  std::vector<char> thin(n_clusters, 1);
  for (size_t c = 0; c < n_clusters; ++c) {
    if ((*members)[c].size() < 4) continue;
    try {
      const double v = HullVolume(ComputeConvexHull((*members)[c], false));
      thin[c] = v < 0.05 * diameter * 0.5 * area[c];
    } catch (const Error&) {  // flat: thin
    }
  }
  for (size_t k = 0; k < s.triangles.size(); ++k) {
    const long c = partition[k];
    if (c < 0 || static_cast<size_t>(c) >= n_clusters || !thin[static_cast<size_t>(c)]) continue;
    const auto& t = s.triangles[k];
    const Eigen::Vector3d a = s.points[t[0]], b = s.points[t[1]], e = s.points[t[2]];
    Eigen::Vector3d n = (b - a).cross(e - a);
    if (!(n.norm() > 0)) continue;
    n.normalize();
    const Eigen::Vector3d centre = (a + b + e) / 3.0;
    double depth = depth_along(centre, -n, k);
    for (const Eigen::Vector3d& corner : {a, b, e})
      depth = std::min(depth, depth_along(corner + 0.1 * (centre - corner), -n, k));
    if (!std::isfinite(depth)) continue;
    for (const Eigen::Vector3d& corner : {a, b, e})
      (*members)[static_cast<size_t>(c)].push_back(corner - depth * n);
  }
}

// Merging: two neighbouring pieces (boxes within 2 % of the part's size) become the hull of
// both, the one that fills the least first (the hull's volume outside both pieces, on a grid),
// while all the merges together fill at most merge_volume of the part's volume (a gear's tooth
// gaps, not a casing's pocket); beyond max_pieces, at any cost. Every piece's contacts cost
// the solver: a pile of 60 ring gears (z30, m1) of 55 pieces took 8.5 s of wall time per
// simulated second. Merging only ever covers more, never opens a hole.
std::vector<Solid> MergePieces(std::vector<Solid> pieces, const CollisionOptions& options,
                               double volume, double diameter) {
  struct Merged {
    double fill;  // the merged hull's volume outside both pieces
    Solid solid;
  };
  std::vector<char> alive(pieces.size(), 1);
  std::map<std::pair<size_t, size_t>, Merged> merges;
  const double near = 0.02 * diameter;
  const auto consider = [&](size_t a, size_t b, bool any_distance) {
    if (!any_distance && pieces[a].box.exteriorDistance(pieces[b].box) > near) return;
    std::vector<Eigen::Vector3d> both = pieces[a].corners;
    both.insert(both.end(), pieces[b].corners.begin(), pieces[b].corners.end());
    Solid merged = MakeSolid(SimplifiedCorners(ComputeConvexHull(both, false).vertices,
                                               options.tolerance_mm, options.max_corners));
    const double fill = GridVolume(merged.box, 4096, [&](const Eigen::Vector3d& p) {
      return Inside(merged, p) && !Inside(pieces[a], p) && !Inside(pieces[b], p);
    });
    merges[{std::min(a, b), std::max(a, b)}] = {fill, std::move(merged)};
  };
  for (size_t a = 0; a < pieces.size(); ++a) {
    for (size_t b = a + 1; b < pieces.size(); ++b) consider(a, b, false);
  }
  size_t count = pieces.size();
  double filled = 0;  // by the merges so far
  while (count > 1) {
    if (merges.empty()) {
      if (count <= static_cast<size_t>(options.max_pieces)) break;
      for (size_t a = 0; a < pieces.size(); ++a) {  // too many, none near: any two
        for (size_t b = a + 1; b < pieces.size(); ++b) {
          if (alive[a] && alive[b]) consider(a, b, true);
        }
      }
    }
    auto best = merges.begin();
    for (auto it = merges.begin(); it != merges.end(); ++it) {
      if (it->second.fill < best->second.fill) best = it;
    }
    if (count <= static_cast<size_t>(options.max_pieces) &&
        filled + best->second.fill > options.merge_volume * volume)
      break;
    filled += best->second.fill;
    const auto [a, b] = best->first;
    pieces[a] = std::move(best->second.solid);
    alive[b] = 0;
    --count;
    for (auto it = merges.begin(); it != merges.end();) {
      const bool stale = it->first.first == a || it->first.second == a || it->first.first == b ||
                         it->first.second == b;
      it = stale ? merges.erase(it) : std::next(it);
    }
    for (size_t k = 0; k < pieces.size(); ++k) {
      if (alive[k] && k != a) consider(a, k, false);
    }
  }
  std::vector<Solid> kept;
  for (size_t k = 0; k < pieces.size(); ++k) {
    if (alive[k]) kept.push_back(std::move(pieces[k]));
  }
  return kept;
}

// The volume the pieces cover together, each point once (on a grid of 2^18 cells).
double CoveredVolume(const std::vector<Solid>& kept) {
  Eigen::AlignedBox3d all;
  for (const Solid& piece : kept) all.extend(piece.box);
  return GridVolume(all, 1 << 18, [&](const Eigen::Vector3d& p) {
    for (const Solid& piece : kept) {
      if (Inside(piece, p)) return true;
    }
    return false;
  });
}

// The shape as MakeCollisionShape makes it, the decomposition stopped at start + time limit.
CollisionShape MakeShape(const Part& part, const CollisionOptions& options,
                         std::chrono::steady_clock::time_point start) {
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
  if (options.time_limit_s > 0) {
    tls_deadline = start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                               std::chrono::duration<double>(options.time_limit_s));
    hacd.SetCallBack(StopWhenLate);
  }
  try {
    if (!hacd.Compute()) throw Error("part '" + part.name + "': the convex decomposition failed");
  } catch (const OutOfTime&) {
    shape.timed_out = true;  // the hull, as made above
    return shape;
  }
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
  AddWallsBehindThinPatches(s, partition, n_clusters, diameter, &members);
  std::vector<Solid> pieces;
  for (size_t c = 0; c < n_clusters; ++c) {
    if (members[c].size() < 4) continue;
    try {
      const ConvexHull hull_c = ComputeConvexHull(members[c], false);
      pieces.push_back(
          MakeSolid(SimplifiedCorners(hull_c.vertices, options.tolerance_mm, options.max_corners)));
    } catch (const Error&) {
      continue;  // a flat cluster: its neighbours' pieces cover it
    }
  }
  if (pieces.empty())
    throw Error("part '" + part.name + "': the convex decomposition found no solid pieces");
  const std::vector<Solid> kept = MergePieces(std::move(pieces), options, volume, diameter);
  shape.pieces.clear();
  for (const Solid& piece : kept) shape.pieces.push_back(piece.corners);
  shape.decomposed = true;
  shape.volume_ratio = CoveredVolume(kept) / volume;
  return shape;
}

}  // namespace

CollisionShape MakeCollisionShape(const Part& part, const CollisionOptions& options) {
  std::string why;
  if (!options.Check(&why)) throw Error("collision options: " + why);
  const auto start = std::chrono::steady_clock::now();
  CollisionShape shape = MakeShape(part, options, start);
  shape.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (shape.timed_out) {
    std::ostringstream text;
    text << "part '" << part.name << "': its convex decomposition did not finish within "
         << options.time_limit_s
         << " s (collision.time_limit); it is simulated as its convex hull, "
         << std::setprecision(3) << shape.volume_ratio
         << " times its volume. Raise collision.time_limit, or lower collision.max_triangles";
    Warn(text.str());
  }
  return shape;
}

std::string EncodeCollisionShape(const CollisionShape& shape) {
  ByteWriter out;
  out.Put<uint8_t>(shape.decomposed);
  out.Put<double>(shape.volume_ratio);
  out.Put<uint8_t>(shape.timed_out);
  out.Put<uint64_t>(shape.pieces.size());
  for (const auto& piece : shape.pieces) out.PutArray(piece);
  return std::move(out.bytes());
}

CollisionShape DecodeCollisionShape(const std::string& bytes) {
  ByteReader in(bytes);
  CollisionShape shape;
  shape.decomposed = in.Get<uint8_t>() != 0;
  shape.volume_ratio = in.Get<double>();
  shape.timed_out = in.Get<uint8_t>() != 0;
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
