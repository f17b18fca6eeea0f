// Gear recognition against gears whose parameters are known: the spur_gear and ring_gear
// families' parts written to STEP and read back (nothing of the family survives the file), and
// the paper's left_gear.STL, whose teeth can be counted on its picture.
#include "cad/gear_recognition.h"

#include <cmath>

#include <gtest/gtest.h>
#include <BRepAlgoAPI_Cut.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakePolygon.hxx>
#include <BRepPrimAPI_MakePrism.hxx>

#include "cad/import.h"
#include "cad/occt_shape.h"
#include "cad/shape.h"
#include "cad/step.h"
#include "tests/test_support.h"
#include "variants/families.h"
#include "variants/gear.h"

namespace cadsynth {
namespace {

constexpr double kDeg = M_PI / 180;

// The family's part through a STEP file, and what is recognised on it.
struct ReadBack {
  Part part;
  std::optional<RecognizedGear> gear;
};
ReadBack ThroughStep(const std::string& family_name, const ParamValues& values,
                     bool detect = false) {
  const FamilyInfo& family = *FindFamily(family_name);
  const ShapeAssembly shapes = BuildVariantShapes(family, CompleteParams(family, values));
  testing::ScratchDir dir;
  WriteStep(dir / "gear.step", "gear", {StepComponent{"gear", shapes.components.at(0).shape}});
  ImportOptions import;
  import.tessellation = TessellationOptions{0.02, 0.2};
  ReadBack out;
  out.part = ImportCad(dir / "gear.step", import).parts.at(0);
  // The B-rep's axes of revolution (tip and root cylinders, a bore) carry the axis; `detect`
  // adds the symmetry's main axis, as the pipeline does (slower: the tests use it once).
  out.gear = RecognizePartGear(
      out.part, detect ? DetectSymmetries(out.part.mesh, PartSymmetryOptions(out.part))
                       : DetectedSymmetries{});
  return out;
}

TEST(GearRecognition, SpurGearsGiveBackTheirModuleAndPressureAngle) {
  struct Case {
    int teeth;
    double module, pressure_deg, face, bore;
  };
  for (const Case c : {Case{20, 2.0, 20.0, 10.0, 0.0}, Case{33, 1.25, 20.0, 8.0, 12.0},
                       Case{17, 3.0, 25.0, 15.0, 0.0}, Case{60, 1.0, 14.5, 6.0, 20.0}}) {
    SCOPED_TRACE(c.teeth);
    const ReadBack r = ThroughStep("spur_gear", {{"teeth", double(c.teeth)},
                                                 {"module", c.module},
                                                 {"pressure_angle", c.pressure_deg * kDeg},
                                                 {"face_width", c.face},
                                                 {"bore", c.bore}});
    ASSERT_TRUE(r.gear.has_value());
    const RecognizedGear& g = *r.gear;
    EXPECT_EQ(g.teeth, c.teeth);
    EXPECT_FALSE(g.internal);
    EXPECT_NEAR(g.module_mm, c.module, 0.01 * c.module);
    EXPECT_NEAR(g.pressure_angle_rad, c.pressure_deg * kDeg, 0.01 * c.pressure_deg * kDeg);
    EXPECT_EQ(g.helix_angle_rad, 0.0);
    EXPECT_NEAR(g.face_width_mm, c.face, 1e-3);
    EXPECT_NEAR(g.profile_shift, 0.0, 0.02);
    EXPECT_NEAR(g.bore_diameter_mm, c.bore, c.bore > 0 ? 0.01 * c.bore : 0.0);
    // The B-rep's flanks are B-splines within microns of the involute; the mesh's vertices lie on
    // them.
    EXPECT_LT(g.involute_deviation_mm, 0.01 * c.module) << DescribeGear(g);
    EXPECT_NEAR(std::abs(g.axis.z()), 1.0, 1e-6);
  }
}

TEST(GearRecognition, HelicalShiftedAndInternalGears) {
  {
    const ReadBack r = ThroughStep("spur_gear", {{"teeth", 24.0},
                                                 {"module", 1.5},
                                                 {"helix_angle", 15 * kDeg},
                                                 {"profile_shift", 0.3},
                                                 {"face_width", 12.0},
                                                 {"bore", 8.0}});  // the bore gives the axis
    ASSERT_TRUE(r.gear.has_value());
    const RecognizedGear& g = *r.gear;
    EXPECT_EQ(g.teeth, 24);
    EXPECT_NEAR(g.module_mm, 1.5, 0.015);
    EXPECT_NEAR(g.helix_angle_rad, 15 * kDeg, 0.01 * 15 * kDeg) << DescribeGear(g);
    EXPECT_NEAR(g.pressure_angle_rad, 20 * kDeg, 0.01 * 20 * kDeg) << DescribeGear(g);
    EXPECT_NEAR(g.profile_shift, 0.3, 0.02);
    EXPECT_NEAR(g.face_width_mm, 12.0, 1e-3);
  }
  {  // Left hand.
    const ReadBack r =
        ThroughStep("spur_gear", {{"teeth", 30.0}, {"helix_angle", -20 * kDeg}}, /*detect=*/true);
    ASSERT_TRUE(r.gear.has_value());
    EXPECT_NEAR(r.gear->helix_angle_rad, -20 * kDeg, 0.01 * 20 * kDeg) << DescribeGear(*r.gear);
  }
  {
    const ReadBack r = ThroughStep("ring_gear", {{"teeth", 48.0}, {"module", 1.0}});
    ASSERT_TRUE(r.gear.has_value());
    const RecognizedGear& g = *r.gear;
    EXPECT_TRUE(g.internal);
    EXPECT_EQ(g.teeth, 48);
    EXPECT_NEAR(g.module_mm, 1.0, 0.01);
    EXPECT_NEAR(g.pressure_angle_rad, 20 * kDeg, 0.01 * 20 * kDeg) << DescribeGear(g);
  }
}

// Cases a first version got wrong (found in review): a gear on a hex bore (its inner outline
// swings more than its teeth), a ring of few teeth (its base circle among its flanks) and a
// helical gear 60 modules wide (its teeth turn more than a pitch along the band).
TEST(GearRecognition, HexBoreFewTeethRingAndWideHelix) {
  {
    GearOptions o;
    o.teeth = 36;
    o.module_mm = 1.0;
    o.face_width_mm = 8.0;
    BRepBuilderAPI_MakePolygon hexagon;
    for (int k = 0; k < 6; ++k)
      hexagon.Add(gp_Pnt(5 * std::cos(k * M_PI / 3), 5 * std::sin(k * M_PI / 3), -1));
    hexagon.Close();
    const TopoDS_Shape prism =
        BRepPrimAPI_MakePrism(BRepBuilderAPI_MakeFace(hexagon.Wire()).Face(), gp_Vec(0, 0, 10));
    const TopoDS_Shape bored = BRepAlgoAPI_Cut(OcctShape(MakeGear(o)), prism).Shape();
    const Part part = MakePart("hex_bored", WrapShape(bored), TessellationOptions{0.02, 0.2});
    // The tip cylinders give the axis.
    const std::optional<RecognizedGear> g = RecognizePartGear(part, DetectedSymmetries{});
    ASSERT_TRUE(g.has_value());
    EXPECT_FALSE(g->internal);
    EXPECT_EQ(g->teeth, 36);
    EXPECT_NEAR(g->module_mm, 1.0, 0.01);
    EXPECT_EQ(g->bore_diameter_mm, 0.0);  // not round
  }
  {
    const ReadBack r = ThroughStep("ring_gear", {{"teeth", 20.0}, {"module", 2.0}});
    ASSERT_TRUE(r.gear.has_value());
    EXPECT_TRUE(r.gear->internal);
    EXPECT_EQ(r.gear->teeth, 20);
    EXPECT_NEAR(r.gear->pressure_angle_rad, 20 * kDeg, 0.01 * 20 * kDeg) << DescribeGear(*r.gear);
  }
  {
    const ReadBack r = ThroughStep("spur_gear", {{"teeth", 20.0},
                                                 {"module", 1.0},
                                                 {"helix_angle", 30 * kDeg},
                                                 {"face_width", 60.0},
                                                 {"bore", 6.0}});
    ASSERT_TRUE(r.gear.has_value());
    EXPECT_NEAR(r.gear->helix_angle_rad, 30 * kDeg, 0.01 * 30 * kDeg) << DescribeGear(*r.gear);
    EXPECT_NEAR(r.gear->face_width_mm, 60.0, 1e-3);
  }
}

TEST(GearRecognition, PartsThatAreNotGearsAreNot) {
  for (const char* family : {"hex_nut", "washer", "hex_bolt", "ball_bearing"}) {
    const FamilyInfo& f = *FindFamily(family);
    const Part part = BuildVariant(f, CompleteParams(f, {}), ImportOptions{}).parts.at(0);
    const DetectedSymmetries d = DetectSymmetries(part.mesh, PartSymmetryOptions(part));
    const std::optional<RecognizedGear> g = RecognizePartGear(part, d);
    EXPECT_FALSE(g.has_value()) << family << ": " << DescribeGear(*g);
  }
}

TEST(GearRecognition, ThePapersLeftGearIsAHerringboneOfTwentyTeeth) {
  CADSYNTH_REQUIRE_DATA(file, "mesh/seed_speed_reducer/left_gear.STL");
  ImportOptions import;
  import.unit = "m";
  const Part part = ImportCad(file, import).parts.at(0);
  const DetectedSymmetries d = DetectSymmetries(part.mesh, PartSymmetryOptions(part));
  const std::optional<RecognizedGear> g = RecognizePartGear(part, d);
  ASSERT_TRUE(g.has_value());
  EXPECT_EQ(g->teeth, 20) << DescribeGear(*g);
  EXPECT_FALSE(g->internal);
  // What its designer chose: a herringbone of module 1 mm, 20 degrees, 30 degree helices (its
  // tips lie on 20 x 1 / cos 30 / 2 + 1 = 12.547 mm), 12 mm wide on a 7 mm bore.
  EXPECT_TRUE(g->herringbone);
  EXPECT_NEAR(g->module_mm, 1.0, 0.01);
  EXPECT_NEAR(g->pressure_angle_rad, 20 * kDeg, 0.01 * 20 * kDeg);
  EXPECT_NEAR(std::abs(g->helix_angle_rad), 30 * kDeg, 0.01 * 30 * kDeg);
  EXPECT_NEAR(g->face_width_mm, 12.0, 0.01);
  EXPECT_NEAR(g->bore_diameter_mm, 7.0, 0.02);
  EXPECT_LT(g->involute_deviation_mm, 0.01);
  EXPECT_NEAR(2 * g->tip_radius_mm, 25.09, 0.01);
}

// A gear somebody else drew: Onshape's "Spur gear (25 teeth)" in the microscope assembly.
TEST(GearRecognition, TheOnshapeMicroscopesSpurGear) {
  CADSYNTH_REQUIRE_DATA(file, "step/assemblies/digital_microscope_onshape.step");
  const Assembly a = ImportCad(file, ImportOptions{});
  int gears = 0;
  for (const Part& part : a.parts) {
    const std::optional<RecognizedGear> g =
        RecognizePartGear(part, DetectSymmetries(part.mesh, PartSymmetryOptions(part)));
    if (!g) continue;
    ++gears;
    EXPECT_EQ(part.name, "Spur gear (25 teeth)");
    EXPECT_EQ(g->teeth, 25);
    EXPECT_NEAR(g->module_mm, 2.0, 0.02);
    EXPECT_NEAR(g->pressure_angle_rad, 20 * kDeg, 0.2 * kDeg);
    EXPECT_EQ(g->helix_angle_rad, 0.0);
    EXPECT_NEAR(g->face_width_mm, 10.0, 0.01);
    EXPECT_LT(g->involute_deviation_mm, 0.01);
  }
  EXPECT_EQ(gears, 1);  // the other five parts are not gears
}

}  // namespace
}  // namespace cadsynth
