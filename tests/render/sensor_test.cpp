// Depth sensor models and grey cameras against their formulas (render/sensor.h).
#include "render/sensor.h"

#include <tbb/global_control.h>

#include <cmath>
#include <set>

#include <gtest/gtest.h>

#include "tests/render/render_support.h"

#include "cad/shape.h"
#include "render/path_tracer.h"
#include "render/renderer.h"

namespace cadsynth {
namespace {

using testing::LookingDown;

struct Stats {
  double mean = 0, sd = 0;
  int valid = 0;
};
Stats Measure(const std::vector<float>& depth) {
  Stats s;
  double sum = 0, sum2 = 0;
  for (float z : depth) {
    if (z <= 0) continue;
    sum += z, sum2 += double(z) * z, ++s.valid;
  }
  s.mean = sum / s.valid;
  s.sd = std::sqrt(std::max(0.0, sum2 / s.valid - s.mean * s.mean));
  return s;
}

// A fronto-parallel plane at z (mm) filling a 640 x 480 image, facing the camera.
struct Plane {
  Intrinsics k;
  std::vector<float> depth;
  std::vector<Eigen::Vector3f> normals;
  explicit Plane(float z)
      : depth(size_t(640) * 480, z), normals(depth.size(), Eigen::Vector3f(0, 0, -1)) {}
  DepthSensorInput Input() const {
    DepthSensorInput in;
    in.intrinsics = k;
    in.depth = depth.data();
    in.normals = normals.data();
    return in;
  }
};

TEST(DepthSensor, KinectV1OnAPlaneIsUnbiasedWithTheNguyenSigma) {
  // sigma(z) = 1.2 mm + 1.9 mm (z - 0.4 m)^2 / m^2 (Nguyen et al. 2012): 1.219, 2.884, 5.964 and
  // 14.044 mm at 0.5, 1, 2 and 3 m. 307,200 pixels: the mean's standard error is under 0.03 mm.
  const DepthModel model = DepthModel::Defaults(DepthModel::Kind::kKinectV1);
  for (const double z : {500.0, 1000.0, 2000.0, 3000.0}) {
    const Plane plane(static_cast<float>(z));
    const Stats s = Measure(SimulateDepth(model, plane.Input(), 7));
    const double sigma = 1.2 + 1.9 * (z / 1000 - 0.4) * (z / 1000 - 0.4);
    EXPECT_DOUBLE_EQ(KinectV1AxialSigma(z), sigma);
    EXPECT_EQ(s.valid, 640 * 480) << z;  // a plane facing the camera: no holes
    EXPECT_NEAR(s.mean, z, 1.0) << z;
    EXPECT_NEAR(s.sd, sigma, 0.15 * sigma) << z;
  }
}

TEST(DepthSensor, KinectV1DepthsTakeOnlyQuantisedDisparityLevels) {
  // d = f B / z with f = 580 px, B = 75 mm, rounded to 1/8 px: every value is f B / (n / 8) for
  // an integer n (at 2 m, d = 21.75 px and one level is 11.5 mm of depth).
  const DepthModel model = DepthModel::Defaults(DepthModel::Kind::kKinectV1);
  const Plane plane(2000.0f);
  const std::vector<float> depth = SimulateDepth(model, plane.Input(), 1);
  std::set<int> levels;
  for (float z : depth) {
    ASSERT_GT(z, 0.0f);
    const double eighths = 580.0 * 75.0 / z * 8.0;
    ASSERT_NEAR(eighths, std::round(eighths), 2e-3) << z;
    levels.insert(static_cast<int>(std::lround(eighths)));
  }
  // sigma 5.96 mm at 2 m is 0.35 px of disparity (f B / z^2 * sigma): a handful of levels.
  EXPECT_GE(levels.size(), 5u);
  EXPECT_LE(levels.size(), 30u);
}

TEST(DepthSensor, AzureKinectFollowsBlenderProcsSigma) {
  const DepthModel model = DepthModel::Defaults(DepthModel::Kind::kAzureKinect);
  for (const double z : {400.0, 1000.0, 3000.0}) {
    const Plane plane(static_cast<float>(z));
    const Stats s = Measure(SimulateDepth(model, plane.Input(), 3));
    const double sigma = 0.5 + std::max(z - 500.0, 0.0) / 1000.0;  // 0.5, 1.0, 3.0 mm
    EXPECT_DOUBLE_EQ(AzureKinectSigma(z), sigma);
    EXPECT_EQ(s.valid, 640 * 480);
    EXPECT_NEAR(s.mean, z, 0.05);
    EXPECT_NEAR(s.sd, sigma, 0.05 * sigma) << z;
  }
}

TEST(DepthSensor, AzureKinectLosesDarkPixelsAndBigJumps) {
  // Left half black (grey 0 < 15), right half mid grey; a step of 1 m (over BlenderProc's 0.8 m)
  // at row 200.
  Plane plane(1000.0f);
  std::vector<uint8_t> rgb(3 * plane.depth.size(), 128);
  for (int v = 0; v < 480; ++v) {
    for (int u = 0; u < 640; ++u) {
      if (u < 320) std::fill_n(&rgb[3 * (size_t(v) * 640 + u)], 3, 0);
      if (v >= 200) plane.depth[size_t(v) * 640 + u] = 2000.0f;
    }
  }
  DepthSensorInput in = plane.Input();
  in.rgb = rgb.data();
  const std::vector<float> depth =
      SimulateDepth(DepthModel::Defaults(DepthModel::Kind::kAzureKinect), in, 0);
  EXPECT_EQ(depth[100 * 640 + 100], 0.0f);  // dark
  EXPECT_GT(depth[100 * 640 + 500], 0.0f);
  EXPECT_EQ(depth[199 * 640 + 500], 0.0f);  // at the jump
  EXPECT_EQ(depth[200 * 640 + 500], 0.0f);
  EXPECT_GT(depth[196 * 640 + 500], 0.0f);
  EXPECT_GT(depth[203 * 640 + 500], 0.0f);
}

TEST(DepthSensor, StructuredLightNoiseGrowsWithTheSquareOfTheRange) {
  DepthModel model = DepthModel::Defaults(DepthModel::Kind::kStructuredLight);
  model.noise_mm = 0.2;
  for (const double z : {500.0, 1000.0, 2000.0}) {
    const Stats s = Measure(SimulateDepth(model, Plane(static_cast<float>(z)).Input(), 2));
    const double sigma = 0.2 * (z / 1000) * (z / 1000);  // 0.05, 0.2, 0.8 mm
    EXPECT_EQ(s.valid, 640 * 480);
    EXPECT_NEAR(s.mean, z, 0.01);
    EXPECT_NEAR(s.sd, sigma, 0.05 * sigma) << z;
  }
}

TEST(DepthSensor, SignalAndIncidenceMakeHoles) {
  DepthModel model = DepthModel::Defaults(DepthModel::Kind::kStructuredLight);
  Plane plane(1000.0f);
  std::vector<float> signal(plane.depth.size(), 0.5f);
  signal[10] = 0.01f;  // dark (min_signal 0.03)
  signal[11] = 10.0f;  // a glint (max_signal 4)
  // 85 degrees from the camera ray (max_incidence 80) at pixel (319, 239), whose ray is the
  // optical axis within 0.1 degrees: the normal turned about y.
  const size_t grazing = 239 * 640 + 319;
  plane.normals[grazing] =
      Eigen::Vector3f(std::sin(85 * M_PI / 180), 0, -std::cos(85 * M_PI / 180));
  std::vector<uint8_t> seen(plane.depth.size(), 1);
  seen[13] = 0;  // the projector's shadow
  DepthSensorInput in = plane.Input();
  in.signal = signal.data();
  in.projector_seen = seen.data();
  const std::vector<float> depth = SimulateDepth(model, in, 0);
  for (size_t p : {size_t{10}, size_t{11}, grazing, size_t{13}}) EXPECT_EQ(depth[p], 0.0f) << p;
  EXPECT_GT(depth[9], 0.0f);
  EXPECT_GT(depth[12], 0.0f);
  EXPECT_GT(depth[14], 0.0f);
  EXPECT_GT(depth[grazing + 1], 0.0f);
}

TEST(DepthSensor, DrawsDependOnTheViewAndSeedOnly) {
  const DepthModel model = DepthModel::Defaults(DepthModel::Kind::kKinectV1);
  const Plane plane(1500.0f);
  const std::vector<float> a = SimulateDepth(model, plane.Input(), 4);
  std::vector<float> b;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    b = SimulateDepth(model, plane.Input(), 4);
  }
  EXPECT_EQ(a, b);
  EXPECT_NE(a, SimulateDepth(model, plane.Input(), 5));
  DepthModel other = model;
  other.seed = 1;
  EXPECT_NE(a, SimulateDepth(other, plane.Input(), 4));
}

TEST(DepthSensor, ChecksItsParameters) {
  std::string why;
  DepthModel m = DepthModel::Defaults(DepthModel::Kind::kKinectV1);
  EXPECT_TRUE(m.Check(&why)) << why;
  m.baseline_mm = 0;
  EXPECT_FALSE(m.Check(&why));
  EXPECT_NE(why.find("baseline"), std::string::npos);
  m = DepthModel::Defaults(DepthModel::Kind::kStructuredLight);
  m.max_signal = m.min_signal;
  EXPECT_FALSE(m.Check(&why));
  m = DepthModel::Defaults(DepthModel::Kind::kAzureKinect);
  m.max_incidence_rad = 2.0;
  EXPECT_FALSE(m.Check(&why));
  m.max_incidence_rad = 0;
  m.dark_gray = 300;
  EXPECT_FALSE(m.Check(&why));
  m = DepthModel::Defaults(DepthModel::Kind::kAzureKinect);
  m.min_range_mm = 500, m.max_range_mm = 400;
  EXPECT_FALSE(m.Check(&why));
  EXPECT_EQ(why, "max_range must be 0 (none) or larger than min_range");
  m.max_range_mm = -1;
  EXPECT_FALSE(m.Check(&why));
  EXPECT_EQ(why, "min_range and max_range must be lengths between 0 and 1 km");
}

TEST(DepthSensor, NoDepthOutsideTheOperatingRange) {
  // A plane at 1 m: every pixel returns inside [500, 1500] mm, none with the range below or
  // beyond it, for every model with a range.
  const Plane plane(1000.0f);
  for (const auto kind : {DepthModel::Kind::kKinectV1, DepthModel::Kind::kAzureKinect,
                          DepthModel::Kind::kStructuredLight}) {
    DepthModel m = DepthModel::Defaults(kind);
    const auto returns = [&] {
      int n = 0;
      for (float z : SimulateDepth(m, plane.Input(), 0)) n += z > 0.0f;
      return n;
    };
    m.min_range_mm = 500, m.max_range_mm = 1500;
    EXPECT_EQ(returns(), 640 * 480);
    m.max_range_mm = 900;
    EXPECT_EQ(returns(), 0);
    m.min_range_mm = 1100, m.max_range_mm = 0;
    EXPECT_EQ(returns(), 0);
  }
}

// A 100 x 100 x 400 mm box standing on the floor under a camera 1200 mm up: its top at depth
// z1 = 800 mm, the floor at z2 = 1200 mm.
struct BoxOnFloor {
  std::vector<Part> parts = {MakePart("box", MakeBox(100, 100, 400), TessellationOptions{})};
  Scene scene;
  Camera camera;
  BoxOnFloor() {
    scene.instances = {Instance{0, "box", Eigen::Isometry3d(Eigen::Translation3d(0, 0, 200))}};
    camera.world_from_cam = LookingDown({0, 0, 1200});  // f = 525, c = (319.5, 239.5)
  }
};

TEST(DepthSensor, ProjectorShadowHasTheWidthTheGeometryGives) {
  // The projector at (B, 0, 0) of the camera, B = 75 mm, sees past the box's top-left edge down to
  // the floor at x = B - (50 + B) z2 / z1 = -112.5 mm; the camera sees the floor from x = -50
  // z2 / z1 = -75 mm outwards. The floor between is shadowed: 37.5 mm at depth 1200, f B (1/z1 -
  // 1/z2) = 525 * 75 * (1/800 - 1/1200) = 16.4 px, left of the box (shadows fall away from the
  // projector). On the right the projector sees everything the camera does.
  BoxOnFloor s;
  SensorOptions sensor;
  sensor.depth = DepthModel::Defaults(DepthModel::Kind::kStructuredLight);
  sensor.depth.baseline_mm = 75;
  sensor.depth.noise_mm = 0;
  sensor.depth.max_incidence_rad = 0;
  sensor.depth.min_signal = 0;
  sensor.depth.max_signal = 0;
  const Renderer renderer(s.parts, s.scene);
  const Frame frame = renderer.Render(s.camera, 0, sensor);
  ASSERT_EQ(frame.sensor_depth.size(), frame.depth.size());
  const int v = 240;
  int holes = 0, first = -1, last = -1;
  for (int u = 0; u < 640; ++u) {
    const size_t p = size_t(v) * 640 + u;
    ASSERT_GT(frame.depth[p], 0.0f);
    if (frame.sensor_depth[p] == 0.0f) {
      ++holes;
      if (first < 0) first = u;
      last = u;
    } else {
      EXPECT_FLOAT_EQ(frame.sensor_depth[p], frame.depth[p]);  // exact where seen, noise 0
    }
  }
  EXPECT_NEAR(holes, 525.0 * 75.0 * (1.0 / 800 - 1.0 / 1200), 1.0);
  EXPECT_EQ(last - first + 1, holes);  // one band
  // It ends where the camera's view of the floor ends, at x = -75 mm: u = 319.5 - 525 * 75 / 1200.
  EXPECT_NEAR(last + 1, 319.5 - 525.0 * 75 / 1200, 1.0);
  // A projector on the other side throws the shadow right of the box.
  sensor.depth.baseline_mm = -75;
  const Frame mirrored = renderer.Render(s.camera, 0, sensor);
  int right = 0;
  for (int u = 320; u < 640; ++u) right += mirrored.sensor_depth[size_t(v) * 640 + u] == 0.0f;
  EXPECT_NEAR(right, 16.4, 1.0);
}

TEST(DepthSensor, DarkAndGlintingSurfacesLoseTheirDepthPerMaterial) {
  // The physically based mode's signal pi f cos: a white Lambert floor under a projector beside
  // the camera returns about cos(theta) ~ 1; a black box returns 0 (a hole); a polished mirror
  // sends the pattern away everywhere but at its specular point.
  BoxOnFloor s;
  s.scene.light_sources.clear();
  Material white, black, mirror;
  white.surface.base_color.setOnes();
  white.surface.metallic = 0, white.surface.specular = 0, white.surface.roughness = 1;
  black = white;
  black.surface.base_color.setZero();
  mirror.surface.base_color.setOnes();
  mirror.surface.metallic = 1, mirror.surface.roughness = 0.01f;
  s.scene.floor_material = white;
  s.scene.materials = {black};
  s.scene.instance_material = {0};
  RenderOptions pbr;
  pbr.mode = RenderOptions::Mode::kPbr;
  pbr.samples = 1;
  pbr.amodal_masks = false;
  SensorOptions sensor;
  sensor.depth = DepthModel::Defaults(DepthModel::Kind::kStructuredLight);
  sensor.depth.baseline_mm = 20;
  sensor.depth.noise_mm = 0;
  const Frame dark = Renderer(s.parts, s.scene, pbr).Render(s.camera, 0, sensor);
  const size_t centre = size_t(240) * 640 + 320, floor_px = size_t(240) * 640 + 600;
  EXPECT_EQ(dark.sensor_depth[centre], 0.0f);  // the black box top
  EXPECT_FLOAT_EQ(dark.sensor_depth[floor_px], dark.depth[floor_px]);
  // Every pixel of the box top returns when it is white.
  const auto top_returns = [&](const Frame& frame, int* top) {
    int returns = 0;
    *top = 0;
    for (size_t p = 0; p < frame.depth.size(); ++p) {
      if (frame.instance[p] != 1 || std::abs(frame.depth[p] - 800.0f) > 0.5f) continue;
      ++*top;
      returns += frame.sensor_depth[p] > 0.0f;
    }
    return returns;
  };
  int top = 0;
  s.scene.materials = {white};
  const Frame lambert = Renderer(s.parts, s.scene, pbr).Render(s.camera, 0, sensor);
  EXPECT_EQ(top_returns(lambert, &top), top);
  EXPECT_GT(top, 4000);  // 65.6 px square
  // The mirror (alpha = roughness^2 = 1e-4, F = G = 1) sends back pi f cos = pi D / (4 cos_o) ~
  // alpha^2 / (4 theta^4) at a half-vector tilt theta >> alpha. Camera and projector are 800 mm
  // above the top, so theta is the distance from the specular point over 800 mm, i.e. its pixels
  // over 525. The return is over max_signal (4, a glint) for theta^2 < alpha / (2 sqrt(4)) and
  // under min_signal (0.03) beyond theta^2 = alpha / (2 sqrt(0.03)): only the ring between
  // returns, pi (2.887 - 0.25) alpha rad^2 = 8.28e-4 * 525^2 = 228 px of the top's 4,300.
  s.scene.materials = {mirror};
  const Frame shiny = Renderer(s.parts, s.scene, pbr).Render(s.camera, 0, sensor);
  const int shiny_returns = top_returns(shiny, &top);
  EXPECT_NEAR(shiny_returns, 228, 0.15 * 228);
}

TEST(GrayCamera, IsTheLuminanceOfTheColourRender) {
  BoxOnFloor s;
  s.scene.part_colors = {Eigen::Vector3f(0.9f, 0.3f, 0.1f)};
  s.scene.floor_color = Eigen::Vector3f(0.2f, 0.5f, 0.7f);
  RenderOptions options;
  options.hdr = true;  // keep the colour before rounding
  options.amodal_masks = false;
  SensorOptions sensor;
  sensor.image = SensorOptions::Image::kGray;
  const Frame fast = Renderer(s.parts, s.scene, options).Render(s.camera, 0, sensor);
  ASSERT_EQ(fast.gray.size(), fast.depth.size());
  for (size_t p = 0; p < fast.gray.size(); p += 97) {
    const float* c = &fast.radiance[3 * p];
    const float y = 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2];
    ASSERT_FLOAT_EQ(fast.gray[p], std::clamp(y, 0.0f, 1.0f)) << p;
  }
  // Path traced: the display transform of the radiance's luminance.
  options.mode = RenderOptions::Mode::kPbr;
  options.samples = 2;
  const Frame pbr = Renderer(s.parts, s.scene, options).Render(s.camera, 3, sensor);
  for (size_t p = 0; p < pbr.gray.size(); p += 97) {
    const float* c = &pbr.radiance[3 * p];
    const float y = 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2];
    ASSERT_FLOAT_EQ(pbr.gray[p], DisplayValue(y, true)) << p;
  }
  // A colour camera has no grey image, and the exact depth is the sensor's depth.
  const Frame colour = Renderer(s.parts, s.scene).Render(s.camera);
  EXPECT_TRUE(colour.gray.empty());
  EXPECT_TRUE(colour.sensor_depth.empty());
}

// A floor filling the view, lit by the ambient term alone: the fast mode's colour is exactly the
// floor's albedo at every pixel (before the image sensor).
struct FlatField {
  Scene scene;
  RenderOptions options;
  explicit FlatField(float level) {
    scene.lights.clear();
    scene.ambient = 1.0f;
    scene.floor_color.setConstant(level);
    options.hdr = true;  // fast mode: the colour before rounding, after the image sensor
    options.amodal_masks = false;
  }
};

TEST(ImageSensor, VignettingFollowsTheCosineFourthLaw) {
  const FlatField flat(0.5f);
  const Renderer renderer(std::vector<Part>{}, flat.scene, flat.options);
  SensorOptions sensor;
  sensor.imager.vignetting = 0.6;
  const Camera camera{Intrinsics{}, LookingDown({0, 0, 1000})};
  const Frame frame = renderer.Render(camera, 0, sensor);
  const Intrinsics& k = camera.intrinsics;
  for (const auto& [u, v] : {std::pair{320, 240}, {0, 0}, {639, 479}, {100, 400}}) {
    const double x = (u + 0.5 - k.cx) / k.fx, y = (v + 0.5 - k.cy) / k.fy;
    const double cos2 = 1.0 / (1.0 + x * x + y * y);  // cos^2 of the ray's angle to the axis
    const double expected = 0.5 * (0.4 + 0.6 * cos2 * cos2);
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(frame.radiance[3 * (size_t(v) * 640 + u) + c], expected, 1e-6) << u << "," << v;
  }
  // The corner of a 640 x 480, f = 525 image is 37.3 degrees off axis: cos^4 = 0.40.
  EXPECT_NEAR(frame.radiance[0] / frame.radiance[3 * (240 * 640 + 320)], 0.4 + 0.6 * 0.401, 0.01);
}

TEST(ImageSensor, NoiseHasThePoissonGaussianVariance) {
  // A pixel of linear value x reads x + N(0, x / full_well + (read / full_well)^2): with 2,000
  // electrons at full scale and 20 electrons of read noise, sigma = 0.0071 at x = 0.1, 0.0145 at
  // 0.4 and 0.0201 at 0.8.
  SensorOptions colour;
  colour.imager.full_well = 2000;
  colour.imager.read_noise = 20;
  SensorOptions grey = colour;
  grey.image = SensorOptions::Image::kGray;
  const Camera camera{Intrinsics{}, LookingDown({0, 0, 1000})};
  for (float x : {0.1f, 0.4f, 0.8f}) {
    const FlatField flat(x);
    const Renderer renderer(std::vector<Part>{}, flat.scene, flat.options);
    const Frame rgb = renderer.Render(camera, 1, colour);
    const Frame gray = renderer.Render(camera, 1, grey);
    double sum = 0, sum2 = 0, green2 = 0, cross = 0, gray_sum = 0, gray_sum2 = 0;
    const size_t n = gray.gray.size();
    for (size_t p = 0; p < n; ++p) {
      const double r = rgb.radiance[3 * p] - x, g = rgb.radiance[3 * p + 1] - x;
      const double k = gray.gray[p] - x;
      sum += r, sum2 += r * r, green2 += g * g, cross += r * g;
      gray_sum += k, gray_sum2 += k * k;
    }
    const double variance = x / 2000.0 + (20.0 / 2000) * (20.0 / 2000);
    SCOPED_TRACE(x);
    EXPECT_NEAR(sum / n, 0.0, 5 * std::sqrt(variance / n));  // unbiased
    EXPECT_NEAR(sum2 / n / variance, 1.0, 0.02);             // 307,200 samples: 0.26% sd
    EXPECT_NEAR(green2 / n / variance, 1.0, 0.02);
    EXPECT_NEAR(cross / n / variance, 0.0, 0.02);  // channels draw independently
    EXPECT_NEAR(gray_sum / n, 0.0, 5 * std::sqrt(variance / n));
    EXPECT_NEAR(gray_sum2 / n / variance, 1.0, 0.02);  // a grey camera's pixels alike
  }
  // Another view, another draw; the same view, the same bytes.
  const FlatField flat(0.4f);
  const Renderer renderer(std::vector<Part>{}, flat.scene, flat.options);
  EXPECT_EQ(renderer.Render(camera, 5, colour).rgb, renderer.Render(camera, 5, colour).rgb);
  EXPECT_NE(renderer.Render(camera, 5, colour).rgb, renderer.Render(camera, 6, colour).rgb);
}

// A grey camera's noise takes both numbers of a Box-Muller pair, for pixels 2k and 2k + 1: still
// standard normal and uncorrelated between neighbours (the cosine's and the sine's numbers of one
// pair are independent), and unlike the colour camera's draws.
TEST(ImageSensor, GreyNoiseIsStandardNormalAndNeighboursAreIndependent) {
  const size_t n = 400001;  // odd: the last pixel takes half a pair
  const std::vector<float> z = GreyImageNoise(12345, n);
  ASSERT_EQ(z.size(), n);
  double sum = 0, squares = 0, pairs = 0, across = 0, beyond = 0;
  for (size_t p = 0; p < n; ++p) {
    sum += z[p];
    squares += double{z[p]} * z[p];
    beyond += std::abs(z[p]) > 2.0;
    if (p + 1 < n) (p % 2 == 0 ? pairs : across) += double{z[p]} * z[p + 1];
  }
  // Standard errors: mean 1/sqrt(n) = 0.0016, variance sqrt(2/n) = 0.0022, products
  // 1/sqrt(n/2) = 0.0022; bounds at about 5 of them.
  EXPECT_NEAR(sum / n, 0.0, 0.008);
  EXPECT_NEAR(squares / n, 1.0, 0.011);
  EXPECT_NEAR(pairs / (n / 2), 0.0, 0.011);   // 2k with 2k + 1: one pair
  EXPECT_NEAR(across / (n / 2), 0.0, 0.011);  // 2k + 1 with 2k + 2: two pairs
  EXPECT_NEAR(beyond / n, 0.0455, 0.0017);    // P(|z| > 2) of the normal distribution
  // Not the colour camera's numbers for the same pixel, nor another frame's.
  int same = 0;
  const std::vector<float> other = GreyImageNoise(12346, 1000);
  for (size_t p = 0; p < 1000; ++p) {
    same += z[p] == static_cast<float>(ImageNoisePair(12345, p, 1).y());
    same += z[p] == other[p];
  }
  EXPECT_EQ(same, 0);
}

TEST(ImageSensor, ChecksItsParameters) {
  std::string why;
  ImageSensor s;
  EXPECT_TRUE(s.Check(&why));
  s.vignetting = 1.5;
  EXPECT_FALSE(s.Check(&why));
  EXPECT_EQ(why, "vignetting must lie between 0 and 1");
  s.vignetting = 0;
  s.read_noise = 3;
  EXPECT_FALSE(s.Check(&why));
  EXPECT_EQ(why, "read_noise needs full_well (the electrons at full scale)");
}

}  // namespace
}  // namespace cadsynth
