#include "cad/mesh_analysis.h"

#include <gtest/gtest.h>

#include "cad/shape.h"

namespace cadsynth {
namespace {

TEST(MeshTopology, TessellatedSolidsAreWatertight) {
  const std::pair<const char*, Shape> shapes[] = {
      {"box", MakeBox(40, 30, 20)}, {"cylinder", MakeCylinder(10, 50)}, {"sphere", MakeSphere(15)}};
  for (const auto& [name, shape] : shapes) {
    const MeshTopology t = AnalyzeTopology(Tessellate(shape, TessellationOptions{0.05, 0.3}));
    EXPECT_TRUE(t.watertight()) << name << ": " << t.boundary_edges << " " << t.non_manifold_edges
                                << " " << t.misoriented_edges;
  }
}

TEST(MeshTopology, FindsHolesAndFlippedTriangles) {
  Mesh box = Tessellate(MakeBox(1, 1, 1), TessellationOptions{});
  Mesh open = box;
  open.triangles.pop_back();  // a hole of one triangle: three boundary edges
  EXPECT_EQ(AnalyzeTopology(open).boundary_edges, 3u);
  EXPECT_FALSE(AnalyzeTopology(open).watertight());
  Mesh flipped = box;
  std::swap(flipped.triangles[0][1], flipped.triangles[0][2]);
  EXPECT_EQ(AnalyzeTopology(flipped).misoriented_edges, 3u);
  EXPECT_EQ(AnalyzeTopology(box).edges, 18u);  // 12 cube edges + 6 face diagonals
}

TEST(MeshMassProperties, BoxMatchesTheClosedForm) {
  Mesh box = Tessellate(MakeBox(40, 30, 20), TessellationOptions{});
  box.Transform(Eigen::Translation3d(5, 6, 7) * Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()));
  const MassProperties m = ComputeMeshMassProperties(box);
  // Positions are floats: expect agreement to about 1e-7 relative.
  EXPECT_NEAR(m.volume_mm3, 24000.0, 24000.0 * 1e-7);
  const Eigen::Vector3d com = Eigen::Translation3d(5, 6, 7) *
                              Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()) *
                              Eigen::Vector3d(20, 15, 10);
  EXPECT_TRUE(m.center_of_mass.isApprox(com, 1e-6));
  // Izz is invariant under rotation about z: V (a^2 + b^2) / 12.
  EXPECT_NEAR(m.inertia(2, 2), 24000.0 * (40 * 40 + 30 * 30) / 12.0, 5e6 * 1e-6);
  const MassProperties exact = ComputeMassProperties(MakeBox(40, 30, 20));
  EXPECT_NEAR(m.inertia.trace(), exact.inertia.trace(), exact.inertia.trace() * 1e-6);
}

TEST(MeshMassProperties, FineCylinderApproachesTheBrep) {
  const Mesh mesh = Tessellate(MakeCylinder(10, 50), TessellationOptions{0.001, 0.05});
  EXPECT_NEAR(ComputeMeshMassProperties(mesh).volume_mm3, M_PI * 100 * 50, M_PI * 100 * 50 * 2e-4);
}

}  // namespace
}  // namespace cadsynth
