#include "variants/gear.h"

#include <map>

#include <gtest/gtest.h>

#include "cad/core/error.h"
#include "cad/shape.h"

namespace cadsynth {
namespace {

const TessellationOptions kFine{0.01, 0.1};

double PolygonArea(const std::vector<Eigen::Vector2d>& p) {
  double area = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    const auto& a = p[i];
    const auto& b = p[(i + 1) % p.size()];
    area += a.x() * b.y() - b.x() * a.y();
  }
  return 0.5 * area;
}

// Points where the mesh crosses the plane z = h (one per crossing edge).
std::vector<Eigen::Vector2d> Section(const Mesh& mesh, double h) {
  std::vector<Eigen::Vector2d> points;
  for (const auto& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3f a = mesh.positions[t[k]], b = mesh.positions[t[(k + 1) % 3]];
      if ((a.z() - h) * (b.z() - h) < 0) {
        const float s = (h - a.z()) / (b.z() - a.z());
        const Eigen::Vector3f p = a + s * (b - a);
        points.emplace_back(p.x(), p.y());
      }
    }
  }
  return points;
}

// Teeth counted on a section: walk round by angle and count the climbs from below to above the
// pitch radius.
int CountTeeth(const std::vector<Eigen::Vector2d>& section, double pitch_radius,
               double max_radius = 1e300) {
  std::vector<std::pair<double, double>> polar;
  for (const auto& p : section) {
    if (p.norm() > 0.5 * pitch_radius && p.norm() < max_radius)
      polar.emplace_back(std::atan2(p.y(), p.x()), p.norm());
  }
  std::sort(polar.begin(), polar.end());
  int climbs = 0;
  for (size_t i = 0; i < polar.size(); ++i) {
    const bool below = polar[i].second < pitch_radius;
    const bool next_above = polar[(i + 1) % polar.size()].second > pitch_radius;
    climbs += below && next_above;
  }
  return climbs;
}

TEST(Gear, DiametersFollowModuleAndTeeth) {
  GearOptions o;
  o.teeth = 20;
  o.module_mm = 2.0;
  EXPECT_DOUBLE_EQ(2 * o.PitchRadius(), 40.0);  // m z
  EXPECT_DOUBLE_EQ(2 * o.TipRadius(), 44.0);    // m (z + 2)
  EXPECT_DOUBLE_EQ(2 * o.RootRadius(), 35.0);   // m (z - 2.5)
  EXPECT_NEAR(o.BaseRadius(), 20.0 * std::cos(20.0 * M_PI / 180.0), 1e-12);
  o.profile_shift = 0.3;
  EXPECT_DOUBLE_EQ(2 * o.TipRadius(), 44.0 + 1.2);
  o.helix_angle_rad = 15.0 * M_PI / 180.0;  // transverse module m / cos(beta)
  EXPECT_NEAR(2 * o.PitchRadius(), 40.0 / std::cos(o.helix_angle_rad), 1e-12);

  GearOptions g;
  g.teeth = 17;
  g.module_mm = 3.0;
  const Mesh mesh = Tessellate(MakeGear(g), kFine);  // CAD frame: the axis is the z axis
  double r_max = 0, r_min = 1e9;
  for (const auto& p : Section(mesh, 0.5 * g.face_width_mm)) {
    r_max = std::max(r_max, p.norm());
    r_min = std::min(r_min, p.norm());
  }
  EXPECT_NEAR(r_max, g.TipRadius(), 0.01);   // 28.5
  EXPECT_NEAR(r_min, g.RootRadius(), 0.02);  // 21.75
}

TEST(Gear, FlankIsAnInvoluteToOneMicrometre) {
  for (int teeth : {8, 20, 57}) {
    GearOptions o;
    o.teeth = teeth;
    o.module_mm = 5.0;
    EXPECT_LT(InvoluteFitError(o), 1e-3) << teeth;
  }
}

TEST(Gear, TeethCountedOnASectionOfTheMesh) {
  for (int teeth : {7, 12, 31, 60}) {
    GearOptions o;
    o.teeth = teeth;
    o.module_mm = 1.5;
    o.bore_diameter_mm = 5;
    const Mesh mesh = Tessellate(MakeGear(o), TessellationOptions{0.02, 0.2});
    EXPECT_EQ(CountTeeth(Section(mesh, 0.37 * o.face_width_mm), o.PitchRadius()), teeth);
  }
}

TEST(Gear, VolumeIsProfileAreaTimesFaceWidth) {
  for (int teeth : {9, 24, 45}) {
    GearOptions o;
    o.teeth = teeth;
    o.module_mm = 2.5;
    o.face_width_mm = 12;
    o.profile_shift = teeth < 17 ? 0.3 : 0.0;
    const double area = PolygonArea(GearOutline(o, 400));
    const double volume = ComputeMassProperties(MakeGear(o)).volume_mm3;
    EXPECT_NEAR(volume, area * o.face_width_mm, 0.005 * volume) << teeth;
    // Unshifted, the area is about the pitch disc's (teeth and spaces balance).
    if (o.profile_shift == 0) {
      EXPECT_NEAR(area, M_PI * o.PitchRadius() * o.PitchRadius(), 0.02 * area) << teeth;
    }
  }
}

TEST(Gear, BoreAndHubChangeTheVolumeByTheirCylinders) {
  GearOptions o;
  o.teeth = 30;
  const double plain = ComputeMassProperties(MakeGear(o)).volume_mm3;
  o.bore_diameter_mm = 8;
  o.hub_diameter_mm = 16;
  o.hub_length_mm = 6;
  const double with_hub = ComputeMassProperties(MakeGear(o)).volume_mm3;
  const double expected = plain - M_PI * 16 * o.face_width_mm + M_PI * (64 - 16) * 6;
  EXPECT_NEAR(with_hub, expected, 1e-3 * expected);
}

TEST(Gear, HelicalGearHasTheSpurVolume) {
  GearOptions o;
  o.teeth = 18;
  o.module_mm = 2;
  o.helix_angle_rad = 20.0 * M_PI / 180.0;
  const Shape helical = MakeGear(o);
  const double area = PolygonArea(GearOutline(o, 400));  // transverse section is constant
  EXPECT_NEAR(ComputeMassProperties(helical).volume_mm3, area * o.face_width_mm,
              0.005 * area * o.face_width_mm);
  const Mesh mesh = Tessellate(helical, TessellationOptions{0.02, 0.2});
  EXPECT_EQ(CountTeeth(Section(mesh, 0.8 * o.face_width_mm), o.PitchRadius()), 18);
}

TEST(Gear, InternalGearIsARingWithInwardTeeth) {
  GearOptions o;
  o.teeth = 60;
  o.module_mm = 1.5;
  o.internal = true;
  const double outer = o.RootRadius() + 2.5 * o.module_mm;
  const double cutter_area = PolygonArea(GearOutline(o, 300));
  const double volume = ComputeMassProperties(MakeGear(o)).volume_mm3;
  const double expected = (M_PI * outer * outer - cutter_area) * o.face_width_mm;
  EXPECT_NEAR(volume, expected, 0.005 * expected);
  const Mesh mesh = Tessellate(MakeGear(o), TessellationOptions{0.02, 0.2});
  double r_min = 1e9;
  for (const auto& p : Section(mesh, 5.0)) r_min = std::min(r_min, p.norm());
  EXPECT_NEAR(r_min, o.TipRadius(), 0.02);  // 45 - 1.5 = 43.5
  // Counting inward teeth on the toothed surface (not the outer wall): one climb per space.
  EXPECT_EQ(CountTeeth(Section(mesh, 5.0), o.PitchRadius(), o.RootRadius() + 0.5), 60);
}

TEST(Gear, RefusesImpossibleGearsAndSaysWhy) {
  const auto why = [](GearOptions o) {
    std::string reason;
    EXPECT_FALSE(o.Check(&reason));
    EXPECT_THROW(MakeGear(o), Error);
    return reason;
  };
  GearOptions o;
  o.teeth = 4;
  EXPECT_EQ(why(o), "a gear needs at least 5 teeth (got 4)");
  o = GearOptions{};
  o.bore_diameter_mm = 40;
  EXPECT_EQ(why(o), "bore diameter 40 mm must be smaller than the root diameter 35 mm");
  o = GearOptions{};
  o.teeth = 6;
  o.profile_shift = 1.0;
  EXPECT_NE(why(o).find("pointed"), std::string::npos);
  o = GearOptions{};
  o.backlash_mm = 4;
  EXPECT_NE(why(o).find("more than the tooth is thick"), std::string::npos);
  o = GearOptions{};
  o.module_mm = -1;
  EXPECT_NE(why(o).find("module must be positive"), std::string::npos);
}

}  // namespace
}  // namespace cadsynth
