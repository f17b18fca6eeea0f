#include "dataset/pose_metrics.h"

#include "cad/core/error.h"
#include "dataset/bop_read.h"

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

// MSSD by hand on a 60 x 40 x 30 box's corners (centred): a half-turn about z moves each corner
// by twice its distance from the axis, 2 sqrt(30^2 + 20^2) = 72.11 mm, unless the half-turn is
// one of the box's symmetries; a 10 mm shift is 10 mm whatever the symmetries.
TEST(PoseMetrics, MssdAsWorkedOutByHand) {
  std::vector<Eigen::Vector3f> corners;
  for (int c = 0; c < 8; ++c)
    corners.emplace_back(c & 1 ? 30.f : -30.f, c & 2 ? 20.f : -20.f, c & 4 ? 15.f : -15.f);
  const Eigen::Isometry3d truth(Eigen::Translation3d(0, 0, 500));
  const Eigen::Isometry3d turned = truth * Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ());
  const Eigen::Isometry3d half_turn(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ()));
  EXPECT_NEAR(MssdError(corners, turned, truth, {}), 2 * std::sqrt(30.0 * 30 + 20 * 20), 1e-9);
  EXPECT_NEAR(MssdError(corners, turned, truth, {Eigen::Isometry3d::Identity(), half_turn}), 0.0,
              1e-9);
  const Eigen::Isometry3d shifted = Eigen::Translation3d(10, 0, 0) * truth;
  EXPECT_NEAR(MssdError(corners, shifted, truth, {Eigen::Isometry3d::Identity(), half_turn}), 10.0,
              1e-9);
  // Recall over the thresholds 5, 10, ..., 50 mm of a 100 mm object: an error of 10 mm passes
  // 15 to 50 (8 of 10; strictly less), a miss none: (0.8 + 0) / 2.
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_NEAR(AverageRecallMssd({10.0, inf}, {100.0, 100.0}), 0.4, 1e-12);
  EXPECT_EQ(AverageRecallMssd({}, {}), 0.0);
}

TEST(PoseMetrics, ModelsInfoSymmetriesExpandAsBopToolkitDoes) {
  const std::vector<BopModelInfo> info = ParseModelsInfo(R"({
    "1": {"diameter": 10},
    "2": {"diameter": 10, "symmetries_discrete": [[-1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]]},
    "3": {"diameter": 10, "symmetries_continuous": [{"axis": [0, 0, 1], "offset": [0, 0, 0]}],
          "symmetries_discrete": [[1, 0, 0, 0, 0, -1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1]]}})",
                                                         "models_info.json");
  ASSERT_EQ(info.size(), 3u);
  EXPECT_EQ(info[0].symmetry_poses.size(), 1u);  // the identity
  EXPECT_EQ(info[1].symmetry_poses.size(), 2u);
  EXPECT_EQ(info[2].symmetry_poses.size(), 2u * 315u);  // ceil(pi / 0.01) steps, twice
  EXPECT_TRUE(info[2].symmetry_poses[0].isApprox(Eigen::Isometry3d::Identity()));
  EXPECT_THROW(ParseModelsInfo(R"({"1": {"diameter": 1, "symmetries_discrete": [[2, 0, 0, 0, 0, 1,
               0, 0, 0, 0, 1, 0, 0, 0, 0, 1]]}})",
                               "m.json"),
               Error);
  EXPECT_THROW(
      ParseModelsInfo(R"({"1": {"diameter": 1, "symmetries_discrete": [[1, 0]]}})", "m.json"),
      Error);
  EXPECT_THROW(ParseModelsInfo(R"({"1": {"diameter": 1, "symmetries_continuous": [{"axis": [0, 0,
               0], "offset": [0, 0, 0]}]}})",
                               "m.json"),
               Error);
}

}  // namespace
}  // namespace cadsynth
