// Triangle meshes through assimp: one file, one part.
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/Importer.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "cad/core/error.h"
#include "cad/core/units.h"
#include "cad/import.h"
#include "cad/mesh_analysis.h"
#include "cad/mesh_formats.h"
#include "cad/xde.h"

namespace cadsynth {

namespace {

// The `<unit meter="..."/>` a COLLADA file declares in its asset header (1 when it has none, as
// the format says).
double ColladaMetresPerUnit(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::string head(1 << 16, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<size_t>(in.gcount()));
  const size_t unit = head.find("<unit");
  if (unit == std::string::npos) return 1.0;
  const size_t end = head.find('>', unit);
  const size_t meter = head.find("meter=", unit);
  if (meter == std::string::npos || meter > end) return 1.0;
  const char quote = meter + 6 < head.size() ? head[meter + 6] : 0;
  if (quote != '"' && quote != '\'') return 1.0;
  const double value = std::strtod(head.c_str() + meter + 7, nullptr);
  return value > 0 && std::isfinite(value) ? value : 1.0;
}

// A unit name LengthUnitMm knows, for a length in metres; else the length itself.
std::string UnitName(double metres) {
  for (const char* name : {"um", "mm", "cm", "m", "in", "ft"}) {
    const double mm = *LengthUnitMm(name);
    if (std::abs(mm / 1000.0 - metres) <= 1e-9 * metres) return name;
  }
  std::ostringstream out;
  out << metres << " m";
  return out.str();
}

// The whole file, for the checked readers.
std::string ReadBytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::string bytes;
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (!ec) bytes.reserve(size);
  bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  if (in.bad()) throw Error(path.string() + ": cannot read the file");
  return bytes;
}

// Refuses a file whose first bytes (or, for 3MF, last bytes) do not have its format's signature:
// assimp's 3MF reader ran for more than 10 minutes on 3 kB of noise, and the other readers are
// spared bytes they cannot make sense of.
void CheckSignature(const std::filesystem::path& path, const std::string& ext) {
  std::ifstream in(path, std::ios::binary);
  std::string head(64, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<size_t>(in.gcount()));
  const size_t text = head.find_first_not_of(" \t\r\n\xef\xbb\xbf");  // spaces, a UTF-8 BOM
  const char first = text == std::string::npos ? '\0' : head[text];
  const std::string file = path.string();
  if (ext == ".3mf") {
    // A ZIP archive: a local file header first, the end-of-central-directory record within the
    // last 65,557 bytes.
    bool end_record = false;
    std::error_code ec;
    const auto size = std::filesystem::file_size(path, ec);
    if (!ec && head.rfind("PK\x03\x04", 0) == 0) {
      const auto tail = std::min<std::uintmax_t>(size, 65557);
      std::string last(static_cast<size_t>(tail), '\0');
      in.clear();
      in.seekg(static_cast<std::streamoff>(size - tail));
      in.read(last.data(), static_cast<std::streamsize>(tail));
      end_record = in.gcount() == static_cast<std::streamsize>(tail) &&
                   last.find("PK\x05\x06") != std::string::npos;
    }
    if (!end_record)
      throw Error(file +
                  ": not a 3MF file (3MF files are ZIP archives with files in them; this is none)");
  } else if (ext == ".glb") {
    if (head.rfind("glTF", 0) != 0)
      throw Error(file + ": not a binary glTF file (no 'glTF' header)");
  } else if (ext == ".gltf") {
    if (first != '{') throw Error(file + ": not a glTF file (glTF is JSON text starting with '{')");
  } else if (ext == ".dae") {
    if (first != '<')
      throw Error(file + ": not a COLLADA file (COLLADA is XML text starting with '<')");
  }
}

// The triangles assimp gives for `file`, with the material colour the file defines (if any).
// assimp's output is checked, not trusted: every index against its mesh's vertex count.
Mesh ReadWithAssimp(const std::string& file, std::optional<Eigen::Vector3f>* color) {
  Assimp::Importer importer;
  // The file's normals are dropped: ComputeCreaseNormals below makes them, so the crease angle
  // decides which edges stay sharp. (assimp's own smoothing, GenSmoothNormals, finds shared
  // positions with a sort along one axis: quadratic on large flat faces, 80 s of a 4.6M-triangle
  // STL.)
  importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS, aiComponent_NORMALS);
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE,
                              aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  // Keep the file's own axes (COLLADA files here are Z_UP, like our world).
  importer.SetPropertyBool(AI_CONFIG_IMPORT_COLLADA_IGNORE_UP_DIRECTION, true);
  const unsigned flags = aiProcess_Triangulate | aiProcess_RemoveComponent |
                         aiProcess_PreTransformVertices | aiProcess_SortByPType;
  const aiScene* scene = importer.ReadFile(file, flags);
  if (scene == nullptr || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) != 0) {
    throw Error(file + ": not a readable mesh: " +
                internal::PlainAssimpError(importer.GetErrorString(), file));
  }

  Mesh mesh;
  // Texture coordinates (the first set) only when every mesh of the file has them.
  bool uvs = true;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* in = scene->mMeshes[m];
    if ((in->mPrimitiveTypes & aiPrimitiveType_TRIANGLE) == 0) continue;
    const auto base = static_cast<uint32_t>(mesh.positions.size());
    uvs = uvs && in->HasTextureCoords(0);
    for (unsigned v = 0; v < in->mNumVertices; ++v) {
      const aiVector3D& p = in->mVertices[v];
      mesh.positions.emplace_back(p.x, p.y, p.z);
      if (uvs) {
        const aiVector3D& t = in->mTextureCoords[0][v];
        mesh.uvs.emplace_back(t.x, t.y);
      }
    }
    for (unsigned f = 0; f < in->mNumFaces; ++f) {
      const aiFace& face = in->mFaces[f];
      if (face.mNumIndices != 3) continue;
      for (int k = 0; k < 3; ++k) {
        if (face.mIndices[k] >= in->mNumVertices) {
          throw Error(file + ": a face refers to vertex " + std::to_string(face.mIndices[k]) +
                      " of a mesh of " + std::to_string(in->mNumVertices));
        }
      }
      mesh.triangles.emplace_back(base + face.mIndices[0], base + face.mIndices[1],
                                  base + face.mIndices[2]);
    }
    // A colour only from a material the file defines: assimp gives colourless formats (STL) a
    // default material of its own.
    aiColor4D diffuse;
    if (!*color && in->mMaterialIndex < scene->mNumMaterials) {
      const aiMaterial* material = scene->mMaterials[in->mMaterialIndex];
      aiString name;
      const bool own = material->Get(AI_MATKEY_NAME, name) != AI_SUCCESS ||
                       std::string(name.C_Str()) != AI_DEFAULT_MATERIAL_NAME;
      if (own && material->Get(AI_MATKEY_COLOR_DIFFUSE, diffuse) == AI_SUCCESS) {
        *color = Eigen::Vector3f(diffuse.r, diffuse.g, diffuse.b);
      }
    }
  }
  if (!uvs || !mesh.has_uvs()) mesh.uvs.clear();
  for (const Eigen::Vector2f& t : mesh.uvs) {
    if (!t.allFinite()) throw Error(file + ": a texture coordinate is not a finite number");
  }
  return mesh;
}

}  // namespace

namespace internal {

// What assimp's error says about the file, in plain words and short: its wording for the common
// cases ("all meshes are orphaned", "No suitable reader found for the file format of file ...")
// explains nothing to someone who did not write assimp.
std::string PlainAssimpError(std::string why, const std::string& file) {
  const auto has = [&](const char* text) { return why.find(text) != std::string::npos; };
  if (why.empty()) return "the file holds no complete scene";
  if (has("orphaned")) return "its meshes are not placed in its scene (no node uses them)";
  if (has("No meshes remaining")) return "the file holds no triangles (only points or lines?)";
  if (has("No suitable reader")) return "not a file of the format its extension names";
  if (has("Unable to open")) return "cannot open the file";
  if (has("too small") || has("nexpected end") || has("EOF") || has("end of file"))
    return "the file ends too early (cut short?)";
  // Otherwise assimp's own words, without its format prefix or the file's path.
  const std::string name = std::filesystem::path(file).filename().string();
  for (size_t at = why.find(file); at != std::string::npos; at = why.find(file, at + name.size()))
    why.replace(at, file.size(), name);
  const size_t colon = why.find(": ");
  if (colon != std::string::npos && colon < 12 &&
      why.substr(0, colon).find(' ') == std::string::npos)
    why = why.substr(colon + 2);
  if (why.size() > 200) why = why.substr(0, 200) + "...";
  return why;
}

}  // namespace internal

Assembly ReadMesh(const std::filesystem::path& path, double crease_angle_rad) {
  const std::string file = path.string();
  internal::RequireReadableFile(file);
  std::string ext = path.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  // Formats that state their unit: COLLADA in its header (assimp 5.2 scales the numbers by it,
  // into metres), glTF always metres (its specification). Both are turned into mm here.
  double mm_per_unit = 1.0;
  std::string declared_unit;
  if (ext == ".dae") {
    mm_per_unit = 1000.0;
    declared_unit = UnitName(ColladaMetresPerUnit(path));
  } else if (ext == ".gltf" || ext == ".glb") {
    mm_per_unit = 1000.0;
    declared_unit = "m";
  }
  Mesh mesh;
  std::optional<Eigen::Vector3f> color;
  if (HasCheckedMeshReader(ext)) {
    mesh = ParseMeshBytes(ReadBytes(path), ext, file);
  } else {
    CheckSignature(path, ext);
    mesh = ReadWithAssimp(file, &color);
  }
  if (mesh.empty()) throw Error(file + ": the mesh file holds no triangles");
  for (size_t v = 0; v < mesh.positions.size(); ++v) {
    if (!mesh.positions[v].allFinite())
      throw Error(file + ": vertex " + std::to_string(v) + " is not a finite number");
  }
  if (mm_per_unit != 1.0) {
    for (Eigen::Vector3f& p : mesh.positions) p *= static_cast<float>(mm_per_unit);
  }
  // All triangles degenerate (every vertex in one point or on one line): nothing to see or place.
  if (!(mesh.SurfaceArea() > 0)) {
    throw Error(file + ": the mesh has no area (all its " + std::to_string(mesh.num_triangles()) +
                " triangles are degenerate)");
  }
  ComputeCreaseNormals(&mesh, crease_angle_rad);

  Part part;
  part.name = path.stem().string();
  const Eigen::Vector3d centre = mesh.Bounds().center();
  part.cad_from_model = Eigen::Translation3d(centre);
  mesh.Transform(part.cad_from_model.inverse());
  part.mesh = std::move(mesh);
  part.color = color;
  part.watertight = AnalyzeTopology(part.mesh).watertight();
  if (part.watertight) {
    part.mass = ComputeMeshMassProperties(part.mesh);
  } else {
    Warn(file + ": the mesh is not closed; its volume and centre of mass are unknown");
  }

  Assembly assembly;
  assembly.name = part.name;
  assembly.length_unit = declared_unit;
  assembly.format = "mesh (" + ext.substr(ext.empty() ? 0 : 1) + ")";
  assembly.instances = {Instance{0, part.name, part.cad_from_model}};
  assembly.parts.push_back(std::move(part));
  return assembly;
}

}  // namespace cadsynth
