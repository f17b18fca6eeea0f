// Active stereo (render/sensor.h): IR images with a projected dot pattern, matched by SGBM.
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "tests/render/render_support.h"

#include "cad/core/random.h"
#include "cad/shape.h"
#include "render/renderer.h"
#include "render/sensor.h"

namespace cadsynth {
namespace {

using testing::LookingDown;

// A D435-like depth camera: 640 x 480, 87 degrees across (fx = fy = 337.2).
Intrinsics DepthCamera() { return Intrinsics::FromFov(640, 480, 87.0 * M_PI / 180.0); }

struct PlaneError {
  double valid = 0, bias = 0, rms = 0;
};

// The sensor's depth of the floor seen straight down from height z, against the exact depth, over
// the pixels the matcher can match (right of its invalid band, inside the window's border).
PlaneError MeasurePlane(const Renderer& renderer, const SensorOptions& sensor, double z) {
  const Intrinsics k = DepthCamera();
  const Frame frame = renderer.Render(Camera{k, LookingDown({0, 0, z})}, 3, sensor);
  const int band = StereoDisparities(sensor.depth, k);
  double sum = 0, sum2 = 0;
  int valid = 0, total = 0;
  for (int v = 8; v < k.height - 8; ++v) {
    for (int u = band + 8; u < k.width - 8; ++u) {
      const size_t p = size_t(v) * k.width + u;
      ++total;
      if (frame.sensor_depth[p] <= 0.0f) continue;
      const double e = frame.sensor_depth[p] - frame.depth[p];
      sum += e, sum2 += e * e, ++valid;
    }
  }
  return PlaneError{double(valid) / total, sum / valid, std::sqrt(sum2 / valid)};
}

TEST(ActiveStereo, PlaneDepthHasTheRmsOfTheBaselineAndFocalLength) {
  // Triangulation turns a disparity error of s px into a depth error of z^2 s / (f B). SGBM's
  // parabola fit locks towards whole pixels: its error is mostly a bias of up to ~0.2 px that
  // depends on the fraction of the true disparity (here 33.7, 16.9, 8.4 and 5.6 px), plus noise.
  // We state s = 0.25 px. f = 337.2 px, B = 50 mm: 3.7, 14.8, 59 and 133 mm at 0.5, 1, 2, 3 m.
  constexpr double kSubpixel = 0.25;
  Scene scene;
  scene.floor_color.setConstant(0.6f);
  SensorOptions sensor;
  sensor.depth = DepthModel::Defaults(DepthModel::Kind::kActiveStereo);
  const Renderer renderer(std::vector<Part>{}, scene);
  const double fb = DepthCamera().fx * sensor.depth.baseline_mm;
  std::vector<double> rms;
  for (double z : {500.0, 1000.0, 2000.0, 3000.0}) {
    const PlaneError e = MeasurePlane(renderer, sensor, z);
    SCOPED_TRACE(z);
    EXPECT_GT(e.valid, 0.9);
    EXPECT_LT(e.rms, z * z * kSubpixel / fb);
    rms.push_back(e.rms);
  }
  // The error grows with the square of the range (36x from 0.5 to 3 m), not linearly (6x).
  EXPECT_GT(rms.back() / rms.front(), 15.0);
}

TEST(ActiveStereo, HolesWhereThePatternIsOccluded) {
  // A bar 4 mm wide, 20 mm in front of the projector (at x = 25 mm between the cameras at 0 and
  // 50 mm), hides the pattern from the floor 1200 mm below in the band x = 25 +- 2 * 1200 / 20 =
  // [-95, 145] mm, u = 319.5 + 525 x / 1200 = [277.9, 382.9]. Neither camera sees the bar (the left
  // one sees x < 19.1 mm at 20 mm, the right one x > 30.9 mm), so both see the floor there, lit
  // only by the ambient light: nothing to match.
  const std::vector<Part> parts = {MakePart("bar", MakeBox(4, 400, 2), TessellationOptions{})};
  Scene scene;
  scene.instances = {Instance{0, "bar", Eigen::Isometry3d(Eigen::Translation3d(25, 0, 1180))}};
  scene.floor_color.setConstant(0.6f);
  SensorOptions sensor;
  sensor.depth = DepthModel::Defaults(DepthModel::Kind::kActiveStereo);
  const Renderer renderer(parts, scene);
  const Camera camera{Intrinsics{}, LookingDown({0, 0, 1200})};
  const Frame frame = renderer.Render(camera, 0, sensor);
  const int band = StereoDisparities(sensor.depth, camera.intrinsics);
  int shadow = 0, shadow_holes = 0, lit = 0, lit_holes = 0, left = 0, left_holes = 0;
  for (int v = 8; v < 472; ++v) {
    for (int u = 0; u < 632; ++u) {
      const size_t p = size_t(v) * 640 + u;
      ASSERT_EQ(frame.instance[p], 0);  // the floor everywhere
      const bool hole = frame.sensor_depth[p] == 0.0f;
      // The right imager does not see the floor left of u = f B / z = 525 * 50 / 1200 = 21.9 px.
      if (u < 21) ++left, left_holes += hole;
      if (u < band + 8) continue;
      if (u >= 281 && u <= 380) ++shadow, shadow_holes += hole;
      if (u <= 270 || u >= 390) ++lit, lit_holes += hole;
    }
  }
  EXPECT_GT(shadow_holes, 0.99 * shadow);
  EXPECT_LT(lit_holes, 0.05 * lit);
  EXPECT_EQ(left_holes, left);
  // The IR image shows the dots beside the band and none in it.
  const auto row_sd = [&](int u0, int u1) {
    double sum = 0, sum2 = 0;
    for (int u = u0; u < u1; ++u) {
      const double g = frame.infrared[size_t(240) * 640 + u];
      sum += g, sum2 += g * g;
    }
    const double n = u1 - u0;
    return std::sqrt(sum2 / n - sum * sum / (n * n));
  };
  EXPECT_GT(row_sd(150, 250), 30.0);
  EXPECT_LT(row_sd(290, 370), 5.0);
}

TEST(ActiveStereo, TheDotTableGivesThePatternsValues) {
  // The table covers [-0.5, 0.5] x [-0.4, 0.4]; points inside and outside it (drawn as they go)
  // agree with DotPattern's hashed dots within single precision.
  DepthModel m = DepthModel::Defaults(DepthModel::Kind::kActiveStereo);
  m.seed = 99;
  const double fx = 525.0;
  const DotTable table(m, fx, -0.5, 0.5, -0.4, 0.4);
  int lit = 0;
  for (int i = 0; i < 20000; ++i) {
    const double x = -0.7 + 1.4 * ((i * 7919) % 20000) / 20000.0;
    const double y = -0.6 + 1.2 * ((i * 104729) % 20000) / 20000.0;
    const float exact = DotPattern(m, fx, x, y);
    ASSERT_NEAR(table(x, y), exact, 2e-5f) << x << " " << y;
    lit += exact > 0.05f;
  }
  EXPECT_GT(lit, 2000);  // the test sees dots, not only the dark between them
}

TEST(ActiveStereo, SearchesAtMostTheImageWidth) {
  DepthModel m = DepthModel::Defaults(DepthModel::Kind::kActiveStereo);
  // f B / min_depth = 337.2 * 50 / 280 = 60.2 px: 64 disparities.
  EXPECT_EQ(StereoDisparities(m, DepthCamera()), 64);
  m.min_depth_mm = 20;  // 843 px, more than the image is wide: 640 - 1 rounded down to 16
  EXPECT_EQ(StereoDisparities(m, DepthCamera()), 624);
  // An image narrower than the matcher's smallest search renders without depth.
  const Intrinsics tiny{12, 8, 10.0, 10.0, 5.5, 3.5};
  EXPECT_EQ(StereoDisparities(m, tiny), 16);
  Scene scene;
  SensorOptions sensor;
  sensor.depth = m;
  const Frame frame = Renderer(std::vector<Part>{}, scene)
                          .Render(Camera{tiny, LookingDown({0, 0, 1000})}, 0, sensor);
  ASSERT_EQ(frame.sensor_depth.size(), 96u);
  for (float z : frame.sensor_depth) EXPECT_EQ(z, 0.0f);
}

TEST(ActiveStereo, ASmallPlateAloneInTheDarkIsMatchedAndNothingAroundIt) {
  // The matcher searches only the rectangle around the surfaces: a 120 x 80 mm plate facing the
  // camera at 800 mm with no floor (u in 319.5 +- 337.2 * 60 / 800 = [294.2, 344.8], v in
  // 239.5 +- 16.9) is all the image holds. Inside it the depth is there and within the z^2 law's
  // error (as on the whole floor: 0.25 px, 800^2 * 0.25 / (337.2 * 50) = 9.5 mm); beyond a few
  // pixels of its edge nothing is returned.
  const std::vector<Part> parts = {MakePart("plate", MakeBox(120, 80, 2), TessellationOptions{})};
  Scene scene;
  scene.floor = false;
  scene.instances = {Instance{0, "plate", Eigen::Isometry3d(Eigen::Translation3d(0, 0, 200))}};
  scene.part_colors = {Eigen::Vector3f::Constant(0.6f)};
  SensorOptions sensor;
  sensor.depth = DepthModel::Defaults(DepthModel::Kind::kActiveStereo);
  const Renderer renderer(parts, scene);
  const Intrinsics k = DepthCamera();
  const Frame frame = renderer.Render(Camera{k, LookingDown({0, 0, 1002})}, 5, sensor);
  int inside = 0, matched = 0, outside_returns = 0;
  double sum2 = 0;
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const size_t p = size_t(v) * k.width + u;
      const bool interior = u >= 300 && u <= 339 && v >= 228 && v <= 251;
      const bool near_edge = u >= 286 && u <= 353 && v >= 215 && v <= 264;
      if (interior) {
        ++inside;
        ASSERT_GT(frame.depth[p], 0.0f);
        if (frame.sensor_depth[p] > 0.0f) {
          ++matched;
          sum2 += std::pow(frame.sensor_depth[p] - frame.depth[p], 2);
        }
      } else if (!near_edge && frame.sensor_depth[p] > 0.0f) {
        ++outside_returns;
      }
    }
  }
  EXPECT_GT(matched, 0.9 * inside);
  EXPECT_LT(std::sqrt(sum2 / matched), 800.0 * 800.0 * 0.25 / (k.fx * 50.0));
  EXPECT_EQ(outside_returns, 0);
}

TEST(ActiveStereo, AutoExposureBringsThe99thPercentileTo80PercentOfFullScale) {
  // 1000 values 0.000, 0.001, ..., 0.999 in a shuffled order: the 99th percentile (rank 990) is
  // 0.99, so the gain is 0.8 / 0.99.
  std::vector<float> values(1000);
  for (int i = 0; i < 1000; ++i) values[(i * 7919) % 1000] = i / 1000.0f;
  EXPECT_DOUBLE_EQ(InfraredGain(values), 0.8 / static_cast<double>(0.99f));
  // A dark image with a few bright dots: most values 0 (the bins' first), the 99th percentile
  // among the dots; an image of 300 x 200 draws matches a full sort's.
  std::vector<float> image(60000, 0.0f);
  for (size_t p = 0; p < image.size(); p += 37) image[p] = 0.25f + 0.5f * UniformDraw(1, "t", p);
  std::vector<float> sorted = image;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_GT(sorted[59400], 0.25f);
  EXPECT_DOUBLE_EQ(InfraredGain(image), 0.8 / static_cast<double>(sorted[59400]));
  image.assign(60000, 0.0f);
  for (size_t p = 0; p < image.size(); ++p) image[p] = static_cast<float>(UniformDraw(2, "t", p));
  sorted = image;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_DOUBLE_EQ(InfraredGain(image), 0.8 / static_cast<double>(sorted[59400]));
  // Nothing lit: gain 1; a very dim image: at most 64.
  EXPECT_EQ(InfraredGain(std::vector<float>(500, 0.0f)), 1.0);
  EXPECT_EQ(InfraredGain(std::vector<float>(500, 1e-4f)), 64.0);
}

TEST(ActiveStereo, TheSameBytesOnAnyThreadCount) {
  Scene scene;
  scene.floor_color.setConstant(0.6f);
  const std::vector<Part> parts = {MakePart("box", MakeBox(100, 100, 400), TessellationOptions{})};
  scene.instances = {Instance{0, "box", Eigen::Isometry3d(Eigen::Translation3d(0, 0, 200))}};
  SensorOptions sensor;
  sensor.depth = DepthModel::Defaults(DepthModel::Kind::kActiveStereo);
  const Renderer renderer(parts, scene);
  const Camera camera{DepthCamera(), LookingDown({0, 0, 1000})};
  const Frame many = renderer.Render(camera, 7, sensor);
  Frame one;
  {
    tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    one = renderer.Render(camera, 7, sensor);
  }
  EXPECT_EQ(many.infrared, one.infrared);
  EXPECT_EQ(many.sensor_depth, one.sensor_depth);
  // Another view draws other noise.
  EXPECT_NE(renderer.Render(camera, 8, sensor).infrared, many.infrared);
}

}  // namespace
}  // namespace cadsynth
