#include "render/lights.h"

#include <cmath>

namespace cadsynth {

namespace {
bool Finite(const Eigen::Vector3d& v) { return v.allFinite(); }
bool UnitColor(const Eigen::Vector3f& c) { return c.minCoeff() >= 0.0f && c.maxCoeff() <= 1.0f; }
}  // namespace

bool LightSource::Check(std::string* why) const {
  const bool sun = kind == Kind::kSun;
  if (!(power >= 0) || !std::isfinite(power)) {
    *why = sun ? "strength (W/m2) must not be negative" : "power (W) must not be negative";
  } else if (!UnitColor(color)) {
    *why = "color components lie in 0..1";
  } else if (!Finite(position) || position.cwiseAbs().maxCoeff() > 1e6) {
    *why = "the position must lie within 1 km of the origin";
  } else if (!Finite(direction) || direction.norm() == 0) {
    *why = "the direction must not be zero";
  } else if (!(radius_mm >= 0) || !std::isfinite(radius_mm) ||
             (kind == Kind::kDisc && !(radius_mm > 0))) {
    *why = kind == Kind::kDisc ? "a disc light needs a positive radius"
                               : "the radius must not be negative";
  } else if (kind == Kind::kRect && (!(size_x_mm > 0) || !(size_y_mm > 0) ||
                                     !std::isfinite(size_x_mm) || !std::isfinite(size_y_mm))) {
    *why = "a rect light needs a positive size";
  } else if (!Finite(x_axis)) {
    *why = "x_axis must be finite";
  } else if (!(spot_size_rad > 0) || spot_size_rad > M_PI) {
    *why = "spot_size must lie in (0, 180] degrees";
  } else if (!(spot_blend >= 0 && spot_blend <= 1)) {
    *why = "spot_blend must lie in [0, 1]";
  } else if (!(angle_rad >= 0) || angle_rad >= M_PI) {
    *why = "the sun's angle must lie in [0, 180) degrees";
  } else {
    return true;
  }
  return false;
}

bool Environment::Check(std::string* why) const {
  if (!(strength >= 0) || !std::isfinite(strength)) {
    *why = "strength must not be negative";
  } else if (!UnitColor(color) || !UnitColor(zenith) || !UnitColor(horizon) || !UnitColor(ground)) {
    *why = "colour components lie in 0..1";
  } else if (kind == Kind::kImage && image.empty()) {
    *why = "an image environment needs a file";
  } else if (!std::isfinite(rotation_rad)) {
    *why = "rotation must be finite";
  } else {
    return true;
  }
  return false;
}

}  // namespace cadsynth
