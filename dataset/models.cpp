// Object models: diameters and PLY meshes (dataset/models.h), and a BOP dataset's models/ folder
// written from them (declared in dataset/bop.h with the rest of the layout): the meshes,
// models_info.json, models_cad.json, the model clouds and keypoints.
#include "dataset/models.h"

#include <algorithm>
#include <cstring>
#include <functional>
#include <iterator>
#include <vector>

#include <tbb/parallel_for.h>

#include "cad/core/error.h"
#include "cad/hull.h"
#include "dataset/bop.h"
#include "dataset/bop_internal.h"
#include "dataset/file_io.h"
#include "dataset/point_cloud.h"

namespace cadsynth {

double MeshDiameter(const Mesh& mesh) {
  std::vector<Eigen::Vector3d> points;
  points.reserve(mesh.positions.size());
  for (const Eigen::Vector3f& p : mesh.positions) points.push_back(p.cast<double>());
  try {
    return ComputeConvexHull(std::move(points)).diameter;
  } catch (const Error&) {  // flat or collinear: every vertex
    std::vector<Eigen::Vector3d> all;
    all.reserve(mesh.positions.size());
    for (const Eigen::Vector3f& p : mesh.positions) all.push_back(p.cast<double>());
    return PointSetDiameter(std::move(all));
  }
}

double PartDiameter(const Part& part) {
  return part.hull ? part.hull->diameter : MeshDiameter(part.mesh);
}

namespace {

template <typename T>
void Put(std::string* out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));  // x86-64 and aarch64 are little-endian
  out->append(bytes, sizeof(T));
}

}  // namespace

std::string EncodePly(const Mesh& mesh) {
  std::string out =
      "ply\nformat binary_little_endian 1.0\ncomment cadsynth model, units: mm\n"
      "element vertex " +
      std::to_string(mesh.num_vertices()) +
      "\nproperty float x\nproperty float y\nproperty float z\n"
      "property float nx\nproperty float ny\nproperty float nz\n"
      "element face " +
      std::to_string(mesh.num_triangles()) +
      "\nproperty list uchar int vertex_indices\nend_header\n";
  out.reserve(out.size() + mesh.num_vertices() * 24 + mesh.num_triangles() * 13);
  const bool has_normals = mesh.normals.size() == mesh.positions.size();
  for (size_t i = 0; i < mesh.num_vertices(); ++i) {
    for (int c = 0; c < 3; ++c) Put<float>(&out, mesh.positions[i][c]);
    for (int c = 0; c < 3; ++c) Put<float>(&out, has_normals ? mesh.normals[i][c] : 0.0f);
  }
  for (const auto& t : mesh.triangles) {
    Put<uint8_t>(&out, 3);
    for (int c = 0; c < 3; ++c) Put<int32_t>(&out, static_cast<int32_t>(t[c]));
  }
  return out;
}

using bop_internal::Json;
using bop_internal::Vec;
using bop_internal::WriteJson;

void WriteBopModels(const std::filesystem::path& root, const std::vector<Part>& parts,
                    const std::vector<ObjectClass>& classes) {
  if (!classes.empty() && classes.size() != parts.size()) {
    throw Error("bop: " + std::to_string(classes.size()) + " classes for " +
                std::to_string(parts.size()) + " parts");
  }
  const std::filesystem::path dir = root / "models";
  CreateFolder(dir);
  std::vector<double> diameters(parts.size());
  tbb::parallel_for(size_t{0}, parts.size(), [&](size_t i) {
    diameters[i] = PartDiameter(parts[i]);
    WriteFileAtomic(dir / ("obj_" + Id6(static_cast<int>(i) + 1) + ".ply"),
                    EncodePly(parts[i].mesh));
  });
  Json info = Json::object();
  Json cad = Json::object();
  for (size_t i = 0; i < parts.size(); ++i) {
    const Eigen::AlignedBox3d box = parts[i].mesh.Bounds();
    const std::string key = std::to_string(i + 1);
    info[key] = {{"diameter", diameters[i]},  {"min_x", box.min().x()},
                 {"min_y", box.min().y()},    {"min_z", box.min().z()},
                 {"size_x", box.sizes().x()}, {"size_y", box.sizes().y()},
                 {"size_z", box.sizes().z()}};
    // Symmetries as bop_toolkit reads them: 4x4 row-major transforms, and axes with offsets.
    const Symmetries& sym = parts[i].symmetries;
    if (!sym.discrete.empty()) {
      Json discrete = Json::array();
      for (const Eigen::Isometry3d& t : sym.discrete) {
        Json m = Json::array();
        for (int r = 0; r < 4; ++r) {
          for (int c = 0; c < 4; ++c)
            m.push_back(std::abs(t.matrix()(r, c)) < 1e-12 ? 0.0 : t.matrix()(r, c));
        }
        discrete.push_back(m);
      }
      info[key]["symmetries_discrete"] = discrete;
    }
    if (!sym.continuous.empty()) {
      Json continuous = Json::array();
      for (const Symmetries::Axis& a : sym.continuous) {
        continuous.push_back({{"axis", Vec(a.direction)}, {"offset", Vec(a.offset)}});
      }
      info[key]["symmetries_continuous"] = continuous;
    }
    Json cad_from_model = Json::array();
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) cad_from_model.push_back(parts[i].cad_from_model.matrix()(r, c));
    }
    const ObjectClass object_class =
        classes.empty() ? ObjectClass{static_cast<int>(i) + 1, parts[i].name} : classes[i];
    cad[key] = {{"name", parts[i].name},
                {"class_id", object_class.id},
                {"class_name", object_class.name},
                {"cad_from_model", cad_from_model},
                {"volume_mm3", parts[i].mass.volume_mm3},
                {"center_of_mass", Vec(parts[i].mass.center_of_mass)},
                {"mass_from_brep", parts[i].mass_from_brep},
                {"triangles", parts[i].mesh.num_triangles()}};
  }
  WriteJson(dir / "models_info.json", info);
  WriteJson(dir / "models_cad.json", cad);
}

void WriteModelPoints(const std::filesystem::path& root, const std::vector<Part>& parts,
                      const BopOptions& options) {
  if (options.model_points <= 0) return;
  CreateFolder(root / "models" / "points");
  std::vector<Keypoints> keypoints(parts.size());
  tbb::parallel_for(size_t{0}, parts.size(), [&](size_t i) {
    const std::vector<Eigen::Vector3f> points =
        options.even_points
            ? SampleEvenly(parts[i].mesh, options.model_points, options.point_seed + i)
            : SampleSurface(parts[i].mesh, options.model_points, options.point_seed + i);
    WriteFileAtomic(root / "models" / "points" / ("obj_" + Id6(static_cast<int>(i) + 1) + ".ply"),
                    EncodePointPly(points));
    keypoints[i] = ComputeKeypoints(parts[i].mesh, points);
  });
  const auto list = [](const auto& points) {
    Json out = Json::array();
    for (const Eigen::Vector3f& p : points) out.push_back({p.x(), p.y(), p.z()});
    return out;
  };
  Json all = Json::object();
  for (size_t i = 0; i < parts.size(); ++i) {
    const Keypoints& k = keypoints[i];
    all[std::to_string(i + 1)] = {{"fps8", list(k.fps8)},
                                  {"fps16", list(k.fps16)},
                                  {"center", {k.center.x(), k.center.y(), k.center.z()}},
                                  {"corners", list(k.corners)}};
  }
  WriteJson(root / "models" / "keypoints.json", all);
}

}  // namespace cadsynth
