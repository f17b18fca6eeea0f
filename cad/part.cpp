#include "cad/part.h"

#include <cmath>

namespace cadsynth {

Symmetries Symmetries::InFrame(const Eigen::Isometry3d& old_from_new) const {
  Symmetries out;
  const Eigen::Isometry3d new_from_old = old_from_new.inverse();
  for (const Eigen::Isometry3d& s : discrete)
    out.discrete.push_back(new_from_old * s * old_from_new);
  for (const Axis& a : continuous) {
    out.continuous.push_back(
        {(new_from_old.linear() * a.direction).normalized(), new_from_old * a.offset});
  }
  return out;
}

Symmetries Symmetries::Cyclic(int n, bool flips, double mid_z, double flip_angle) {
  Symmetries s;
  const Eigen::Isometry3d to_mid(Eigen::Translation3d(0, 0, mid_z));
  for (int k = 1; k < n; ++k) {
    s.discrete.push_back(
        Eigen::Isometry3d(Eigen::AngleAxisd(2 * M_PI * k / n, Eigen::Vector3d::UnitZ())));
  }
  if (flips) {
    // Half-turns about horizontal axes at angles pi k / n through (0, 0, mid_z).
    for (int k = 0; k < n; ++k) {
      const double a = flip_angle + M_PI * k / n;
      const Eigen::Vector3d axis(std::cos(a), std::sin(a), 0.0);
      s.discrete.push_back(to_mid * Eigen::AngleAxisd(M_PI, axis) * to_mid.inverse());
    }
  }
  return s;
}

Symmetries Symmetries::Revolution(bool flip, double mid_z) {
  Symmetries s;
  s.continuous.push_back({Eigen::Vector3d::UnitZ(), Eigen::Vector3d::Zero()});
  if (flip) {
    const Eigen::Isometry3d to_mid(Eigen::Translation3d(0, 0, mid_z));
    s.discrete.push_back(to_mid * Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()) *
                         to_mid.inverse());
  }
  return s;
}

}  // namespace cadsynth
