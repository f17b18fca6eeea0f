// The plane test (tools/pipeline/sensor_test.h) on sensors whose answers are known, and every
// sensor preset against its published figures (render/sensor_presets.h).
#include "tools/pipeline/sensor_test.h"

#include <tbb/global_control.h>

#include <cmath>

#include <gtest/gtest.h>

#include "cad/core/error.h"

namespace cadsynth {
namespace {

// A 320 x 240 camera, 60 degrees across, looking at an 80 % albedo plane at 1 and 2 m.
PlaneTestOptions Small(DepthModel::Kind kind) {
  PlaneTestOptions o;
  o.name = "test";
  o.intrinsics = Intrinsics::FromFov(320, 240, M_PI / 3.0);
  o.sensor.depth = DepthModel::Defaults(kind);
  o.distances_mm = {1000.0, 2000.0};
  o.frames = 4;
  return o;
}

TEST(PlaneTest, AnIdealSensorHasNoNoiseNoBiasAndFullFill) {
  const PlaneTestResult r = RunPlaneTest(Small(DepthModel::Kind::kIdeal));
  ASSERT_EQ(r.rows.size(), 2u);
  for (const PlaneTestRow& row : r.rows) {
    EXPECT_EQ(row.temporal_mm, 0.0);
    EXPECT_LT(row.plane_rms_mm, 1e-3 * row.distance_mm * 1e-3);  // float depths: ~1e-7 z
    EXPECT_LT(std::abs(row.bias_mm), 1e-9);
    EXPECT_EQ(row.fill, 1.0);
    EXPECT_EQ(row.edge_holes_px, 0.0);  // the exact step: neither holes nor wrong pixels
    EXPECT_EQ(row.edge_wrong_px, 0.0);
  }
}

TEST(PlaneTest, StructuredLightHasItsFormulasNoise) {
  // sigma = noise (z / 1 m)^2 / sqrt(signal), signal = albedo cos(angle to the projector): with
  // the projector 1 mm beside the camera and a white target, 1 mm at 1 m and 4 mm at 2 m where it
  // faces the projector. 49,000 pixels x 4 frames: the sd's standard error is about 0.2 %.
  PlaneTestOptions o = Small(DepthModel::Kind::kStructuredLight);
  o.sensor.depth.noise_mm = 1.0;
  o.sensor.depth.baseline_mm = 1.0;
  o.albedo = 1.0;
  o.step_mm = 0.0;
  PlaneTestResult r = RunPlaneTest(o);
  // The return falls off as the cosine of the angle to the projector (at the camera): at pixel
  // ray (x, y, 1), cos = 1 / sqrt(1 + x^2 + y^2), so the region's variance is sigma^2 times the
  // mean of sqrt(1 + x^2 + y^2) over its pixels (1.05 here).
  const Intrinsics& k = o.intrinsics;
  double mean_secant = 0.0;
  int pixels = 0;
  for (int v = 24; v < 216; ++v) {  // the central 80 %: 32 and 24 px margins
    for (int u = 32; u < 288; ++u, ++pixels) {
      const double x = (u + 0.5 - k.cx) / k.fx, y = (v + 0.5 - k.cy) / k.fy;
      mean_secant += std::sqrt(1.0 + x * x + y * y);
    }
  }
  mean_secant /= pixels;
  for (const PlaneTestRow& row : r.rows) {
    const double sigma = std::pow(row.distance_mm / 1000.0, 2) * std::sqrt(mean_secant);
    SCOPED_TRACE(row.distance_mm);
    EXPECT_NEAR(row.temporal_mm, sigma, 0.02 * sigma);
    // Trimming 0.5 % at each end cuts a normal at +-2.576 sigma: the variance left is 1 - 2 (2.576
    // phi(2.576)) / 0.99 = 0.9248, an RMS of 0.9617 sigma.
    EXPECT_NEAR(row.plane_rms_mm, 0.9617 * sigma, 0.01 * sigma);
    EXPECT_NEAR(row.bias_mm, 0.0, 0.01 * sigma);
    EXPECT_EQ(row.fill, 1.0);
    EXPECT_EQ(row.edge_holes_px, -1.0);  // no step
  }
  // A dark target returns a quarter of the light: twice the noise (fewer photons per code).
  o.albedo = 0.25;
  const PlaneTestResult dark = RunPlaneTest(o);
  for (size_t i = 0; i < r.rows.size(); ++i) {
    EXPECT_NEAR(dark.rows[i].temporal_mm / r.rows[i].temporal_mm, 2.0, 0.04);
  }
}

TEST(PlaneTest, KinectNoiseGrowsOnObliqueSurfaces) {
  // Nguyen et al.: beyond 60 degrees of incidence sigma gains 0.1 mm theta^2 / (pi/2 - theta)^2
  // / sqrt(z / m): 1.2 mm at 70 degrees and 1 m over the 1.9 mm of a facing plane.
  PlaneTestOptions o = Small(DepthModel::Kind::kKinectV1);
  o.distances_mm = {1000.0};
  o.tilts_rad = {0.0, -70.0 * M_PI / 180.0};
  o.step_mm = 0.0;
  o.roi = 0.1;  // the centre, where the incidence is the tilt
  const PlaneTestResult r = RunPlaneTest(o);
  ASSERT_EQ(r.rows.size(), 2u);
  EXPECT_GT(r.rows[1].temporal_mm, 1.4 * r.rows[0].temporal_mm);
}

TEST(PlaneTest, PolishedMetalTiltedTowardsTheProjectorLosesItsDepth) {
  // Structured light with the projector 200 mm right of the camera, a plate 600 mm away turned
  // 9.2 degrees towards it (half the 18.4 degrees between the two rays at the centre): the
  // mirror-like plate sends the pattern into the camera in a small glint (saturated: holes) and
  // away from it everywhere else (too weak: holes); a diffuse plate returns it everywhere.
  PlaneTestOptions o = Small(DepthModel::Kind::kStructuredLight);
  o.distances_mm = {600.0};
  o.tilts_rad = {9.2 * M_PI / 180.0};
  o.step_mm = 0.0;
  o.frames = 2;
  o.material = "abs";
  const PlaneTestResult diffuse = RunPlaneTest(o);
  o.material = "polished_steel";
  const PlaneTestResult polished = RunPlaneTest(o);
  EXPECT_GT(diffuse.rows[0].fill, 0.99);
  EXPECT_LT(polished.rows[0].fill, 0.2);
}

TEST(PlaneTest, TheSameNumbersOnOneAndTwoThreads) {
  PlaneTestOptions o = Small(DepthModel::Kind::kActiveStereo);
  o.distances_mm = {800.0};
  o.frames = 2;
  std::string one;
  {
    const tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    one = PlaneTestJson(RunPlaneTest(o));
  }
  const tbb::global_control two(tbb::global_control::max_allowed_parallelism, 2);
  EXPECT_EQ(PlaneTestJson(RunPlaneTest(o)), one);
}

TEST(PlaneTest, RefusesImpossibleOptions) {
  PlaneTestOptions o = Small(DepthModel::Kind::kStructuredLight);
  o.frames = 1;
  EXPECT_THROW(RunPlaneTest(o), Error);
  o = Small(DepthModel::Kind::kStructuredLight);
  o.material = "unobtainium";
  try {
    RunPlaneTest(o);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no material preset called 'unobtainium'"),
              std::string::npos);
  }
  o = Small(DepthModel::Kind::kStructuredLight);
  o.distances_mm = {5.0};
  EXPECT_THROW(RunPlaneTest(o), Error);
}

// Every sensor preset meets every published figure it claims, on the plane test as
// `cadsynth sensor-test PRESET` runs it (4 frames here, as the docs' tables were made).
TEST(SensorPresets, MeetTheirPublishedFigures) {
  for (const SensorPreset& preset : SensorPresets()) {
    SCOPED_TRACE(preset.name);
    PlaneTestOptions o = PlaneTestFor(preset);
    o.frames = 4;
    o.step_mm = 0.0;
    const PlaneTestResult r = RunPlaneTest(o);
    EXPECT_EQ(r.checks.size(), preset.figures.size());
    for (const FigureCheck& c : r.checks) {
      EXPECT_TRUE(c.met) << QuantityName(c.figure.quantity) << " at " << c.figure.distance_mm
                         << " mm: " << c.figure.value << ", measured " << c.measured << " ("
                         << c.figure.source << ")";
    }
  }
}

}  // namespace
}  // namespace cadsynth
