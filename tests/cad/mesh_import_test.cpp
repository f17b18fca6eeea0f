// Mesh formats through assimp: files written by assimp's own exporters read back the same.
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>

#include <array>
#include <cmath>
#include <fstream>
#include <limits>

#include <gtest/gtest.h>

#include "cad/error.h"
#include "cad/import.h"
#include "cad/mesh_formats.h"
#include "tests/test_support.h"

namespace cadsynth {
namespace {

// A closed cube, 20 mm, one corner at the origin, written as OBJ with outward quads.
std::filesystem::path WriteCube(const testing::ScratchDir& dir) {
  std::ofstream(dir / "cube.obj")
      << "v 0 0 0\nv 20 0 0\nv 20 20 0\nv 0 20 0\nv 0 0 20\nv 20 0 20\nv 20 20 20\n"
         "v 0 20 20\nf 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
  return dir / "cube.obj";
}

TEST(ReadMesh, EveryFormatAssimpWritesReadsBackAsTheSameCube) {
  testing::ScratchDir dir;
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(WriteCube(dir).string(), aiProcess_Triangulate);
  ASSERT_NE(scene, nullptr) << importer.GetErrorString();
  Assimp::Exporter exporter;
  const std::pair<const char*, const char*> formats[] = {
      {"stlb", "cube.stl"},        {"stl", "cube_ascii.stl"}, {"ply", "cube.ply"},
      {"plyb", "cube_binary.ply"}, {"gltf2", "cube.gltf"},    {"glb2", "cube.glb"},
      {"3mf", "cube.3mf"},         {"collada", "cube.dae"},   {"obj", "cube_out.obj"}};
  for (const auto& [id, name] : formats) {
    ASSERT_EQ(exporter.Export(scene, id, (dir / name).string()), AI_SUCCESS)
        << id << ": " << exporter.GetErrorString();
    // glTF is in metres, and assimp's COLLADA writer says metres: the cube's 20 is 20 m there,
    // unless the recipe states the numbers are mm.
    const std::string ext = std::filesystem::path(name).extension().string();
    const bool metres = ext == ".gltf" || ext == ".glb" || ext == ".dae";
    if (metres) {
      const Assembly m = ImportCad(dir / name, ImportOptions{});
      EXPECT_EQ(m.length_unit, "m") << name;
      EXPECT_TRUE(m.parts[0].mesh.Bounds().sizes().isApprox(Eigen::Vector3d::Constant(2e4), 1e-5))
          << name;
    }
    ImportOptions options;
    if (metres) options.unit = "mm";
    const Assembly a = ImportCad(dir / name, options);
    ASSERT_EQ(a.parts.size(), 1u) << name;
    const Part& p = a.parts[0];
    EXPECT_EQ(p.mesh.num_triangles(), 12u) << name;
    EXPECT_TRUE(p.watertight) << name;
    EXPECT_NEAR(p.mass.volume_mm3, 8000.0, 1e-2) << name;
    EXPECT_TRUE(p.mesh.Bounds().sizes().isApprox(Eigen::Vector3d(20, 20, 20), 1e-5)) << name;
  }
}

TEST(ReadMesh, CreaseAngleDecidesSmoothOrSharp) {
  testing::ScratchDir dir;
  const std::filesystem::path cube = WriteCube(dir);
  // A cube's faces meet at 90 degrees: below a 100-degree crease angle its corners are smoothed,
  // at 30 degrees (the default) every normal is a face normal.
  const Assembly sharp = ImportCad(cube, ImportOptions{});
  for (const Eigen::Vector3f& n : sharp.parts[0].mesh.normals) {
    EXPECT_NEAR(n.cwiseAbs().maxCoeff(), 1.0f, 1e-5f);
  }
  ImportOptions smooth;
  smooth.crease_angle_rad = 100.0 * M_PI / 180.0;
  int diagonal = 0;
  const Assembly smoothed = ImportCad(cube, smooth);
  for (const Eigen::Vector3f& n : smoothed.parts[0].mesh.normals) {
    diagonal += n.cwiseAbs().maxCoeff() < 0.9f;
  }
  EXPECT_GT(diagonal, 0);
  ImportOptions faceted;
  faceted.crease_angle_rad = 0.0;
  EXPECT_EQ(ImportCad(cube, faceted).parts[0].mesh.num_vertices(), 36u);
}

// COLLADA's <unit meter="..."> is honoured: the same cube declared in millimetres is 20 mm.
TEST(ReadMesh, ColladaUnitIsHonoured) {
  testing::ScratchDir dir;
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(WriteCube(dir).string(), aiProcess_Triangulate);
  ASSERT_NE(scene, nullptr);
  Assimp::Exporter exporter;
  ASSERT_EQ(exporter.Export(scene, "collada", (dir / "m.dae").string()), AI_SUCCESS);
  std::string text = testing::ReadFile(dir / "m.dae");
  const size_t unit = text.find("meter=\"1\"");
  ASSERT_NE(unit, std::string::npos) << text.substr(0, 600);
  text.replace(unit, 9, "meter=\"0.001\"");
  std::ofstream(dir / "mm.dae") << text;
  const Assembly a = ImportCad(dir / "mm.dae", ImportOptions{});
  EXPECT_EQ(a.length_unit, "mm");
  EXPECT_TRUE(a.parts[0].mesh.Bounds().sizes().isApprox(Eigen::Vector3d(20, 20, 20), 1e-5))
      << a.parts[0].mesh.Bounds().sizes().transpose();
}

// A binary STL of the given triangles (no normals).
std::filesystem::path WriteBinaryStl(const std::filesystem::path& path,
                                     const std::vector<std::array<float, 9>>& triangles) {
  std::ofstream out(path, std::ios::binary);
  const std::string header(80, ' ');
  out.write(header.data(), 80);
  const uint32_t n = static_cast<uint32_t>(triangles.size());
  out.write(reinterpret_cast<const char*>(&n), 4);
  for (const auto& t : triangles) {
    const float normal[3] = {0, 0, 0};
    out.write(reinterpret_cast<const char*>(normal), 12);
    out.write(reinterpret_cast<const char*>(t.data()), 36);
    const uint16_t attributes = 0;
    out.write(reinterpret_cast<const char*>(&attributes), 2);
  }
  return path;
}

// One NaN or infinite coordinate is refused when the file is read, naming it (generate died of
// SIGFPE in the convex hull while inspect accepted the file).
TEST(ReadMesh, NonFiniteVertexIsAnError) {
  testing::ScratchDir dir;
  for (const float bad : {std::nanf(""), std::numeric_limits<float>::infinity()}) {
    const auto path = WriteBinaryStl(
        dir / "bad.stl", {{0, 0, 0, 10, 0, 0, 0, 10, 0}, {0, 0, 0, 0, 10, 0, 0, 0, bad}});
    try {
      ImportCad(path, ImportOptions{});
      ADD_FAILURE() << bad;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("is not a finite number"), std::string::npos)
          << e.what();
      EXPECT_EQ(std::string(e.what()).rfind(path.string(), 0), 0u) << e.what();
    }
  }
}

// The checked STL reader gives exactly the vertices and triangles assimp gives, on every real STL
// of the shared data (binary ones, and one whose binary header begins with "solid").
TEST(ReadMesh, CheckedStlReaderAgreesWithAssimpOnRealFiles) {
  CADSYNTH_REQUIRE_DATA(folder, "mesh");
  int files = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(folder)) {
    std::string ext = entry.path().extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (ext != ".stl") continue;
    ++files;
    Assimp::Importer importer;
    const aiScene* scene = importer.ReadFile(
        entry.path().string(), aiProcess_Triangulate | aiProcess_PreTransformVertices);
    ASSERT_NE(scene, nullptr) << entry.path();
    std::vector<Eigen::Vector3f> positions;
    std::vector<Eigen::Matrix<uint32_t, 3, 1>> triangles;
    for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
      const aiMesh* in = scene->mMeshes[m];
      const auto base = static_cast<uint32_t>(positions.size());
      for (unsigned v = 0; v < in->mNumVertices; ++v)
        positions.emplace_back(in->mVertices[v].x, in->mVertices[v].y, in->mVertices[v].z);
      for (unsigned f = 0; f < in->mNumFaces; ++f) {
        const aiFace& face = in->mFaces[f];
        triangles.emplace_back(base + face.mIndices[0], base + face.mIndices[1],
                               base + face.mIndices[2]);
      }
    }
    const Mesh mine = ParseStl(testing::ReadFile(entry.path()), entry.path().string());
    EXPECT_TRUE(mine.positions == positions) << entry.path();
    EXPECT_TRUE(mine.triangles == triangles) << entry.path();
  }
  EXPECT_GE(files, 10);
}

}  // namespace
}  // namespace cadsynth
