// Cameras shared by the render tests.
#pragma once

#include <Eigen/Geometry>

namespace cadsynth::testing {

// A camera at `eye` looking straight down (-z), image x along world +x, image y along world -y.
inline Eigen::Isometry3d LookingDown(const Eigen::Vector3d& eye) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  T.translation() = eye;
  return T;
}

}  // namespace cadsynth::testing
