#include "cad/part_cache.h"

#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <system_error>

#include <BinTools.hxx>
#include <Standard_Failure.hxx>
#include <TopoDS_Shape.hxx>
#define XXH_INLINE_ALL
#include <xxhash.h>

#include "cad/core/error.h"
#include "cad/occt_shape.h"

namespace cadsynth {
namespace {

constexpr char kMagic[8] = {'c', 's', 'c', 'a', 'c', 'h', 'e', '1'};
constexpr uint32_t kAssemblyTag = 0x41535331;  // "ASS1"
constexpr uint32_t kHullTag = 0x48554c32;      // "HUL2"
constexpr uint32_t kSymmetryTag = 0x53594d31;  // "SYM1"

XXH3_state_t* State(void* p) { return static_cast<XXH3_state_t*>(p); }

void PutTransform(ByteWriter* out, const Eigen::Isometry3d& t) {
  for (int k = 0; k < 16; ++k) out->Put<double>(t.matrix().data()[k]);
}

Eigen::Isometry3d GetTransform(ByteReader* in) {
  Eigen::Matrix4d m;
  for (int k = 0; k < 16; ++k) m.data()[k] = in->Get<double>();
  Eigen::Isometry3d t;
  t.matrix() = m;
  return t;
}

template <int N>
void PutVector(ByteWriter* out, const Eigen::Matrix<double, N, 1>& v) {
  for (int k = 0; k < N; ++k) out->Put<double>(v[k]);
}

Eigen::Vector3d GetVector3(ByteReader* in) {
  Eigen::Vector3d v;
  for (int k = 0; k < 3; ++k) v[k] = in->Get<double>();
  return v;
}

void PutSymmetries(ByteWriter* out, const Symmetries& symmetries) {
  out->Put<uint64_t>(symmetries.discrete.size());
  for (const Eigen::Isometry3d& s : symmetries.discrete) PutTransform(out, s);
  out->Put<uint64_t>(symmetries.continuous.size());
  for (const Symmetries::Axis& a : symmetries.continuous) {
    PutVector<3>(out, a.direction);
    PutVector<3>(out, a.offset);
  }
}

Symmetries GetSymmetries(ByteReader* in) {
  Symmetries symmetries;
  const uint64_t discrete = in->Get<uint64_t>();
  for (uint64_t k = 0; k < discrete; ++k) symmetries.discrete.push_back(GetTransform(in));
  const uint64_t continuous = in->Get<uint64_t>();
  for (uint64_t k = 0; k < continuous; ++k) {
    Symmetries::Axis axis;
    axis.direction = GetVector3(in);
    axis.offset = GetVector3(in);
    symmetries.continuous.push_back(axis);
  }
  return symmetries;
}

void PutColor(ByteWriter* out, const std::optional<Eigen::Vector3f>& color) {
  out->Put<uint8_t>(color.has_value());
  if (color) {
    for (int k = 0; k < 3; ++k) out->Put<float>((*color)[k]);
  }
}

std::optional<Eigen::Vector3f> GetColor(ByteReader* in) {
  if (in->Get<uint8_t>() == 0) return std::nullopt;
  Eigen::Vector3f c;
  for (int k = 0; k < 3; ++k) c[k] = in->Get<float>();
  return c;
}

void PutMesh(ByteWriter* out, const Mesh& mesh) {
  out->PutArray(mesh.positions);
  out->PutArray(mesh.normals);
  out->PutArray(mesh.triangles);
  out->PutArray(mesh.face_ids);
  out->PutArray(mesh.uvs);
}

Mesh GetMesh(ByteReader* in) {
  Mesh mesh;
  mesh.positions = in->GetArray<Eigen::Vector3f>();
  mesh.normals = in->GetArray<Eigen::Vector3f>();
  mesh.triangles = in->GetArray<Eigen::Matrix<uint32_t, 3, 1>>();
  mesh.face_ids = in->GetArray<uint32_t>();
  mesh.uvs = in->GetArray<Eigen::Vector2f>();
  if (!mesh.uvs.empty() && mesh.uvs.size() != mesh.positions.size())
    throw Error("part cache: texture coordinates do not match the vertices");
  for (const auto& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      if (t[k] >= mesh.positions.size())
        throw Error("part cache: a triangle index is out of range");
    }
  }
  return mesh;
}

void PutShape(ByteWriter* out, const Shape& shape) {
  out->Put<uint8_t>(!shape.IsNull());
  if (shape.IsNull()) return;
  std::ostringstream stream(std::ios::binary);
  try {
    BinTools::Write(OcctShape(shape), stream, Standard_True, Standard_False,
                    BinTools_FormatVersion_CURRENT);
  } catch (const Standard_Failure& failure) {
    throw Error(std::string("part cache: OpenCASCADE could not write a shape: ") +
                failure.GetMessageString());
  }
  out->PutText(stream.str());
}

Shape GetShape(ByteReader* in) {
  if (in->Get<uint8_t>() == 0) return Shape();
  std::istringstream stream(in->GetText(), std::ios::binary);
  TopoDS_Shape shape;
  try {
    BinTools::Read(shape, stream);
  } catch (const Standard_Failure& failure) {
    throw Error(std::string("part cache: OpenCASCADE could not read a shape: ") +
                failure.GetMessageString());
  }
  if (shape.IsNull()) throw Error("part cache: a stored shape is empty");
  return WrapShape(shape);
}

}  // namespace

std::string CacheKey::Hex() const {
  char text[33];
  std::snprintf(text, sizeof(text), "%016llx%016llx", static_cast<unsigned long long>(high),
                static_cast<unsigned long long>(low));
  return text;
}

KeyHasher::KeyHasher() : state_(XXH3_createState()) {
  if (state_ == nullptr) throw std::bad_alloc();
  XXH3_128bits_reset(State(state_));
}

KeyHasher::~KeyHasher() { XXH3_freeState(State(state_)); }

KeyHasher& KeyHasher::Bytes(const void* data, size_t size) {
  XXH3_128bits_update(State(state_), data, size);
  return *this;
}

KeyHasher& KeyHasher::Text(std::string_view text) {
  Value<uint64_t>(text.size());
  return Bytes(text.data(), text.size());
}

KeyHasher& KeyHasher::Geometry(const Mesh& mesh) {
  const auto array = [this](const auto& values) {
    Value<uint64_t>(values.size());
    Bytes(values.data(), values.size() * sizeof(values[0]));
  };
  array(mesh.positions);
  array(mesh.normals);
  array(mesh.triangles);
  array(mesh.face_ids);
  if (!mesh.uvs.empty()) array(mesh.uvs);  // keys of meshes without them stay as they were
  return *this;
}

CacheKey KeyHasher::Key() const {
  const XXH128_hash_t h = XXH3_128bits_digest(State(state_));
  return CacheKey{h.high64, h.low64};
}

void ByteWriter::PutText(std::string_view text) {
  Put<uint64_t>(text.size());
  bytes_.append(text.data(), text.size());
}

std::string ByteReader::GetText() {
  const uint64_t n = Get<uint64_t>();
  if (n > bytes_.size() - at_) Fail();
  return std::string(Take(n), n);
}

const char* ByteReader::Take(size_t size) {
  if (size > bytes_.size() - at_) Fail();
  const char* p = bytes_.data() + at_;
  at_ += size;
  return p;
}

void ByteReader::Fail() { throw Error("part cache: the entry is truncated"); }

std::string EncodeHull(const ConvexHull& hull) {
  ByteWriter out;
  out.Put<uint32_t>(kHullTag);
  out.PutArray(hull.vertices);
  out.PutArray(hull.triangles);
  out.Put<double>(hull.diameter);
  return std::move(out.bytes());
}

std::string EncodeDetectedSymmetries(const DetectedSymmetries& found,
                                     const std::vector<double>& entry_deviation) {
  ByteWriter out;
  out.Put<uint32_t>(kSymmetryTag);
  PutSymmetries(&out, found.symmetries);
  out.PutArray(found.discrete_deviation_mm);
  out.PutArray(found.continuous_deviation_mm);
  out.PutArray(found.discrete_brep_mm);
  out.PutArray(found.continuous_brep_mm);
  out.Put<int32_t>(found.brep_faces_not_compared);
  out.Put<double>(found.tolerance_mm);
  out.Put<uint64_t>(found.axes.size());
  for (const DetectedSymmetries::Axis& axis : found.axes) {
    PutVector<3>(&out, axis.direction);
    out.Put<int32_t>(axis.order);
  }
  PutVector<3>(&out, found.centre);
  out.PutArray(entry_deviation);
  return std::move(out.bytes());
}

DetectedSymmetries DecodeDetectedSymmetries(std::string_view bytes,
                                            std::vector<double>* entry_deviation) {
  ByteReader in(bytes);
  if (in.Get<uint32_t>() != kSymmetryTag) throw Error("part cache: not a part's symmetries");
  DetectedSymmetries found;
  found.symmetries = GetSymmetries(&in);
  found.discrete_deviation_mm = in.GetArray<double>();
  found.continuous_deviation_mm = in.GetArray<double>();
  found.discrete_brep_mm = in.GetArray<double>();
  found.continuous_brep_mm = in.GetArray<double>();
  found.brep_faces_not_compared = in.Get<int32_t>();
  found.tolerance_mm = in.Get<double>();
  const uint64_t axes = in.Get<uint64_t>();
  for (uint64_t k = 0; k < axes; ++k) {
    DetectedSymmetries::Axis axis;
    axis.direction = GetVector3(&in);
    axis.order = in.Get<int32_t>();
    found.axes.push_back(axis);
  }
  found.centre = GetVector3(&in);
  *entry_deviation = in.GetArray<double>();
  if (!in.done()) throw Error("part cache: trailing bytes after a part's symmetries");
  if (found.discrete_deviation_mm.size() != found.symmetries.discrete.size() ||
      found.continuous_deviation_mm.size() != found.symmetries.continuous.size()) {
    throw Error("part cache: a part's symmetries and their deviations do not match");
  }
  return found;
}

std::string EncodeGrasps(const std::vector<ParallelJawGrasp>& jaw,
                         const std::vector<SuctionGrasp>& suction) {
  ByteWriter out;
  out.Put<uint64_t>(jaw.size());
  for (const ParallelJawGrasp& g : jaw) {
    PutTransform(&out, g.model_from_gripper);
    out.Put<double>(g.width_mm);
    out.Put<double>(g.opening_mm);
    out.Put<double>(g.depth_mm);
    out.Put<uint8_t>(g.free_when_open);
    for (int c = 0; c < 2; ++c) {
      PutVector<3>(&out, g.contacts[c]);
      PutVector<3>(&out, g.normals[c]);
    }
    out.Put<double>(g.quality);
  }
  out.Put<uint64_t>(suction.size());
  for (const SuctionGrasp& g : suction) {
    PutVector<3>(&out, g.point);
    PutVector<3>(&out, g.approach);
    out.Put<double>(g.seal);
    out.Put<double>(g.wrench);
    out.Put<double>(g.rim_height_mm);
  }
  return std::move(out.bytes());
}

void DecodeGrasps(std::string_view bytes, std::vector<ParallelJawGrasp>* jaw,
                  std::vector<SuctionGrasp>* suction) {
  ByteReader in(bytes);
  const uint64_t jaws = in.Get<uint64_t>();
  if (jaws > bytes.size()) throw Error("part cache: damaged grasps");
  jaw->clear();
  for (uint64_t i = 0; i < jaws; ++i) {
    ParallelJawGrasp g;
    g.model_from_gripper = GetTransform(&in);
    g.width_mm = in.Get<double>();
    g.opening_mm = in.Get<double>();
    g.depth_mm = in.Get<double>();
    g.free_when_open = in.Get<uint8_t>() != 0;
    for (int c = 0; c < 2; ++c) {
      g.contacts[c] = GetVector3(&in);
      g.normals[c] = GetVector3(&in);
    }
    g.quality = in.Get<double>();
    jaw->push_back(g);
  }
  const uint64_t cups = in.Get<uint64_t>();
  if (cups > bytes.size()) throw Error("part cache: damaged grasps");
  suction->clear();
  for (uint64_t i = 0; i < cups; ++i) {
    SuctionGrasp g;
    g.point = GetVector3(&in);
    g.approach = GetVector3(&in);
    g.seal = in.Get<double>();
    g.wrench = in.Get<double>();
    g.rim_height_mm = in.Get<double>();
    suction->push_back(g);
  }
  if (!in.done()) throw Error("part cache: trailing bytes after grasps");
}

ConvexHull DecodeHull(std::string_view bytes) {
  ByteReader in(bytes);
  if (in.Get<uint32_t>() != kHullTag) throw Error("part cache: not a convex hull");
  ConvexHull hull;
  hull.vertices = in.GetArray<Eigen::Vector3d>();
  hull.triangles = in.GetArray<std::array<int, 3>>();
  hull.diameter = in.Get<double>();
  for (const auto& t : hull.triangles) {
    for (int v : t) {
      if (v < 0 || static_cast<size_t>(v) >= hull.vertices.size())
        throw Error("part cache: a hull index is out of range");
    }
  }
  if (!in.done()) throw Error("part cache: trailing bytes after a convex hull");
  return hull;
}

std::string EncodeAssembly(const Assembly& assembly, const std::vector<std::string>& warnings) {
  ByteWriter out;
  out.Put<uint32_t>(kAssemblyTag);
  out.PutText(assembly.name);
  out.PutText(assembly.format);
  out.PutText(assembly.length_unit);
  out.Put<uint64_t>(assembly.parts.size());
  for (const Part& part : assembly.parts) {
    out.PutText(part.name);
    PutMesh(&out, part.mesh);
    PutTransform(&out, part.cad_from_model);
    out.Put<double>(part.mass.volume_mm3);
    PutVector<3>(&out, part.mass.center_of_mass);
    for (int k = 0; k < 9; ++k) out.Put<double>(part.mass.inertia.data()[k]);
    out.Put<uint8_t>(part.mass_from_brep);
    out.Put<uint8_t>(part.watertight);
    out.Put<double>(part.max_deviation_mm);
    PutColor(&out, part.color);
    PutSymmetries(&out, part.symmetries);
    PutShape(&out, part.brep);
  }
  out.Put<uint64_t>(assembly.instances.size());
  for (const Instance& instance : assembly.instances) {
    out.Put<int32_t>(instance.part);
    out.PutText(instance.name);
    PutTransform(&out, instance.world_from_model);
    PutColor(&out, instance.color);
    out.PutText(instance.path);
  }
  out.Put<uint64_t>(warnings.size());
  for (const std::string& w : warnings) out.PutText(w);
  return std::move(out.bytes());
}

Assembly DecodeAssembly(std::string_view bytes, std::vector<std::string>* warnings) {
  ByteReader in(bytes);
  if (in.Get<uint32_t>() != kAssemblyTag) throw Error("part cache: not an assembly");
  Assembly assembly;
  assembly.name = in.GetText();
  assembly.format = in.GetText();
  assembly.length_unit = in.GetText();
  const uint64_t parts = in.Get<uint64_t>();
  for (uint64_t p = 0; p < parts; ++p) {
    Part part;
    part.name = in.GetText();
    part.mesh = GetMesh(&in);
    part.cad_from_model = GetTransform(&in);
    part.mass.volume_mm3 = in.Get<double>();
    part.mass.center_of_mass = GetVector3(&in);
    for (int k = 0; k < 9; ++k) part.mass.inertia.data()[k] = in.Get<double>();
    part.mass_from_brep = in.Get<uint8_t>() != 0;
    part.watertight = in.Get<uint8_t>() != 0;
    part.max_deviation_mm = in.Get<double>();
    part.color = GetColor(&in);
    part.symmetries = GetSymmetries(&in);
    part.brep = GetShape(&in);
    assembly.parts.push_back(std::move(part));
  }
  const uint64_t instances = in.Get<uint64_t>();
  for (uint64_t i = 0; i < instances; ++i) {
    Instance instance;
    instance.part = in.Get<int32_t>();
    if (instance.part < 0 || static_cast<uint64_t>(instance.part) >= parts)
      throw Error("part cache: an instance names no part");
    instance.name = in.GetText();
    instance.world_from_model = GetTransform(&in);
    instance.color = GetColor(&in);
    instance.path = in.GetText();
    assembly.instances.push_back(std::move(instance));
  }
  const uint64_t n_warnings = in.Get<uint64_t>();
  std::vector<std::string> found;
  for (uint64_t k = 0; k < n_warnings; ++k) found.push_back(in.GetText());
  if (!in.done()) throw Error("part cache: trailing bytes after an assembly");
  if (warnings) *warnings = std::move(found);
  return assembly;
}

PartCache::PartCache(std::filesystem::path dir, std::string salt)
    : dir_(std::move(dir)), salt_(std::move(salt)) {}

void PartCache::Start(KeyHasher* hasher, std::string_view kind) const {
  hasher->Text("cadsynth part cache").Text(salt_).Text(kind);
}

std::filesystem::path PartCache::Path(std::string_view kind, const CacheKey& key) const {
  const std::string hex = key.Hex();
  return dir_ / std::string(kind) / hex.substr(0, 2) / (hex + ".bin");
}

std::optional<std::string> PartCache::Load(std::string_view kind, const CacheKey& key) const {
  std::ifstream in(Path(kind, key), std::ios::binary);
  if (!in) return std::nullopt;
  char magic[sizeof(kMagic)];
  uint64_t size = 0, checksum = 0;
  in.read(magic, sizeof(magic));
  in.read(reinterpret_cast<char*>(&size), sizeof(size));
  in.read(reinterpret_cast<char*>(&checksum), sizeof(checksum));
  if (!in || std::memcmp(magic, kMagic, sizeof(kMagic)) != 0 || size > (uint64_t{1} << 40))
    return std::nullopt;
  std::string bytes(size, '\0');
  in.read(bytes.data(), static_cast<std::streamsize>(size));
  if (!in || in.peek() != std::char_traits<char>::eof()) return std::nullopt;
  if (XXH3_64bits(bytes.data(), bytes.size()) != checksum) return std::nullopt;
  return bytes;
}

void PartCache::Store(std::string_view kind, const CacheKey& key, std::string_view bytes) const {
  const std::filesystem::path path = Path(kind, key);
  std::error_code ec;
  std::filesystem::create_directories(path.parent_path(), ec);
  // A name of this process and thread, so that shards storing the same entry never share one.
  static std::atomic<uint64_t> counter{0};
  const std::filesystem::path temporary =
      path.string() + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(++counter);
  bool ok = !ec;
  if (ok) {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    const uint64_t size = bytes.size(), checksum = XXH3_64bits(bytes.data(), bytes.size());
    out.write(kMagic, sizeof(kMagic));
    out.write(reinterpret_cast<const char*>(&size), sizeof(size));
    out.write(reinterpret_cast<const char*>(&checksum), sizeof(checksum));
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    out.close();
    ok = static_cast<bool>(out);
    if (ok) std::filesystem::rename(temporary, path, ec), ok = !ec;
  }
  if (!ok) {
    std::filesystem::remove(temporary, ec);
    if (!warned_.exchange(true)) {
      Warn("part cache: cannot write to " + dir_.string() +
           " (full or read-only?); going on without storing results");
    }
  }
}

std::optional<std::filesystem::path> PartCache::DefaultDirectory() {
  if (const char* set = std::getenv("CADSYNTH_CACHE"); set != nullptr && *set != '\0') {
    if (std::string(set) == "off") return std::nullopt;
    return std::filesystem::path(set);
  }
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg != nullptr && *xdg == '/')
    return std::filesystem::path(xdg) / "cadsynth";
  if (const char* home = std::getenv("HOME"); home != nullptr && *home == '/')
    return std::filesystem::path(home) / ".cache" / "cadsynth";
  return std::nullopt;
}

}  // namespace cadsynth
