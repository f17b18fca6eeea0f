// A user's gear as a family: a spur gear with a hub and a bore, written to STEP by our own code,
// recognised and rebuilt with other teeth, modules and face widths. The rebuilt gear is
// recognised again with the asked parameters, and its hub and bore are the file's, to the
// OpenCASCADE tolerance.
#include "variants/gear_from_file.h"

#include <cmath>

#include <gtest/gtest.h>

#include "cad/core/error.h"
#include "cad/import.h"
#include "cad/shape.h"
#include "cad/step.h"
#include "tests/test_support.h"
#include "variants/families.h"
#include "variants/gear.h"

namespace cadsynth {
namespace {

// z 20, module 2, 10 mm wide, 8 mm bore, a 20 mm hub 8 mm long below it.
struct HubbedGear {
  HubbedGear() {
    GearOptions o;
    o.teeth = 20;
    o.module_mm = 2.0;
    o.face_width_mm = 10.0;
    o.bore_diameter_mm = 8.0;
    o.hub_diameter_mm = 20.0;
    o.hub_length_mm = 8.0;
    WriteStep(dir / "gear.step", "gear", {StepComponent{"my_gear", MakeGear(o)}});
    part = ImportCad(dir / "gear.step", ImportOptions{}).parts.at(0);
    gear = RecognizePartGear(part, DetectedSymmetries{});  // the bore gives the axis
  }
  testing::ScratchDir dir;
  Part part;
  std::optional<RecognizedGear> gear;
};

std::optional<RecognizedGear> Recognise(const Shape& shape) {
  const Part p = MakePart("rebuilt", shape, TessellationOptions{});
  return RecognizePartGear(p, DetectedSymmetries{});  // the bore gives the axis
}

TEST(GearFromFile, RebuiltTeethAreRecognisedAndTheHubIsKept) {
  const HubbedGear file;
  ASSERT_TRUE(file.gear.has_value());
  ASSERT_EQ(file.gear->teeth, 20);
  // The body inside the smaller root circle less a quarter module is the file's: the same
  // volume inside that cylinder (the hub, the web and the bore).
  const auto inside = [&](const Shape& s, double r) {
    const Shape probe =
        Transformed(MakeCylinder(r, 40), Eigen::Isometry3d(Eigen::Translation3d(0, 0, -20)));
    return CommonVolume(s, Eigen::Isometry3d::Identity(), probe, Eigen::Isometry3d::Identity());
  };
  struct Case {
    GearRebuild change;
    int teeth;
    double module, face;
  };
  for (const Case& c : {Case{{30, 0, 0}, 30, 2.0, 10.0}, Case{{0, 1.5, 0}, 20, 1.5, 10.0},
                        Case{{16, 0, 14.0}, 16, 2.0, 14.0}}) {
    SCOPED_TRACE(c.teeth);
    const Shape rebuilt = RebuildGear(file.part, *file.gear, c.change);
    const std::optional<RecognizedGear> g = Recognise(rebuilt);
    ASSERT_TRUE(g.has_value());
    EXPECT_EQ(g->teeth, c.teeth);
    EXPECT_NEAR(g->module_mm, c.module, 0.01 * c.module);
    EXPECT_NEAR(g->pressure_angle_rad, 20 * M_PI / 180, 0.01 * 20 * M_PI / 180);
    EXPECT_NEAR(g->face_width_mm, c.face, 1e-3);
    EXPECT_NEAR(g->bore_diameter_mm, 8.0, 0.05);
    const double root = std::min(file.gear->root_radius_mm, g->root_radius_mm);
    const double r = root - 0.25 * std::min(c.module, 2.0) - 0.01;
    EXPECT_NEAR(inside(rebuilt, r), inside(file.part.brep, r), 1e-3 * inside(file.part.brep, r));
    // The hub still reaches 8 mm below the teeth; the new band is centred on the old one.
    const Part mesh = MakePart("b", rebuilt, TessellationOptions{});
    const Eigen::Vector3d shift = mesh.cad_from_model.translation();
    EXPECT_NEAR(mesh.mesh.Bounds().min().z() + shift.z(), -8.0, 1e-3);
    EXPECT_NEAR(mesh.mesh.Bounds().max().z() + shift.z(), 5.0 + 0.5 * c.face, 1e-3);
  }
}

// A flange wider than the teeth beside the toothed band (a 60 mm "hub" 3 mm thick, as a gear's
// shoulder or a sprocket's plate): kept whole, only the teeth are rebuilt.
TEST(GearFromFile, AFlangeBesideTheTeethIsKept) {
  GearOptions o;
  o.teeth = 20;
  o.module_mm = 2.0;
  o.face_width_mm = 10.0;
  o.bore_diameter_mm = 8.0;
  o.hub_diameter_mm = 60.0;
  o.hub_length_mm = 3.0;
  const Shape body = MakeGear(o);
  const Part part = MakePart("flanged", body, TessellationOptions{0.05, 0.3});
  const std::optional<RecognizedGear> gear = RecognizePartGear(part, DetectedSymmetries{});
  ASSERT_TRUE(gear.has_value());
  EXPECT_EQ(gear->teeth, 20);
  const Shape rebuilt = RebuildGear(part, *gear, GearRebuild{32, 0, 0});
  // The flange: pi (30^2 - 4^2) 3 mm^3, in the file and after the rebuild.
  const Shape slab =
      Transformed(MakeCylinder(31, 3), Eigen::Isometry3d(Eigen::Translation3d(0, 0, -3)));
  const double expected = M_PI * (30 * 30 - 4 * 4) * 3;
  const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();
  EXPECT_NEAR(CommonVolume(body, identity, slab, identity), expected, 1e-3 * expected);
  EXPECT_NEAR(CommonVolume(rebuilt, identity, slab, identity), expected, 1e-3 * expected);
  const Part back = MakePart("back", rebuilt, TessellationOptions{0.05, 0.3});
  const std::optional<RecognizedGear> g = RecognizePartGear(back, DetectedSymmetries{});
  ASSERT_TRUE(g.has_value());
  EXPECT_EQ(g->teeth, 32);
}

TEST(GearFromFile, TheFamilyBuildsVariantsAndRefusesWhatItCannot) {
  const HubbedGear file;
  const FamilyInfo& family = *FindFamily("from_file");
  const std::string path = (file.dir / "gear.step").string();
  const Assembly a = BuildVariant(family, CompleteParams(family, {{"file", path}, {"teeth", 25.0}}),
                                  ImportOptions{});
  ASSERT_EQ(a.parts.size(), 1u);
  EXPECT_EQ(a.parts[0].name, "my_gear as z25 m2");
  const std::optional<RecognizedGear> g = RecognizePartGear(
      a.parts[0], DetectSymmetries(a.parts[0].mesh, PartSymmetryOptions(a.parts[0])));
  ASSERT_TRUE(g.has_value());
  EXPECT_EQ(g->teeth, 25);

  const auto error = [&](const ParamValues& values) {
    try {
      BuildVariant(family, CompleteParams(family, values), ImportOptions{});
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  // Six teeth of module 2: a 3.5 mm root circle inside an 8 mm bore.
  EXPECT_NE(error({{"file", path}, {"teeth", 6.0}}).find("of wall around the 8 mm bore"),
            std::string::npos)
      << error({{"file", path}, {"teeth", 6.0}});
  EXPECT_NE(error({{"file", path}, {"part", std::string("my_gearr")}})
                .find("has no part 'my_gearr' (did you mean 'my_gear'?)"),
            std::string::npos);
  EXPECT_NE(error({{"file", std::string("")}}).find("give the file"), std::string::npos);
  // A file with no gear in it.
  WriteStep(file.dir / "block.step", "block", {StepComponent{"block", MakeBox(30, 20, 10)}});
  EXPECT_NE(error({{"file", (file.dir / "block.step").string()}}).find("no gear recognised"),
            std::string::npos);
}

TEST(GearFromFile, AMeshHasNoBrepToRebuild) {
  CADSYNTH_REQUIRE_DATA(file, "mesh/seed_speed_reducer/left_gear.STL");
  ImportOptions import;
  import.unit = "m";
  const Part part = ImportCad(file, import).parts.at(0);
  const std::optional<RecognizedGear> g =
      RecognizePartGear(part, DetectSymmetries(part.mesh, PartSymmetryOptions(part)));
  ASSERT_TRUE(g.has_value());
  try {
    RebuildGear(part, *g, GearRebuild{});
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("is a mesh: rebuilding its gear needs the B-rep"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace cadsynth
