#include "variants/stable_pose.h"

#include <cmath>
#include <memory>

#include <gtest/gtest.h>

#include "cad/core/error.h"
#include "cad/shape.h"

namespace cadsynth {
namespace {

std::vector<Eigen::Vector3d> Points(const Mesh& mesh) {
  std::vector<Eigen::Vector3d> points;
  for (const auto& p : mesh.positions) points.push_back(p.cast<double>());
  return points;
}

double Sum(const std::vector<StablePose>& poses) {
  double total = 0;
  for (const StablePose& p : poses) total += p.probability;
  return total;
}

TEST(StablePoses, CubeRestsOnAnyFaceWithEqualOdds) {
  const Mesh cube = Tessellate(MakeBox(30, 30, 30), TessellationOptions{});
  const auto poses = StablePoses(Points(cube), Eigen::Vector3d(15, 15, 15));
  ASSERT_EQ(poses.size(), 6u);
  for (const StablePose& p : poses) {
    EXPECT_NEAR(p.probability, 1.0 / 6.0, 1e-9);
    EXPECT_NEAR(p.height, 15.0, 1e-9);
  }
}

// A 40 x 40 x 30 block rests on its four sides at height 20 and on its two caps at height 15.
// Which faces are one pose is the part's symmetry's to say: the square prism's (4 turns about z
// and 4 flips) pools the sides and the caps; a part that only a half-turn about z keeps (a hole
// through one side and its opposite, a boss on top) rests 4 distinct ways. Without symmetries
// the height decides.
TEST(StablePoses, SymmetriesDecideWhichFacesAreOnePose) {
  const Mesh block = Tessellate(MakeBox(40, 40, 30), TessellationOptions{});
  const Eigen::Vector3d centre(20, 20, 15);
  const auto count = [&](const Symmetries* s) {
    const std::vector<StablePose> poses = StablePoses(Points(block), centre, s);
    EXPECT_EQ(poses.size(), 6u);
    int most = 0;
    for (const StablePose& p : poses) most = std::max(most, p.pose + 1);
    return most;
  };
  EXPECT_EQ(count(nullptr), 2);
  const Symmetries square =
      Symmetries::Cyclic(4, true, 15).InFrame(Eigen::Isometry3d(Eigen::Translation3d(-20, -20, 0)));
  EXPECT_EQ(count(&square), 2);
  const Symmetries half =
      Symmetries::Cyclic(2, false).InFrame(Eigen::Isometry3d(Eigen::Translation3d(-20, -20, 0)));
  EXPECT_EQ(count(&half), 4);  // +-x, +-y, top, bottom
  // A cylinder (r 10, h 20) that only a 5-fold turn keeps (five holes round its axis, say):
  // its 5-fold symmetry cannot relate the rim's tessellated flats (their count is no multiple
  // of 5), which are still one pose, the side; the caps stay two (no flip relates them).
  const Mesh cylinder = Tessellate(MakeCylinder(10, 20), TessellationOptions{});
  const Symmetries five = Symmetries::Cyclic(5, false);
  const std::vector<StablePose> rolls = StablePoses(Points(cylinder), {0, 0, 10}, &five);
  int most = 0;
  for (const StablePose& p : rolls) most = std::max(most, p.pose + 1);
  EXPECT_EQ(most, 3);
  EXPECT_GT(rolls.size(), 10u);
  // The pooled sides still share the probability the faces have together.
  const std::vector<StablePose> poses = StablePoses(Points(block), centre, &half);
  double total = 0;
  for (const StablePose& p : poses) total += p.probability;
  EXPECT_NEAR(total, 1.0, 1e-9);
}

TEST(StablePoses, CylinderCapsAndSideAsWorkedByHand) {
  // r = 10, h = 20: each cap subtends 2 pi (1 - 10 / sqrt(10^2 + 10^2)) = 2 pi (1 - 0.7071) sr at
  // the centre: probability 0.1464 each; the side takes the remaining 0.7071.
  const Mesh cylinder = Tessellate(MakeCylinder(10, 20), TessellationOptions{0.005, 0.05});
  const auto poses = StablePoses(Points(cylinder), Eigen::Vector3d(0, 0, 10));
  EXPECT_NEAR(Sum(poses), 1.0, 1e-9);
  double caps = 0, side = 0;
  for (const StablePose& p : poses) {
    if (std::abs(p.normal.z()) > 0.999) {
      caps += p.probability;
      EXPECT_NEAR(p.probability, 0.5 * (1 - 1 / std::sqrt(2.0)), 1e-3);
      EXPECT_NEAR(p.height, 10.0, 1e-6);
    } else {
      side += p.probability;
      EXPECT_NEAR(p.height, 10.0, 0.01);  // the hull's flats lie inside the circle by the sagitta
    }
  }
  EXPECT_NEAR(caps, 1 - 1 / std::sqrt(2.0), 2e-3);
  EXPECT_NEAR(side, 1 / std::sqrt(2.0), 2e-3);
  // The side's many flats are one pose (the most probable), the caps another.
  EXPECT_NEAR(poses.front().pose_probability, 1 / std::sqrt(2.0), 2e-3);
  EXPECT_LT(std::abs(poses.front().normal.z()), 0.01);
  EXPECT_EQ(poses.back().pose, 1);
  EXPECT_NEAR(poses.back().pose_probability, 1 - 1 / std::sqrt(2.0), 2e-3);
}

TEST(StablePoses, FlatPlateLiesFlatMostOften) {
  // 100 x 60 x 10 plate: a big face is a 100 x 60 rectangle 5 mm from the centre, subtending
  // 4 asin(a b / sqrt((a^2 + 4 d^2)(b^2 + 4 d^2))) sr.
  const double a = 100, b = 60, d = 5;
  const double omega = 4 * std::asin(a * b / std::sqrt((a * a + 4 * d * d) * (b * b + 4 * d * d)));
  const Mesh plate = Tessellate(MakeBox(a, b, 10), TessellationOptions{});
  const auto poses = StablePoses(Points(plate), Eigen::Vector3d(50, 30, 5));
  ASSERT_EQ(poses.size(), 6u);
  EXPECT_NEAR(poses[0].probability, omega / (4 * M_PI), 1e-9);
  EXPECT_NEAR(poses[1].probability, omega / (4 * M_PI), 1e-9);
  EXPECT_NEAR(std::abs(poses[0].normal.z()), 1.0, 1e-12);  // most stable: lying flat
  EXPECT_GT(poses[0].probability, 0.35);
  EXPECT_NEAR(Sum(poses), 1.0, 1e-9);
  // Resting on its most stable face: the face is on the floor and the centre of mass 5 mm up.
  const Eigen::Vector3d com = poses[0].floor_from_body * Eigen::Vector3d(50, 30, 5);
  EXPECT_NEAR(com.z(), 5.0, 1e-9);
}

TEST(StablePoses, UnstableFacesTipOntoTheirNeighbours) {
  // An L of two boxes: the 40 x 10 bar with a 10 x 30 post at one end. Standing on the post's top
  // face the centre of mass overhangs it, so that face is not a pose and passes its odds on.
  Mesh l = Tessellate(MakeBox(40, 10, 10), TessellationOptions{});
  Mesh post = Tessellate(MakeBox(10, 10, 30), TessellationOptions{});
  l.Append(post);
  // Centre of mass: bar (4000 mm3 at (20, 5, 5)) and post (3000 mm3 at (5, 5, 15)) minus the
  // shared cube (1000 mm3 at (5, 5, 5)): (80000 + 15000 - 5000, 30000, 20000 + 45000 - 5000) /
  // 6000.
  const Eigen::Vector3d com(15.0, 5.0, 10.0);
  const auto poses = StablePoses(Points(l), com);
  EXPECT_NEAR(Sum(poses), 1.0, 1e-9);
  bool on_bar_bottom = false, on_post_side = false;
  for (const StablePose& p : poses) {
    EXPECT_FALSE(p.normal.isApprox(Eigen::Vector3d(0, 0, 1), 1e-9))
        << "the post top cannot hold it";
    on_bar_bottom = on_bar_bottom || p.normal.isApprox(Eigen::Vector3d(0, 0, -1), 1e-9);
    // The post's outer side (x = 0) is 10 x 30 mm; the centre of mass (z = 10) projects inside.
    on_post_side = on_post_side || p.normal.isApprox(Eigen::Vector3d(-1, 0, 0), 1e-9);
  }
  EXPECT_TRUE(on_bar_bottom);
  EXPECT_TRUE(on_post_side);
}

}  // namespace
}  // namespace cadsynth

namespace cadsynth {
namespace {

// CGAL's hull lists its triangles in an order that depends on memory addresses; the poses must
// not: every call on the same points gives the same bits (before the canonical order, about one
// call in 30 differed in the last bits, so two shards could rest a part differently).
TEST(StablePoses, SameBitsOnEveryCallWhateverTheHeap) {
  const Part part = MakePart("c", MakeCylinder(20, 60), TessellationOptions{});
  std::vector<Eigen::Vector3d> points;
  for (const Eigen::Vector3f& p : part.mesh.positions) points.push_back(p.cast<double>());
  const std::vector<StablePose> first = StablePoses(points, Eigen::Vector3d(0, 0, 0.1));
  std::vector<std::unique_ptr<char[]>> noise;  // moves later allocations elsewhere
  int differ = 0;
  for (int i = 0; i < 200; ++i) {
    noise.emplace_back(new char[1 + (i * 7919) % 5000]);
    const std::vector<StablePose> again = StablePoses(points, Eigen::Vector3d(0, 0, 0.1));
    bool same = again.size() == first.size();
    for (size_t k = 0; same && k < first.size(); ++k) {
      same = again[k].floor_from_body.matrix() == first[k].floor_from_body.matrix() &&
             again[k].normal == first[k].normal && again[k].probability == first[k].probability;
    }
    differ += !same;
  }
  EXPECT_EQ(differ, 0);
}

// A flat polygon (a sheet: no volume) rests on either side of its plane, 1/2 each, lying in the
// floor (a planar octagon of 8 or more vertices crashed the hull before).
TEST(StablePoses, FlatPolygonRestsOnEitherSide) {
  std::vector<Eigen::Vector3d> octagon;
  const Eigen::Isometry3d tilt =
      Eigen::Translation3d(5, 6, 7) * Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 1, 0).normalized());
  for (int i = 0; i < 8; ++i)
    octagon.push_back(tilt *
                      Eigen::Vector3d(10 * std::cos(i * M_PI / 4), 10 * std::sin(i * M_PI / 4), 0));
  const std::vector<StablePose> poses = StablePoses(octagon, tilt * Eigen::Vector3d::Zero());
  ASSERT_EQ(poses.size(), 2u);
  for (size_t k = 0; k < 2; ++k) {
    EXPECT_EQ(poses[k].pose, static_cast<int>(k));
    EXPECT_DOUBLE_EQ(poses[k].probability, 0.5);
    EXPECT_NEAR(poses[k].height, 0.0, 1e-9);
    for (const Eigen::Vector3d& p : octagon)
      EXPECT_NEAR((poses[k].floor_from_body * p).z(), 0.0, 1e-9);
  }
  EXPECT_NEAR(poses[0].normal.dot(poses[1].normal), -1.0, 1e-12);
  // Exactly flat (the hull has no volume): the same.
  EXPECT_EQ(
      StablePoses({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}}, Eigen::Vector3d::Zero()).size(),
      2u);
  // Collinear points have no area to rest on.
  EXPECT_THROW(StablePoses({{0, 0, 0}, {1, 1, 1}, {2, 2, 2}, {3, 3, 3}}, Eigen::Vector3d(1, 1, 1)),
               Error);
}

}  // namespace
}  // namespace cadsynth
