#include "cad/mesh_analysis.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <map>
#include <unordered_map>
#include <utility>
#include <vector>

namespace cadsynth {
namespace {

struct PositionHash {
  size_t operator()(const Eigen::Vector3f& p) const {
    uint32_t bits[3];
    std::memcpy(bits, p.data(), sizeof(bits));
    return (size_t{bits[0]} * 73856093u) ^ (size_t{bits[1]} * 19349663u) ^
           (size_t{bits[2]} * 83492791u);
  }
};

}  // namespace

MeshTopology AnalyzeTopology(const Mesh& mesh) {
  // Weld: one id per distinct position.
  std::unordered_map<Eigen::Vector3f, uint32_t, PositionHash> ids;
  ids.reserve(mesh.positions.size());
  std::vector<uint32_t> weld(mesh.positions.size());
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    weld[i] = ids.emplace(mesh.positions[i], static_cast<uint32_t>(ids.size())).first->second;
  }
  // Directed edges, sorted so each undirected edge's uses are adjacent.
  struct Use {
    uint32_t lo, hi;
    bool forward;
  };
  std::vector<Use> uses;
  uses.reserve(3 * mesh.triangles.size());
  for (const auto& t : mesh.triangles) {
    const uint32_t w[3] = {weld[t[0]], weld[t[1]], weld[t[2]]};
    // Triangles that weld to a line (OpenCASCADE makes them at sphere poles) have no surface.
    if (w[0] == w[1] || w[1] == w[2] || w[0] == w[2]) continue;
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = w[k], b = w[(k + 1) % 3];
      uses.push_back({std::min(a, b), std::max(a, b), a < b});
    }
  }
  std::sort(uses.begin(), uses.end(),
            [](const Use& x, const Use& y) { return x.lo != y.lo ? x.lo < y.lo : x.hi < y.hi; });
  MeshTopology topology;
  for (size_t i = 0; i < uses.size();) {
    size_t j = i;
    int forward = 0;
    while (j < uses.size() && uses[j].lo == uses[i].lo && uses[j].hi == uses[i].hi) {
      forward += uses[j].forward ? 1 : 0;
      ++j;
    }
    const size_t count = j - i;
    ++topology.edges;
    if (count == 1) {
      ++topology.boundary_edges;
    } else if (count > 2) {
      ++topology.non_manifold_edges;
    } else if (forward != 1) {
      ++topology.misoriented_edges;
    }
    i = j;
  }
  return topology;
}

MassProperties ComputeMeshMassProperties(const Mesh& mesh) {
  // Sum over the tetrahedra (origin, a, b, c) with signed volume det[a b c] / 6. The second
  // moment of a tetrahedron with one vertex at the origin is det(A) A C A^T, with
  // C = [[2,1,1],[1,2,1],[1,1,2]] / 120 and A = [a b c].
  Eigen::Matrix3d canonical;
  canonical << 2, 1, 1, 1, 2, 1, 1, 1, 2;
  canonical /= 120.0;
  double volume = 0.0;
  Eigen::Vector3d first_moment = Eigen::Vector3d::Zero();
  Eigen::Matrix3d second_moment = Eigen::Matrix3d::Zero();
  // Work relative to the mesh centre to keep the sums well conditioned.
  const Eigen::Vector3d origin = mesh.Bounds().center();
  for (const auto& t : mesh.triangles) {
    Eigen::Matrix3d a;
    for (int k = 0; k < 3; ++k) a.col(k) = mesh.positions[t[k]].cast<double>() - origin;
    const double det = a.determinant();
    volume += det / 6.0;
    first_moment += det / 24.0 * (a.col(0) + a.col(1) + a.col(2));
    second_moment += det * a * canonical * a.transpose();
  }
  MassProperties result;
  result.volume_mm3 = volume;
  if (volume == 0.0) return result;
  const Eigen::Vector3d com = first_moment / volume;
  const Eigen::Matrix3d central = second_moment - volume * com * com.transpose();
  result.center_of_mass = com + origin;
  result.inertia = central.trace() * Eigen::Matrix3d::Identity() - central;
  return result;
}

void ComputeCreaseNormals(Mesh* mesh, double crease_angle_rad) {
  const size_t n_triangles = mesh->triangles.size();
  const size_t n_vertices = mesh->positions.size();
  // Unit face normals, in double.
  std::vector<Eigen::Vector3d> face(n_triangles, Eigen::Vector3d::Zero());
  for (size_t t = 0; t < n_triangles; ++t) {
    const auto& tri = mesh->triangles[t];
    const Eigen::Vector3d a = mesh->positions[tri[0]].cast<double>();
    const Eigen::Vector3d n = (mesh->positions[tri[1]].cast<double>() - a)
                                  .cross(mesh->positions[tri[2]].cast<double>() - a);
    const double length = n.norm();
    if (length > 0 && std::isfinite(length)) face[t] = n / length;
  }
  // Corners grouped by position: sorted by coordinates, then triangle.
  std::vector<uint64_t> corners(3 * n_triangles);
  for (size_t c = 0; c < corners.size(); ++c) corners[c] = c;
  const auto position = [&](uint64_t c) -> const Eigen::Vector3f& {
    return mesh->positions[mesh->triangles[c / 3][c % 3]];
  };
  std::sort(corners.begin(), corners.end(), [&](uint64_t a, uint64_t b) {
    const Eigen::Vector3f& p = position(a);
    const Eigen::Vector3f& q = position(b);
    if (p.x() != q.x()) return p.x() < q.x();
    if (p.y() != q.y()) return p.y() < q.y();
    if (p.z() != q.z()) return p.z() < q.z();
    return a < b;
  });
  const double limit = std::cos(crease_angle_rad);
  std::vector<Eigen::Vector3f> corner_normal(3 * n_triangles);
  for (size_t begin = 0; begin < corners.size();) {
    size_t end = begin + 1;
    while (end < corners.size() && position(corners[end]) == position(corners[begin])) ++end;
    Eigen::Vector3d all = Eigen::Vector3d::Zero();  // for degenerate triangles
    for (size_t i = begin; i < end; ++i) all += face[corners[i] / 3];
    for (size_t i = begin; i < end; ++i) {
      const Eigen::Vector3d& own = face[corners[i] / 3];
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      if (own.squaredNorm() > 0) {
        for (size_t j = begin; j < end; ++j) {
          const Eigen::Vector3d& other = face[corners[j] / 3];
          if (own.dot(other) >= limit) sum += other;
        }
      } else {
        sum = all;
      }
      const double length = sum.norm();
      corner_normal[corners[i]] = length > 0 && std::isfinite(length)
                                      ? Eigen::Vector3f((sum / length).cast<float>())
                                      : Eigen::Vector3f::UnitZ();
    }
    begin = end;
  }
  // Each vertex takes the normal of its first corner; corners that need another get a copy.
  std::vector<char> assigned(n_vertices, 0);
  const bool with_uvs = mesh->has_uvs();
  if (!with_uvs) mesh->uvs.clear();
  mesh->normals.assign(n_vertices, Eigen::Vector3f::UnitZ());
  std::map<std::pair<uint32_t, std::array<float, 3>>, uint32_t> copies;
  for (size_t t = 0; t < n_triangles; ++t) {
    for (int k = 0; k < 3; ++k) {
      uint32_t& v = mesh->triangles[t][k];
      const Eigen::Vector3f& n = corner_normal[3 * t + k];
      if (!assigned[v]) {
        assigned[v] = 1;
        mesh->normals[v] = n;
        continue;
      }
      if (mesh->normals[v] == n) continue;
      const auto key = std::make_pair(v, std::array<float, 3>{n.x(), n.y(), n.z()});
      const auto found = copies.find(key);
      if (found != copies.end()) {
        v = found->second;
        continue;
      }
      const auto copy = static_cast<uint32_t>(mesh->positions.size());
      mesh->positions.push_back(mesh->positions[v]);
      mesh->normals.push_back(n);
      if (with_uvs) mesh->uvs.push_back(mesh->uvs[v]);
      copies.emplace(key, copy);
      v = copy;
    }
  }
}

}  // namespace cadsynth
