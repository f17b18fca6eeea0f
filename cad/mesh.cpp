#include "cad/mesh.h"

namespace cadsynth {

Eigen::AlignedBox3d Mesh::Bounds() const { return Bounds(Eigen::Isometry3d::Identity()); }

Eigen::AlignedBox3d Mesh::Bounds(const Eigen::Isometry3d& transform) const {
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3f& p : positions) box.extend(transform * p.cast<double>());
  return box;
}

void Mesh::Transform(const Eigen::Isometry3d& transform) {
  const Eigen::Matrix3f rotation = transform.linear().cast<float>();
  const Eigen::Isometry3f t = transform.cast<float>();
  for (Eigen::Vector3f& p : positions) p = t * p;
  for (Eigen::Vector3f& n : normals) n = rotation * n;
}

void Mesh::Append(const Mesh& other) {
  const bool keep_face_ids = (empty() || !face_ids.empty()) && !other.face_ids.empty();
  const bool keep_uvs = (positions.empty() || has_uvs()) && other.has_uvs();
  const auto offset = static_cast<uint32_t>(positions.size());
  positions.insert(positions.end(), other.positions.begin(), other.positions.end());
  normals.insert(normals.end(), other.normals.begin(), other.normals.end());
  for (const auto& t : other.triangles) triangles.push_back(t.array() + offset);
  if (keep_face_ids) {
    face_ids.insert(face_ids.end(), other.face_ids.begin(), other.face_ids.end());
  } else {
    face_ids.clear();
  }
  if (keep_uvs) {
    uvs.insert(uvs.end(), other.uvs.begin(), other.uvs.end());
  } else {
    uvs.clear();
  }
}

void Mesh::MakeFaceted() {
  std::vector<Eigen::Vector3f> positions, normals;
  std::vector<Eigen::Vector2f> uvs;
  positions.reserve(3 * triangles.size());
  normals.reserve(3 * triangles.size());
  const bool with_uvs = has_uvs();
  for (auto& t : triangles) {
    if (with_uvs) uvs.insert(uvs.end(), {this->uvs[t[0]], this->uvs[t[1]], this->uvs[t[2]]});
    const Eigen::Vector3f a = this->positions[t[0]], b = this->positions[t[1]],
                          c = this->positions[t[2]];
    Eigen::Vector3f n = (b - a).cross(c - a);
    n = n.norm() > 0 ? n.normalized() : Eigen::Vector3f::UnitZ();
    const auto base = static_cast<uint32_t>(positions.size());
    positions.insert(positions.end(), {a, b, c});
    normals.insert(normals.end(), {n, n, n});
    t = Eigen::Matrix<uint32_t, 3, 1>(base, base + 1, base + 2);
  }
  this->positions = std::move(positions);
  this->normals = std::move(normals);
  this->uvs = std::move(uvs);
}

double Mesh::SurfaceArea() const {
  double area = 0.0;
  for (const auto& t : triangles) {
    const Eigen::Vector3d a = positions[t[0]].cast<double>();
    const Eigen::Vector3d b = positions[t[1]].cast<double>();
    const Eigen::Vector3d c = positions[t[2]].cast<double>();
    area += 0.5 * (b - a).cross(c - a).norm();
  }
  return area;
}

}  // namespace cadsynth
