#include "render/camera.h"

#include <cmath>
#include <sstream>

namespace cadsynth {

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

}  // namespace cadsynth
