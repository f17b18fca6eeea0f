// Mesh formats through assimp: files written by assimp's own exporters read back the same.
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>

#include <array>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>

#include <gtest/gtest.h>

#include "cad/core/error.h"
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

// Texture coordinates survive the import: vertices split at creases keep theirs, and glTF's
// (v down from the image's top) come out in OpenGL's convention like OBJ's (v up).
TEST(ReadMesh, TextureCoordinatesAreKept) {
  testing::ScratchDir dir;
  // A cube whose every face maps the whole image, u along the face's first edge.
  std::ofstream(dir / "uv_cube.obj")
      << "v 0 0 0\nv 20 0 0\nv 20 20 0\nv 0 20 0\nv 0 0 20\nv 20 0 20\nv 20 20 20\n"
         "v 0 20 20\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
         "f 1/1 4/2 3/3 2/4\nf 5/1 6/2 7/3 8/4\nf 1/1 2/2 6/3 5/4\nf 2/1 3/2 7/3 6/4\n"
         "f 3/1 4/2 8/3 7/4\nf 4/1 1/2 5/3 8/4\n";
  const Mesh cube = ImportCad(dir / "uv_cube.obj", ImportOptions{}).parts[0].mesh;
  ASSERT_TRUE(cube.has_uvs());
  EXPECT_EQ(cube.num_triangles(), 12u);
  // Every corner of the top face (z = +10 after centring) has the uv its OBJ line gives it.
  const std::map<std::pair<int, int>, Eigen::Vector2f> top = {
      {{-10, -10}, {0, 0}}, {{10, -10}, {1, 0}}, {{10, 10}, {1, 1}}, {{-10, 10}, {0, 1}}};
  int checked = 0;
  for (const auto& t : cube.triangles) {
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3f& p = cube.positions[t[k]];
      if (p.z() != 10.0f || cube.normals[t[k]].z() < 0.99f) continue;
      const auto it = top.find({static_cast<int>(p.x()), static_cast<int>(p.y())});
      ASSERT_NE(it, top.end());
      EXPECT_EQ(cube.uvs[t[k]], it->second) << p.transpose();
      ++checked;
    }
  }
  EXPECT_EQ(checked, 6);
  // A glTF triangle with (u, v) = (0.1, 0.2), (0.9, 0.2), (0.1, 0.7) in glTF's convention.
  const float data[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0.1f, 0.2f, 0.9f, 0.2f, 0.1f, 0.7f};
  static_assert(sizeof(data) % 3 == 0, "base64 without padding");
  const auto* bytes = reinterpret_cast<const uint8_t*>(data);
  static const char* kBase64 = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string encoded;
  for (size_t i = 0; i < sizeof(data); i += 3) {
    const uint32_t n = (uint32_t{bytes[i]} << 16) | (uint32_t{bytes[i + 1]} << 8) | bytes[i + 2];
    for (int k = 0; k < 4; ++k) encoded += kBase64[(n >> (18 - 6 * k)) & 63];
  }
  std::ofstream(dir / "tri.gltf")
      << R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],)"
      << R"("meshes":[{"primitives":[{"attributes":{"POSITION":0,"TEXCOORD_0":1}}]}],)"
      << R"("buffers":[{"byteLength":60,"uri":"data:application/octet-stream;base64,)" << encoded
      << R"("}],"bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36},)"
      << R"({"buffer":0,"byteOffset":36,"byteLength":24}],"accessors":[)"
      << R"({"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],)"
      << R"("max":[1,1,0]},{"bufferView":1,"componentType":5126,"count":3,"type":"VEC2"}]})";
  ImportOptions mm;
  mm.unit = "mm";
  const Mesh tri = ImportCad(dir / "tri.gltf", mm).parts[0].mesh;
  ASSERT_TRUE(tri.has_uvs());
  ASSERT_EQ(tri.num_triangles(), 1u);
  const Eigen::Vector2f expected[] = {{0.1f, 0.8f}, {0.9f, 0.8f}, {0.1f, 0.3f}};
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3f p = tri.positions[tri.triangles[0][k]];
    const int corner = p.x() > 0 ? 1 : (p.y() > 0 ? 2 : 0);
    EXPECT_TRUE(tri.uvs[tri.triangles[0][k]].isApprox(expected[corner], 1e-6f)) << k;
  }
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
