// Triangle meshes, the geometry every stage after cad/ works with.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace cadsynth {

// An indexed triangle mesh. Positions are in millimetres; triangles wind counter-clockwise seen
// from outside the part (so the right-hand normal points out). Vertices are not shared across
// B-rep faces, which keeps sharp edges sharp; `normals` holds one unit normal per vertex.
struct Mesh {
  std::vector<Eigen::Vector3f> positions;
  std::vector<Eigen::Vector3f> normals;
  std::vector<Eigen::Matrix<uint32_t, 3, 1>> triangles;
  // Optional: for each triangle, the index of the B-rep face it came from (empty when unknown).
  std::vector<uint32_t> face_ids;
  // Optional: texture coordinates, one per vertex (empty when the file has none). OpenGL's
  // convention, as assimp gives them: (0, 0) is the image's bottom-left corner, v grows upwards.
  std::vector<Eigen::Vector2f> uvs;

  bool has_uvs() const { return !uvs.empty() && uvs.size() == positions.size(); }

  bool empty() const { return triangles.empty(); }
  size_t num_vertices() const { return positions.size(); }
  size_t num_triangles() const { return triangles.size(); }

  // Axis-aligned bounds of the vertices (empty box for an empty mesh).
  Eigen::AlignedBox3d Bounds() const;
  // Bounds of the vertices after moving them by `transform`.
  Eigen::AlignedBox3d Bounds(const Eigen::Isometry3d& transform) const;

  // Moves every vertex (and rotates every normal) by `transform`.
  void Transform(const Eigen::Isometry3d& transform);

  // Appends `other` (indices are offset). Face ids and texture coordinates are kept only when
  // both meshes have them.
  void Append(const Mesh& other);

  // Sum of triangle areas in mm^2.
  double SurfaceArea() const;

  // Flat shading: three vertices of its own for every triangle, each with the triangle's normal.
  void MakeFaceted();
};

}  // namespace cadsynth
