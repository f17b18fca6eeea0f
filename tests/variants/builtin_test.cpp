#include "variants/builtin.h"

#include <gtest/gtest.h>

#include "cad/error.h"

namespace cadsynth {
namespace {

TEST(GearBlank, TipRootAndBoreFollowTheModule) {
  GearBlankOptions o;
  o.teeth = 20;
  o.module_mm = 3.0;
  EXPECT_DOUBLE_EQ(o.TipRadius(), 33.0);    // m (z + 2) / 2
  EXPECT_DOUBLE_EQ(o.RootRadius(), 26.25);  // m (z - 2.5) / 2
  const Part part = MakePart("gear", MakeGearBlank(o), TessellationOptions{0.01, 0.1});
  const Eigen::Vector3d size = part.mesh.Bounds().sizes();
  EXPECT_NEAR(size.z(), o.face_width_mm, 1e-4);
  // The tip corners of tooth 0 sit at +-0.15 pitch: the outline spans 2 r_tip cos(0.15 * 2 pi / z)
  // ... at most 2 r_tip.
  EXPECT_LE(size.x(), 2 * o.TipRadius() + 1e-4);
  EXPECT_GT(size.x(), 2 * o.TipRadius() * std::cos(0.15 * 2 * M_PI / o.teeth) - 1e-4);
  // Every vertex lies between the bore and the tip circle (in the model frame, centred).
  for (const Eigen::Vector3f& p : part.mesh.positions) {
    const double r = Eigen::Vector2d(p.x(), p.y()).norm();
    EXPECT_LE(r, o.TipRadius() + 1e-3);
    EXPECT_GE(r, 0.5 * o.bore_diameter_mm - 1e-3);
  }
  // Volume: the toothed outline minus the bore, between the root and tip circle areas.
  const double bore = M_PI * 36.0 * o.face_width_mm;
  EXPECT_GT(part.mass.volume_mm3, M_PI * o.RootRadius() * o.RootRadius() * o.face_width_mm - bore);
  EXPECT_LT(part.mass.volume_mm3, M_PI * o.TipRadius() * o.TipRadius() * o.face_width_mm - bore);
}

TEST(GearBlank, RefusesImpossibleParameters) {
  GearBlankOptions o;
  o.teeth = 4;
  std::string why;
  EXPECT_FALSE(o.Check(&why));
  EXPECT_NE(why.find("at least 5 teeth"), std::string::npos);
  EXPECT_THROW(MakeGearBlank(o), Error);
  o = GearBlankOptions{};
  o.bore_diameter_mm = 60.0;  // root diameter is 52.5
  EXPECT_FALSE(o.Check(&why));
  EXPECT_NE(why.find("root diameter"), std::string::npos);
}

TEST(DefaultParts, BoxPegAndGearOneInstanceEach) {
  const Assembly a = MakeDefaultParts(TessellationOptions{});
  ASSERT_EQ(a.parts.size(), 3u);
  ASSERT_EQ(a.instances.size(), 3u);
  EXPECT_EQ(a.parts[0].name, "box");
  EXPECT_TRUE(a.parts[0].mesh.Bounds().sizes().isApprox(Eigen::Vector3d(80, 60, 40), 1e-6));
  EXPECT_TRUE(a.parts[1].mesh.Bounds().sizes().isApprox(Eigen::Vector3d(30, 30, 80), 1e-3));
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(a.instances[i].part, static_cast<int>(i));
    // The instance puts the part back where the CAD had it.
    EXPECT_TRUE(a.instances[i].world_from_model.isApprox(a.parts[i].cad_from_model));
  }
}

}  // namespace
}  // namespace cadsynth
