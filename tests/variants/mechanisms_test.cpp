#include "variants/mechanisms.h"

#include <gtest/gtest.h>

#include "cad/core/error.h"

namespace cadsynth {
namespace {

double Overlap(const ShapeAssembly& a, int i, int j) {
  return CommonVolume(a.components[a.placements[i].component].shape, a.placements[i].pose,
                      a.components[a.placements[j].component].shape, a.placements[j].pose);
}

double Volume(const ShapeAssembly& a, int i) {
  return ComputeMassProperties(a.components[a.placements[i].component].shape).volume_mm3;
}

TEST(GearPair, MeshesAtTheCentreDistanceWithoutInterference) {
  GearPairOptions o;
  o.first.teeth = 14;
  o.second.teeth = 31;
  for (GearOptions* g : {&o.first, &o.second}) {
    g->module_mm = 2.0;
    g->backlash_mm = 0.05;
  }
  EXPECT_DOUBLE_EQ(o.CentreDistance(), 45.0);  // m (z1 + z2) / 2
  const ShapeAssembly pair = MakeGearPair(o);
  EXPECT_NEAR(pair.placements[1].pose.translation().x(), 45.0, 1e-12);
  EXPECT_LT(Overlap(pair, 0, 1), 1e-6 * Volume(pair, 0));
  // Half a pitch off, teeth sit in teeth: the check would see it.
  ShapeAssembly wrong = pair;
  wrong.placements[1].pose =
      wrong.placements[1].pose * Eigen::AngleAxisd(M_PI / 31, Eigen::Vector3d::UnitZ());
  EXPECT_GT(Overlap(wrong, 0, 1), 10.0);
}

TEST(GearPair, ProfileShiftWidensTheCentreDistance) {
  GearPairOptions o;
  o.first.teeth = 12;
  o.second.teeth = 20;
  o.first.profile_shift = 0.4;
  o.second.profile_shift = 0.2;
  // inv(a_w) = 2 tan 20 (0.6) / 32 + inv 20 = 0.013649 + 0.014904 = 0.028553 -> a_w = 24.61 deg;
  // a = 32 cos 20 / cos a_w = 33.077.
  EXPECT_NEAR(o.CentreDistance(), 33.077, 2e-3);
  o.first.backlash_mm = o.second.backlash_mm = 0.05;
  const ShapeAssembly pair = MakeGearPair(o);
  EXPECT_LT(Overlap(pair, 0, 1), 1e-3);
}

TEST(GearPair, RefusesGearsThatCannotMesh) {
  GearPairOptions o;
  o.second.module_mm = 3.0;
  std::string why;
  EXPECT_FALSE(o.Check(&why));
  EXPECT_NE(why.find("modules differ"), std::string::npos);
  EXPECT_THROW(MakeGearPair(o), Error);
}

TEST(Planetary, EveryMeshEngagesWithoutInterference) {
  PlanetaryOptions o;  // sun 18, planets 18, ring 54, three planets: (18 + 54) / 3 = 24
  EXPECT_EQ(o.RingTeeth(), 54);
  const ShapeAssembly box = MakePlanetary(o);
  ASSERT_EQ(box.placements.size(), 6u);  // sun, 3 planets, ring, carrier
  const int sun = 0, ring = 4, carrier = 5;
  for (int planet = 1; planet <= 3; ++planet) {
    EXPECT_LT(Overlap(box, sun, planet), 1e-3) << planet;
    EXPECT_LT(Overlap(box, ring, planet), 1e-3) << planet;
    const Eigen::Vector3d c = box.placements[planet].pose.translation();
    EXPECT_NEAR(std::hypot(c.x(), c.y()), o.CentreDistance(), 1e-9);  // m (z_s + z_p) / 2 = 27
  }
  EXPECT_LT(Overlap(box, sun, ring), 1e-3);
  EXPECT_LT(Overlap(box, carrier, 1), 1e-3);  // the pin passes through the planet's bore
  // A planet turned by half a pitch collides with sun and ring.
  ShapeAssembly wrong = box;
  wrong.placements[2].pose =
      wrong.placements[2].pose * Eigen::AngleAxisd(M_PI / 18, Eigen::Vector3d::UnitZ());
  EXPECT_GT(Overlap(wrong, sun, 2), 10.0);
}

TEST(Planetary, OddPlanetCountsPhaseToo) {
  PlanetaryOptions o;
  o.sun_teeth = 21;
  o.planet_teeth = 15;  // ring 51; (21 + 51) / 4 = 18
  o.planets = 4;
  const ShapeAssembly box = MakePlanetary(o);
  ASSERT_EQ(box.placements.size(), 7u);  // sun, 4 planets, ring (5), carrier (6)
  for (int planet = 1; planet <= 4; ++planet) {
    EXPECT_LT(Overlap(box, 0, planet), 1e-3) << planet;
    EXPECT_LT(Overlap(box, 5, planet), 1e-3) << planet;
  }
}

TEST(Planetary, RefusesSetsThatCannotBeAssembled) {
  PlanetaryOptions o;
  o.planets = 5;  // (18 + 54) / 5 = 14.4
  std::string why;
  EXPECT_FALSE(o.Check(&why));
  EXPECT_EQ(why,
            "planets cannot be spaced evenly: (z_sun + z_ring) / planets = (18 + 54) / 5 is not a "
            "whole number");
  EXPECT_THROW(MakePlanetary(o), Error);
  o.planets = 6;  // 72 / 6 = 12 but six 30 mm planets on a 27 mm circle collide
  EXPECT_FALSE(o.Check(&why));
  EXPECT_NE(why.find("collide"), std::string::npos);
}

TEST(SliderCrank, PinsLineUpAndNothingCollides) {
  for (double angle : {0.0, 0.7, 2.0, M_PI, 4.5}) {
    SliderCrankOptions o;
    o.crank_angle_rad = angle;
    const ShapeAssembly s = MakeSliderCrank(o);
    const Eigen::Isometry3d& crank = s.placements[1].pose;
    const Eigen::Isometry3d& rod = s.placements[2].pose;
    const Eigen::Isometry3d& slider = s.placements[3].pose;
    // Crank pin = rod's first hole; rod's second hole = slider centre (in the plane).
    EXPECT_TRUE((crank * Eigen::Vector3d(o.crank_mm, 0, 0))
                    .head<2>()
                    .isApprox(rod.translation().head<2>(), 1e-9));
    EXPECT_TRUE((rod * Eigen::Vector3d(o.rod_mm, 0, 0))
                    .head<2>()
                    .isApprox(slider.translation().head<2>(), 1e-9));
    EXPECT_NEAR(slider.translation().y(), 0.0, 1e-12);
    EXPECT_NEAR(slider.translation().x(), o.SliderX(), 1e-12);
    for (int i = 0; i < 4; ++i) {
      for (int j = i + 1; j < 4; ++j)
        EXPECT_LT(Overlap(s, i, j), 1e-6) << angle << ": " << i << " " << j;
    }
  }
  SliderCrankOptions o;
  o.rod_mm = 30;
  std::string why;
  EXPECT_FALSE(o.Check(&why));
  EXPECT_NE(why.find("must be longer than the crank"), std::string::npos);
}

}  // namespace
}  // namespace cadsynth
