// Suction grasps against answers worked out by hand: a flat face seals, a ridge and an edge do
// not, and the wrench score follows 1 - (m g + 2 M / a) / V.
#include "variants/grasp/suction.h"

#include <cmath>

#include <gtest/gtest.h>

#include "cad/core/error.h"
#include "cad/shape.h"

namespace cadsynth {
namespace {

TEST(SuctionGrasps, AFlatFaceSealsAnEdgeAndARidgeDoNot) {
  const Part cube = MakePart("cube", MakeBox(40, 40, 40), TessellationOptions{});
  const SuctionCup cup;  // 20 mm across
  const Eigen::Vector3d down(0, 0, -1);
  // The middle of the top face: the rim lies flat, no spring stretches.
  EXPECT_NEAR(SuctionSeal(cube, cup, {0, 0, 20}, down), 1.0, 1e-9);
  EXPECT_NEAR(SuctionSeal(cube, cup, {9.5, -9.5, 20}, down), 1.0, 1e-9);
  // Within 10 mm of the face's edge the rim hangs over it: a leak.
  EXPECT_LT(SuctionSeal(cube, cup, {12, 0, 20}, down), 0.0);
  // On the edge itself, coming in at 45 degrees: half the rim on each face.
  const Eigen::Vector3d diagonal = Eigen::Vector3d(0, -1, -1).normalized();
  EXPECT_LT(SuctionSeal(cube, cup, {0, 20, 20}, diagonal), 0.0);
  // A 90-degree ridge (a square prism on its edge) under a vertical cup: the rim's heights are
  // -r |sin t|, 6.4 mm off their best plane for r = 10, beyond the 2 mm compliance.
  const Part prism = MakePart("prism", MakeBox(40, 40, 100), TessellationOptions{});
  Part ridge = prism;
  ridge.mesh.Transform(Eigen::Isometry3d(
      Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitY()) *
      Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX())));  // long axis along y, edge up
  const double top = 20 * std::sqrt(2.0);
  EXPECT_LT(SuctionSeal(ridge, cup, {0, 0, top}, down), 0.0);
  // A 19.9 mm compliance takes up the ridge's heights, but not its 40% perimeter stretch
  // (1 / cos 45 - 1 at the ring's steepest points, less the chords' rounding).
  SuctionCup soft = cup;
  soft.compliance_mm = 19.9;
  EXPECT_LT(SuctionSeal(ridge, soft, {0, 0, top}, down), 0.0);
  soft.stretch = 1.0;
  EXPECT_GT(SuctionSeal(ridge, soft, {0, 0, top}, down), 0.0);
}

TEST(SuctionGrasps, CubeGraspsSealOnFacesAndTheWrenchFollowsTheMoment) {
  const Part cube = MakePart("cube", MakeBox(40, 40, 40), TessellationOptions{});
  const SuctionCup cup;
  SuctionOptions o;
  o.samples = 600;
  o.density_kg_m3 = 7850;
  const std::vector<SuctionGrasp> grasps = SampleSuctionGrasps(cube, cup, o);
  ASSERT_GT(grasps.size(), 50u);
  // m g = 7850 kg/m^3 x 64e-6 m^3 x 9.80665 = 4.927 N; V = 80 kPa x pi (0.01 m)^2 = 25.13 N.
  const double weight = 7850 * 64e-6 * 9.80665, vacuum = 80e3 * M_PI * 1e-4;
  EXPECT_NEAR(cup.vacuum_force_n(), vacuum, 1e-9);
  for (const SuctionGrasp& g : grasps) {
    // Head-on to a face, the rim inside it (at most 20 - 10 = 10 mm off the face's centre).
    EXPECT_NEAR(g.approach.cwiseAbs().maxCoeff(), 1.0, 1e-9);
    const Eigen::Vector3d in_plane = g.point - g.point.dot(g.approach) * g.approach;
    EXPECT_LE(in_plane.cwiseAbs().maxCoeff(), 10.0 + 1e-6);
    EXPECT_NEAR(g.seal, 1.0, 1e-9);
    // The moment arm: the centre of mass (the origin) off the approach line through the point.
    const double arm = in_plane.norm() * 1e-3;
    EXPECT_NEAR(g.wrench, 1 - (weight + 2 * weight * arm / 0.01) / vacuum, 1e-9);
    EXPECT_NEAR(g.quality(), g.seal * g.wrench, 1e-12);
  }
  // Same seed, same grasps.
  const std::vector<SuctionGrasp> again = SampleSuctionGrasps(cube, cup, o);
  ASSERT_EQ(again.size(), grasps.size());
  for (size_t i = 0; i < grasps.size(); ++i) EXPECT_EQ(again[i].point, grasps[i].point);
  // Four times as dense: m g = 19.7 N, and the moment of a grasp 2.5 mm off centre
  // (2 x 19.7 x 0.0025 / 0.01 = 9.9 N) is more than the 25.1 N vacuum has left: only grasps
  // nearer the centre hold.
  o.density_kg_m3 = 4 * 7850;
  o.samples = 20000;  // 1.4 mm discs on the faces: 0.4% of the surface
  const std::vector<SuctionGrasp> heavy = SampleSuctionGrasps(cube, cup, o);
  EXPECT_GT(heavy.size(), 20u);
  for (const SuctionGrasp& g : heavy) {
    const Eigen::Vector3d in_plane = g.point - g.point.dot(g.approach) * g.approach;
    EXPECT_LT(in_plane.norm(), 1.4);  // (25.13 / 19.70 - 1) x 10 / 2 = 1.38 mm
  }
}

TEST(SuctionGrasps, ImpossibleOptionsAreRefused) {
  const Part cube = MakePart("cube", MakeBox(40, 40, 40), TessellationOptions{});
  SuctionCup cup;
  cup.ring_points = 2;
  EXPECT_THROW(SampleSuctionGrasps(cube, cup, SuctionOptions{}), Error);
  SuctionOptions o;
  o.density_kg_m3 = 0;
  EXPECT_THROW(SampleSuctionGrasps(cube, SuctionCup{}, o), Error);
  EXPECT_THROW(SampleSuctionGrasps(Part{}, SuctionCup{}, SuctionOptions{}), Error);
}

}  // namespace
}  // namespace cadsynth
