// What a camera measures, as opposed to the exact images the renderer traces: grey or colour
// images, and depth as a real sensor returns it (noise, quantisation, holes).
//
// The depth models work on the exact depth and on what the renderer knows per pixel (the surface
// normal, whether the sensor's projector sees the point, how much of the projector's light the
// surface sends back to the camera, the colour image). Each is a published model:
//
//   ideal             the exact depth.
//   kinect_v1         Kinect v1 / PrimeSense (Nguyen, Izadi, Lovell 2012, "Modeling Kinect Sensor
//                     Noise for Improved 3D Reconstruction and Tracking"; Khoshelham and Elberink
//                     2012 for the disparity): each pixel reads the depth of a pixel shifted by
//                     lateral noise of sigma_L = lateral + 0.035 theta / (pi/2 - theta) px (theta:
//                     the angle between the surface normal and the camera ray); axial noise
//                     sigma_z = 1.2 mm + 1.9 mm (z - 0.4 m)^2 / m^2 (plus, beyond 60 degrees of
//                     incidence, 0.1 mm theta^2 / (pi/2 - theta)^2 / sqrt(z / m)) in total, of
//                     which the disparity quantisation supplies q^2 / 12 (q: the depth step below);
//                     then the disparity d = f B / z is rounded to `disparity_step` px (1/8) and z
//                     = f B / d, with f = `focal` (580 px) and B = `baseline` (75 mm). Holes where
//                     the projector is shadowed (a ray from the point to the projector at
//                     (baseline, 0, 0) in the camera frame hits something), on grazing surfaces
//                     (theta > `max_incidence`), at depth jumps (the 3 x 3 neighbourhood spans more
//                     than `jump`) and where the surface returns too little of the pattern
//                     (`min_signal`).
//   azure_kinect      time of flight, BlenderProc's add_kinect_azure_noise (after Tölgyessy et
//                     al. 2021): the depth resampled (bilinearly) at positions shifted by
//                     N(0, `lateral` = 0.25 px) in u and v, plus N(0, 0.5 mm + 1 mm per metre
//                     beyond 0.5 m); holes where the 3 x 3 neighbourhood of the noisy depth spans
//                     more than `jump` (800 mm) and where the colour image's grey value (OpenCV's
//                     0.299 R + 0.587 G + 0.114 B) is below `dark_gray` (15).
//   structured_light  Photoneo, Zivid, the XYZ sensor of XYZ-IBD: the exact depth where both the
//                     camera and the projector at (baseline, 0, 0) see the point, plus N(0,
//                     noise (z / 1 m)^2 / sqrt(min(signal, 1))) (triangulation error grows with the
//                     square of the range, and as the return weakens); holes where the projector is
//                     shadowed, on grazing surfaces, and where the surface sends back too little of
//                     the pattern (dark, or a polished metal reflecting it away: `min_signal`) or
//                     so much that the camera saturates (a specular glint: `max_signal`).
//   active_stereo     RealSense D4xx style: two IR cameras `baseline` apart (the left one is the
//                     camera, the right one at (baseline, 0, 0)) and a dot projector between them
//                     at (baseline / 2, 0, 0). The renderer traces both IR images: each pixel sees
//                     `dot_power` signal dots (1 m / distance)^2 of the projector's random-dot
//                     pattern where the projector lights the point, plus `ambient` times the
//                     Lambert shading of the scene's lights, plus N(0, `ir_noise`) read noise,
//                     rounded to 8 bits. OpenCV's StereoSGBM (3 paths, MODE_SGBM_3WAY; `block` x
//                     `block` windows, P1 = 8 block^2, P2 = 32 block^2, uniqueness 10 %, left-right
//                     check 1 px, speckle filter of 100 px within 2 px) matches them with
//                     disparities up to f B / `min_depth`, and z = f B / d (d in 1/16 px); like the
//                     texture threshold of RealSense's and OpenCV's block matchers, pixels whose
//                     `block` x `block` window in the left image has a grey standard deviation
//                     under `min_texture` are holes (SGBM alone would match the noise there).
//                     Edge fattening,
//                     holes where the pattern is occluded or too faint (dark, shiny, far), the
//                     invalid band at the left edge and the 1/16 px disparity steps all come from
//                     the matcher, as on the real sensor.
//
// Every model but ideal has holes outside its operating range [min_range, max_range] when given.
//
// The signal is the projector's light the surface reflects towards the camera, relative to a
// white Lambertian surface facing the projector: pi f(camera, projector) cos(theta_projector), with
// f the surface's BSDF (the material in render.mode: pbr, the Lambert colour in fast mode),
// luminance-weighted. Every draw is seeded by (seed, view, pixel): the same bytes on any thread
// count and shard.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "cad/core/schema.h"
#include "render/camera.h"

namespace cadsynth {

struct DepthModel {
  enum class Kind { kIdeal, kKinectV1, kAzureKinect, kStructuredLight, kActiveStereo };
  Kind kind = Kind::kIdeal;
  // The projector's position on the camera's x axis, mm (kinect_v1, structured_light; positive:
  // to the image's right, as a Kinect v1's emitter seen from its camera, so shadows fall left).
  double baseline_mm = 0.0;
  double focal_px = 580.0;         // kinect_v1: the IR camera's focal length in the disparity
  double disparity_step_px = 0.0;  // kinect_v1: disparity quantum (1/8 px)
  double noise_mm = 0.0;           // structured_light: sigma at 1 m, growing with z^2
  double lateral_px = 0.0;         // kinect_v1, azure_kinect: lateral sigma (px)
  double max_incidence_rad = 0.0;  // holes where the camera ray meets the surface more obliquely
  double jump_mm = 0.0;            // holes where a 3 x 3 neighbourhood spans more (0: none)
  double min_signal = 0.0;         // holes where the surface returns less of the projector
  double max_signal = 0.0;         // holes where it returns more (saturation; 0: none)
  int dark_gray = 0;               // azure_kinect: holes where the colour image is darker
  // active_stereo: the projected pattern, the IR images and the matcher.
  double dot_spacing_px = 0.0;  // pitch of the dot grid, in the camera's pixels
  double dot_power = 0.0;       // dots on a white Lambert surface facing the projector at 1 m
  double ambient = 0.0;         // IR image of a white surface under the scene's lights
  double ir_noise = 0.0;        // read noise sigma of the IR images (fraction of full scale)
  double min_depth_mm = 0.0;    // nearest depth matched: disparities up to f B / min_depth
  int block = 0;                // SGBM window (odd, 3-11)
  double min_texture = 0.0;     // holes where the left window's grey sd is lower (0-255)
  // The operating range: holes where the exact depth lies nearer or farther (0: no limit).
  double min_range_mm = 0.0;
  double max_range_mm = 0.0;
  uint64_t seed = 0;

  // The published defaults of `kind` (the table in docs/sensors.md).
  static DepthModel Defaults(Kind kind);
  bool Check(std::string* why) const;
  bool needs_projector() const { return kind == Kind::kKinectV1 || kind == Kind::kStructuredLight; }

  // Every field, once (cad/core/schema.h): the recipe's `camera.depth` section, the run key.
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.kind, Field{"model",
                        "choice",
                        "depth sensor model (its defaults fill the other keys)",
                        {"ideal", "kinect_v1", "azure_kinect", "structured_light", "active_stereo"},
                        true});
    visit(o.baseline_mm,
          Field{"baseline", "length",
                "projector's x in the camera frame (active_stereo: the right IR camera's)"});
    visit(o.focal_px, Field{"focal", "number", "kinect_v1: focal length of the disparity (px)"});
    visit(o.disparity_step_px,
          Field{"disparity_step", "number", "kinect_v1: disparity quantum (px; 0.125)"});
    visit(o.noise_mm, Field{"noise", "length", "structured_light: sigma at 1 m (grows with z^2)"});
    visit(o.lateral_px, Field{"lateral", "number", "lateral noise sigma (px)"});
    visit(o.max_incidence_rad,
          Field{"max_incidence", "angle", "holes on surfaces seen more obliquely (0-90 degrees)"});
    visit(o.jump_mm, Field{"jump", "length", "holes where 3 x 3 pixels span more depth (0: none)"});
    visit(o.min_signal,
          Field{"min_signal", "number", "holes where the projector's return is weaker (0-1)"});
    visit(o.max_signal,
          Field{"max_signal", "number", "holes where it is stronger: specular glints (0: none)"});
    visit(o.dark_gray,
          Field{"dark_gray", "integer", "azure_kinect: holes where the colour is darker (0-255)"});
    visit(o.dot_spacing_px,
          Field{"dot_spacing", "number", "active_stereo: pitch of the projected dots (px)"});
    visit(o.dot_power,
          Field{"dot_power", "number", "active_stereo: dot brightness on white at 1 m (0-100)"});
    visit(o.ambient,
          Field{"ambient", "number", "active_stereo: IR image of the scene's own light (0-10)"});
    visit(o.ir_noise,
          Field{"ir_noise", "number", "active_stereo: IR read noise sigma (0-1 of full scale)"});
    visit(o.min_depth_mm,
          Field{"min_depth", "length", "active_stereo: nearest depth the matcher searches"});
    visit(o.block, Field{"block", "integer", "active_stereo: SGBM window (odd, 3-11)"});
    visit(o.min_texture, Field{"min_texture", "number",
                               "active_stereo: holes where the window's grey sd is lower (0-255)"});
    visit(o.min_range_mm,
          Field{"min_range", "length", "holes nearer than this (the operating range; 0: none)"});
    visit(o.max_range_mm, Field{"max_range", "length", "holes farther than this (0: none)"});
    visit(o.seed, RunSeed("seed", "seed of the noise"));
  }
  // Whether exact depth z (mm, > 0) lies in the operating range.
  bool InRange(double z) const {
    return z >= min_range_mm && (max_range_mm <= 0.0 || z <= max_range_mm);
  }
};

// The image sensor and lens of a colour or grey camera: photon shot noise and read noise (the
// Poisson-Gaussian model of Foi et al. 2008, in its Gaussian form: a pixel of linear value x, 1 =
// full scale, reads x + N(0, x / full_well + (read_noise / full_well)^2)), and natural
// vignetting: the image falls off by (1 - vignetting) + vignetting cos^4(theta), theta the angle
// between the pixel's ray and the optical axis. Applied to the linear value before the display
// transform (pbr: the exposed radiance; fast: the Lambert colour), per channel, and separately to
// the grey image; labels and depth are untouched.
struct ImageSensor {
  double full_well = 0.0;   // electrons at full scale (0: no shot noise)
  double read_noise = 0.0;  // electrons (sigma)
  double vignetting = 0.0;  // 0: none, 1: the full cos^4 fall-off
  uint64_t seed = 0;

  bool Check(std::string* why) const;
  bool active() const { return full_well > 0.0 || vignetting > 0.0; }
  // The pixel's vignetting factor for a ray through (x, y, 1) in the camera frame.
  double Vignette(double x, double y) const {
    const double cos2 = 1.0 / (1.0 + x * x + y * y);
    return (1.0 - vignetting) + vignetting * cos2 * cos2;
  }
  // Linear value `x` as the sensor reads it: vignetted by `vignette`, plus noise of standard
  // normal draw `normal`.
  double Read(double x, double vignette, double normal) const {
    x *= vignette;
    if (full_well > 0.0) {
      const double r = read_noise / full_well;
      x += std::sqrt(std::max(x, 0.0) / full_well + r * r) * normal;
    }
    return x;
  }

  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.full_well,
          Field{"full_well", "number", "electrons at full scale: shot noise (0: no noise)"});
    visit(o.read_noise, Field{"read_noise", "number", "read noise sigma (electrons)"});
    visit(o.vignetting,
          Field{"vignetting", "number", "share of the cos^4 fall-off towards the corners (0-1)"});
    visit(o.seed, RunSeed("seed", "seed of the image noise"));
  }
};

// The image sensor's noise in frame `view` (streams sensor.image_frame, sensor.image): the frame's
// seed, then per pixel of a colour camera two Box-Muller pairs of standard normal draws, {R, G}
// (pair 0) and {B, unused} (pair 1). Grey cameras draw from GreyImageNoise instead.
uint64_t ImageNoiseSeed(const ImageSensor& sensor, uint64_t view);
Eigen::Vector2d ImageNoisePair(uint64_t frame_seed, uint64_t pixel, int pair);
// A grey camera's noise (stream sensor.image_grey): one standard normal number per pixel, the
// Box-Muller pair k giving pixels 2k and 2k + 1 (half the draws of a pair per pixel).
std::vector<float> GreyImageNoise(uint64_t frame_seed, size_t pixels);

// What one camera measures: its image (colour, or grey as industrial and IR cameras give), the
// image sensor's noise and vignetting, and its depth model.
struct SensorOptions {
  enum class Image { kRgb, kGray, kGray16 };
  Image image = Image::kRgb;
  ImageSensor imager;
  DepthModel depth;
  ThinLens lens;        // depth of field (pbr colour only)
  CameraMotion motion;  // motion blur (pbr colour only)
  bool Check(std::string* why) const {
    return imager.Check(why) && depth.Check(why) && lens.Check(why) && motion.Check(why);
  }

  // The image; the imager, depth, lens and motion describe their own fields.
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.image,
          Field{"image", "choice", "a colour or a grey camera", {"rgb", "gray", "gray16"}});
  }
};

class PixelRays;  // render/pixel_rays.h

// Per pixel, what the renderer knows for a depth model (row-major, width x height).
struct DepthSensorInput {
  Intrinsics intrinsics;
  // The camera's pixel rays as the renderer traced them (a distorting lens's table); null: from
  // the intrinsics, per pixel.
  const PixelRays* rays = nullptr;
  const float* depth = nullptr;              // exact camera z, mm; 0 = nothing
  const Eigen::Vector3f* normals = nullptr;  // camera frame, facing the camera; null: facing it
  const uint8_t* projector_seen = nullptr;   // 1 where the projector sees the point; null: all
  const float* signal = nullptr;             // the projector's return (see above); null: 1
  const uint8_t* rgb = nullptr;              // the colour image (azure_kinect's dark pixels)
  const uint8_t* ir_left = nullptr;          // active_stereo: the IR images (8 bit)
  const uint8_t* ir_right = nullptr;
};

// The depth `model` returns for `input` in frame `view` (mm, 0 = no return). kIdeal copies it.
std::vector<float> SimulateDepth(const DepthModel& model, const DepthSensorInput& input,
                                 uint64_t view);

// active_stereo: the projector's dot pattern at direction (x, y, 1) of the projector's frame (axes
// parallel to the camera's): 0 between dots, up to 1 at a dot's centre. A jittered grid of pitch
// dot_spacing / fx radians; each cell holds a dot with probability 1/2 at a random place, a
// Gaussian of sigma = 0.35 pitch cut at 3 sigma. Fixed per sensor (seeded by `seed` only), like a
// real DOE.
float DotPattern(const DepthModel& model, double fx, double x, double y);
// active_stereo: DotPattern with the dots of the cells over a window of the projector's
// directions, [x0, x1] x [y0, y1], drawn once (a frame looks at each dot from many pixels);
// outside it, drawn as DotPattern draws them. Close to DotPattern's values: a dot's place within
// its cell, and the dot's shape inside the table, are worked out in single precision.
class DotTable {
 public:
  DotTable(const DepthModel& model, double fx, double x0, double x1, double y0, double y1);
  float operator()(double x, double y) const;
  // The values at the n <= 16 points (x[i], y[i]), each as operator() gives it: the dots of the
  // nine cells around the points summed for all of them at once (SIMD over the points).
  void operator()(int n, const double* x, const double* y, float* out) const;
  // Whether this is the table DotTable(model, fx, x0, x1, y0, y1) would build (the same dots over
  // the same window): a renderer keeps one for its frames.
  bool Is(const DepthModel& model, double fx, double x0, double x1, double y0, double y1) const;

 private:
  // A cell without a dot: a centre this far away is beyond every cut.
  static constexpr float kNone = 1e4f;
  DepthModel model_;
  double fx_, inv_pitch_;
  double x0_, x1_, y0_, y1_;
  float peak_, exponent_, cut2_;
  int i0_ = 0, j0_ = 0, ni_ = 0, nj_ = 0;
  std::vector<Eigen::Vector2f> centres_;  // per cell: the dot's place in it, or kNone
};
// active_stereo: the sensor's auto exposure, one gain for both IR images: the one that brings the
// 99th percentile of `linear` (the left image) to 0.8 of full scale, within [1/4, 64].
double InfraredGain(const std::vector<float>& linear);
// active_stereo: the left and right IR images of frame `view` from their noiseless linear values:
// times `gain`, plus read noise N(0, ir_noise) (one Box-Muller pair per pixel: left, right, in
// single precision: NormalPairsFloat), rounded to 8 bits.
std::array<std::vector<uint8_t>, 2> InfraredImages(const DepthModel& model, uint64_t view,
                                                   const std::vector<float>& left,
                                                   const std::vector<float>& right, double gain);
// active_stereo: the number of disparities the matcher searches (a multiple of 16).
int StereoDisparities(const DepthModel& model, const Intrinsics& intrinsics);

// Kinect v1's axial noise sigma (mm) at depth z (mm) on a surface seen at incidence theta (rad,
// between its normal and the camera ray): 1.2 + 1.9 (z / 1 m - 0.4)^2, and beyond 60 degrees
// Nguyen et al.'s angle term 0.1 / sqrt(z / 1 m) theta^2 / (pi / 2 - theta)^2.
double KinectV1AxialSigma(double z_mm, double theta_rad = 0.0);
// structured_light's sigma (mm) at depth z with return `signal`: noise (z / 1 m)^2, growing as
// 1 / sqrt(signal) where the surface sends back less than a white one facing the projector
// (fewer photons per decoded code: dark, oblique and shiny surfaces are noisier).
double StructuredLightSigma(double noise_mm, double z_mm, double signal);
// BlenderProc's Azure Kinect noise sigma (mm): 0.5 + max(z - 500, 0) / 1000.
double AzureKinectSigma(double z_mm);

}  // namespace cadsynth
