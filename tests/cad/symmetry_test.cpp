// Symmetry detection against answers known by construction: boxes, a cylinder, and the families'
// own parts, whose declared symmetries the detector must find again from the mesh alone.
#include "cad/symmetry.h"

#include <cmath>

#include <gtest/gtest.h>

#include "cad/error.h"
#include "cad/shape.h"
#include "variants/families.h"

namespace cadsynth {
namespace {

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
      // A helical gear keeps its half-turns about radial axes (a helix does: a rotation keeps its
      // hand), though the family declares only its 20 turns.
      {"spur_gear", {{"teeth", 20.0}, {"helix_angle", 0.3}}, 39, 20},
  };
  for (const Case& c : cases) {
    const Part part = FamilyPart(c.family, c.values);
    const DetectedSymmetries d = DetectSymmetries(part.mesh);
    ExpectWithinTolerance(d);
    EXPECT_TRUE(d.symmetries.continuous.empty()) << c.family;
    EXPECT_EQ(d.symmetries.discrete.size(), c.discrete) << c.family;
    if (!c.values.count("helix_angle"))
      EXPECT_EQ(d.symmetries.discrete.size(), part.symmetries.discrete.size()) << c.family;
    ASSERT_FALSE(d.axes.empty());
    EXPECT_EQ(d.axes[0].order, c.order) << c.family;
  }
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
