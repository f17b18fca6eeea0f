#include "variants/families.h"

#include <gtest/gtest.h>

#include "cad/core/error.h"
#include "cad/step.h"
#include "tests/test_support.h"

namespace cadsynth {
namespace {

TEST(Families, EveryParametricFamilyBuildsWithItsDefaults) {
  for (const FamilyInfo& family : Families()) {
    if (family.name == "scaled" || family.name == "from_file") continue;  // they need a file
    const Assembly a = BuildVariant(family, CompleteParams(family, {}), ImportOptions{});
    EXPECT_FALSE(a.parts.empty()) << family.name;
    for (const Part& p : a.parts) {
      EXPECT_TRUE(p.watertight) << family.name << " " << p.name;
      EXPECT_GT(p.mass.volume_mm3, 0) << family.name << " " << p.name;
      EXPECT_FALSE(p.brep.IsNull()) << family.name;
    }
  }
}

TEST(Families, ParametersAreCheckedByNameAndKind) {
  const FamilyInfo& gear = *FindFamily("spur_gear");
  try {
    CompleteParams(gear, {{"teth", 12.0}});
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()),
              "family 'spur_gear' has no parameter 'teth' (did you mean 'teeth'?)");
  }
  EXPECT_THROW(CompleteParams(gear, {{"teeth", std::string("many")}}), Error);
  EXPECT_THROW(CompleteParams(gear, {{"teeth", 12.5}}), Error);
  const ParamValues v = CompleteParams(gear, {{"teeth", 31.0}});
  EXPECT_EQ(std::get<double>(v.at("teeth")), 31.0);
  EXPECT_EQ(std::get<double>(v.at("module")), 2.0);  // default
  try {
    BuildVariant(gear, CompleteParams(gear, {{"teeth", 4.0}}), ImportOptions{});
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "spur_gear: gear: a gear needs at least 5 teeth (got 4)");
  }
  EXPECT_EQ(FindFamily("sprocket"), nullptr);
}

// Listings write angles as recipes do, in degrees (they printed radians: 0.349066).
TEST(Families, DescribedParametersShowAnglesInDegrees) {
  const FamilyInfo& gear = *FindFamily("spur_gear");
  const ParamValues v = CompleteParams(gear, {{"teeth", 31.0}});
  const std::string text = DescribeParams(v, &gear);
  EXPECT_NE(text.find("pressure_angle=20 deg"), std::string::npos) << text;
  EXPECT_NE(text.find("helix_angle=0 deg"), std::string::npos) << text;
  EXPECT_NE(text.find("teeth=31"), std::string::npos) << text;
  EXPECT_NE(text.find("module=2,"), std::string::npos) << text;
  EXPECT_NE(DescribeParams(v).find("pressure_angle=0.349066"), std::string::npos);  // no family
}

TEST(ScaleVariant, UniformPerAxisAndMeshes) {
  testing::ScratchDir dir;
  const Eigen::Isometry3d turned(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()));
  WriteStep(
      dir / "blocks.step", "blocks",
      {StepComponent{"block",
                     MakeBox(10, 20, 30),
                     {Eigen::Isometry3d::Identity(), Eigen::Translation3d(50, 0, 0) * turned}}});
  const FamilyInfo& scaled = *FindFamily("scaled");
  const auto build = [&](double s, double sx, double sy, double sz) {
    return BuildVariant(scaled,
                        CompleteParams(scaled, {{"file", (dir / "blocks.step").string()},
                                                {"scale", s},
                                                {"scale_x", sx},
                                                {"scale_y", sy},
                                                {"scale_z", sz}}),
                        ImportOptions{});
  };
  const Assembly twice = build(2, 1, 1, 1);
  ASSERT_EQ(twice.parts.size(), 1u);  // uniform: still one part, two instances
  ASSERT_EQ(twice.instances.size(), 2u);
  EXPECT_NEAR(twice.parts[0].mass.volume_mm3, 8 * 6000.0, 1e-6);
  EXPECT_TRUE(twice.parts[0]
                  .mesh.Bounds(twice.instances[1].world_from_model)
                  .min()
                  .isApprox(Eigen::Vector3d(60, 0, 0), 1e-4));

  // Stretched along x: the turned copy stretches along its own y, so it is a part of its own.
  const Assembly stretched = build(1, 2, 1, 1);
  ASSERT_EQ(stretched.parts.size(), 2u);
  for (const Instance& i : stretched.instances) {
    EXPECT_NEAR(stretched.parts[i.part].mass.volume_mm3, 2 * 6000.0, 1e-6);
  }
  const Eigen::Vector3d a = stretched.parts[0].mesh.Bounds().sizes(),
                        b = stretched.parts[1].mesh.Bounds().sizes();
  EXPECT_TRUE(a.isApprox(Eigen::Vector3d(20, 20, 30), 1e-5)) << a.transpose();
  EXPECT_TRUE(b.isApprox(Eigen::Vector3d(40, 10, 30), 1e-5)) << b.transpose();
}

}  // namespace
}  // namespace cadsynth
