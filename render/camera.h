// Pinhole cameras and the camera sweep around the scene.
//
// Camera frame: OpenCV/BOP convention, x right, y down, z forward. A point moves between frames as
// x_in_world = world_from_cam * x_in_cam. Pixel (u, v) covers [u, u+1) x [v, v+1); its centre is
// (u + 0.5, v + 0.5), so the ray of a pinhole camera's pixel (u, v) passes through
//   ((u + 0.5 - cx) / fx, (v + 0.5 - cy) / fy, 1) in the camera frame,
// and that of a camera with lens distortion through the point Intrinsics::Unproject gives.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "cad/core/schema.h"

namespace cadsynth {

// OpenCV's lens distortion (calib3d's model, coefficients in OpenCV's order k1, k2, p1, p2, k3):
// the ray through (x, y, 1) in the camera frame shows at pixel (fx x' + cx, fy y' + cy) with
//   x' = x (1 + k1 r^2 + k2 r^4 + k3 r^6) + 2 p1 x y + p2 (r^2 + 2 x^2),
//   y' = y (1 + k1 r^2 + k2 r^4 + k3 r^6) + p1 (r^2 + 2 y^2) + 2 p2 x y,   r^2 = x^2 + y^2.
// The polynomial describes a lens only where it is one-to-one: inside the fold radius, where the
// radial map r (1 + k1 r^2 + k2 r^4 + k3 r^6) stops growing (barrel distortion folds back outside
// the calibrated field). Rays beyond it are not imaged. (Strong tangential terms can fold the map
// before that radius; Undistort also refuses a Jacobian of non-positive determinant, but the
// bounds of PixelRays::RectOfPlane assume the fold is the radial one.)
struct Distortion {
  double k1 = 0.0, k2 = 0.0, p1 = 0.0, p2 = 0.0, k3 = 0.0;

  bool active() const { return k1 != 0.0 || k2 != 0.0 || p1 != 0.0 || p2 != 0.0 || k3 != 0.0; }
  // (x', y') of (x, y), and its Jacobian if `jacobian` is not null.
  Eigen::Vector2d Distort(const Eigen::Vector2d& xy, Eigen::Matrix2d* jacobian = nullptr) const;
  // The first radius where d/dr [r (1 + k1 r^2 + k2 r^4 + k3 r^6)] = 0; infinity if there is none.
  double FoldRadius() const;
  // The (x, y) inside the fold radius, with a Jacobian of positive determinant, that distorts to
  // `xd` (to 1e-12), by damped Newton steps from `guess`; false if there is none.
  bool Undistort(const Eigen::Vector2d& xd, const Eigen::Vector2d& guess,
                 Eigen::Vector2d* xy) const;
  // r^2 lies inside the fold radius (without finding it: a few evaluations of the polynomial).
  bool InsideFold(double r2) const;

  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.k1, Field{"k1", "number", "radial, r^2"});
    visit(o.k2, Field{"k2", "number", "radial, r^4"});
    visit(o.p1, Field{"p1", "number", "tangential"});
    visit(o.p2, Field{"p2", "number", "tangential"});
    visit(o.k3, Field{"k3", "number", "radial, r^6"});
  }
};

// Intrinsics in pixels, and the lens distortion (none by default).
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

  Distortion distortion;

  Eigen::Matrix3d K() const;
  // The camera-frame ray (x, y, 1) through image point (u, v) (pixel centres at + 0.5); false
  // where the lens images no ray (beyond the fold radius). Exact for a pinhole camera; with
  // distortion, Distortion::Undistort from the pinhole guess.
  bool Unproject(double u, double v, Eigen::Vector2d* xy) const;
  // The image point of camera-frame point `p`, distorted, in `uv`; false when the camera does not
  // image it (behind the camera, or beyond the distortion's fold radius, where `uv` means
  // nothing).
  bool Project(const Eigen::Vector3d& p, Eigen::Vector2d* uv) const;
  // Also that every point of the image (its border's pixel corners) has a ray.
  bool Check(std::string* why) const;

  // The size and K; `distortion` describes its own (Distortion::Fields). The recipe's `preset`
  // (every field) and `hfov` (fx, fy, cx, cy from the width and height) are read by hand.
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.width, Field{"width", "integer", "image width (px)"});
    visit(o.height, Field{"height", "integer", "image height (px)"});
    visit(o.fx, Field{"fx", "number", "focal length along x (px)"});
    visit(o.fy, Field{"fy", "number", "focal length along y (px)"});
    visit(o.cx, Field{"cx", "number", "principal point x (px)"});
    visit(o.cy, Field{"cy", "number", "principal point y (px)"});
  }
};

// A thin lens: depth of field in the physically based colour image (labels and depth keep the
// pinhole's exact values). The aperture's diameter is focal_length / f_number, and the plane z =
// focus_distance is sharp; a point at depth z blurs into a disc of f_px * aperture * |1 / focus -
// 1 / z| pixels (f_px = fx). Blender's depth of field in the same terms (lens mm, f-stop, focus
// distance). The focal length sets only the aperture: the image's scale is K's.
struct ThinLens {
  double focal_length_mm = 0.0;  // 0: a pinhole, everything sharp
  double f_number = 2.8;
  double focus_distance_mm = 1000.0;

  bool active() const { return focal_length_mm > 0.0; }
  double aperture_mm() const { return focal_length_mm / f_number; }
  bool Check(std::string* why) const;

  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.focal_length_mm,
          Field{"focal_length", "length", "the lens's focal length (sets the aperture only)"});
    visit(o.f_number, Field{"f_number", "number", "aperture: focal_length / f_number (0.5-128)"});
    visit(o.focus_distance_mm,
          Field{"focus_distance", "length", "depth of the sharp plane, along the optical axis"});
  }
};

// The camera's motion while the shutter is open: motion blur in the physically based colour image
// (labels and depth keep the pose at mid-exposure, the frame's pose). A constant velocity (mm/s)
// and angular velocity (rad/s) in the camera's own frame over `exposure_s`, centred on the
// frame's pose: at time tau * exposure_s from mid-exposure the camera sits at world_from_cam *
// At(tau), tau in [-1/2, 1/2].
struct CameraMotion {
  Eigen::Vector3d velocity_mm_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d angular_velocity_rad_s = Eigen::Vector3d::Zero();
  double exposure_s = 0.0;

  bool active() const {
    return exposure_s > 0.0 &&
           (velocity_mm_s.squaredNorm() > 0.0 || angular_velocity_rad_s.squaredNorm() > 0.0);
  }
  bool Check(std::string* why) const;
  // cam_mid_from_cam at tau: SE(3)'s exponential of the twist times tau * exposure_s.
  Eigen::Isometry3d At(double tau) const;
  // The motion of a camera fixed to this one (a rig), at this_from_other: the same rigid motion
  // in the other camera's frame (the adjoint: w' = R^T w, v' = R^T (v + w x t)).
  CameraMotion Seen(const Eigen::Isometry3d& this_from_other) const;

  // The recipe's `exposure_ms` must be given with a motion (checked by hand).
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.velocity_mm_s, Field{"velocity_mm_s", "vector3", "mm/s along the camera's axes"});
    visit(o.angular_velocity_rad_s,
          Field{"angular_velocity_deg_s", "degrees3", "degrees/s about its axes"});
    visit(o.exposure_s, Field{"exposure_ms", "milliseconds", "how long the shutter is open"});
  }
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

  // Each axis is a series (a value, a list or {from, to, step}: the recipe's own syntax, read by
  // hand).
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(
        o.yaw_rad,
        Field{.key = "yaw", .kind = "series_angle", .doc = "about the vertical", .by_hand = true});
    visit(o.pitch_rad, Field{.key = "pitch",
                             .kind = "series_angle",
                             .doc = "elevation above the floor; 90: straight down",
                             .by_hand = true});
    visit(o.radius_mm, Field{.key = "radius",
                             .kind = "series_length",
                             .doc = "distance to the target",
                             .by_hand = true});
    visit(o.target, Field{"target", "length3", "the point the camera looks at"});
  }
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

  // The band and the radii come from the sweep's series (set by the reader, in the run key).
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.kind,
          Field{"sampler", "choice", "how views are placed", {"grid", "fibonacci", "random"}});
    visit(o.count, Field{"count", "integer", "fibonacci, random: how many views"});
    Field seed = RunSeed("seed", "random views and jitter");
    seed.by_hand = true;  // read by hand: a negative one wraps, as randomize.seed's
    visit(o.seed, seed);
    visit(o.roll_jitter_rad,
          Field{"roll_jitter", "angle", "each view rolls about its axis by up to this"});
    visit(o.target_jitter_mm,
          Field{"target_jitter", "length", "each view aims within this of the target"});
    visit(o.min_pitch_rad, Field{.internal_name = "min_pitch"});
    visit(o.max_pitch_rad, Field{.internal_name = "max_pitch"});
    visit(o.min_radius_mm, Field{.internal_name = "min_radius"});
    visit(o.max_radius_mm, Field{.internal_name = "max_radius"});
  }
};

// The views of `sampler` (grid and fibonacci radii come from `sweep`). Seeded draws are the same on
// every machine. View i's jitter depends only on (seed, i).
std::vector<SweepView> SampleViews(const ViewSampler& sampler, const SweepOptions& sweep);

}  // namespace cadsynth
