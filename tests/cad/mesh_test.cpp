#include "cad/mesh.h"

#include <gtest/gtest.h>

namespace cadsynth {
namespace {

// Two triangles: the unit square in the z = 0 plane, facing +z.
Mesh UnitSquare() {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  m.normals.assign(4, Eigen::Vector3f::UnitZ());
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  m.face_ids = {0, 0};
  return m;
}

TEST(Mesh, BoundsAndArea) {
  const Mesh m = UnitSquare();
  EXPECT_EQ(m.Bounds().min(), Eigen::Vector3d(0, 0, 0));
  EXPECT_EQ(m.Bounds().max(), Eigen::Vector3d(1, 1, 0));
  EXPECT_DOUBLE_EQ(m.SurfaceArea(), 1.0);
  EXPECT_TRUE(Mesh().Bounds().isEmpty());
}

TEST(Mesh, TransformMovesPointsAndRotatesNormals) {
  Mesh m = UnitSquare();
  const Eigen::Isometry3d t =
      Eigen::Translation3d(10, 0, 0) * Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX());
  m.Transform(t);
  EXPECT_TRUE(m.positions[2].isApprox(Eigen::Vector3f(11, 0, 1), 1e-6f));
  EXPECT_TRUE(m.normals[0].isApprox(Eigen::Vector3f(0, -1, 0), 1e-6f));
  const Eigen::AlignedBox3d b = UnitSquare().Bounds(t);
  EXPECT_NEAR(b.min().x(), 10.0, 1e-12);
  EXPECT_NEAR(b.max().z(), 1.0, 1e-12);
}

TEST(Mesh, FacetedGivesEachTriangleItsOwnVerticesAndNormal) {
  Mesh m = UnitSquare();
  m.normals.assign(4, Eigen::Vector3f(0, 0.6f, 0.8f));  // smooth normals, tilted
  m.MakeFaceted();
  ASSERT_EQ(m.num_vertices(), 6u);
  for (const auto& n : m.normals) EXPECT_EQ(n, Eigen::Vector3f::UnitZ());
  EXPECT_EQ(m.positions[3], Eigen::Vector3f(0, 0, 0));  // second triangle starts at vertex 0
  EXPECT_EQ(m.triangles[1], (Eigen::Matrix<uint32_t, 3, 1>(3, 4, 5)));
  EXPECT_DOUBLE_EQ(m.SurfaceArea(), 1.0);
}

TEST(Mesh, TextureCoordinatesFollowFacetingAndAppending) {
  Mesh m = UnitSquare();
  m.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  Mesh faceted = m;
  faceted.MakeFaceted();
  ASSERT_TRUE(faceted.has_uvs());
  // The second triangle (0, 2, 3) now has vertices 3, 4, 5.
  EXPECT_EQ(faceted.uvs[4], Eigen::Vector2f(1, 1));
  EXPECT_EQ(faceted.uvs[5], Eigen::Vector2f(0, 1));
  Mesh both = m;
  both.Append(m);
  ASSERT_TRUE(both.has_uvs());
  EXPECT_EQ(both.uvs[6], Eigen::Vector2f(1, 1));
  // A mesh without them makes the whole mesh have none (half a mapping is no mapping).
  both.Append(UnitSquare());
  EXPECT_FALSE(both.has_uvs());
  EXPECT_TRUE(both.uvs.empty());
  Mesh empty;
  empty.Append(m);
  EXPECT_TRUE(empty.has_uvs());
}

TEST(Mesh, AppendOffsetsIndices) {
  Mesh m = UnitSquare();
  m.Append(UnitSquare());
  ASSERT_EQ(m.num_triangles(), 4u);
  EXPECT_EQ(m.triangles[2], (Eigen::Matrix<uint32_t, 3, 1>(4, 5, 6)));
  EXPECT_EQ(m.face_ids.size(), 4u);
  Mesh no_ids = UnitSquare();
  no_ids.face_ids.clear();
  m.Append(no_ids);
  EXPECT_TRUE(m.face_ids.empty());
}

}  // namespace
}  // namespace cadsynth
