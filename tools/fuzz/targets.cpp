#include "tools/fuzz/targets.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include "cad/core/error.h"
#include "cad/hull.h"
#include "cad/import.h"
#include "cad/mesh_analysis.h"
#include "cad/mesh_formats.h"
#include "cad/part_cache.h"
#include "cad/step_tessellated.h"
#include "dataset/bop.h"
#include "dataset/bop_read.h"
#include "dataset/point_cloud.h"
#include "recipes/recipe.h"
#include "variants/stable_pose.h"

namespace cadsynth::fuzz {

namespace {

std::string_view Bytes(const uint8_t* data, size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

// The bytes written to a file of this process with the given extension (the readers take paths).
std::filesystem::path AsFile(std::string_view bytes, const std::string& extension) {
  const std::filesystem::path path = std::filesystem::temp_directory_path() /
                                     ("cadsynth_fuzz_" + std::to_string(::getpid()) + extension);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return path;
}

// Runs `f`, accepting only cadsynth::Error.
template <typename F>
int Run(F&& f) {
  try {
    f();
  } catch (const Error&) {
  }
  return 0;
}

void Require(bool condition) {
  if (!condition) __builtin_trap();
}

// The extension the first byte picks for a target that reads several formats.
const std::string& Extension(const std::string& target, uint8_t first) {
  for (const NamedTarget& t : Targets()) {
    if (t.name == target) return t.extensions[first % t.extensions.size()];
  }
  __builtin_trap();
}

}  // namespace

int Recipe(const uint8_t* data, size_t size) {
  return Run([&] { ParseRecipe(std::string(Bytes(data, size)), "fuzz.yaml", "/nonexistent"); });
}

int StepTessellated(const uint8_t* data, size_t size) {
  return Run([&] { internal::ReadStepTessellated(AsFile(Bytes(data, size), ".stp"), 1.0); });
}

int PartCacheHull(const uint8_t* data, size_t size) {
  return Run([&] {
    const ConvexHull hull = DecodeHull(Bytes(data, size));
    for (const auto& t : hull.triangles) {
      for (int v : t) Require(v >= 0 && static_cast<size_t>(v) < hull.vertices.size());
    }
  });
}

int MeshFormats(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  return Run([&] {
    Mesh mesh =
        ParseMeshBytes(Bytes(data + 1, size - 1), Extension("mesh_formats", data[0]), "fuzz");
    for (const auto& t : mesh.triangles) {
      for (int k = 0; k < 3; ++k) Require(t[k] < mesh.positions.size());
    }
    // What ReadMesh and prepare do next, for a mesh ReadMesh accepts.
    if (mesh.empty()) return;
    for (const Eigen::Vector3f& p : mesh.positions) {
      if (!p.allFinite()) return;
    }
    ComputeCreaseNormals(&mesh, 0.5);
    Require(mesh.normals.size() == mesh.positions.size());
    if (AnalyzeTopology(mesh).watertight()) ComputeMeshMassProperties(mesh);
    const ConvexHull hull = ComputeConvexHull(mesh);
    StablePoses(hull, mesh.Bounds().center());
  });
}

int MeshAssimp(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  return Run([&] {
    const Assembly a =
        ReadMesh(AsFile(Bytes(data + 1, size - 1), Extension("mesh_assimp", data[0])), 0.5);
    for (const Part& p : a.parts) {
      for (const auto& t : p.mesh.triangles) {
        for (int k = 0; k < 3; ++k) Require(t[k] < p.mesh.positions.size());
      }
    }
  });
}

int CadEntry(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  return Run([&] {
    ImportCad(AsFile(Bytes(data + 1, size - 1), Extension("cad_entry", data[0])), ImportOptions{});
  });
}

int BopReaders(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const std::string text(Bytes(data + 1, size - 1));
  return Run([&] {
    switch (data[0] % 5) {
      case 0:
        ParseBopResults(text, "fuzz.csv");
        break;
      case 1:
        ParseSceneGt(text, "scene_gt.json");
        break;
      case 2:
        ParseModelsInfo(text, "models_info.json");
        break;
      case 3:
        CheckFragmentText(text, "000000.json");
        break;
      default:
        DecodePointPly(text, "points.ply");
    }
  });
}

const std::vector<NamedTarget>& Targets() {
  static const std::vector<NamedTarget> kTargets = {
      {"recipe", &Recipe, {}, true},
      {"step_tessellated", &StepTessellated, {}, true},
      {"part_cache_hull", &PartCacheHull, {}, true},
      {"mesh_formats", &MeshFormats, {".stl", ".ply", ".off"}, true},
      {"mesh_assimp", &MeshAssimp, {".obj", ".gltf", ".glb", ".dae", ".3mf"}, false},
      {"cad_entry", &CadEntry, {".step", ".iges", ".brep"}, false},
      {"bop_readers", &BopReaders, {}, true},
  };
  return kTargets;
}

}  // namespace cadsynth::fuzz
