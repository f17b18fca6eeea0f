#include "cad/mesh_analysis.h"

#include <cmath>

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

// A cube whose 8 corners are shared by all 12 triangles: at 30 degrees every edge is sharp, so
// each corner splits into 3 vertices, one per face, each with its face's normal.
TEST(CreaseNormals, SharedCubeCornersSplitPerFace) {
  Mesh cube;
  for (int i = 0; i < 8; ++i) cube.positions.emplace_back(i & 1, (i >> 1) & 1, (i >> 2) & 1);
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};  // outward quads
  for (const auto& q : faces) {
    cube.triangles.emplace_back(q[0], q[1], q[2]);
    cube.triangles.emplace_back(q[0], q[2], q[3]);
  }
  ComputeCreaseNormals(&cube, 30 * M_PI / 180);
  ASSERT_EQ(cube.positions.size(), 24u);
  ASSERT_EQ(cube.normals.size(), 24u);
  EXPECT_TRUE(AnalyzeTopology(cube).watertight());  // same positions: still closed
  for (const auto& t : cube.triangles) {
    const Eigen::Vector3f face = (cube.positions[t[1]] - cube.positions[t[0]])
                                     .cross(cube.positions[t[2]] - cube.positions[t[0]]);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(cube.normals[t[k]], face.normalized()) << t.transpose();
  }
  // At 100 degrees every edge is smooth: each corner's normal is the sum of its three faces'
  // (two triangles of each face at every corner but the quads' diagonals), pointing outward.
  Mesh smooth;
  for (int i = 0; i < 8; ++i) smooth.positions.emplace_back(i & 1, (i >> 1) & 1, (i >> 2) & 1);
  for (const auto& q : faces) {
    smooth.triangles.emplace_back(q[0], q[1], q[2]);
    smooth.triangles.emplace_back(q[0], q[2], q[3]);
  }
  ComputeCreaseNormals(&smooth, 100 * M_PI / 180);
  for (size_t v = 0; v < smooth.positions.size(); ++v) {
    const Eigen::Vector3f out =
        (smooth.positions[v] - Eigen::Vector3f::Constant(0.5f)).normalized();
    EXPECT_GT(smooth.normals[v].dot(out), 0.9f) << v;
    EXPECT_NEAR(smooth.normals[v].norm(), 1.0f, 1e-6f);
  }
}

// Two triangles folded by 10 degrees along a shared edge (unshared vertices, as STL stores them):
// within a 30-degree crease the edge's corners get the bisector; at 5 degrees they stay apart.
TEST(CreaseNormals, FoldWithinTheCreaseIsSmoothOutsideItSharp) {
  const double fold = 10 * M_PI / 180;
  const auto make = [&] {
    Mesh m;
    const Eigen::Vector3f a(0, 0, 0), b(0, 1, 0), c(-1, 0.5f, 0);
    const Eigen::Vector3f d(static_cast<float>(std::cos(fold)), 0.5f,
                            static_cast<float>(std::sin(fold)));
    m.positions = {a, c, b, a, b, d};
    m.triangles = {{0, 2, 1}, {3, 5, 4}};
    return m;
  };
  const Eigen::Vector3d n1(0, 0, 1);  // (b - a) x (c - a) for the first triangle
  const Eigen::Vector3d n2(-std::sin(fold), 0, std::cos(fold));  // (d - a) x (b - a), unit
  Mesh smooth = make();
  ComputeCreaseNormals(&smooth, 30 * M_PI / 180);
  const Eigen::Vector3f bisector = (n1 + n2).normalized().cast<float>();
  for (int v : {0, 2, 3, 4}) EXPECT_TRUE(smooth.normals[v].isApprox(bisector, 1e-6f)) << v;
  EXPECT_TRUE(smooth.normals[1].isApprox(n1.cast<float>(), 1e-6f));  // alone at its position
  EXPECT_TRUE(smooth.normals[5].isApprox(n2.cast<float>(), 1e-6f));
  Mesh sharp = make();
  ComputeCreaseNormals(&sharp, 5 * M_PI / 180);
  for (int v : {0, 1, 2}) EXPECT_TRUE(sharp.normals[v].isApprox(n1.cast<float>(), 1e-6f)) << v;
  for (int v : {3, 4, 5}) EXPECT_TRUE(sharp.normals[v].isApprox(n2.cast<float>(), 1e-6f)) << v;
}

// A degenerate triangle (zero area) takes its neighbours' normal instead of NaN.
TEST(CreaseNormals, DegenerateTriangleTakesItsNeighbours) {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  m.triangles = {{0, 1, 2}, {3, 4, 5}};
  ComputeCreaseNormals(&m, 30 * M_PI / 180);
  for (int v : {3, 4}) EXPECT_EQ(m.normals[v], Eigen::Vector3f(0, 0, 1)) << v;
  EXPECT_EQ(m.normals[5], Eigen::Vector3f(0, 0, 1));  // nothing else there: +z
  for (const auto& n : m.normals) EXPECT_TRUE(n.allFinite());
}

}  // namespace
}  // namespace cadsynth
