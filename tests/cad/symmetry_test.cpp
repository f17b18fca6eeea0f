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

TEST(Symmetry, BadInputIsRefused) {
  EXPECT_THROW(DetectSymmetries(Mesh{}), Error);
  const Part box = MakePart("box", MakeBox(10, 10, 10), TessellationOptions{});
  SymmetryOptions o;
  o.max_order = 1;
  EXPECT_THROW(DetectSymmetries(box.mesh, o), Error);
}

}  // namespace
}  // namespace cadsynth
