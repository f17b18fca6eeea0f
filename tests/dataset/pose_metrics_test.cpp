#include "dataset/pose_metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace cadsynth {
namespace {

// A 9 x 9 grid on a 40 mm square in the xy plane, centred at the origin: it maps onto itself
// under a quarter turn about z, point for point.
std::vector<Eigen::Vector3f> SquareGrid() {
  std::vector<Eigen::Vector3f> points;
  for (int i = -4; i <= 4; ++i) {
    for (int j = -4; j <= 4; ++j) points.emplace_back(5.0f * i, 5.0f * j, 0.0f);
  }
  return points;
}

TEST(PoseMetrics, PureTranslationOfTenMillimetresGivesAddOfTen) {
  Eigen::Isometry3d truth = Eigen::Isometry3d::Identity();
  truth.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  truth.translation() = Eigen::Vector3d(10, -20, 800);
  Eigen::Isometry3d estimate = truth;
  estimate.translation() += Eigen::Vector3d(6, 0, 8);  // |(6, 0, 8)| = 10
  EXPECT_NEAR(AddError(SquareGrid(), estimate, truth), 10.0, 1e-9);
  EXPECT_LE(AddSError(SquareGrid(), estimate, truth), 10.0 + 1e-9);  // never more than ADD
}

TEST(PoseMetrics, RotationBySymmetryGivesZeroAddSButNotZeroAdd) {
  const Eigen::Isometry3d truth = Eigen::Translation3d(0, 0, 700) * Eigen::Isometry3d::Identity();
  const Eigen::Isometry3d estimate = truth * Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ());
  EXPECT_NEAR(AddSError(SquareGrid(), estimate, truth), 0.0, 1e-9);
  // Hand-worked: a quarter turn moves a point at radius r by r sqrt(2); ADD is the mean of that.
  double expected = 0;
  for (const Eigen::Vector3f& p : SquareGrid())
    expected += p.cast<double>().norm() * std::sqrt(2.0);
  expected /= SquareGrid().size();
  EXPECT_NEAR(AddError(SquareGrid(), estimate, truth), expected, 1e-9);
}

TEST(PoseMetrics, AucIntegratesTheAccuracyStepCurve) {
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_DOUBLE_EQ(AccuracyAuc({0, 0, 0}, 100), 1.0);
  EXPECT_DOUBLE_EQ(AccuracyAuc({50, 50}, 100), 0.5);   // accuracy 0 up to 50 mm, then 1
  EXPECT_DOUBLE_EQ(AccuracyAuc({20, inf}, 100), 0.4);  // a miss never counts
  EXPECT_DOUBLE_EQ(AccuracyAuc({150}, 100), 0.0);
  EXPECT_DOUBLE_EQ(AccuracyAuc({}, 100), 0.0);
  EXPECT_DOUBLE_EQ(ShareBelow({1, 5, 9, inf}, 6), 0.5);
}

}  // namespace
}  // namespace cadsynth
