#include "cad/assembly.h"

#include "cad/part_cache.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <unordered_map>
#include <utility>
#include <vector>

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>
#include <Eigen/Eigenvalues>

#include "cad/core/error.h"
#include "cad/part_cache.h"

namespace cadsynth {
namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, std::vector<Triangle>::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

// Area-weighted moments of a mesh surface: centroid and principal axes (columns, ascending
// eigenvalues, right-handed).
struct SurfaceMoments {
  double area = 0.0;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  Eigen::Vector3d eigenvalues = Eigen::Vector3d::Zero();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
};

SurfaceMoments Moments(const Mesh& mesh) {
  SurfaceMoments m;
  Eigen::Vector3d first = Eigen::Vector3d::Zero();
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.positions[t[0]].cast<double>();
    const Eigen::Vector3d b = mesh.positions[t[1]].cast<double>();
    const Eigen::Vector3d c = mesh.positions[t[2]].cast<double>();
    const double w = 0.5 * (b - a).cross(c - a).norm();
    const Eigen::Vector3d sum = a + b + c;
    m.area += w;
    first += w * sum / 3.0;
    // Integral of x x^T over a triangle: w/12 (a a^T + b b^T + c c^T + sum sum^T).
    second += w / 12.0 *
              (a * a.transpose() + b * b.transpose() + c * c.transpose() + sum * sum.transpose());
  }
  if (m.area <= 0.0) return m;
  m.centroid = first / m.area;
  const Eigen::Matrix3d covariance = second / m.area - m.centroid * m.centroid.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  m.eigenvalues = solver.eigenvalues();
  m.axes = solver.eigenvectors();
  if (m.axes.determinant() < 0) m.axes.col(2) = -m.axes.col(2);
  return m;
}

class SurfaceDistance {
 public:
  explicit SurfaceDistance(const Mesh& mesh) : mesh_(mesh) {
    triangles_.reserve(mesh.num_triangles());
    for (const auto& t : mesh.triangles) {
      const auto p = [&](int k) {
        const Eigen::Vector3f& v = mesh.positions[t[k]];
        return Point(v.x(), v.y(), v.z());
      };
      if (!CGAL::collinear(p(0), p(1), p(2))) triangles_.emplace_back(p(0), p(1), p(2));
    }
    tree_.insert(triangles_.begin(), triangles_.end());
    tree_.accelerate_distance_queries();
  }
  // Largest distance from `points` (moved by `transform`) to the surface; stops early past `limit`.
  double MaxDistance(const std::vector<Eigen::Vector3d>& points, const Eigen::Isometry3d& transform,
                     double limit) const {
    double worst = 0.0;
    for (const Eigen::Vector3d& x : points) {
      const Eigen::Vector3d y = transform * x;
      worst = std::max(worst, std::sqrt(tree_.squared_distance(Point(y.x(), y.y(), y.z()))));
      if (worst > limit) break;
    }
    return worst;
  }

  // Whether every point of `points` (moved by `transform`) lies within `tolerance` of the surface.
  // A point within `tolerance` of one of the mesh's vertices is (the vertex lies on the surface):
  // a hash grid of the vertices answers that for most points of congruent meshes at a fraction of
  // the cost of the exact distance, which decides the others.
  bool AllWithin(const std::vector<Eigen::Vector3d>& points, const Eigen::Isometry3d& transform,
                 double tolerance) const {
    if (grid_cell_ != tolerance) BuildGrid(tolerance);
    const double t2 = tolerance * tolerance;
    for (const Eigen::Vector3d& x : points) {
      const Eigen::Vector3d y = transform * x;
      if (NearVertex(y, t2)) continue;
      if (tree_.squared_distance(Point(y.x(), y.y(), y.z())) > t2) return false;
    }
    return true;
  }

 private:
  static int64_t Key(int64_t i, int64_t j, int64_t k) {
    return (i * 73856093) ^ (j * 19349663) ^ (k * 83492791);
  }
  Eigen::Vector3i Cell(const Eigen::Vector3d& p) const {
    return (p / grid_cell_).array().floor().cast<int>();
  }
  void BuildGrid(double cell) const {
    grid_cell_ = cell;
    grid_.clear();
    for (uint32_t v = 0; v < mesh_.num_vertices(); ++v) {
      const Eigen::Vector3i c = Cell(mesh_.positions[v].cast<double>());
      grid_.emplace(Key(c.x(), c.y(), c.z()), v);
    }
  }
  bool NearVertex(const Eigen::Vector3d& y, double t2) const {
    if (!(y.array().abs() < 1e9 * grid_cell_).all()) return false;  // far outside: no cell index
    const Eigen::Vector3i c = Cell(y);
    for (int i = -1; i <= 1; ++i) {
      for (int j = -1; j <= 1; ++j) {
        for (int k = -1; k <= 1; ++k) {
          const auto range = grid_.equal_range(Key(c.x() + i, c.y() + j, c.z() + k));
          for (auto it = range.first; it != range.second; ++it) {
            if ((mesh_.positions[it->second].cast<double>() - y).squaredNorm() <= t2) return true;
          }
        }
      }
    }
    return false;
  }

  const Mesh& mesh_;
  std::vector<Triangle> triangles_;
  Tree tree_;
  mutable double grid_cell_ = 0.0;
  mutable std::unordered_multimap<int64_t, uint32_t> grid_;
};

std::vector<Eigen::Vector3d> Vertices(const Mesh& mesh, size_t at_most) {
  std::vector<Eigen::Vector3d> points;
  const size_t step = std::max<size_t>(1, mesh.num_vertices() / std::max<size_t>(1, at_most));
  for (size_t i = 0; i < mesh.num_vertices(); i += step)
    points.push_back(mesh.positions[i].cast<double>());
  return points;
}

bool Near(double x, double y, double relative) {
  return std::abs(x - y) <= relative * std::max(std::abs(x), std::abs(y)) + 1e-9;
}

}  // namespace

double MaxSurfaceDistance(const Mesh& surface, const Mesh& points,
                          const Eigen::Isometry3d& transform) {
  return SurfaceDistance(surface).MaxDistance(Vertices(points, points.num_vertices()), transform,
                                              1e300);
}

std::optional<Eigen::Isometry3d> FindCongruence(const Mesh& a, const Mesh& b, double tolerance_mm) {
  if (a.empty() || b.empty()) return std::nullopt;
  const SurfaceMoments ma = Moments(a), mb = Moments(b);
  // Tessellations of one surface agree in area and moments to well under a percent.
  if (!Near(ma.area, mb.area, 0.01)) return std::nullopt;
  const double scale = ma.eigenvalues.maxCoeff();
  for (int k = 0; k < 3; ++k) {
    if (std::abs(ma.eigenvalues[k] - mb.eigenvalues[k]) > 0.01 * scale) return std::nullopt;
  }
  const auto equal = [&](int i, int j) {
    return std::abs(ma.eigenvalues[i] - ma.eigenvalues[j]) < 1e-3 * scale;
  };

  // Candidate rotations a_from_b (about the centroids).
  std::vector<Eigen::Matrix3d> candidates;
  const SurfaceDistance surface_a(a);
  const auto add_from_axes = [&](const Eigen::Matrix3d& axes_b) {
    for (int sx : {1, -1}) {
      for (int sy : {1, -1}) {
        const Eigen::Vector3d signs(sx, sy, sx * sy);  // keep det = +1
        candidates.push_back(ma.axes * signs.asDiagonal() * axes_b.transpose());
      }
    }
  };
  const bool pair01 = equal(0, 1), pair12 = equal(1, 2);
  if (pair01 && pair12) {
    // No preferred axes: the 24 rotations taking coordinate axes to coordinate axes.
    for (int perm = 0; perm < 6; ++perm) {
      int idx[3] = {0, 1, 2};
      for (int p = 0; p < perm; ++p) std::next_permutation(idx, idx + 3);
      for (int signs = 0; signs < 8; ++signs) {
        Eigen::Matrix3d r = Eigen::Matrix3d::Zero();
        for (int row = 0; row < 3; ++row) r(row, idx[row]) = (signs >> row) & 1 ? -1.0 : 1.0;
        if (r.determinant() > 0) candidates.push_back(r);
      }
    }
  } else if (pair01 || pair12) {
    // One distinct axis u: search the angle about it (1 degree, then 0.01 degree around the best).
    const int unique = pair01 ? 2 : 0;
    const Eigen::Vector3d ua = ma.axes.col(unique), ub = mb.axes.col(unique);
    const std::vector<Eigen::Vector3d> probe = Vertices(b, 64);
    for (double flip : {1.0, -1.0}) {
      const Eigen::Matrix3d align =
          Eigen::Quaterniond::FromTwoVectors(ub, flip * ua).toRotationMatrix();
      double best = 0.0, best_score = 1e300;
      // An angle's score stops counting once it exceeds the best so far (it cannot win), which
      // skips most of the probe points of most angles.
      const auto score = [&](double angle) {
        Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
        t.linear() = Eigen::AngleAxisd(angle, flip * ua).toRotationMatrix() * align;
        t.translation() = ma.centroid - t.linear() * mb.centroid;
        return surface_a.MaxDistance(probe, t, best_score);
      };
      for (int deg = 0; deg < 360; ++deg) {
        const double s = score(deg * M_PI / 180.0);
        if (s < best_score) best_score = s, best = deg * M_PI / 180.0;
      }
      const double coarse = best;
      for (int step = -100; step <= 100; ++step) {
        const double angle = coarse + step * 0.01 * M_PI / 180.0;
        const double s = score(angle);
        if (s < best_score) best_score = s, best = angle;
      }
      candidates.push_back(Eigen::AngleAxisd(best, flip * ua).toRotationMatrix() * align);
    }
  } else {
    add_from_axes(mb.axes);
  }

  // Verify both ways on every vertex.
  const SurfaceDistance surface_b(b);
  const std::vector<Eigen::Vector3d> va = Vertices(a, a.num_vertices()),
                                     vb = Vertices(b, b.num_vertices());
  for (const Eigen::Matrix3d& r : candidates) {
    Eigen::Isometry3d a_from_b = Eigen::Isometry3d::Identity();
    a_from_b.linear() = r;
    a_from_b.translation() = ma.centroid - r * mb.centroid;
    if (surface_a.AllWithin(vb, a_from_b, tolerance_mm) &&
        surface_b.AllWithin(va, a_from_b.inverse(), tolerance_mm)) {
      return a_from_b;
    }
  }
  return std::nullopt;
}

std::optional<Eigen::Isometry3d> FindCongruence(const Mesh& a, const Mesh& b, double tolerance_mm,
                                                const PartCache* cache) {
  if (cache == nullptr) return FindCongruence(a, b, tolerance_mm);
  KeyHasher hasher;
  cache->Start(&hasher, "congruence 1");
  hasher.Geometry(a).Geometry(b).Value(tolerance_mm);
  const CacheKey key = hasher.Key();
  if (const std::optional<std::string> bytes = cache->Load("congruence", key)) {
    try {
      ByteReader in(*bytes);
      std::optional<Eigen::Isometry3d> stored;
      if (in.Get<uint8_t>() != 0) {
        stored = Eigen::Isometry3d::Identity();
        for (int k = 0; k < 16; ++k) stored->matrix().data()[k] = in.Get<double>();
      }
      if (in.done()) return stored;
    } catch (const Error&) {  // damaged: computed again below
    }
  }
  const std::optional<Eigen::Isometry3d> found = FindCongruence(a, b, tolerance_mm);
  ByteWriter out;
  out.Put<uint8_t>(found.has_value());
  if (found) {
    for (int k = 0; k < 16; ++k) out.Put<double>(found->matrix().data()[k]);
  }
  cache->Store("congruence", key, out.bytes());
  return found;
}

size_t MergeIdenticalParts(Assembly* assembly, double tolerance_mm, const PartCache* cache) {
  std::vector<Part>& parts = assembly->parts;
  std::vector<int> target(parts.size());
  std::vector<Eigen::Isometry3d> kept_from_part(parts.size(), Eigen::Isometry3d::Identity());
  std::vector<Part> kept;
  for (size_t i = 0; i < parts.size(); ++i) {
    int found = -1;
    for (size_t k = 0; k < kept.size() && found < 0; ++k) {
      // Exact volumes, when both parts have them, tell apart shapes closer than the meshes can
      // (a planet's bore 0.1 mm wider than the sun's): one solid's volume agrees to ~1e-9.
      if (kept[k].mass_from_brep && parts[i].mass_from_brep &&
          !Near(kept[k].mass.volume_mm3, parts[i].mass.volume_mm3, 1e-6)) {
        continue;
      }
      const std::optional<Eigen::Isometry3d> congruence =
          FindCongruence(kept[k].mesh, parts[i].mesh, tolerance_mm, cache);
      if (congruence) {
        found = static_cast<int>(k);
        kept_from_part[i] = *congruence;
      }
    }
    if (found < 0) {
      found = static_cast<int>(kept.size());
      kept.push_back(std::move(parts[i]));
    }
    target[i] = found;
  }
  // x_world = world_from_part * x_part and x_kept = kept_from_part * x_part, so the instance's
  // pose for the kept model is world_from_part * inverse(kept_from_part).
  for (Instance& instance : assembly->instances) {
    instance.world_from_model = instance.world_from_model * kept_from_part[instance.part].inverse();
    instance.part = target[instance.part];
  }
  const size_t merged = parts.size() - kept.size();
  parts = std::move(kept);
  return merged;
}

Assembly FuseAssembly(const Assembly& assembly) {
  if (assembly.instances.empty())
    throw Error("assembly '" + assembly.name + "' has no instances to fuse");
  Part fused;
  fused.name = assembly.name;
  fused.watertight = true;
  fused.mass_from_brep = true;
  double volume = 0.0;
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();
  for (const Instance& instance : assembly.instances) {
    const Part& part = assembly.parts.at(instance.part);
    Mesh piece = part.mesh;
    piece.Transform(instance.world_from_model);
    fused.mesh.Append(piece);
    fused.watertight = fused.watertight && part.watertight;
    fused.mass_from_brep = fused.mass_from_brep && part.mass_from_brep;
    volume += part.mass.volume_mm3;
    moment += part.mass.volume_mm3 * (instance.world_from_model * part.mass.center_of_mass);
  }
  fused.mesh.face_ids.clear();  // face ids of different parts would collide
  const Eigen::Vector3d centre = fused.mesh.Bounds().center();
  fused.cad_from_model = Eigen::Translation3d(centre);
  fused.mesh.Transform(fused.cad_from_model.inverse());
  if (volume > 0.0) {
    const Eigen::Vector3d com = moment / volume;  // assembly frame
    Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
    for (const Instance& instance : assembly.instances) {
      const Part& part = assembly.parts.at(instance.part);
      const Eigen::Matrix3d r = instance.world_from_model.linear();
      const Eigen::Vector3d d = instance.world_from_model * part.mass.center_of_mass - com;
      inertia += r * part.mass.inertia * r.transpose() +
                 part.mass.volume_mm3 *
                     (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
    }
    fused.mass.volume_mm3 = volume;
    fused.mass.center_of_mass = com - centre;
    fused.mass.inertia = inertia;
  }
  Assembly out;
  out.name = assembly.name;
  out.format = assembly.format;
  out.length_unit = assembly.length_unit;
  out.instances = {Instance{0, assembly.name, fused.cad_from_model}};
  out.parts.push_back(std::move(fused));
  return out;
}

}  // namespace cadsynth
