// Symmetry detection against answers known by construction: boxes, a cylinder, and the families'
// own parts, whose declared symmetries the detector must find again from the mesh alone.
#include "cad/symmetry.h"

#include <cmath>

#include <gtest/gtest.h>
#include <BRepFilletAPI_MakeChamfer.hxx>
#include <BRep_Tool.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>

#include "cad/core/error.h"
#include "cad/import.h"
#include "cad/occt_shape.h"
#include "cad/shape.h"
#include "cad/step.h"
#include "tests/test_support.h"
#include "variants/families.h"

namespace cadsynth {
namespace {

// Whether a and b move the corners of `box` to within `within` of each other.
bool Same(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, const Eigen::AlignedBox3d& box,
          double within) {
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d p = box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c));
    if ((a * p - b * p).norm() > within) return false;
  }
  return true;
}

// Every product of two members (and each member) is a member: the set is a group.
void ExpectClosed(const std::vector<Eigen::Isometry3d>& members, const Eigen::AlignedBox3d& box,
                  double within) {
  std::vector<Eigen::Isometry3d> all = members;
  all.push_back(Eigen::Isometry3d::Identity());
  for (const Eigen::Isometry3d& a : all) {
    for (const Eigen::Isometry3d& b : all) {
      bool found = false;
      for (const Eigen::Isometry3d& c : all) found = found || Same(a * b, c, box, within);
      EXPECT_TRUE(found);
    }
  }
}

void ExpectWithinTolerance(const DetectedSymmetries& d) {
  ASSERT_EQ(d.discrete_deviation_mm.size(), d.symmetries.discrete.size());
  for (double deviation : d.discrete_deviation_mm) EXPECT_LE(deviation, d.tolerance_mm);
  for (double deviation : d.continuous_deviation_mm) EXPECT_LE(deviation, d.tolerance_mm);
}

TEST(Symmetry, ABox60x40x30HasTheThreeHalfTurns) {
  const Part box = MakePart("box", MakeBox(60, 40, 30), TessellationOptions{});
  const DetectedSymmetries d = DetectSymmetries(box.mesh);
  ExpectWithinTolerance(d);
  EXPECT_TRUE(d.symmetries.continuous.empty());
  ASSERT_EQ(d.symmetries.discrete.size(), 3u);
  for (const Eigen::Isometry3d& t : d.symmetries.discrete) {
    // A half-turn about x, y or z: a diagonal rotation with two -1s, about the origin.
    EXPECT_NEAR((t.linear().cwiseAbs() - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-6);
    EXPECT_NEAR(t.linear().trace(), -1.0, 1e-6);
    EXPECT_NEAR(t.translation().norm(), 0.0, 1e-6);
  }
}

TEST(Symmetry, ABumpOnOneCornerBreaksThemAll) {
  Part box = MakePart("box", MakeBox(60, 40, 30), TessellationOptions{});
  Mesh bump = MakePart("bump", MakeBox(4, 4, 4), TessellationOptions{}).mesh;
  bump.Transform(Eigen::Isometry3d(Eigen::Translation3d(28, 18, 13)));
  box.mesh.Append(bump);
  const DetectedSymmetries d = DetectSymmetries(box.mesh);
  EXPECT_TRUE(d.symmetries.empty()) << d.symmetries.discrete.size();
}

TEST(Symmetry, ACylinderTurnsFreelyAndFlips) {
  const Part rod = MakePart("rod", MakeCylinder(15, 40), TessellationOptions{0.01, 0.1});
  const DetectedSymmetries d = DetectSymmetries(rod.mesh);
  ExpectWithinTolerance(d);
  ASSERT_EQ(d.symmetries.continuous.size(), 1u);
  EXPECT_NEAR(std::abs(d.symmetries.continuous[0].direction.z()), 1.0, 1e-6);
  ASSERT_EQ(d.symmetries.discrete.size(), 1u);  // one flip: the rotations make the others
  EXPECT_NEAR((d.symmetries.discrete[0].linear() * Eigen::Vector3d::UnitZ()).z(), -1.0, 1e-6);
}

// The family's default part, with the named parameters changed.
Part FamilyPart(const std::string& name, const ParamValues& values) {
  const FamilyInfo& family = *FindFamily(name);
  return BuildVariant(family, CompleteParams(family, values), ImportOptions{}).parts.at(0);
}

TEST(Symmetry, FamilyPartsGetTheirDeclaredSymmetriesBack) {
  struct Case {
    std::string family;
    ParamValues values;
    size_t discrete;  // the declared group's size less the identity
    int order;
  };
  const Case cases[] = {
      {"hex_nut", {}, 11, 6},                    // 6 turns and 6 flips
      {"spur_gear", {{"teeth", 17.0}}, 33, 17},  // 17 turns and 17 flips
      // A helical gear keeps its half-turns about radial axes (a rotation keeps a helix's hand),
      // turned by the twist at mid-face.
      {"spur_gear", {{"teeth", 20.0}, {"helix_angle", 0.3}}, 39, 20},
      // With a hub it can no longer be turned over.
      {"spur_gear",
       {{"teeth", 20.0}, {"helix_angle", 0.3}, {"hub_diameter", 20.0}, {"hub_length", 8.0}},
       19,
       20},
  };
  for (const Case& c : cases) {
    const Part part = FamilyPart(c.family, c.values);
    const DetectedSymmetries d = DetectSymmetries(part.mesh);
    ExpectWithinTolerance(d);
    EXPECT_TRUE(d.symmetries.continuous.empty()) << c.family;
    EXPECT_EQ(d.symmetries.discrete.size(), c.discrete) << c.family;
    EXPECT_EQ(d.symmetries.discrete.size(), part.symmetries.discrete.size()) << c.family;
    ASSERT_FALSE(d.axes.empty());
    EXPECT_EQ(d.axes[0].order, c.order) << c.family;
    const Eigen::AlignedBox3d box = part.mesh.Bounds().cast<double>();
    ExpectClosed(d.symmetries.discrete, box, d.tolerance_mm);
    // Each declared symmetry is one found (the same motion of the part's box corners).
    for (const Eigen::Isometry3d& declared : part.symmetries.discrete) {
      bool found = false;
      for (const Eigen::Isometry3d& t : d.symmetries.discrete)
        found = found || Same(declared, t, box, d.tolerance_mm);
      EXPECT_TRUE(found) << c.family;
    }
  }
}

// Fewer surface points (1,500): the same answers on these parts, a quarter of the time under the
// sanitizers.
SymmetryOptions Sparse(SymmetryOptions o) {
  o.max_points = 1500;
  return o;
}

// Every symmetry a family declares maps its default part's mesh onto itself within the default
// tolerance, and its B-rep's surfaces onto each other: measured, not assumed.
TEST(Symmetry, EveryFamilysDeclaredSymmetriesAreMeasuredToHold) {
  int measured = 0;
  for (const FamilyInfo& family : Families()) {
    if (family.name == "scaled" || family.name == "from_file") continue;
    const Assembly a = BuildVariant(family, CompleteParams(family, {}), ImportOptions{});
    for (const Part& part : a.parts) {
      if (part.symmetries.empty()) continue;
      DetectedSymmetries d =
          MeasureSymmetries(part.mesh, part.symmetries, Sparse(PartSymmetryOptions(part)));
      ExpectWithinTolerance(d);
      CompareBrepFaces(part, &d);
      ASSERT_EQ(d.discrete_brep_mm.size(), d.symmetries.discrete.size()) << family.name;
      ASSERT_EQ(d.continuous_brep_mm.size(), d.symmetries.continuous.size()) << family.name;
      EXPECT_EQ(d.brep_faces_not_compared, 0) << family.name << " " << part.name;
      for (double v : d.discrete_brep_mm) EXPECT_LT(v, 1e-6) << family.name << " " << part.name;
      for (double v : d.continuous_brep_mm) EXPECT_LT(v, 1e-6) << family.name << " " << part.name;
      ++measured;
    }
  }
  EXPECT_GE(measured, 15);
}

TEST(Symmetry, AnswersDoNotDependOnEarlierCalls) {
  // Found once by valgrind: an uninitialised Eigen vector made a box's answer depend on what had
  // been detected before. The same mesh before and after another gives the same bytes.
  const Part box = MakePart("box", MakeBox(30, 24, 6), TessellationOptions{});
  const Part rod = MakePart("rod", MakeCylinder(15, 40), TessellationOptions{});
  const DetectedSymmetries first = DetectSymmetries(box.mesh);
  DetectSymmetries(rod.mesh);
  const DetectedSymmetries again = DetectSymmetries(box.mesh);
  ASSERT_EQ(first.symmetries.discrete.size(), 3u);
  ASSERT_EQ(again.symmetries.discrete.size(), first.symmetries.discrete.size());
  for (size_t i = 0; i < first.symmetries.discrete.size(); ++i)
    EXPECT_EQ(first.symmetries.discrete[i].matrix(), again.symmetries.discrete[i].matrix());
}

// The half-turns in `found`, and whether the n-fold turn about the main axis is there.
size_t Flips(const DetectedSymmetries& d) {
  size_t flips = 0;
  const Eigen::Vector3d a = d.axes.at(0).direction;
  for (const Eigen::Isometry3d& t : d.symmetries.discrete) flips += (t.linear() * a).dot(a) < -0.5;
  return flips;
}

TEST(Symmetry, FamilyPartsWrittenToStepAndReadBackKeepTheirSymmetries) {
  // The known answers, through a STEP file: the symmetries come from the B-rep's axes of
  // revolution and the mesh read back, nothing of the family survives the file.
  struct Case {
    std::string family;
    ParamValues values;
    int order;     // main axis: n-fold, 0 continuous
    size_t flips;  // half-turns turning it over
  };
  const Case cases[] = {
      {"spur_gear", {{"teeth", 23.0}}, 23, 23},
      {"spur_gear", {{"teeth", 25.0}, {"module", 1.5}, {"bore", 10.0}}, 25, 25},
      {"spur_gear", {{"teeth", 20.0}, {"helix_angle", 0.3}}, 20, 20},
      {"spur_gear",
       {{"teeth", 20.0}, {"helix_angle", 0.3}, {"hub_diameter", 20.0}, {"hub_length", 8.0}},
       20,
       0},
      {"hex_nut", {}, 6, 6},
      {"washer", {}, 0, 1},
  };
  testing::ScratchDir dir;
  for (const Case& c : cases) {
    const FamilyInfo& family = *FindFamily(c.family);
    const ShapeAssembly shapes = BuildVariantShapes(family, CompleteParams(family, c.values));
    const std::filesystem::path file = dir.path() / (c.family + ".step");
    WriteStep(file, c.family, {StepComponent{c.family, shapes.components.at(0).shape}});
    ImportOptions import;
    import.tessellation = TessellationOptions{0.03, 0.3};
    const Assembly back = ImportCad(file, import);
    ASSERT_EQ(back.parts.size(), 1u) << c.family;
    const Part& part = back.parts[0];
    ASSERT_TRUE(part.symmetries.empty()) << "a STEP file carries no symmetries";
    const DetectedSymmetries d = DetectSymmetries(part.mesh, PartSymmetryOptions(part));
    ExpectWithinTolerance(d);
    ASSERT_FALSE(d.axes.empty()) << c.family;
    EXPECT_EQ(d.axes[0].order, c.order) << c.family << ": " << DescribeSymmetries(d);
    EXPECT_NEAR(std::abs(d.axes[0].direction.z()), 1.0, 1e-6) << c.family;
    EXPECT_EQ(Flips(d), c.flips) << c.family << ": " << DescribeSymmetries(d);
    if (c.order == 0) {
      EXPECT_EQ(d.symmetries.continuous.size(), 1u);
    } else {
      EXPECT_EQ(d.symmetries.discrete.size(), c.order - 1 + c.flips) << c.family;
    }
    // On the exact B-rep every surface finds its partner (to the mesh's refined angles).
    DetectedSymmetries exact = d;
    CompareBrepFaces(part, &exact);
    ASSERT_EQ(exact.discrete_brep_mm.size(), d.symmetries.discrete.size());
    ASSERT_EQ(exact.continuous_brep_mm.size(), d.symmetries.continuous.size());
    for (double v : exact.discrete_brep_mm) EXPECT_LT(v, 0.05) << c.family;
    for (double v : exact.continuous_brep_mm) EXPECT_LT(v, 0.05) << c.family;
    EXPECT_EQ(exact.brep_faces_not_compared, 0) << c.family;
  }
}

TEST(Symmetry, OneChamferedCornerBreaksThemOrShowsInTheDeviation) {
  // A 2 mm chamfer on one vertical edge of the 60 x 40 x 30 box.
  const Shape solid = MakeBox(60, 40, 30);
  const TopoDS_Shape& box = OcctShape(solid);
  TopTools_IndexedMapOfShape edges;
  TopExp::MapShapes(box, TopAbs_EDGE, edges);
  BRepFilletAPI_MakeChamfer chamfer(box);
  bool added = false;
  for (int i = 1; i <= edges.Extent() && !added; ++i) {
    TopoDS_Vertex a, b;
    TopExp::Vertices(TopoDS::Edge(edges(i)), a, b);
    const gp_Pnt p = BRep_Tool::Pnt(a), q = BRep_Tool::Pnt(b);
    if (std::abs(p.X() - 60) < 1e-6 && std::abs(q.X() - 60) < 1e-6 && std::abs(p.Y() - 40) < 1e-6 &&
        std::abs(q.Y() - 40) < 1e-6) {
      chamfer.Add(2.0, TopoDS::Edge(edges(i)));
      added = true;
    }
  }
  ASSERT_TRUE(added);
  const Part part = MakePart("chamfered", WrapShape(chamfer.Shape()), TessellationOptions{});
  EXPECT_TRUE(DetectSymmetries(part.mesh, PartSymmetryOptions(part)).symmetries.empty());
  // Within a 3 mm tolerance the three half-turns are back, each with the chamfer's deviation:
  // its corner point moved onto the sharp corner lies 2 / sqrt(2) mm from the chamfer face.
  const DetectedSymmetries loose = DetectSymmetries(part.mesh, PartSymmetryOptions(part, 3.0));
  ASSERT_EQ(loose.symmetries.discrete.size(), 3u) << DescribeSymmetries(loose);
  size_t broken = 0;
  for (double deviation : loose.discrete_deviation_mm) {
    EXPECT_LE(deviation, std::sqrt(2.0) + 0.05);
    broken += deviation > 1.0;
  }
  // The half-turn about z moves the chamfered edge onto the sharp one diagonally opposite; the
  // other two move it onto edges as well: all three see it.
  EXPECT_EQ(broken, 3u);
  // On the B-rep the chamfer's plane has no partner under any of them: named, not measured.
  DetectedSymmetries exact = loose;
  CompareBrepFaces(part, &exact);
  ASSERT_EQ(exact.discrete_brep_mm.size(), 3u);
  for (double v : exact.discrete_brep_mm) EXPECT_TRUE(std::isinf(v));
  EXPECT_NE(DescribeSymmetries(exact).find("some B-rep surfaces have no match"), std::string::npos);
  // The plain box's surfaces match exactly.
  const Part plain_box = MakePart("plain_box", MakeBox(60, 40, 30), TessellationOptions{});
  DetectedSymmetries plain = DetectSymmetries(plain_box.mesh, PartSymmetryOptions(plain_box));
  CompareBrepFaces(plain_box, &plain);
  ASSERT_EQ(plain.discrete_brep_mm.size(), 3u);
  for (double v : plain.discrete_brep_mm) EXPECT_LT(v, 1e-9);
}

TEST(Symmetry, TheEightCylindersOfEightCylStpTurnFreelyAndFlip) {
  CADSYNTH_REQUIRE_DATA(file, "step/assemblies/eight_cyl.stp");
  const Assembly a = ImportCad(file, ImportOptions{});
  ASSERT_EQ(a.parts.size(), 1u);
  const DetectedSymmetries d = DetectSymmetries(a.parts[0].mesh, PartSymmetryOptions(a.parts[0]));
  ExpectWithinTolerance(d);
  ASSERT_EQ(d.symmetries.continuous.size(), 1u) << DescribeSymmetries(d);
  ASSERT_EQ(d.symmetries.discrete.size(), 1u) << DescribeSymmetries(d);
  // The flip turns the axis over.
  const Eigen::Vector3d axis = d.symmetries.continuous[0].direction;
  EXPECT_NEAR((d.symmetries.discrete[0].linear() * axis).dot(axis), -1.0, 1e-6);
  // In the scene, each of the eight copies turns about its own axis.
  EXPECT_EQ(a.instances.size(), 8u);
}

TEST(Symmetry, RevolutionAxesAreTheBrepsExactAxes) {
  // A cylinder along z through (0, 0): one axis, exactly z.
  const std::vector<SymmetryOptions::Line> axes = RevolutionAxes(MakeCylinder(15, 40));
  ASSERT_EQ(axes.size(), 1u);
  EXPECT_NEAR(std::abs(axes[0].direction.z()), 1.0, 1e-12);
  EXPECT_NEAR(axes[0].point.head<2>().norm(), 0.0, 1e-12);
  EXPECT_TRUE(RevolutionAxes(MakeBox(1, 2, 3)).empty());
  EXPECT_TRUE(RevolutionAxes(Shape()).empty());
}

TEST(Symmetry, AListGivenByHandIsCompletedAndMeasured) {
  const Part box = MakePart("box", MakeBox(60, 40, 30), TessellationOptions{});
  // A half-turn about z and one about x through the box's centre make the third (about y).
  Symmetries given;
  given.discrete.push_back(Eigen::Isometry3d(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ())));
  given.discrete.push_back(Eigen::Isometry3d(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX())));
  const DetectedSymmetries d = MeasureSymmetries(box.mesh, given);
  ASSERT_EQ(d.symmetries.discrete.size(), 3u);
  for (double deviation : d.discrete_deviation_mm) EXPECT_LT(deviation, 1e-4);
  ASSERT_FALSE(d.axes.empty());
  EXPECT_EQ(d.axes[0].order, 2);
  // A quarter-turn about z does not hold: measured, the long side's end lands 10 mm outside.
  Symmetries wrong;
  wrong.discrete.push_back(
      Eigen::Isometry3d(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ())));
  const DetectedSymmetries w = MeasureSymmetries(box.mesh, wrong);
  ASSERT_EQ(w.symmetries.discrete.size(), 3u);  // quarter, half and three-quarter turns
  EXPECT_EQ(w.axes.at(0).order, 4);
  EXPECT_NEAR(w.discrete_deviation_mm[0], 10.0, 1e-3);
}

TEST(Symmetry, BadInputIsRefused) {
  EXPECT_THROW(DetectSymmetries(Mesh{}), Error);
  const Part box = MakePart("box", MakeBox(10, 10, 10), TessellationOptions{});
  SymmetryOptions o;
  o.max_order = 1;
  EXPECT_THROW(DetectSymmetries(box.mesh, o), Error);
}

}  // namespace
}  // namespace cadsynth
