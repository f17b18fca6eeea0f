// Pinhole cameras and the camera sweep around the scene.
//
// Camera frame: OpenCV/BOP convention, x right, y down, z forward. A point moves between frames as
// x_in_world = world_from_cam * x_in_cam. Pixel (u, v) covers [u, u+1) x [v, v+1); its centre is
// (u + 0.5, v + 0.5), so the ray of pixel (u, v) passes through
//   ((u + 0.5 - cx) / fx, (v + 0.5 - cy) / fy, 1) in the camera frame.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace cadsynth {

// Intrinsics in pixels. No distortion.
struct Intrinsics {
  int width = 640;
  int height = 480;
  double fx = 525.0;
  double fy = 525.0;
  double cx = 319.5;
  double cy = 239.5;

  // The Kinect v1 of the reference paper: 640x480, fx = fy = 525, cx = 319.5, cy = 239.5.
  static Intrinsics KinectV1() { return Intrinsics{}; }

  Eigen::Matrix3d K() const;
  bool Check(std::string* why) const;
};

struct Camera {
  Intrinsics intrinsics;
  Eigen::Isometry3d world_from_cam = Eigen::Isometry3d::Identity();
};

// The reference paper's hemisphere sweep: the camera sits on a sphere around `target`
// at every combination of yaw (about world +z, 0 = on the +x axis), pitch (elevation above the
// floor plane, 90 degrees = straight down) and radius, and looks at `target`. Image x points
// along (-sin yaw, cos yaw, 0), so the image never rolls, not even straight overhead.
struct SweepOptions {
  std::vector<double> yaw_rad;
  std::vector<double> pitch_rad;
  std::vector<double> radius_mm;
  Eigen::Vector3d target = Eigen::Vector3d::Zero();  // world point the camera looks at (mm)

  bool Check(std::string* why) const;
  size_t NumViews() const { return yaw_rad.size() * pitch_rad.size() * radius_mm.size(); }
};

// One pose of the sweep. Views are ordered radius-major, then pitch, then yaw (yaw varies fastest).
struct SweepView {
  double yaw_rad = 0.0;
  double pitch_rad = 0.0;
  double radius_mm = 0.0;
  Eigen::Isometry3d world_from_cam = Eigen::Isometry3d::Identity();
};

// world_from_cam of a camera on the sphere, looking at `target` (see SweepOptions).
Eigen::Isometry3d WorldFromCamOnSphere(const Eigen::Vector3d& target, double yaw_rad,
                                       double pitch_rad, double radius_mm);

std::vector<SweepView> ExpandSweep(const SweepOptions& options);

}  // namespace cadsynth
