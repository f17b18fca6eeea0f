#include "cad/gear_recognition.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <sstream>

namespace cadsynth {

namespace {

constexpr int kBins = 4096;  // angular bins of a section's radius profile
constexpr double kInf = std::numeric_limits<double>::infinity();

double Involute(double a) { return std::tan(a) - a; }

// Cylindrical coordinates about an axis: h along it, r and theta about it (theta counter-
// clockwise seen from the axis's tip, from `u`).
struct Frame {
  Frame(const SymmetryOptions::Line& line) : origin(line.point), axis(line.direction.normalized()) {
    const Eigen::Vector3d hint =
        std::abs(axis.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    u = (hint - hint.dot(axis) * axis).normalized();
    v = axis.cross(u);
  }
  Eigen::Vector3d Local(const Eigen::Vector3d& p) const {  // (x, y, h)
    const Eigen::Vector3d d = p - origin;
    return {d.dot(u), d.dot(v), d.dot(axis)};
  }
  Eigen::Vector3d origin, axis, u, v;
};

// A transverse section's radius profile: per angular bin the largest and the smallest radius of
// the section's outline (empty bins filled from their neighbours).
struct Profile {
  std::vector<double> outer, inner;
  bool ok = false;
};

int Bin(double theta) {
  const int b = static_cast<int>(std::floor((theta + M_PI) / (2 * M_PI) * kBins));
  return std::clamp(b, 0, kBins - 1);
}
double BinAngle(int b) { return -M_PI + (b + 0.5) * 2 * M_PI / kBins; }

// Fills the bins left at `empty` by walking round from the last filled one (a bin the outline
// crosses only between samples).
bool Fill(std::vector<double>* p, double empty) {
  int first = -1;
  for (int b = 0; b < kBins && first < 0; ++b) first = (*p)[b] != empty ? b : -1;
  if (first < 0) return false;
  double last = (*p)[first];
  for (int k = 1; k <= kBins; ++k) {
    double& x = (*p)[(first + k) % kBins];
    if (x == empty) {
      x = last;
    } else {
      last = x;
    }
  }
  return true;
}

double Wrap(double angle, double period) {  // into [-period / 2, period / 2)
  return angle - period * std::floor(angle / period + 0.5);
}

Profile Section(const Mesh& mesh, const std::vector<Eigen::Vector3d>& local, double h,
                double step) {
  Profile p;
  p.outer.assign(kBins, -kInf);
  p.inner.assign(kBins, kInf);
  for (const auto& t : mesh.triangles) {
    Eigen::Vector2d ends[2];
    int n = 0;
    for (int e = 0; e < 3 && n < 2; ++e) {
      const Eigen::Vector3d& a = local[t[e]];
      const Eigen::Vector3d& b = local[t[(e + 1) % 3]];
      if ((a.z() >= h) == (b.z() >= h)) continue;
      const double s = (h - a.z()) / (b.z() - a.z());
      ends[n++] = a.head<2>() + s * (b.head<2>() - a.head<2>());
    }
    if (n < 2) continue;
    // Dense enough in length and in angle (a bore's outline is short but turns all the way).
    const double turn = std::abs(Wrap(
        std::atan2(ends[1].y(), ends[1].x()) - std::atan2(ends[0].y(), ends[0].x()), 2 * M_PI));
    const int samples =
        1 + static_cast<int>(std::max((ends[1] - ends[0]).norm() / step, turn * kBins / M_PI));
    for (int k = 0; k <= samples; ++k) {
      const Eigen::Vector2d q = ends[0] + (ends[1] - ends[0]) * (double(k) / samples);
      const int b = Bin(std::atan2(q.y(), q.x()));
      const double r = q.norm();
      p.outer[b] = std::max(p.outer[b], r);
      p.inner[b] = std::min(p.inner[b], r);
    }
  }
  p.ok = Fill(&p.outer, -kInf) && Fill(&p.inner, kInf);
  return p;
}

// Teeth of a periodic radius profile: rises through 65% of its range after falling below 35%.
int CountTeeth(const std::vector<double>& p) {
  const auto [lo_it, hi_it] = std::minmax_element(p.begin(), p.end());
  const double lo = *lo_it, hi = *hi_it;
  if (!(hi - lo > 0)) return 0;
  const double low = lo + 0.35 * (hi - lo), high = lo + 0.65 * (hi - lo);
  const int start = static_cast<int>(lo_it - p.begin());
  bool up = false;
  int count = 0;
  for (int k = 1; k <= kBins; ++k) {
    const double x = p[(start + k) % kBins];
    if (!up && x > high) up = true, ++count;
    if (up && x < low) up = false;
  }
  return count;
}

// The angle of the profile's peaks (mod 2 pi / z): its z-th Fourier component's phase.
double Phase(const std::vector<double>& p, int z) {
  std::complex<double> c = 0;
  for (int b = 0; b < kBins; ++b) c += p[b] * std::polar(1.0, -z * BinAngle(b));
  return -std::arg(c) / z;
}

std::optional<RecognizedGear> Measure(const Mesh& mesh, const Frame& frame,
                                      const std::vector<Eigen::Vector3d>& local, double step,
                                      bool internal, int z, double h_best);

std::optional<RecognizedGear> AboutAxis(const Mesh& mesh, const SymmetryOptions::Line& line) {
  const Frame frame(line);
  std::vector<Eigen::Vector3d> local;
  local.reserve(mesh.positions.size());
  double h_lo = kInf, h_hi = -kInf, r_max = 0;
  for (const Eigen::Vector3f& p : mesh.positions) {
    local.push_back(frame.Local(p.cast<double>()));
    h_lo = std::min(h_lo, local.back().z());
    h_hi = std::max(h_hi, local.back().z());
    r_max = std::max(r_max, local.back().head<2>().norm());
  }
  if (!(h_hi > h_lo) || !(r_max > 0)) return std::nullopt;
  const double step = 2 * M_PI * r_max / (4 * kBins);

  // Per side (outer: external teeth; inner: internal), the section whose profile swings most
  // with 5 or more teeth; the side that swings more is tried first, then the other (a gear on
  // a hex bore swings more inside than out, and is still an external gear).
  struct Candidate {
    bool internal = false;
    int z = 0;
    double swing = 0, h = 0;
  };
  Candidate sides[2];
  for (int k = 0; k < 9; ++k) {
    const double h = h_lo + (k + 0.5) / 9 * (h_hi - h_lo);
    const Profile p = Section(mesh, local, h, step);
    if (!p.ok) continue;
    for (const bool in : {false, true}) {
      const std::vector<double>& q = in ? p.inner : p.outer;
      const auto [lo, hi] = std::minmax_element(q.begin(), q.end());
      const int teeth = CountTeeth(q);
      const double swing = (*hi - *lo) / *hi;
      Candidate& c = sides[in ? 1 : 0];
      if (teeth >= 5 && swing > c.swing + 1e-9) c = {in, teeth, swing, h};
    }
  }
  if (sides[1].swing > sides[0].swing) std::swap(sides[0], sides[1]);
  for (const Candidate& c : sides) {
    if (c.z < 5) continue;
    if (std::optional<RecognizedGear> g = Measure(mesh, frame, local, step, c.internal, c.z, c.h))
      return g;
  }
  return std::nullopt;
}

// What measuring one side's gear shares: the mesh in the axis's cylindrical coordinates, the
// sections' sampling step, the side (internal: the inner outline's teeth) and the tooth count.
struct GearSide {
  const Mesh& mesh;
  const std::vector<Eigen::Vector3d>& local;
  double step;
  bool internal;
  int z;

  double Radius(size_t i) const { return local[i].head<2>().norm(); }
  Profile SectionAt(double h) const { return Section(mesh, local, h, step); }
  const std::vector<double>& Outline(const Profile& p) const {
    return internal ? p.inner : p.outer;
  }
};

// The toothed band: tip and root radii, the teeth's depth and the heights they span.
struct Band {
  double tip = 0, root = 0, depth = 0, h0 = 0, h1 = 0;
};

// The band measured from the section at h_best, if its teeth are as deep as a gear's.
std::optional<Band> FindBand(const GearSide& s, double h_best) {
  const bool internal = s.internal;
  const std::vector<Eigen::Vector3d>& local = s.local;
  const Profile first = s.SectionAt(h_best);
  const std::vector<double>& q0 = s.Outline(first);
  const auto [lo0, hi0] = std::minmax_element(q0.begin(), q0.end());
  // Tip and root as the section samples them (between vertices a chord cuts in), then exactly:
  // the outline's vertices lie on the surface.
  const double tip_s = internal ? *lo0 : *hi0, root_s = internal ? *hi0 : *lo0;
  const double depth_s = std::abs(tip_s - root_s);
  const auto near = [&](double r, double target) { return std::abs(r - target) < 0.1 * depth_s; };
  double tip = internal ? kInf : -kInf;
  for (size_t i = 0; i < local.size(); ++i) {
    const double r = s.Radius(i);
    if (near(r, tip_s)) tip = internal ? std::min(tip, r) : std::max(tip, r);
  }
  if (!std::isfinite(tip)) return std::nullopt;
  // The toothed band: the heights of the vertices on the teeth's outer half (from the tips to
  // mid-depth: a chamfered or rounded tip is shorter than the tooth).
  double h0 = kInf, h1 = -kInf;
  for (size_t i = 0; i < local.size(); ++i) {
    const double into = internal ? s.Radius(i) - tip : tip - s.Radius(i);  // depth below the tip
    if (into > -0.02 * depth_s && into < 0.5 * depth_s)
      h0 = std::min(h0, local[i].z()), h1 = std::max(h1, local[i].z());
  }
  if (!(h1 > h0)) return std::nullopt;
  double root = internal ? -kInf : kInf;
  for (size_t i = 0; i < local.size(); ++i) {
    const double r = s.Radius(i);
    if (local[i].z() >= h0 && local[i].z() <= h1 && near(r, root_s))
      root = internal ? std::max(root, r) : std::min(root, r);
  }
  if (!std::isfinite(root)) return std::nullopt;
  const double depth = std::abs(tip - root);
  // A gear's teeth are about as deep as 0.7 of their pitch; a hexagon's corners are not.
  const double pitch_at_tip = 2 * M_PI * tip / s.z;
  if (!(depth > 0.3 * pitch_at_tip && depth < 1.2 * pitch_at_tip)) return std::nullopt;
  return Band{tip, root, depth, h0, h1};
}

// Least squares phase = phi0 + twist * shape(h); returns the residual sum of squares.
template <typename Shape>
double FitPhase(const std::vector<double>& hs, const std::vector<double>& phases,
                const Shape& shape, double* phi0, double* twist) {
  double mh = 0, mp = 0;
  for (size_t i = 0; i < hs.size(); ++i)
    mh += shape(hs[i]) / hs.size(), mp += phases[i] / hs.size();
  double shh = 0, shp = 0;
  for (size_t i = 0; i < hs.size(); ++i)
    shh += (shape(hs[i]) - mh) * (shape(hs[i]) - mh), shp += (shape(hs[i]) - mh) * (phases[i] - mp);
  *twist = shh > 0 ? shp / shh : 0;
  *phi0 = mp - *twist * mh;
  double sse = 0;
  for (size_t i = 0; i < hs.size(); ++i) {
    const double res = phases[i] - *phi0 - *twist * shape(hs[i]);
    sse += res * res;
  }
  return sse;
}

// The teeth's phase along the band (h from its bottom): phi0 + twist * h, or for a herringbone
// phi0 + twist * (apex - |h - apex|).
struct Twist {
  double phi0 = 0, twist = 0, apex = 0;
  bool herringbone = false;

  double Vee(double h) const { return apex - std::abs(h - apex); }
  double Turn(double h) const { return twist * (herringbone ? Vee(h) : h); }
};

// The teeth's phase along the band: a straight line in h (a helix's twist), or a V with its
// apex at mid-face (a double helical, herringbone gear).
std::optional<Twist> FitTwist(const GearSide& s, const Band& band) {
  const int z = s.z;
  const double h0 = band.h0, h1 = band.h1;
  // Between neighbouring sections the teeth must turn less than half a pitch (else the phase
  // wraps unseen): a helix of up to 50 degrees turns b tan(50) / r_p over the band.
  const double r_pitch = 0.5 * (band.tip + band.root);
  const int slices =
      std::clamp(1 + static_cast<int>(std::ceil(4 * (h1 - h0) * std::tan(50 * M_PI / 180) /
                                                r_pitch * z / (2 * M_PI))),
                 13, 400);
  std::vector<double> hs, phases;
  for (int k = 0; k < slices; ++k) {
    const double h = h0 + (0.04 + 0.92 * k / (slices - 1)) * (h1 - h0);
    const Profile p = s.SectionAt(h);
    if (!p.ok) continue;
    double phi = Phase(s.Outline(p), z);
    if (!phases.empty()) phi += (2 * M_PI / z) * std::round((phases.back() - phi) / (2 * M_PI / z));
    hs.push_back(h - h0);
    phases.push_back(phi);
  }
  if (hs.size() < 3) return std::nullopt;
  Twist t;
  t.apex = 0.5 * (h1 - h0);
  const auto straight = [](double h) { return h; };
  const auto vee = [&t](double h) { return t.Vee(h); };
  double phi0_v = 0, twist_v = 0;
  const double sse = FitPhase(hs, phases, straight, &t.phi0, &t.twist);
  const double sse_v = FitPhase(hs, phases, vee, &phi0_v, &twist_v);
  // A V fits far better than a line only where the teeth really turn back.
  t.herringbone = sse_v < 0.1 * sse && std::abs(twist_v) * t.apex > 1e-3 * (2 * M_PI / z);
  if (t.herringbone) t.phi0 = phi0_v, t.twist = twist_v;
  return t;
}

// A flank vertex: its radius, its angle from the middle of its tooth (internal: of its tooth
// space) and the side of the middle it lies on (+1 or -1).
struct FlankPoint {
  double r, y, side;
};

// The band's vertices between radii r_lo and r_hi, at their angles from their teeth's middles.
std::vector<FlankPoint> FlankPoints(const GearSide& s, const Band& band, const Twist& twist,
                                    double r_lo, double r_hi) {
  const std::vector<Eigen::Vector3d>& local = s.local;
  const double h0 = band.h0, h1 = band.h1;
  std::vector<FlankPoint> flank;
  const double period = 2 * M_PI / s.z;
  for (size_t i = 0; i < local.size(); ++i) {
    const double r = s.Radius(i), h = local[i].z();
    if (r < r_lo || r > r_hi || h < h0 || h > h1) continue;
    const double delta =
        Wrap(std::atan2(local[i].y(), local[i].x()) - twist.phi0 - twist.Turn(h - h0), period);
    flank.push_back({r, std::abs(delta), delta >= 0 ? 1.0 : -1.0});
  }
  return flank;
}

// An involute flank fit: base radius rb, the tooth's half angle psi at the base circle, a phase
// correction e, and the residual sum of squares.
struct InvoluteFit {
  double rb = 0, psi = 0, e = 0, sse = kInf;
};

// The best psi and e for base radius rb: least squares for y + inv = psi + side e.
InvoluteFit FitAtBase(const std::vector<FlankPoint>& flank, double rb) {
  double n = 0, s = 0, ss = 0, t = 0, st = 0;
  for (const FlankPoint& p : flank) {
    const double target = p.y + Involute(std::acos(std::min(1.0, rb / p.r)));
    n += 1, s += p.side, ss += p.side * p.side, t += target, st += p.side * target;
  }
  InvoluteFit f;
  f.rb = rb;
  const double det = n * ss - s * s;
  if (!(std::abs(det) > 0)) return f;
  f.psi = (ss * t - s * st) / det;
  f.e = (n * st - s * t) / det;
  f.sse = 0;
  for (const FlankPoint& p : flank) {
    const double target = p.y + Involute(std::acos(std::min(1.0, rb / p.r)));
    const double res = target - f.psi - p.side * f.e;
    f.sse += res * res;
  }
  return f;
}

// The base radius in [a, b] fitting best: golden-section search.
InvoluteFit FitInvolute(const std::vector<FlankPoint>& flank, double a, double b) {
  const auto fit = [&](double rb) { return FitAtBase(flank, rb); };
  const double golden = 0.5 * (std::sqrt(5.0) - 1);
  double x1 = b - golden * (b - a), x2 = a + golden * (b - a);
  InvoluteFit f1 = fit(x1), f2 = fit(x2);
  for (int it = 0; it < 80; ++it) {
    if (f1.sse < f2.sse) {
      b = x2, x2 = x1, f2 = f1, x1 = b - golden * (b - a), f1 = fit(x1);
    } else {
      a = x1, x1 = x2, f1 = f2, x2 = a + golden * (b - a), f2 = fit(x2);
    }
  }
  return f1.sse < f2.sse ? f1 : f2;
}

// The flanks' rms distance from the fitted involute (mm along the surface's normal); *worst
// gets the largest.
double FlankDeviation(const std::vector<FlankPoint>& flank, const InvoluteFit& fit, double* worst) {
  double sum = 0;
  *worst = 0;
  for (const FlankPoint& p : flank) {
    const double alpha = std::acos(std::min(1.0, fit.rb / p.r));
    const double res = p.y + Involute(alpha) - fit.psi - p.side * fit.e;
    const double mm = std::abs(res) * p.r * std::cos(alpha);
    *worst = std::max(*worst, mm);
    sum += mm * mm;
  }
  return std::sqrt(sum / flank.size());
}

// A round bore at mid-face: the inner outline, when most of it lies on one circle well inside
// the root (a key way may cut the rest), measured on its vertices.
std::optional<double> BoreDiameter(const GearSide& s, const Band& band) {
  const std::vector<Eigen::Vector3d>& local = s.local;
  const double h0 = band.h0, h1 = band.h1;
  const Profile mid = s.SectionAt(0.5 * (h0 + h1));
  std::vector<double> inner = mid.inner;
  std::nth_element(inner.begin(), inner.begin() + kBins / 2, inner.end());
  const double median = inner[kBins / 2];
  int round = 0;
  for (double r : mid.inner) round += std::abs(r - median) < 0.02 * median;
  if (!(mid.ok && median < band.root - 0.25 * band.depth && round > 0.75 * kBins))
    return std::nullopt;
  std::vector<double> on;
  for (size_t i = 0; i < local.size(); ++i) {
    const double r = s.Radius(i);
    if (local[i].z() >= h0 && local[i].z() <= h1 && std::abs(r - median) < 0.02 * median)
      on.push_back(r);
  }
  if (on.empty()) return std::nullopt;
  std::nth_element(on.begin(), on.begin() + on.size() / 2, on.end());
  return 2 * on[on.size() / 2];
}

// The gear on one side of the profile with z teeth, measured from the section at h_best.
std::optional<RecognizedGear> Measure(const Mesh& mesh, const Frame& frame,
                                      const std::vector<Eigen::Vector3d>& local, double step,
                                      bool internal, int z, double h_best) {
  const GearSide side{mesh, local, step, internal, z};
  const std::optional<Band> band = FindBand(side, h_best);
  if (!band) return std::nullopt;
  const double tip = band->tip, root = band->root, depth = band->depth;
  RecognizedGear g;
  g.teeth = z;
  g.internal = internal;
  g.tip_radius_mm = tip;
  g.root_radius_mm = root;
  g.face_width_mm = band->h1 - band->h0;
  g.module_mm = depth / 2.25;

  const std::optional<Twist> twist = FitTwist(side, *band);
  if (!twist) return std::nullopt;
  g.herringbone = twist->herringbone;
  const double sin_helix = twist->twist * z * g.module_mm / 2;
  if (!(std::abs(sin_helix) < 0.8)) return std::nullopt;
  g.helix_angle_rad = std::asin(sin_helix);
  if (std::abs(g.helix_angle_rad) < 1e-4) g.helix_angle_rad = 0;
  g.transverse_module_mm = g.module_mm / std::cos(g.helix_angle_rad);
  g.pitch_radius_mm = 0.5 * z * g.transverse_module_mm;

  // The flanks: vertices of the band between the root's fillet and the tip's corner, each at its
  // angle from the middle of its tooth (internal: of its tooth space). An involute tooth's half
  // angle at radius r is psi_b - inv(acos(r_b / r)); fit r_b, psi_b and a phase correction e.
  const double r_lo = internal
                          ? tip + 0.1 * depth
                          : std::max(root + 0.35 * depth, g.pitch_radius_mm - 0.15 * g.module_mm);
  const double r_hi = internal ? root - 0.35 * depth : tip - 0.1 * depth;
  const std::vector<FlankPoint> flank = FlankPoints(side, *band, *twist, r_lo, r_hi);
  if (flank.size() < 8) return std::nullopt;
  // The base circle lies below the flanks of an external gear; a ring's (up to about 25 teeth at
  // 20 degrees) may lie among them, where the clamp makes the part below it radial.
  const InvoluteFit best_fit = FitInvolute(flank, 0.5 * r_lo, 0.99999 * (internal ? r_hi : r_lo));
  double worst = 0;
  const double rms = FlankDeviation(flank, best_fit, &worst);
  if (!(rms < 0.05 * g.module_mm)) return std::nullopt;
  const double phi0 = twist->phi0 + best_fit.e;
  g.involute_deviation_mm = worst;
  g.base_radius_mm = best_fit.rb;
  if (!(g.base_radius_mm < g.pitch_radius_mm)) return std::nullopt;
  g.transverse_pressure_angle_rad = std::acos(g.base_radius_mm / g.pitch_radius_mm);
  g.pressure_angle_rad =
      std::atan(std::tan(g.transverse_pressure_angle_rad) * std::cos(g.helix_angle_rad));
  g.profile_shift = (tip - g.pitch_radius_mm) / g.module_mm + (internal ? 1.0 : -1.0);

  if (!internal) {
    if (const std::optional<double> bore = BoreDiameter(side, *band)) g.bore_diameter_mm = *bore;
  }
  g.axis = frame.axis;
  g.centre = frame.origin + band->h0 * frame.axis;
  g.reference = std::cos(phi0) * frame.u + std::sin(phi0) * frame.v;
  return g;
}

}  // namespace

std::optional<RecognizedGear> RecognizeGear(const Mesh& mesh,
                                            const std::vector<SymmetryOptions::Line>& axes) {
  if (mesh.triangles.empty()) return std::nullopt;
  std::vector<SymmetryOptions::Line> tried;
  for (const SymmetryOptions::Line& line : axes) {
    if (!(line.direction.norm() > 0)) continue;
    bool seen = false;
    for (const SymmetryOptions::Line& t : tried) {
      const Eigen::Vector3d d = t.direction.normalized(), off = line.point - t.point;
      seen = seen || (std::abs(line.direction.normalized().dot(d)) > 1 - 1e-9 &&
                      (off - off.dot(d) * d).norm() < 1e-6);
    }
    if (seen) continue;
    tried.push_back(line);
    if (std::optional<RecognizedGear> g = AboutAxis(mesh, line)) return g;
  }
  return std::nullopt;
}

std::optional<RecognizedGear> RecognizePartGear(const Part& part, const DetectedSymmetries& found) {
  std::vector<SymmetryOptions::Line> axes;
  for (const DetectedSymmetries::Axis& a : found.axes) {
    if (a.order >= 2) axes.push_back({found.centre, a.direction});
  }
  for (const SymmetryOptions::Line& line : PartSymmetryOptions(part).axis_hints)
    axes.push_back(line);
  return RecognizeGear(part.mesh, axes);
}

std::string DescribeGear(const RecognizedGear& g) {
  std::ostringstream out;
  out.precision(4);
  const double deg = 180 / M_PI;
  out << (g.internal ? "internal " : "")
      << (g.herringbone            ? "herringbone"
          : g.helix_angle_rad == 0 ? "spur"
                                   : "helical")
      << ", " << g.teeth << " teeth, module " << g.module_mm << " mm, pressure angle "
      << g.pressure_angle_rad * deg << " deg";
  // (A herringbone's hand depends on which half is looked at: its helices only.)
  if (g.herringbone) {
    out << ", helices " << std::abs(g.helix_angle_rad) * deg << " deg";
  } else if (g.helix_angle_rad != 0) {
    out << ", helix " << std::abs(g.helix_angle_rad) * deg << " deg "
        << (g.helix_angle_rad > 0 ? "right" : "left") << " hand";
  }
  out << ", face width " << g.face_width_mm << " mm";
  if (std::abs(g.profile_shift) >= 0.005) out << ", profile shift " << g.profile_shift;
  if (g.bore_diameter_mm > 0) out << ", bore " << g.bore_diameter_mm << " mm";
  out << "; tip/root/base radius " << g.tip_radius_mm << "/" << g.root_radius_mm << "/"
      << g.base_radius_mm << " mm; flanks within " << g.involute_deviation_mm
      << " mm of an involute";
  return out.str();
}

}  // namespace cadsynth
