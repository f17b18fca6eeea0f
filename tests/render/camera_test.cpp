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
