#include "render/camera.h"

#include <gtest/gtest.h>

namespace cadsynth {
namespace {

constexpr double kDeg = M_PI / 180.0;

TEST(Intrinsics, KinectV1Preset) {
  const Intrinsics k = Intrinsics::KinectV1();
  EXPECT_EQ(k.width, 640);
  EXPECT_EQ(k.height, 480);
  Eigen::Matrix3d expected;
  expected << 525, 0, 319.5, 0, 525, 239.5, 0, 0, 1;
  EXPECT_EQ(k.K(), expected);
  std::string why;
  EXPECT_TRUE(k.Check(&why));
  EXPECT_FALSE((Intrinsics{0, 480, 525, 525, 0, 0}).Check(&why));
  EXPECT_FALSE((Intrinsics{640, 480, -1, 525, 0, 0}).Check(&why));
}

TEST(Intrinsics, PresetsAndFieldOfView) {
  const Intrinsics d435 = Intrinsics::RealSenseD435(1280);
  EXPECT_EQ(d435.width, 1280);
  EXPECT_EQ(d435.height, 720);
  EXPECT_DOUBLE_EQ(d435.fx, 923.0);
  EXPECT_DOUBLE_EQ(d435.cx, 639.5);
  EXPECT_DOUBLE_EQ(Intrinsics::RealSenseD435(640).fx, 615.0);
  // 90 degrees across 640 px: f = 320 / tan(45) = 320.
  const Intrinsics wide = Intrinsics::FromFov(640, 480, M_PI / 2);
  EXPECT_NEAR(wide.fx, 320.0, 1e-9);
  EXPECT_NEAR(wide.fy, 320.0, 1e-9);
  EXPECT_DOUBLE_EQ(wide.cy, 239.5);
}

TEST(ViewSampler, FibonacciCoversTheBandEvenly) {
  SweepOptions sweep;
  sweep.radius_mm = {800, 1200};
  ViewSampler s;
  s.kind = ViewSampler::Kind::kFibonacci;
  s.count = 400;
  s.min_pitch_rad = 10 * kDeg;
  s.max_pitch_rad = 80 * kDeg;
  const std::vector<SweepView> views = SampleViews(s, sweep);
  ASSERT_EQ(views.size(), 800u);
  double mean_sin = 0;
  int upper_half_yaw = 0;
  for (size_t i = 0; i < 400; ++i) {
    EXPECT_GE(views[i].pitch_rad, s.min_pitch_rad - 1e-12);
    EXPECT_LE(views[i].pitch_rad, s.max_pitch_rad + 1e-12);
    EXPECT_DOUBLE_EQ(views[i].radius_mm, 800);
    mean_sin += std::sin(views[i].pitch_rad) / 400;
    upper_half_yaw += views[i].yaw_rad < M_PI;
  }
  // Equal area: sin(pitch) uniform between sin 10 and sin 80; yaw spread round.
  EXPECT_NEAR(mean_sin, 0.5 * (std::sin(10 * kDeg) + std::sin(80 * kDeg)), 0.002);
  EXPECT_NEAR(upper_half_yaw, 200, 10);
}

TEST(ViewSampler, RandomShellIsSeededAndWithinItsRanges) {
  ViewSampler s;
  s.kind = ViewSampler::Kind::kRandom;
  s.count = 200;
  s.min_pitch_rad = 20 * kDeg;
  s.max_pitch_rad = 70 * kDeg;
  s.min_radius_mm = 600;
  s.max_radius_mm = 900;
  s.seed = 4;
  const auto a = SampleViews(s, SweepOptions{}), b = SampleViews(s, SweepOptions{});
  s.seed = 5;
  const auto c = SampleViews(s, SweepOptions{});
  ASSERT_EQ(a.size(), 200u);
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_TRUE(a[i].world_from_cam.isApprox(b[i].world_from_cam, 0.0));
    EXPECT_GE(a[i].radius_mm, 600);
    EXPECT_LE(a[i].radius_mm, 900);
    EXPECT_GE(a[i].pitch_rad, 20 * kDeg - 1e-12);
    EXPECT_LE(a[i].pitch_rad, 70 * kDeg + 1e-12);
  }
  EXPECT_FALSE(a[0].world_from_cam.isApprox(c[0].world_from_cam, 1e-6));
}

TEST(ViewSampler, JitterStaysWithinItsBounds) {
  SweepOptions sweep;
  for (int y = 0; y < 360; y += 45) sweep.yaw_rad.push_back(y * kDeg);
  sweep.pitch_rad = {30 * kDeg, 90 * kDeg};
  sweep.radius_mm = {1000};
  sweep.target = Eigen::Vector3d(5, -5, 20);
  ViewSampler s;
  s.roll_jitter_rad = 10 * kDeg;
  s.target_jitter_mm = 30;
  s.seed = 1;
  const auto plain = ExpandSweep(sweep);
  const auto jittered = SampleViews(s, sweep);
  ASSERT_EQ(jittered.size(), plain.size());
  double largest_offset = 0, largest_roll = 0;
  for (size_t i = 0; i < jittered.size(); ++i) {
    const Eigen::Isometry3d& T = jittered[i].world_from_cam;
    EXPECT_TRUE(
        T.translation().isApprox(plain[i].world_from_cam.translation(), 1e-12));  // same eye
    EXPECT_NEAR(T.linear().determinant(), 1.0, 1e-12);
    // The optical axis passes within 30 mm of the target.
    const Eigen::Vector3d in_cam = T.inverse() * sweep.target;
    const double offset = in_cam.head<2>().norm();
    EXPECT_LE(offset, 30.0 + 1e-9);
    largest_offset = std::max(largest_offset, offset);
    if (sweep.pitch_rad[i / 8] <
        80 * kDeg) {  // away from straight down, roll is the tilt of image x
      largest_roll = std::max(largest_roll, std::asin(std::abs(T.linear().col(0).z())));
      EXPECT_LE(std::asin(std::abs(T.linear().col(0).z())), 10 * kDeg + 1e-6);
    }
  }
  EXPECT_GT(largest_offset, 5.0);  // it does jitter
  EXPECT_GT(largest_roll, 1 * kDeg);
}

TEST(Sweep, CameraSitsOnTheSphereAndLooksAtTheTarget) {
  const Eigen::Vector3d target(10, -20, 30);
  for (double yaw : {0.0, 40.0, 190.0}) {
    for (double pitch : {0.0, 30.0, 90.0}) {
      const Eigen::Isometry3d T = WorldFromCamOnSphere(target, yaw * kDeg, pitch * kDeg, 800.0);
      EXPECT_NEAR((T.translation() - target).norm(), 800.0, 1e-9);
      EXPECT_NEAR(T.translation().z() - target.z(), 800.0 * std::sin(pitch * kDeg), 1e-9);
      // The optical axis passes through the target: it projects to the principal point.
      const Eigen::Vector3d in_cam = T.inverse() * target;
      EXPECT_NEAR(in_cam.x(), 0.0, 1e-9);
      EXPECT_NEAR(in_cam.y(), 0.0, 1e-9);
      EXPECT_NEAR(in_cam.z(), 800.0, 1e-9);
      EXPECT_TRUE((T.linear().transpose() * T.linear()).isIdentity(1e-12));
      EXPECT_NEAR(T.linear().determinant(), 1.0, 1e-12);
      EXPECT_NEAR(T.linear().col(0).z(), 0.0, 1e-12);  // image x stays horizontal: no roll
      EXPECT_LE(T.linear().col(1).z(), 1e-12);         // image y points down (or level)
    }
  }
}

TEST(Sweep, PaperSweepHasItsViewsInOrder) {
  SweepOptions s;
  for (int y = 0; y <= 360; y += 10) s.yaw_rad.push_back(y * kDeg);
  for (int p = 0; p <= 90; p += 10) s.pitch_rad.push_back(p * kDeg);
  for (int r = 0; r < 9; ++r) s.radius_mm.push_back(650.0 + 100.0 * r);
  std::string why;
  ASSERT_TRUE(s.Check(&why)) << why;
  const std::vector<SweepView> views = ExpandSweep(s);
  ASSERT_EQ(views.size(), 37u * 10u * 9u);
  EXPECT_DOUBLE_EQ(views[1].yaw_rad, 10 * kDeg);  // yaw varies fastest
  EXPECT_DOUBLE_EQ(views[37].pitch_rad, 10 * kDeg);
  EXPECT_DOUBLE_EQ(views[370].radius_mm, 750.0);
  EXPECT_DOUBLE_EQ(views.back().radius_mm, 1450.0);
}

TEST(Sweep, RejectsEmptyOrImpossibleAxes) {
  SweepOptions s;
  std::string why;
  EXPECT_FALSE(s.Check(&why));
  s.yaw_rad = {0};
  s.pitch_rad = {100 * kDeg};
  s.radius_mm = {500};
  EXPECT_FALSE(s.Check(&why));
  EXPECT_NE(why.find("pitch"), std::string::npos);
  s.pitch_rad = {10 * kDeg};
  s.radius_mm = {0};
  EXPECT_FALSE(s.Check(&why));
}

}  // namespace
}  // namespace cadsynth
