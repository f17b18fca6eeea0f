#include "render/camera.h"

#include "cad/core/random.h"
#include "cad/core/util.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace cadsynth {

Intrinsics Intrinsics::RealSenseD435(int width) {
  if (width == 1280) return Intrinsics{1280, 720, 923.0, 923.0, 639.5, 359.5};
  return Intrinsics{640, 480, 615.0, 615.0, 319.5, 239.5};
}

Intrinsics Intrinsics::FromFov(int width, int height, double hfov_rad) {
  const double f = 0.5 * width / std::tan(0.5 * hfov_rad);
  return Intrinsics{width, height, f, f, 0.5 * width - 0.5, 0.5 * height - 0.5};
}

const std::vector<CameraPreset>& CameraPresets() {
  const auto fov = [](int w, int h, double hfov_deg) {
    return Intrinsics::FromFov(w, h, hfov_deg * M_PI / 180.0);
  };
  static const std::vector<CameraPreset> presets = {
      {"kinect_v1", "Kinect v1 of the reference paper: 640 x 480, f = 525", Intrinsics::KinectV1()},
      {"realsense_d435", "RealSense D435 colour camera, 1280 x 720, 69 degrees across",
       Intrinsics::RealSenseD435(1280)},
      {"realsense_d435_640", "RealSense D435 colour camera, 640 x 480, 55 degrees across",
       Intrinsics::RealSenseD435(640)},
      {"realsense_d435_depth",
       "RealSense D435 depth (left IR) camera, 848 x 480, 87 degrees across", fov(848, 480, 87.0)},
      {"realsense_l515", "RealSense L515 depth camera, 1024 x 768, 70 degrees across",
       fov(1024, 768, 70.0)},
      {"azure_kinect_nfov",
       "Azure Kinect depth, narrow field of view unbinned, 640 x 576, 75 degrees",
       fov(640, 576, 75.0)},
      {"azure_kinect_wfov",
       "Azure Kinect depth, wide field of view unbinned, 1024 x 1024, 120 degrees",
       fov(1024, 1024, 120.0)},
      {"xyz_ibd",
       "XYZ-IBD's XYZ structured-light sensor, grey 1440 x 1080 (BOP's size); f = 1800 is "
       "our assumption (44 degrees across)",
       Intrinsics{1440, 1080, 1800.0, 1800.0, 719.5, 539.5}, true},
      {"photoneo_phoxi_m",
       "Photoneo PhoXi 3D Scanner M, grey 2064 x 1544; 590 mm across at 650 mm "
       "(48.8 degrees)",
       Intrinsics{2064, 1544, 2275.0, 2275.0, 1031.5, 771.5}, true},
      {"photoneo_phoxi_l",
       "Photoneo PhoXi 3D Scanner L, grey 2064 x 1544; 1082 mm across at 1239 mm "
       "(47.2 degrees)",
       Intrinsics{2064, 1544, 2363.5, 2363.5, 1031.5, 771.5}, true},
      {"itodd",
       "MVTec ITODD's 3D sensor, grey 1280 x 960, K as we recall BOP's itodd camera.json (not "
       "checked here; 24 degrees across)",
       Intrinsics{1280, 960, 2992.6, 2997.4, 633.9, 489.8}, true},
      {"zivid2_m70", "Zivid 2 M70, 1944 x 1200 colour, 770 mm across at 700 mm (57.6 degrees)",
       fov(1944, 1200, 57.6)},
  };
  return presets;
}

const CameraPreset* FindCameraPreset(const std::string& name) {
  for (const CameraPreset& p : CameraPresets()) {
    if (name == p.name) return &p;
  }
  return nullptr;
}

Eigen::Matrix3d Intrinsics::K() const {
  Eigen::Matrix3d k;
  k << fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0;
  return k;
}

Eigen::Vector2d Distortion::Distort(const Eigen::Vector2d& xy, Eigen::Matrix2d* jacobian) const {
  const double x = xy.x(), y = xy.y(), r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
  const Eigen::Vector2d out(x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
                            y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y);
  if (jacobian != nullptr) {
    // d radial / dx = 2 x radial', radial' = k1 + 2 k2 r^2 + 3 k3 r^4.
    const double slope = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2);
    const double cross = 2.0 * x * y * slope + 2.0 * p1 * x + 2.0 * p2 * y;
    *jacobian << radial + 2.0 * x * x * slope + 2.0 * p1 * y + 6.0 * p2 * x, cross, cross,
        radial + 2.0 * y * y * slope + 6.0 * p1 * y + 2.0 * p2 * x;
  }
  return out;
}

namespace {

// g(s) = d/dr [r (1 + k1 r^2 + k2 r^4 + k3 r^6)] = 1 + 3 k1 s + 5 k2 s^2 + 7 k3 s^3, s = r^2.
double RadialSlope(const Distortion& d, double s) {
  return 1.0 + s * (3.0 * d.k1 + s * (5.0 * d.k2 + s * 7.0 * d.k3));
}

// The positive roots of g' = 3 k1 + 10 k2 s + 21 k3 s^2 below `last`, in order, then `last`: the
// ends of the pieces of [0, last] on which g is monotonic (in ends[0..count)). The quadratic's
// roots in the cancellation-free form.
int MonotonicEnds(const Distortion& d, double last, double ends[3]) {
  double roots[2];
  int n = 0;
  const double qa = 21.0 * d.k3, qb = 10.0 * d.k2, qc = 3.0 * d.k1;
  if (qa != 0.0) {
    const double disc = qb * qb - 4.0 * qa * qc;
    if (disc >= 0.0) {
      const double q = -0.5 * (qb + std::copysign(std::sqrt(disc), qb));
      roots[n++] = q / qa;
      if (q != 0.0) roots[n++] = qc / q;
    }
  } else if (qb != 0.0) {
    roots[n++] = -qc / qb;
  }
  if (n == 2 && roots[1] < roots[0]) std::swap(roots[0], roots[1]);
  int count = 0;
  for (int i = 0; i < n; ++i) {
    if (roots[i] > 0.0 && roots[i] < last) ends[count++] = roots[i];
  }
  ends[count++] = last;
  return count;
}

}  // namespace

double Distortion::FoldRadius() const {
  // The first piece whose end has g <= 0 holds g's first root (g(0) = 1): bisect it.
  double lo = 0.0, ends[3];
  const int count = MonotonicEnds(*this, 1e12, ends);  // up to r = 10^6: no lens images farther
  for (int e = 0; e < count; ++e) {
    double hi = ends[e];
    if (RadialSlope(*this, hi) <= 0.0) {
      for (int i = 0; i < 200 && hi - lo > 1e-15 * hi; ++i) {
        const double mid = 0.5 * (lo + hi);
        (RadialSlope(*this, mid) > 0.0 ? lo : hi) = mid;
      }
      return std::sqrt(lo);
    }
    lo = hi;
  }
  return std::numeric_limits<double>::infinity();
}

bool Distortion::InsideFold(double r2) const {
  // g is monotonic between the ends, so its least value on [0, r2] is at one of them or at r2.
  double ends[3];
  const int count = MonotonicEnds(*this, r2, ends);
  for (int e = 0; e < count; ++e) {
    if (!(RadialSlope(*this, ends[e]) > 0.0)) return false;
  }
  return true;
}

bool Distortion::Undistort(const Eigen::Vector2d& xd, const Eigen::Vector2d& guess,
                           Eigen::Vector2d* xy) const {
  Eigen::Vector2d p = guess;
  Eigen::Matrix2d jacobian;
  double error = (Distort(p, &jacobian) - xd).norm();
  for (int iteration = 0; iteration < 60 && error > 1e-13; ++iteration) {
    const Eigen::Vector2d step = jacobian.inverse() * (Distort(p) - xd);
    if (!step.allFinite()) return false;
    // Halve the step until the residual falls.
    double t = 1.0;
    for (; t > 1e-6; t *= 0.5) {
      const Eigen::Vector2d q = p - t * step;
      const double e = (Distort(q) - xd).norm();
      if (e < error) {
        p = q;
        error = e;
        break;
      }
    }
    if (t <= 1e-6) break;
    Distort(p, &jacobian);
  }
  if (!(error <= 1e-12) || !InsideFold(p.squaredNorm())) return false;
  Distort(p, &jacobian);
  if (!(jacobian.determinant() > 0.0)) return false;
  *xy = p;
  return true;
}

bool Intrinsics::Unproject(double u, double v, Eigen::Vector2d* xy) const {
  const Eigen::Vector2d pinhole((u - cx) / fx, (v - cy) / fy);
  if (!distortion.active()) {
    *xy = pinhole;
    return true;
  }
  return distortion.Undistort(pinhole, pinhole, xy);
}

bool Intrinsics::Project(const Eigen::Vector3d& p, Eigen::Vector2d* uv) const {
  if (!distortion.active()) {
    *uv = Eigen::Vector2d(fx * p.x() / p.z() + cx, fy * p.y() / p.z() + cy);
    return p.z() > 0.0;
  }
  const Eigen::Vector2d xy(p.x() / p.z(), p.y() / p.z());
  const Eigen::Vector2d d = distortion.Distort(xy);
  *uv = Eigen::Vector2d(fx * d.x() + cx, fy * d.y() + cy);
  return p.z() > 0.0 && distortion.InsideFold(xy.squaredNorm());
}

bool Intrinsics::Check(std::string* why) const {
  std::ostringstream out;
  if (width <= 0 || height <= 0 || width > 16384 || height > 16384) {
    out << "image size " << width << "x" << height << " must be between 1 and 16384 pixels";
  } else if (!(fx > 0.0) || !(fy > 0.0) || !std::isfinite(fx) || !std::isfinite(fy)) {
    out << "focal lengths must be positive (fx = " << fx << ", fy = " << fy << ")";
  } else if (!std::isfinite(cx) || !std::isfinite(cy)) {
    out << "principal point must be finite";
  } else if (!std::isfinite(distortion.k1) || !std::isfinite(distortion.k2) ||
             !std::isfinite(distortion.p1) || !std::isfinite(distortion.p2) ||
             !std::isfinite(distortion.k3)) {
    out << "distortion coefficients must be finite";
  } else {
    // Every pixel corner on the image's border must have a ray: the fold lies outside the image.
    if (distortion.active()) {
      // The border's pixel corners, in order: top and bottom rows, then left and right columns.
      std::vector<Eigen::Vector2i> border;
      for (int u = 0; u <= width; ++u) border.emplace_back(u, 0), border.emplace_back(u, height);
      for (int v = 0; v <= height; ++v) border.emplace_back(0, v), border.emplace_back(width, v);
      for (const Eigen::Vector2i& p : border) {
        const Eigen::Vector2d pinhole((p.x() - cx) / fx, (p.y() - cy) / fy);
        Eigen::Vector2d xy;
        if (!distortion.Undistort(pinhole, pinhole, &xy)) {
          out << "pixel (" << p.x() << ", " << p.y() << ")";
          break;
        }
      }
      if (out.tellp() > 0) {
        out << " has no ray: the distortion polynomial folds back inside the image (fold radius "
            << distortion.FoldRadius() << " on the normalised plane); check the coefficients";
        *why = out.str();
        return false;
      }
    }
    return true;
  }
  *why = out.str();
  return false;
}

bool ThinLens::Check(std::string* why) const {
  if (!(focal_length_mm >= 0.0) || !std::isfinite(focal_length_mm)) {
    *why = "focal_length must be a length of 0 (a pinhole) or more";
  } else if (!(f_number >= 0.5 && f_number <= 128.0)) {
    *why = "f_number must lie between 0.5 and 128";
  } else if (!(focus_distance_mm > 0.0) || focus_distance_mm > kMaxSceneExtentMm) {
    *why = "focus_distance must be a positive length up to 1 km";
  } else {
    return true;
  }
  return false;
}

bool CameraMotion::Check(std::string* why) const {
  if (!velocity_mm_s.allFinite() || velocity_mm_s.norm() > 1e6) {
    *why = "velocity must be finite and at most 1000 m/s";
  } else if (!angular_velocity_rad_s.allFinite() || angular_velocity_rad_s.norm() > 1e4) {
    *why = "angular velocity must be finite and at most 10^4 rad/s";
  } else if (!(exposure_s >= 0.0 && exposure_s <= 10.0)) {
    *why = "exposure must lie between 0 and 10 s";
  } else {
    return true;
  }
  return false;
}

Eigen::Isometry3d CameraMotion::At(double tau) const {
  const double t = tau * exposure_s;
  const Eigen::Vector3d w = angular_velocity_rad_s * t, v = velocity_mm_s * t;
  const double theta = w.norm();
  Eigen::Matrix3d hat;
  hat << 0.0, -w.z(), w.y(), w.z(), 0.0, -w.x(), -w.y(), w.x(), 0.0;
  // V = I + (1 - cos) / theta^2 [w] + (theta - sin) / theta^3 [w]^2, by series near 0.
  double a = 0.5, b = 1.0 / 6.0;
  if (theta > 1e-6) {
    a = (1.0 - std::cos(theta)) / (theta * theta);
    b = (theta - std::sin(theta)) / (theta * theta * theta);
  }
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  if (theta > 0.0) out.linear() = Eigen::AngleAxisd(theta, w / theta).toRotationMatrix();
  out.translation() = (Eigen::Matrix3d::Identity() + a * hat + b * hat * hat) * v;
  return out;
}

CameraMotion CameraMotion::Seen(const Eigen::Isometry3d& this_from_other) const {
  CameraMotion out = *this;
  const Eigen::Matrix3d r_t = this_from_other.linear().transpose();
  out.angular_velocity_rad_s = r_t * angular_velocity_rad_s;
  out.velocity_mm_s =
      r_t * (velocity_mm_s + angular_velocity_rad_s.cross(this_from_other.translation()));
  return out;
}

bool SweepOptions::Check(std::string* why) const {
  if (yaw_rad.empty() || pitch_rad.empty() || radius_mm.empty()) {
    *why = "the sweep needs at least one yaw, one pitch and one radius";
    return false;
  }
  for (double pitch : pitch_rad) {
    if (!(pitch >= -0.5 * M_PI - 1e-12 && pitch <= 0.5 * M_PI + 1e-12)) {
      *why = "pitch must lie between -90 and 90 degrees";
      return false;
    }
  }
  for (double radius : radius_mm) {
    if (!(radius > 0.0) || !std::isfinite(radius)) {
      *why = "radius must be a positive length";
      return false;
    }
    if (radius > kMaxSceneExtentMm) {
      *why = "radius must be at most 1 km (the tracer's single precision would lose the parts)";
      return false;
    }
  }
  if (!target.allFinite() || target.norm() > kMaxSceneExtentMm) {
    *why = "the target must lie within 1 km of the origin";
    return false;
  }
  return true;
}

Eigen::Isometry3d WorldFromCamOnSphere(const Eigen::Vector3d& target, double yaw_rad,
                                       double pitch_rad, double radius_mm) {
  const double cy = std::cos(yaw_rad), sy = std::sin(yaw_rad);
  const double cp = std::cos(pitch_rad), sp = std::sin(pitch_rad);
  const Eigen::Vector3d eye_dir(cp * cy, cp * sy, sp);  // from target to eye, unit length
  const Eigen::Vector3d z = -eye_dir;                   // forward
  const Eigen::Vector3d x(-sy, cy, 0.0);                // right; horizontal at every pitch
  const Eigen::Vector3d y = z.cross(x);                 // down
  Eigen::Isometry3d world_from_cam = Eigen::Isometry3d::Identity();
  world_from_cam.linear().col(0) = x;
  world_from_cam.linear().col(1) = y;
  world_from_cam.linear().col(2) = z;
  world_from_cam.translation() = target + radius_mm * eye_dir;
  return world_from_cam;
}

std::vector<SweepView> ExpandSweep(const SweepOptions& options) {
  std::vector<SweepView> views;
  views.reserve(options.NumViews());
  for (double radius : options.radius_mm) {
    for (double pitch : options.pitch_rad) {
      for (double yaw : options.yaw_rad) {
        views.push_back(
            {yaw, pitch, radius, WorldFromCamOnSphere(options.target, yaw, pitch, radius)});
      }
    }
  }
  return views;
}

bool ViewSampler::Check(std::string* why) const {
  std::ostringstream out;
  if (kind != Kind::kGrid && (count < 1 || count > 10000000)) {
    out << "count must be 1 to 10,000,000";
  } else if (!(min_pitch_rad <= max_pitch_rad) || min_pitch_rad < -0.5 * M_PI - 1e-12 ||
             max_pitch_rad > 0.5 * M_PI + 1e-12) {
    out << "the pitch band must lie within -90 to 90 degrees, lowest first";
  } else if (kind == Kind::kRandom && !(min_radius_mm > 0 && min_radius_mm <= max_radius_mm)) {
    out << "the radius range must be positive, smallest first";
  } else if (kind == Kind::kRandom && max_radius_mm > kMaxSceneExtentMm) {
    out << "the radius must be at most 1 km (the tracer's single precision would lose the parts)";
  } else if (!(roll_jitter_rad >= 0) || !(target_jitter_mm >= 0)) {
    out << "jitter must not be negative";
  } else if (target_jitter_mm > kMaxSceneExtentMm) {
    out << "the target jitter must be at most 1 km";
  } else {
    return true;
  }
  *why = out.str();
  return false;
}

namespace {

// Pitch from a uniform number, uniform in area over the band (sin(pitch) uniform).
double PitchForArea(double u, double lo, double hi) {
  const double s = std::sin(lo) + u * (std::sin(hi) - std::sin(lo));
  return std::asin(std::clamp(s, -1.0, 1.0));
}

}  // namespace

std::vector<SweepView> SampleViews(const ViewSampler& sampler, const SweepOptions& sweep) {
  std::vector<SweepView> views;
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  switch (sampler.kind) {
    case ViewSampler::Kind::kGrid:
      views = ExpandSweep(sweep);
      break;
    case ViewSampler::Kind::kFibonacci:
      for (double radius : sweep.radius_mm) {
        for (int i = 0; i < sampler.count; ++i) {
          const double pitch =
              PitchForArea((i + 0.5) / sampler.count, sampler.min_pitch_rad, sampler.max_pitch_rad);
          const double yaw = std::fmod(i * golden, 2 * M_PI);
          views.push_back(
              {yaw, pitch, radius, WorldFromCamOnSphere(sweep.target, yaw, pitch, radius)});
        }
      }
      break;
    case ViewSampler::Kind::kRandom:
      for (int i = 0; i < sampler.count; ++i) {
        const double yaw = 2 * M_PI * UniformDraw(sampler.seed, streams::kViewYaw, i);
        const double pitch = PitchForArea(UniformDraw(sampler.seed, streams::kViewPitch, i),
                                          sampler.min_pitch_rad, sampler.max_pitch_rad);
        const double radius =
            sampler.min_radius_mm + UniformDraw(sampler.seed, streams::kViewRadius, i) *
                                        (sampler.max_radius_mm - sampler.min_radius_mm);
        views.push_back(
            {yaw, pitch, radius, WorldFromCamOnSphere(sweep.target, yaw, pitch, radius)});
      }
      break;
  }
  if (sampler.roll_jitter_rad > 0 || sampler.target_jitter_mm > 0) {
    for (size_t i = 0; i < views.size(); ++i) {
      SweepView& v = views[i];
      // Aim at a point in a ball around the target (uniform in volume), then roll.
      Eigen::Vector3d offset = Eigen::Vector3d::Zero();
      if (sampler.target_jitter_mm > 0) {
        const double z = 2 * UniformDraw(sampler.seed, streams::kTargetHeight, i) - 1,
                     a = 2 * M_PI * UniformDraw(sampler.seed, streams::kTargetAzimuth, i);
        const double r = sampler.target_jitter_mm *
                         std::cbrt(UniformDraw(sampler.seed, streams::kTargetRadius, i));
        offset = r * Eigen::Vector3d(std::sqrt(1 - z * z) * std::cos(a),
                                     std::sqrt(1 - z * z) * std::sin(a), z);
      }
      const Eigen::Vector3d eye = v.world_from_cam.translation();
      const Eigen::Vector3d aim = sweep.target + offset;
      Eigen::Isometry3d pose = v.world_from_cam;
      const Eigen::Vector3d z = (aim - eye).normalized();
      Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ());
      if (x.norm() < 1e-9) x = v.world_from_cam.linear().col(0);  // straight down: keep the yaw
      x.normalize();
      pose.linear().col(0) = x;
      pose.linear().col(1) = z.cross(x);
      pose.linear().col(2) = z;
      const double roll =
          sampler.roll_jitter_rad * (2 * UniformDraw(sampler.seed, streams::kViewRoll, i) - 1);
      pose.linear() =
          pose.linear() * Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      v.world_from_cam = pose;
    }
  }
  return views;
}

}  // namespace cadsynth
