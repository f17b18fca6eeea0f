// Pinhole cameras and the camera sweep around the scene.
//
// Camera frame: OpenCV/BOP convention, x right, y down, z forward. A point moves between frames as
// x_in_world = world_from_cam * x_in_cam. Pixel (u, v) covers [u, u+1) x [v, v+1); its centre is
// (u + 0.5, v + 0.5), so the ray of pixel (u, v) passes through
//   ((u + 0.5 - cx) / fx, (v + 0.5 - cy) / fy, 1) in the camera frame.
#pragma once

#include <cstdint>
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
  // Intel RealSense D435 colour camera, nominal (datasheet field of view 69 x 42 degrees): 1280x720
  // with fx = fy = 923, or 640x480 with fx = fy = 615; principal point at the centre. Real units
  // differ by a few percent: give the calibrated K for training on a real camera.
  static Intrinsics RealSenseD435(int width);
  // Square pixels, principal point at the centre, horizontal field of view `hfov_rad`.
  static Intrinsics FromFov(int width, int height, double hfov_rad);

  Eigen::Matrix3d K() const;
  bool Check(std::string* why) const;
};

// Named cameras (the recipe's camera.preset). Nominal: square pixels and a centred principal point
// from the maker's field of view unless said otherwise; a real unit differs by a few percent, so
// give the calibrated K when training for a real camera.
struct CameraPreset {
  const char* name;
  const char* what;  // the sensor, and where its numbers come from
  Intrinsics intrinsics;
  bool gray = false;  // an industrial grey camera (the recipe's camera.image defaults to gray)
};
const std::vector<CameraPreset>& CameraPresets();
// The preset called `name`, or null.
const CameraPreset* FindCameraPreset(const std::string& name);

struct Camera {
  Intrinsics intrinsics;
  Eigen::Isometry3d world_from_cam = Eigen::Isometry3d::Identity();
};

// Cameras and targets farther than this from the origin (1 km) are refused: Embree traces in
// single precision, and at 1e19 mm it aborts the process.
inline constexpr double kMaxSceneExtentMm = 1e6;

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

// Other ways to place cameras around the target, all looking at it.
struct ViewSampler {
  enum class Kind {
    kGrid,       // SweepOptions' yaw x pitch x radius grid (the reference paper)
    kFibonacci,  // `count` directions spread evenly over the band of pitches (a Fibonacci
                 // lattice, equal area per view), at each radius of the sweep
    kRandom,     // `count` views uniform on the band of pitches, radius uniform in its range
  };
  Kind kind = Kind::kGrid;
  int count = 100;
  double min_pitch_rad = 0.0, max_pitch_rad = 1.5707963267948966;  // the band (fibonacci, random)
  double min_radius_mm = 650.0, max_radius_mm = 1450.0;            // random
  // Jitter, for every sampler: the camera rolls about its optical axis by up to +-roll_jitter and
  // aims at a point up to target_jitter_mm from the target (uniform in a ball).
  double roll_jitter_rad = 0.0;
  double target_jitter_mm = 0.0;
  uint64_t seed = 0;

  bool Check(std::string* why) const;
};

// The views of `sampler` (grid and fibonacci radii come from `sweep`). Seeded draws are the same on
// every machine. View i's jitter depends only on (seed, i).
std::vector<SweepView> SampleViews(const ViewSampler& sampler, const SweepOptions& sweep);

}  // namespace cadsynth
