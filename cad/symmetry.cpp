#include "cad/symmetry.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <sstream>
#include <string>

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>
#include <Eigen/Eigenvalues>

#include "cad/core/error.h"

namespace cadsynth {

namespace {

using K = CGAL::Simple_cartesian<double>;
using Triangles = std::vector<K::Triangle_3>;
using Primitive = CGAL::AABB_triangle_primitive<K, Triangles::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;

// Distances to a mesh's surface (CGAL's AABB tree).
class Surface {
 public:
  Surface(const Surface&) = delete;
  Surface& operator=(const Surface&) = delete;
  explicit Surface(const Mesh& mesh) {
    const auto point = [&](uint32_t i) {
      const Eigen::Vector3f& p = mesh.positions[i];
      return K::Point_3(p.x(), p.y(), p.z());
    };
    for (const auto& t : mesh.triangles)
      triangles_.emplace_back(point(t[0]), point(t[1]), point(t[2]));
    tree_.insert(triangles_.cbegin(), triangles_.cend());
    tree_.build();
    tree_.accelerate_distance_queries();
  }
  double Distance(const Eigen::Vector3d& p) const {
    return std::sqrt(tree_.squared_distance(K::Point_3(p.x(), p.y(), p.z())));
  }

 private:
  Triangles triangles_;
  Tree tree_;
};

// How far `t` moves surface points off the surface: the largest distance, or the first above
// `stop` (then the test has failed anyway).
double Deviation(const Surface& surface, const std::vector<Eigen::Vector3d>& points,
                 const Eigen::Isometry3d& t, double stop) {
  double worst = 0;
  for (const Eigen::Vector3d& p : points) {
    worst = std::max(worst, surface.Distance(t * p));
    if (worst > stop) break;
  }
  return worst;
}

Eigen::Isometry3d RotationAbout(const Eigen::Vector3d& centre, const Eigen::Vector3d& axis,
                                double angle) {
  return Eigen::Translation3d(centre) * Eigen::AngleAxisd(angle, axis) *
         Eigen::Translation3d(-centre);
}

// Whether a and b move every corner of `box` to within `within` of each other: the same motion
// as far as the part can tell (a flip refined to 0.0003 rad is the exact one).
bool SameMotion(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b,
                const Eigen::AlignedBox3d& box, double within) {
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d p = box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c));
    if ((a * p - b * p).norm() > within) return false;
  }
  return true;
}

// Irrational-looking angles: a shape symmetric under all three is taken as a solid of revolution.
constexpr double kContinuousAngles[] = {0.70710678, 2.23606798, 4.12310563};

}  // namespace

bool SymmetryOptions::Check(std::string* why) const {
  if (!(tolerance_mm >= 0 && tolerance_mm <= 1000)) {
    *why = "symmetry tolerance must lie in [0, 1000] mm (0: automatic)";
  } else if (!(deviation_mm >= 0 && deviation_mm <= 1000)) {
    *why = "tessellation deviation must lie in [0, 1000] mm";
  } else if (max_order < 2 || max_order > 10000) {
    *why = "max_order must be 2 to 10,000";
  } else if (max_points < 16 || max_points > 10000000) {
    *why = "max_points must be 16 to 10,000,000";
  } else {
    return true;
  }
  return false;
}

namespace {

// What detection and measurement share: the surface's centroid, moments and flat areas, the
// tolerance, the points tested and the distance queries.
struct Probe {
  explicit Probe(const Mesh& mesh, const SymmetryOptions& options);
  bool Holds(const Eigen::Isometry3d& t, double* deviation) const {
    if (Deviation(*surface, quick, t, tol) > tol) return false;
    *deviation = Deviation(*surface, points, t, tol);
    return *deviation <= tol;
  }
  double area = 0;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
  std::map<std::array<int, 3>, std::pair<double, Eigen::Vector3d>> normals;
  Eigen::AlignedBox3d box;
  double tol = 0;
  std::vector<Eigen::Vector3d> points, quick;
  std::unique_ptr<Surface> surface;
};

Probe::Probe(const Mesh& mesh, const SymmetryOptions& options) {
  std::string why;
  if (!options.Check(&why)) throw Error("symmetry: " + why);
  if (mesh.triangles.empty()) throw Error("symmetry: the mesh has no triangles");
  Eigen::Vector3d first = Eigen::Vector3d::Zero();
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.positions[t[0]].cast<double>(),
                          b = mesh.positions[t[1]].cast<double>(),
                          c = mesh.positions[t[2]].cast<double>();
    box.extend(a);
    box.extend(b);
    box.extend(c);
    const Eigen::Vector3d cross = (b - a).cross(c - a);
    const double A = 0.5 * cross.norm();
    if (!(A > 0)) continue;
    const Eigen::Vector3d m = (a + b + c) / 3;
    area += A;
    first += A * m;
    second += A / 12 *
              (a * a.transpose() + b * b.transpose() + c * c.transpose() + 9 * m * m.transpose());
    Eigen::Vector3d n = cross.normalized();
    // One key per line (n and -n together, signed by the largest component), 0.01 wide.
    int largest = 0;
    n.cwiseAbs().maxCoeff(&largest);
    if (n[largest] < 0) n = -n;
    const std::array<int, 3> key = {static_cast<int>(std::lround(100 * n.x())),
                                    static_cast<int>(std::lround(100 * n.y())),
                                    static_cast<int>(std::lround(100 * n.z()))};
    // (Eigen's vectors start uninitialised: the bucket is made with an explicit zero.)
    auto& bucket = normals.try_emplace(key, 0.0, Eigen::Vector3d::Zero()).first->second;
    bucket.first += A;
    bucket.second += A * n;
  }
  if (!(area > 0)) throw Error("symmetry: the mesh has no area");
  centre = first / area;
  const double diagonal = box.diagonal().norm();
  tol = options.tolerance_mm > 0 ? options.tolerance_mm
                                 : 0.0025 * diagonal + 2 * options.deviation_mm;

  // Surface points: every vertex, then triangle centroids, thinned evenly to max_points; a
  // quick subset spread over them.
  std::vector<Eigen::Vector3d> candidates;
  for (const Eigen::Vector3f& p : mesh.positions) candidates.push_back(p.cast<double>());
  for (const auto& t : mesh.triangles) {
    candidates.push_back((mesh.positions[t[0]].cast<double>() +
                          mesh.positions[t[1]].cast<double>() +
                          mesh.positions[t[2]].cast<double>()) /
                         3);
  }
  const size_t max_points = static_cast<size_t>(options.max_points);
  if (candidates.size() <= max_points) {
    points = candidates;
  } else {
    for (size_t i = 0; i < max_points; ++i)
      points.push_back(candidates[i * candidates.size() / max_points]);
  }
  for (size_t i = 0; i < 64; ++i) quick.push_back(points[(i * 7919) % points.size()]);
  surface = std::make_unique<Surface>(mesh);
}

// The group `from` generates, up to `cap` members (identity first), members told apart by how
// they move the box's corners.
std::vector<Eigen::Isometry3d> Closure(const std::vector<Eigen::Isometry3d>& from,
                                       const Eigen::AlignedBox3d& box, double within, size_t cap) {
  std::vector<Eigen::Isometry3d> group = {Eigen::Isometry3d::Identity()};
  for (size_t i = 0; i < group.size() && group.size() < cap; ++i) {
    for (const Eigen::Isometry3d& g : from) {
      const Eigen::Isometry3d product = g * group[i];
      bool known = false;
      for (const Eigen::Isometry3d& e : group) known = known || SameMotion(e, product, box, within);
      if (!known) group.push_back(product);
      if (group.size() >= cap) break;
    }
  }
  return group;
}

// Candidate axes: the principal axes of the surface, then the lines of its largest flat areas.
std::vector<Eigen::Vector3d> CandidateAxes(const Probe& probe, const SymmetryOptions& options) {
  const Eigen::Vector3d& centre = probe.centre;
  std::vector<Eigen::Vector3d> axes;
  const auto add_axis = [&](Eigen::Vector3d a) {
    if (!(a.norm() > 1e-9)) return;
    a.normalize();
    for (const Eigen::Vector3d& b : axes) {
      if (std::abs(a.dot(b)) > 0.9999) return;
    }
    axes.push_back(a);
  };
  const Eigen::Matrix3d covariance = probe.second / probe.area - centre * centre.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
  // An eigenvector is an axis only when its eigenvalue stands apart: within a repeated eigenvalue
  // the vectors are arbitrary (they turn with the last bits of the sums).
  const Eigen::Vector3d values = eigen.eigenvalues();
  const double spread = 1e-6 * std::max(1e-300, values.cwiseAbs().maxCoeff());
  for (int k = 2; k >= 0; --k) {
    bool apart = true;
    for (int j = 0; j < 3; ++j)
      apart = apart && (j == k || std::abs(values[j] - values[k]) > spread);
    if (apart) add_axis(eigen.eigenvectors().col(k));
  }
  // The exact axes of revolution the B-rep gives, where they pass through the centroid.
  for (const SymmetryOptions::Line& line : options.axis_hints) {
    if (!(line.direction.norm() > 1e-9)) continue;
    const Eigen::Vector3d d = line.direction.normalized();
    const Eigen::Vector3d off = centre - line.point;
    if ((off - off.dot(d) * d).norm() <= probe.tol) add_axis(d);
  }
  std::vector<std::pair<double, Eigen::Vector3d>> flats;
  for (const auto& [key, bucket] : probe.normals) flats.push_back(bucket);
  std::stable_sort(flats.begin(), flats.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  for (size_t i = 0; i < flats.size() && i < 12; ++i) add_axis(flats[i].second);
  return axes;
}

// Axis a: continuous, else its largest n-fold rotation (recorded in *out, the turn added to
// *generators), else nothing.
void ClassifyAxis(const Probe& probe, const SymmetryOptions& options, const Eigen::Vector3d& a,
                  DetectedSymmetries* out, std::vector<Eigen::Isometry3d>* generators) {
  const Eigen::Vector3d& centre = probe.centre;
  const double tol = probe.tol;
  const auto holds = [&](const Eigen::Isometry3d& t, double* deviation) {
    return probe.Holds(t, deviation);
  };
  double worst = 0, deviation = 0;
  bool continuous = true;
  for (const double angle : kContinuousAngles) {
    if (!holds(RotationAbout(centre, a, angle), &deviation)) {
      continuous = false;
      break;
    }
    worst = std::max(worst, deviation);
  }
  if (continuous) {
    out->axes.push_back({a, 0});
    out->symmetries.continuous.push_back({a, centre});
    out->continuous_deviation_mm.push_back(worst);
    return;
  }
  for (int n = options.max_order; n >= 2; --n) {
    // Every power must hold, not only the smallest turn (which a loose tolerance lets through
    // for any large n): the smallest on the quick points first (most n fail there), then the
    // half-way turn (the largest move), then the rest.
    if (Deviation(*probe.surface, probe.quick, RotationAbout(centre, a, 2 * M_PI / n), tol) > tol)
      continue;
    if (!holds(RotationAbout(centre, a, 2 * M_PI * (n / 2) / n), &deviation)) continue;
    bool powers = true;
    for (int k = 1; k < n / 2 && powers; ++k)
      powers = holds(RotationAbout(centre, a, 2 * M_PI * k / n), &deviation);
    if (powers) {
      out->axes.push_back({a, n});
      generators->push_back(RotationAbout(centre, a, 2 * M_PI / n));
      break;
    }
  }
}

// The best half-turn about an axis perpendicular to the main one (not yet checked): flip axes of
// an n-fold symmetry repeat every pi / n, so one lies in [0, pi / n); scan it, refine the best.
Eigen::Isometry3d ScanFlip(const Probe& probe, const DetectedSymmetries::Axis& main) {
  const Eigen::Vector3d& centre = probe.centre;
  const Eigen::Vector3d m = main.direction;
  const int n = std::max(1, main.order);
  const Eigen::Vector3d hint =
      std::abs(m.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d u = (hint - hint.dot(m) * m).normalized(), v = m.cross(u);
  const auto flip = [&](double phi) {
    return RotationAbout(centre, std::cos(phi) * u + std::sin(phi) * v, M_PI);
  };
  const auto quick_deviation = [&](double phi) {
    return Deviation(*probe.surface, probe.quick, flip(phi), 1e300);
  };
  const int steps = 96;
  const double period = M_PI / n;
  double best_phi = 0, best = 1e300;
  for (int k = 0; k < steps; ++k) {
    const double phi = period * k / steps;
    const double d = quick_deviation(phi);
    if (d < best) best = d, best_phi = phi;
  }
  // Golden-section search on the quick deviation within a step either side.
  double lo = best_phi - period / steps, hi = best_phi + period / steps;
  const double g = 0.5 * (std::sqrt(5.0) - 1);
  double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
  double f1 = quick_deviation(x1), f2 = quick_deviation(x2);
  for (int it = 0; it < 40; ++it) {
    if (f1 < f2) {
      hi = x2, x2 = x1, f2 = f1, x1 = hi - g * (hi - lo), f1 = quick_deviation(x1);
    } else {
      lo = x1, x1 = x2, f1 = f2, x2 = lo + g * (hi - lo), f2 = quick_deviation(x2);
    }
  }
  const double phi = std::min(f1, f2) < best ? (f1 < f2 ? x1 : x2) : best_phi;
  return flip(phi);
}

// The group the generators make (a continuous axis contributes its flips only), its members
// other than the identity added to *out with their deviations. Candidate axes tilted within the
// tolerance can make near-duplicates without end: at the cap, the group of the main axis's turn
// and the flip alone.
void AddGroup(const Probe& probe, const SymmetryOptions& options,
              const std::vector<Eigen::Isometry3d>& generators,
              std::optional<Eigen::Isometry3d> flip_found, DetectedSymmetries* out) {
  const double tol = probe.tol;
  const size_t cap = 2 * static_cast<size_t>(options.max_order) + 48;
  const auto closure = [&](const std::vector<Eigen::Isometry3d>& from) {
    return Closure(from, probe.box, 0.5 * tol, cap);
  };
  std::vector<Eigen::Isometry3d> group = closure(generators);
  if (group.size() >= cap && !out->axes.empty() && out->axes[0].order >= 2) {
    std::vector<Eigen::Isometry3d> main = {
        RotationAbout(probe.centre, out->axes[0].direction, 2 * M_PI / out->axes[0].order)};
    // (The candidate flips were among the tilted ones: the flip scanned for and refined.)
    if (!flip_found) {
      const Eigen::Isometry3d flip = ScanFlip(probe, out->axes[0]);
      double deviation = 0;
      if (probe.Holds(flip, &deviation)) flip_found = flip;
    }
    if (flip_found) main.push_back(*flip_found);
    group = closure(main);
  }
  // Every member measured; those products that drift beyond the tolerance are left out.
  for (size_t i = 1; i < group.size(); ++i) {
    const double d = Deviation(*probe.surface, probe.points, group[i], tol);
    if (d > tol) continue;
    out->symmetries.discrete.push_back(group[i]);
    out->discrete_deviation_mm.push_back(d);
  }
}

}  // namespace

DetectedSymmetries DetectSymmetries(const Mesh& mesh, const SymmetryOptions& options) {
  const Probe probe(mesh, options);
  DetectedSymmetries out;
  out.centre = probe.centre;
  out.tolerance_mm = probe.tol;

  std::vector<Eigen::Isometry3d> generators;
  for (const Eigen::Vector3d& a : CandidateAxes(probe, options))
    ClassifyAxis(probe, options, a, &out, &generators);
  // The main axis first: continuous, else the highest order (stable: candidates' order).
  std::stable_sort(out.axes.begin(), out.axes.end(), [](const auto& x, const auto& y) {
    const int ox = x.order == 0 ? 1 << 30 : x.order, oy = y.order == 0 ? 1 << 30 : y.order;
    return ox > oy;
  });

  // A half-turn about an axis perpendicular to the main one, scanned for and checked.
  // (Not needed when a candidate axis perpendicular to the main one already turns: the group
  // then has its flips, exactly.)
  bool have_flip = false;
  std::optional<Eigen::Isometry3d> flip_found;
  for (size_t i = 1; i < out.axes.size(); ++i) {
    have_flip = have_flip || (out.axes[i].order >= 2 &&
                              std::abs(out.axes[i].direction.dot(out.axes[0].direction)) < 1e-6);
  }
  if (!out.axes.empty() && !(have_flip && out.axes[0].order != 0)) {
    const Eigen::Isometry3d flip = ScanFlip(probe, out.axes[0]);
    double deviation = 0;
    if (probe.Holds(flip, &deviation)) {
      if (out.axes[0].order == 0) {
        // About a continuous axis BOP lists one flip: the rotations make the others.
        out.symmetries.discrete.push_back(flip);
        out.discrete_deviation_mm.push_back(deviation);
        return out;
      }
      generators.push_back(flip);
      flip_found = flip;
    }
    if (out.axes[0].order == 0) return out;
  }

  AddGroup(probe, options, generators, flip_found, &out);
  return out;
}

DetectedSymmetries MeasureSymmetries(const Mesh& mesh, const Symmetries& given,
                                     const SymmetryOptions& options) {
  const Probe probe(mesh, options);
  DetectedSymmetries out;
  out.centre = probe.centre;
  out.tolerance_mm = probe.tol;
  const auto measure = [&](const Eigen::Isometry3d& t) {
    return Deviation(*probe.surface, probe.points, t, 1e300);
  };
  for (const Symmetries::Axis& a : given.continuous) {
    double worst = 0;
    for (const double angle : kContinuousAngles)
      worst = std::max(worst, measure(RotationAbout(a.offset, a.direction, angle)));
    out.symmetries.continuous.push_back(a);
    out.continuous_deviation_mm.push_back(worst);
    out.axes.push_back({a.direction, 0});
  }
  const std::vector<Eigen::Isometry3d> group = Closure(
      given.discrete, probe.box, 0.5 * probe.tol, 2 * static_cast<size_t>(options.max_order) + 48);
  for (size_t i = 1; i < group.size(); ++i) {
    out.symmetries.discrete.push_back(group[i]);
    out.discrete_deviation_mm.push_back(measure(group[i]));
  }
  // The axes of the listed rotations with their orders (the smallest power that is the
  // identity), the highest first after any continuous one.
  std::vector<DetectedSymmetries::Axis> turns;
  for (const Eigen::Isometry3d& t : given.discrete) {
    const Eigen::AngleAxisd r(t.linear());
    if (!(r.angle() > 1e-9)) continue;
    int order = 0;
    Eigen::Isometry3d power = t;
    for (int n = 2; n <= options.max_order && order == 0; ++n) {
      power = t * power;
      if (SameMotion(power, Eigen::Isometry3d::Identity(), probe.box, 0.5 * probe.tol)) order = n;
    }
    if (order > 0) turns.push_back({r.axis(), order});
  }
  std::stable_sort(turns.begin(), turns.end(),
                   [](const auto& x, const auto& y) { return x.order > y.order; });
  out.axes.insert(out.axes.end(), turns.begin(), turns.end());
  return out;
}

std::string DescribeSymmetries(const DetectedSymmetries& d) {
  std::ostringstream text;
  text.precision(3);
  if (d.axes.empty() || d.symmetries.empty()) return "none";
  const DetectedSymmetries::Axis& main = d.axes[0];
  const Eigen::Vector3d& a = main.direction;
  const auto near_zero = [](double v) { return std::abs(v) < 5e-7 ? 0.0 : v; };
  if (main.order == 0) {
    text << "continuous";
  } else {
    text << main.order << "-fold";
  }
  text << " about (" << near_zero(a.x()) << ", " << near_zero(a.y()) << ", " << near_zero(a.z())
       << ")";
  size_t flips = 0;
  for (const Eigen::Isometry3d& t : d.symmetries.discrete) flips += (t.linear() * a).dot(a) < -0.5;
  if (flips > 0) text << " and " << flips << (flips == 1 ? " flip" : " flips");
  if (d.symmetries.discrete.size() > flips + std::max(0, main.order - 1))
    text << " (" << d.symmetries.discrete.size() << " discrete in all)";
  double worst = 0;
  for (double v : d.discrete_deviation_mm) worst = std::max(worst, v);
  for (double v : d.continuous_deviation_mm) worst = std::max(worst, v);
  text << "; largest deviation " << worst << " mm (tolerance " << d.tolerance_mm << " mm)";
  if (!d.discrete_brep_mm.empty() || !d.continuous_brep_mm.empty()) {
    double brep = 0;
    for (double v : d.discrete_brep_mm) brep = std::max(brep, v);
    for (double v : d.continuous_brep_mm) brep = std::max(brep, v);
    if (std::isfinite(brep)) {
      text << "; B-rep surfaces match within " << brep << " mm";
    } else {
      text << "; some B-rep surfaces have no match (a detail breaks it)";
    }
    if (d.brep_faces_not_compared > 0)
      text << " (" << d.brep_faces_not_compared << " free-form face images not compared)";
  }
  return text.str();
}

}  // namespace cadsynth
