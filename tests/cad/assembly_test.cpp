#include "cad/assembly.h"

#include <gtest/gtest.h>

#include "cad/core/error.h"
#include "cad/shape.h"
#include "variants/gear.h"

namespace cadsynth {
namespace {

const TessellationOptions kFine{0.05, 0.3};

// The mesh of `shape` after moving the B-rep (so the tessellation is made anew), in its model
// frame.
Mesh Remeshed(const Shape& shape, const Eigen::Isometry3d& motion) {
  return MakePart("p", Transformed(shape, motion), kFine).mesh;
}

// Largest distance from the vertices of `b` moved by `t` to the nearest vertex of `a` (a crude
// but independent check: vertices of fine meshes of one surface are close).
double VertexGap(const Mesh& a, const Mesh& b, const Eigen::Isometry3d& t, double min_radius = 0) {
  double worst = 0;
  for (const auto& p : b.positions) {
    if (p.head<2>().norm() < min_radius) continue;
    const Eigen::Vector3d q = t * p.cast<double>();
    double best = 1e300;
    for (const auto& r : a.positions) best = std::min(best, (r.cast<double>() - q).norm());
    worst = std::max(worst, best);
  }
  return worst;
}

TEST(FindCongruence, BoxInAnyOrientation) {
  const Shape box = MakeBox(40, 30, 20);
  const Mesh a = Remeshed(box, Eigen::Isometry3d::Identity());
  const Eigen::Isometry3d turn(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()));
  const Mesh b = Remeshed(box, turn);
  const auto t = FindCongruence(a, b, 0.11);
  ASSERT_TRUE(t);
  EXPECT_LT(VertexGap(a, b, *t), 1e-3);  // box corners land on box corners
}

TEST(FindCongruence, CylinderTurnedAboutItsAxisMovesItsSeam) {
  const Shape cylinder = MakeCylinder(20, 50);
  const Mesh a = Remeshed(cylinder, Eigen::Isometry3d::Identity());
  const Mesh b =
      Remeshed(cylinder, Eigen::Isometry3d(Eigen::AngleAxisd(0.645, Eigen::Vector3d::UnitZ())));
  EXPECT_NE(a.positions, b.positions);
  EXPECT_TRUE(FindCongruence(a, b, 0.11));
}

TEST(FindCongruence, GearRecoversTheTurnModuloOneTooth) {
  GearOptions options;
  options.teeth = 20;  // 18 degrees apart
  options.module_mm = 3.0;
  options.bore_diameter_mm = 12.0;
  const Shape gear = MakeGear(options);
  const Mesh a = Remeshed(gear, Eigen::Isometry3d::Identity());
  const double turn = 7.0 * M_PI / 180.0;
  const Mesh b =
      Remeshed(gear, Eigen::Isometry3d(Eigen::AngleAxisd(turn, Eigen::Vector3d::UnitZ())));
  const auto t = FindCongruence(a, b, 0.11);
  ASSERT_TRUE(t);
  // b is a turned by 7 degrees (both model frames sit on the axis), so t * turn must be one of
  // the gear's symmetries (a multiple of 18 degrees about z, or a flip): it maps a's outline
  // vertices onto a's outline vertices. (The bore's circle is divided independently of the teeth,
  // so only vertices beyond 20 mm, the toothed outline, are compared.)
  const Eigen::Isometry3d symmetry = *t * Eigen::AngleAxisd(turn, Eigen::Vector3d::UnitZ());
  EXPECT_LT(VertexGap(a, a, symmetry, 20.0), 0.02);
  EXPECT_GT(
      VertexGap(a, a, Eigen::Isometry3d(Eigen::AngleAxisd(turn, Eigen::Vector3d::UnitZ())), 20.0),
      1.0);
}

TEST(FindCongruence, DifferentAndMirroredShapesAreNot) {
  const Mesh a = Remeshed(MakeBox(40, 30, 20), Eigen::Isometry3d::Identity());
  EXPECT_FALSE(
      FindCongruence(a, Remeshed(MakeBox(40, 30, 21), Eigen::Isometry3d::Identity()), 0.11));
  // A corner of three bars of different lengths along x, y and z is chiral: its mirror image has
  // the same moments, but no rotation maps one onto the other.
  Mesh l = Tessellate(MakeBox(40, 10, 10), kFine);
  Mesh leg = Tessellate(MakeBox(10, 25, 10), kFine);
  leg.Transform(Eigen::Isometry3d(Eigen::Translation3d(0, 10, 0)));
  l.Append(leg);
  Mesh post = Tessellate(MakeBox(10, 10, 15), kFine);
  post.Transform(Eigen::Isometry3d(Eigen::Translation3d(0, 0, 10)));
  l.Append(post);
  Mesh mirrored = l;
  for (auto& p : mirrored.positions) p.x() = -p.x();
  for (auto& t : mirrored.triangles) std::swap(t[1], t[2]);
  EXPECT_TRUE(FindCongruence(l, l, 0.01));
  EXPECT_FALSE(FindCongruence(l, mirrored, 0.11));
}

TEST(MergeIdenticalParts, CopiesBecomeInstancesAndStayWhereTheyWere) {
  const Shape box = MakeBox(40, 30, 20);
  const Eigen::Isometry3d turn(Eigen::AngleAxisd(1.1, Eigen::Vector3d(0, 1, 1).normalized()));
  Assembly assembly;
  assembly.parts = {MakePart("box", box, kFine), MakePart("cyl", MakeCylinder(10, 30), kFine),
                    MakePart("box copy", Transformed(box, turn), kFine)};
  for (int i = 0; i < 3; ++i) {
    assembly.instances.push_back(
        {i, std::string("i").append(std::to_string(i)),
         Eigen::Translation3d(100.0 * i, 0, 0) * assembly.parts[i].cad_from_model});
  }
  std::vector<Eigen::AlignedBox3d> before;
  for (const Instance& i : assembly.instances)
    before.push_back(assembly.parts[i.part].mesh.Bounds(i.world_from_model));

  EXPECT_EQ(MergeIdenticalParts(&assembly, 0.11), 1u);
  ASSERT_EQ(assembly.parts.size(), 2u);
  EXPECT_EQ(assembly.parts[0].name, "box");
  EXPECT_EQ(assembly.instances[2].part, 0);
  for (size_t k = 0; k < 3; ++k) {
    const Instance& i = assembly.instances[k];
    const Eigen::AlignedBox3d after = assembly.parts[i.part].mesh.Bounds(i.world_from_model);
    EXPECT_TRUE(after.min().isApprox(before[k].min(), 1e-3) ||
                (after.min() - before[k].min()).norm() < 0.1)
        << k;
    EXPECT_LT((after.max() - before[k].max()).norm(), 0.1) << k;
  }
}

TEST(MergeIdenticalParts, ExactVolumesKeepNearTwinsApart) {
  // Two discs whose holes differ by 0.1 mm in radius: within the mesh tolerance, but not the same.
  Assembly assembly;
  assembly.parts = {MakePart("sun", MakeCylinder(20, 10), kFine),
                    MakePart("planet", MakeCylinder(20, 10), kFine)};
  assembly.parts[1].mass.volume_mm3 *= 1.001;  // as if its bore were wider
  assembly.instances = {{0, "a", assembly.parts[0].cad_from_model},
                        {1, "b", assembly.parts[1].cad_from_model}};
  EXPECT_EQ(MergeIdenticalParts(&assembly, 0.21), 0u);
  assembly.parts[1].mass_from_brep = false;  // a mesh: only the geometry can tell
  EXPECT_EQ(MergeIdenticalParts(&assembly, 0.21), 1u);
}

TEST(FuseAssembly, OneRigidPartWithCombinedMass) {
  Assembly assembly;
  assembly.name = "pair";
  assembly.parts = {MakePart("a", MakeBox(10, 10, 10), kFine)};
  assembly.instances = {{0, "left", Eigen::Isometry3d(Eigen::Translation3d(0, 0, 5))},
                        {0, "right", Eigen::Isometry3d(Eigen::Translation3d(30, 0, 5))}};
  const Assembly fused = FuseAssembly(assembly);
  ASSERT_EQ(fused.parts.size(), 1u);
  ASSERT_EQ(fused.instances.size(), 1u);
  const Part& p = fused.parts[0];
  EXPECT_EQ(p.name, "pair");
  EXPECT_NEAR(p.mass.volume_mm3, 2000.0, 1e-6);
  EXPECT_TRUE(p.mass.center_of_mass.isZero(1e-9));  // symmetric pair, model frame at the box centre
  // Izz: two cubes (each V (a^2 + a^2) / 12) plus V d^2 each at d = 15 mm from the middle.
  EXPECT_NEAR(p.mass.inertia(2, 2), 2 * (1000.0 * 200.0 / 12.0 + 1000.0 * 225.0), 1e-6);
  EXPECT_TRUE(p.mesh.Bounds().sizes().isApprox(Eigen::Vector3d(40, 10, 10), 1e-6));
  EXPECT_TRUE(
      fused.instances[0].world_from_model.translation().isApprox(Eigen::Vector3d(15, 0, 5), 1e-9));
  EXPECT_THROW(FuseAssembly(Assembly{}), Error);
}

}  // namespace
}  // namespace cadsynth
