#include "render/camera.h"

#include "cad/random.h"
#include "cad/util.h"

#include <algorithm>
#include <cmath>
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
      {"xyz_ibd",
       "XYZ-IBD's XYZ structured-light sensor, grey 1440 x 1080 (BOP's size); f = 1800 is "
       "our assumption (44 degrees across)",
       Intrinsics{1440, 1080, 1800.0, 1800.0, 719.5, 539.5}, true},
      {"photoneo_phoxi_m",
       "Photoneo PhoXi 3D Scanner M, grey 2064 x 1544; 590 mm across at 650 mm "
       "(48.8 degrees)",
       Intrinsics{2064, 1544, 2275.0, 2275.0, 1031.5, 771.5}, true},
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

bool Intrinsics::Check(std::string* why) const {
  std::ostringstream out;
  if (width <= 0 || height <= 0 || width > 16384 || height > 16384) {
    out << "image size " << width << "x" << height << " must be between 1 and 16384 pixels";
  } else if (!(fx > 0.0) || !(fy > 0.0) || !std::isfinite(fx) || !std::isfinite(fy)) {
    out << "focal lengths must be positive (fx = " << fx << ", fy = " << fy << ")";
  } else if (!std::isfinite(cx) || !std::isfinite(cy)) {
    out << "principal point must be finite";
  } else {
    return true;
  }
  *why = out.str();
  return false;
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
