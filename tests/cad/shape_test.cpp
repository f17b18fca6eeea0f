#include "cad/shape.h"

#include <gtest/gtest.h>

#include <BRep_Builder.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Shell.hxx>
#include <TopoDS_Solid.hxx>

#include "cad/core/error.h"
#include "cad/mesh_analysis.h"
#include "cad/occt_shape.h"

namespace cadsynth {
namespace {

TEST(Shape, BoxTessellatesToTwelveOutwardTriangles) {
  const Mesh mesh = Tessellate(MakeBox(40, 30, 20), TessellationOptions{});
  EXPECT_EQ(mesh.num_triangles(), 12u);
  EXPECT_NEAR(mesh.SurfaceArea(), 2 * (40 * 30 + 30 * 20 + 40 * 20), 1e-6);
  const Eigen::Vector3f centre(20, 15, 10);
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3f a = mesh.positions[t[0]], b = mesh.positions[t[1]],
                          c = mesh.positions[t[2]];
    const Eigen::Vector3f n = (b - a).cross(c - a);
    EXPECT_GT(n.dot((a + b + c) / 3 - centre), 0.0f) << "triangle winds inward";
    for (int i = 0; i < 3; ++i) EXPECT_GT(mesh.normals[t[i]].dot(n), 0.0f);
  }
  ASSERT_EQ(mesh.face_ids.size(), 12u);
  EXPECT_EQ(*std::max_element(mesh.face_ids.begin(), mesh.face_ids.end()), 5u);
}

TEST(Shape, SphereVerticesLieOnTheSphere) {
  const double r = 25.0;
  const Mesh mesh = Tessellate(MakeSphere(r), TessellationOptions{0.05, 0.3});
  ASSERT_GT(mesh.num_vertices(), 100u);
  for (size_t i = 0; i < mesh.num_vertices(); ++i) {
    const Eigen::Vector3f& p = mesh.positions[i];
    EXPECT_NEAR(p.norm(), r, 1e-4);
    EXPECT_GT(mesh.normals[i].dot(p.normalized()), 0.999f);  // exact surface normal, outward
  }
  // Chords lie inside the sphere by at most the deflection: area slightly below 4 pi r^2.
  EXPECT_LT(mesh.SurfaceArea(), 4 * M_PI * r * r);
  EXPECT_GT(mesh.SurfaceArea(), 4 * M_PI * (r - 0.05) * (r - 0.05));
}

TEST(Shape, MeasuredDeviationStaysWithinTheDeflection) {
  // A sphere's chords stray from the surface by the sagitta; the measured maximum must be below
  // the requested deflection but of its order, and zero for a box.
  for (double deflection : {0.5, 0.05}) {
    double deviation = -1;
    Tessellate(MakeSphere(30), TessellationOptions{deflection, 0.5}, &deviation);
    EXPECT_LE(deviation, deflection * 1.05) << deflection;
    EXPECT_GE(deviation, deflection * 0.2) << deflection;
  }
  double deviation = -1;
  Tessellate(MakeBox(10, 20, 30), TessellationOptions{}, &deviation);
  EXPECT_NEAR(deviation, 0.0, 1e-9);
  TessellationOptions measured;
  measured.measure_deviation = true;
  EXPECT_GE(MakePart("c", MakeCylinder(10, 10), measured).max_deviation_mm, 0.0);
  EXPECT_LT(MakePart("c", MakeCylinder(10, 10), TessellationOptions{}).max_deviation_mm, 0.0);
}

TEST(Shape, MassPropertiesAreExact) {
  const MassProperties box = ComputeMassProperties(MakeBox(40, 30, 20));
  EXPECT_NEAR(box.volume_mm3, 24000.0, 1e-6);
  EXPECT_TRUE(box.center_of_mass.isApprox(Eigen::Vector3d(20, 15, 10), 1e-9));
  // Ixx of a box about its centre: m (b^2 + c^2) / 12 with m = volume.
  EXPECT_NEAR(box.inertia(0, 0), 24000.0 * (30 * 30 + 20 * 20) / 12.0, 1e-3);
  const MassProperties cyl = ComputeMassProperties(MakeCylinder(10, 50));
  EXPECT_NEAR(cyl.volume_mm3, M_PI * 100 * 50, 1e-6);
  EXPECT_NEAR(cyl.center_of_mass.z(), 25.0, 1e-9);
}

TEST(Shape, MakePartMovesToTheBoundingBoxCentre) {
  const Eigen::Isometry3d moved = Eigen::Translation3d(100, -50, 7) * Eigen::Isometry3d::Identity();
  const Part part =
      MakePart("brick", Transformed(MakeBox(40, 30, 20), moved), TessellationOptions{});
  EXPECT_EQ(part.name, "brick");
  EXPECT_TRUE(part.cad_from_model.translation().isApprox(Eigen::Vector3d(120, -35, 17), 1e-9));
  EXPECT_TRUE(part.mesh.Bounds().center().isZero(1e-6));
  EXPECT_TRUE(part.mass.center_of_mass.isZero(1e-9));  // a box's centroid is its box centre
  EXPECT_TRUE(part.mass_from_brep);
}

TEST(Shape, HugePartsGetACoarserDeflectionAndAWarning) {
  static std::vector<std::string> warnings;
  warnings.clear();
  const WarningSink previous = SetWarningSink([](const std::string& m) { warnings.push_back(m); });
  // A 20 m cylinder: the floor is 1e-5 of its 34.6 m box diagonal, 0.346 mm, above the 0.1 asked.
  const Part huge =
      MakePart("tank", MakeCylinder(10000.0, 20000.0), TessellationOptions{0.1, 0.35});
  SetWarningSink(previous);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("part 'tank' is 34.6 m across; tessellated with 0.346 mm"),
            std::string::npos)
      << warnings[0];
  // Rim chords 2 sqrt(2 r s) ~ 166 mm: about 2 pi r / 166 ~ 380 segments, not 1,000s.
  EXPECT_LT(huge.mesh.num_triangles(), 4 * 600u);
  EXPECT_GT(huge.mesh.num_triangles(), 4 * 300u);
}

TEST(Shape, HealRepairsAFlippedFaceAndLeavesValidShapesAlone) {
  bool healed = true;
  const Shape box = MakeBox(40, 30, 20);
  EXPECT_EQ(&Heal(box, &healed).impl(), &box.impl());
  EXPECT_FALSE(healed);

  // The box's six faces sewn into a shell with one face turned inside out.
  TopoDS_Shell shell;
  BRep_Builder builder;
  builder.MakeShell(shell);
  int index = 0;
  for (TopExp_Explorer it(OcctShape(box), TopAbs_FACE); it.More(); it.Next(), ++index) {
    builder.Add(shell, index == 2 ? it.Current().Reversed() : it.Current());
  }
  TopoDS_Solid solid;
  builder.MakeSolid(solid);
  builder.Add(solid, shell);
  const Shape broken = WrapShape(solid);
  EXPECT_FALSE(AnalyzeTopology(Tessellate(broken, TessellationOptions{})).watertight());
  const Shape repaired = Heal(broken, &healed);
  EXPECT_TRUE(healed);
  EXPECT_TRUE(AnalyzeTopology(Tessellate(repaired, TessellationOptions{})).watertight());
  EXPECT_NEAR(ComputeMassProperties(repaired).volume_mm3, 24000.0, 1e-6);
}

TEST(Shape, RejectsImpossibleInput) {
  EXPECT_THROW(MakeBox(0, 1, 1), Error);
  EXPECT_THROW(MakeCylinder(-1, 1), Error);
  EXPECT_THROW(Tessellate(MakeBox(1, 1, 1), TessellationOptions{0.0, 0.3}), Error);
  EXPECT_THROW(Tessellate(MakeBox(1, 1, 1), TessellationOptions{0.1, 4.0}), Error);
  EXPECT_THROW(Tessellate(Shape(), TessellationOptions{}), Error);
  std::string why;
  EXPECT_FALSE((TessellationOptions{-1.0, 0.3}).Check(&why));
  EXPECT_NE(why.find("linear_deflection"), std::string::npos);
}

}  // namespace
}  // namespace cadsynth
