#include "cad/part_cache.h"

#include <sys/stat.h>

#include <cstdlib>
#include <fstream>
#include <limits>

#include <gtest/gtest.h>

#include "cad/core/error.h"
#include "cad/shape.h"
#include "tests/test_support.h"

namespace cadsynth {
namespace {

std::vector<std::string>* g_seen = nullptr;
void Collect(const std::string& message) { g_seen->push_back(message); }

Assembly SampleAssembly() {
  Assembly a;
  a.name = "sample";
  a.format = "STEP";
  a.length_unit = "inch";
  TessellationOptions options;
  Part shaft = MakePart("shaft", MakeCylinder(6, 40), options);
  shaft.color = Eigen::Vector3f(0.25f, 0.5f, 0.75f);
  shaft.symmetries = Symmetries::Revolution(true, 1.5);
  shaft.max_deviation_mm = 0.0421;
  a.parts.push_back(shaft);
  Part plate;  // a mesh-only part, no B-rep
  plate.name = "plate";
  plate.mesh = MakePart("p", MakeBox(30, 20, 4), options).mesh;
  plate.mesh.face_ids.clear();
  for (const Eigen::Vector3f& p : plate.mesh.positions) plate.mesh.uvs.emplace_back(p.x(), p.y());
  plate.symmetries = Symmetries::Cyclic(2, true);
  a.parts.push_back(plate);
  Instance i;
  i.part = 1;
  i.name = "plate:1";
  i.path = "root/plate:1";
  i.world_from_model =
      Eigen::Translation3d(1, 2, 3) * Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ());
  i.color = Eigen::Vector3f(1, 0, 0);
  a.instances = {Instance{0, "shaft:1", Eigen::Isometry3d::Identity(), std::nullopt, "root"}, i};
  return a;
}

void ExpectSameMesh(const Mesh& a, const Mesh& b) {
  ASSERT_EQ(a.positions.size(), b.positions.size());
  for (size_t k = 0; k < a.positions.size(); ++k) EXPECT_EQ(a.positions[k], b.positions[k]);
  ASSERT_EQ(a.normals.size(), b.normals.size());
  for (size_t k = 0; k < a.normals.size(); ++k) EXPECT_EQ(a.normals[k], b.normals[k]);
  ASSERT_EQ(a.triangles.size(), b.triangles.size());
  for (size_t k = 0; k < a.triangles.size(); ++k) EXPECT_EQ(a.triangles[k], b.triangles[k]);
  EXPECT_EQ(a.face_ids, b.face_ids);
  ASSERT_EQ(a.uvs.size(), b.uvs.size());
  for (size_t k = 0; k < a.uvs.size(); ++k) EXPECT_EQ(a.uvs[k], b.uvs[k]);
}

// Everything the importer returns comes back bit for bit; the B-rep comes back such that
// tessellating it again gives the same mesh (scaled variants re-tessellate it).
TEST(PartCache, AssemblyRoundTripsExactly) {
  const Assembly a = SampleAssembly();
  const std::string bytes = EncodeAssembly(a, {"first warning", "second"});
  std::vector<std::string> warnings;
  const Assembly b = DecodeAssembly(bytes, &warnings);
  EXPECT_EQ(warnings, (std::vector<std::string>{"first warning", "second"}));
  EXPECT_EQ(b.name, a.name);
  EXPECT_EQ(b.format, a.format);
  EXPECT_EQ(b.length_unit, a.length_unit);
  ASSERT_EQ(b.parts.size(), 2u);
  for (size_t p = 0; p < 2; ++p) {
    SCOPED_TRACE(p);
    const Part& x = a.parts[p];
    const Part& y = b.parts[p];
    EXPECT_EQ(y.name, x.name);
    ExpectSameMesh(x.mesh, y.mesh);
    EXPECT_EQ(y.cad_from_model.matrix(), x.cad_from_model.matrix());
    EXPECT_EQ(y.mass.volume_mm3, x.mass.volume_mm3);
    EXPECT_EQ(y.mass.center_of_mass, x.mass.center_of_mass);
    EXPECT_EQ(y.mass.inertia, x.mass.inertia);
    EXPECT_EQ(y.mass_from_brep, x.mass_from_brep);
    EXPECT_EQ(y.watertight, x.watertight);
    EXPECT_EQ(y.max_deviation_mm, x.max_deviation_mm);
    EXPECT_EQ(y.color.has_value(), x.color.has_value());
    if (x.color) {
      EXPECT_EQ(*y.color, *x.color);
    }
    ASSERT_EQ(y.symmetries.discrete.size(), x.symmetries.discrete.size());
    for (size_t k = 0; k < x.symmetries.discrete.size(); ++k)
      EXPECT_EQ(y.symmetries.discrete[k].matrix(), x.symmetries.discrete[k].matrix());
    ASSERT_EQ(y.symmetries.continuous.size(), x.symmetries.continuous.size());
    for (size_t k = 0; k < x.symmetries.continuous.size(); ++k) {
      EXPECT_EQ(y.symmetries.continuous[k].direction, x.symmetries.continuous[k].direction);
      EXPECT_EQ(y.symmetries.continuous[k].offset, x.symmetries.continuous[k].offset);
    }
    EXPECT_EQ(y.brep.IsNull(), x.brep.IsNull());
  }
  ASSERT_FALSE(b.parts[0].brep.IsNull());
  EXPECT_TRUE(b.parts[0].brep.Bounds().isApprox(a.parts[0].brep.Bounds()));
  TessellationOptions fine;
  fine.linear_deflection_mm = 0.01;
  ExpectSameMesh(MakePart("again", a.parts[0].brep, fine).mesh,
                 MakePart("again", b.parts[0].brep, fine).mesh);
  ASSERT_EQ(b.instances.size(), 2u);
  EXPECT_EQ(b.instances[1].part, 1);
  EXPECT_EQ(b.instances[1].name, "plate:1");
  EXPECT_EQ(b.instances[1].path, "root/plate:1");
  EXPECT_EQ(b.instances[1].world_from_model.matrix(), a.instances[1].world_from_model.matrix());
  EXPECT_EQ(*b.instances[1].color, *a.instances[1].color);
  EXPECT_FALSE(b.instances[0].color.has_value());
}

// Damaged bytes are an Error, never a crash or a wrong part.
TEST(PartCache, TruncatedOrForeignBytesAreErrors) {
  const std::string bytes = EncodeAssembly(SampleAssembly(), {});
  for (size_t cut : {size_t{0}, size_t{3}, size_t{40}, bytes.size() / 2, bytes.size() - 1}) {
    EXPECT_THROW(DecodeAssembly(bytes.substr(0, cut), nullptr), Error) << cut;
  }
  EXPECT_THROW(DecodeAssembly(bytes + "x", nullptr), Error);
  ConvexHull hull;
  hull.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  hull.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  EXPECT_THROW(DecodeAssembly(EncodeHull(hull), nullptr), Error);
  EXPECT_EQ(DecodeHull(EncodeHull(hull)).triangles, hull.triangles);
  ConvexHull bad = hull;
  bad.triangles[3][2] = 4;  // names no vertex
  EXPECT_THROW(DecodeHull(EncodeHull(bad)), Error);
}

TEST(PartCache, DetectedSymmetriesRoundTripExactly) {
  DetectedSymmetries found;
  found.symmetries = Symmetries::Cyclic(6, true, 1.25, 0.3);
  found.discrete_deviation_mm.assign(found.symmetries.discrete.size(), 0.0);
  for (size_t k = 0; k < found.discrete_deviation_mm.size(); ++k)
    found.discrete_deviation_mm[k] = 0.001 * static_cast<double>(k + 1);
  found.discrete_brep_mm = {1e-9, std::numeric_limits<double>::infinity()};
  found.brep_faces_not_compared = 3;
  found.tolerance_mm = 0.0937;
  found.axes = {{Eigen::Vector3d(0, 0, -1), 6}, {Eigen::Vector3d(1, 0, 0), 2}};
  found.centre = Eigen::Vector3d(0.5, -0.25, 3.0);
  const std::vector<double> entries = {0.002, 0.004};
  std::vector<double> entries_read;
  const DetectedSymmetries read =
      DecodeDetectedSymmetries(EncodeDetectedSymmetries(found, entries), &entries_read);
  ASSERT_EQ(read.symmetries.discrete.size(), found.symmetries.discrete.size());
  for (size_t k = 0; k < found.symmetries.discrete.size(); ++k)
    EXPECT_EQ(read.symmetries.discrete[k].matrix(), found.symmetries.discrete[k].matrix());
  EXPECT_EQ(read.discrete_deviation_mm, found.discrete_deviation_mm);
  EXPECT_EQ(read.discrete_brep_mm, found.discrete_brep_mm);
  EXPECT_EQ(read.brep_faces_not_compared, 3);
  EXPECT_EQ(read.tolerance_mm, found.tolerance_mm);
  ASSERT_EQ(read.axes.size(), 2u);
  EXPECT_EQ(read.axes[0].direction, found.axes[0].direction);
  EXPECT_EQ(read.axes[0].order, 6);
  EXPECT_EQ(read.centre, found.centre);
  EXPECT_EQ(entries_read, entries);
  // Cut short, or deviations that do not match the symmetries: errors (a miss).
  const std::string bytes = EncodeDetectedSymmetries(found, entries);
  for (size_t cut : {size_t{0}, size_t{4}, bytes.size() / 2, bytes.size() - 1})
    EXPECT_THROW(DecodeDetectedSymmetries(bytes.substr(0, cut), &entries_read), Error) << cut;
  DetectedSymmetries bad = found;
  bad.discrete_deviation_mm.pop_back();
  EXPECT_THROW(DecodeDetectedSymmetries(EncodeDetectedSymmetries(bad, {}), &entries_read), Error);
}

TEST(PartCache, GraspsRoundTripExactly) {
  ParallelJawGrasp jaw;
  jaw.model_from_gripper =
      Eigen::Translation3d(1, 2, 3) * Eigen::AngleAxisd(0.3, Eigen::Vector3d(0, 0.6, 0.8));
  jaw.width_mm = 12.5;
  jaw.opening_mm = 22.5;
  jaw.depth_mm = 8.8;
  jaw.free_when_open = true;
  jaw.contacts[1] = Eigen::Vector3d(4, 5, 6);
  jaw.normals[0] = Eigen::Vector3d(0, 0, -1);
  jaw.quality = 0.75;
  SuctionGrasp cup;
  cup.point = Eigen::Vector3d(-1, 0.5, 2);
  cup.seal = 0.9;
  cup.wrench = 0.4;
  cup.rim_height_mm = 0.25;
  std::vector<ParallelJawGrasp> jaws;
  std::vector<SuctionGrasp> cups;
  const std::string bytes = EncodeGrasps({jaw, jaw}, {cup});
  DecodeGrasps(bytes, &jaws, &cups);
  ASSERT_EQ(jaws.size(), 2u);
  ASSERT_EQ(cups.size(), 1u);
  EXPECT_EQ(jaws[1].model_from_gripper.matrix(), jaw.model_from_gripper.matrix());
  EXPECT_EQ(jaws[1].width_mm, 12.5);
  EXPECT_EQ(jaws[1].opening_mm, 22.5);
  EXPECT_EQ(jaws[1].depth_mm, 8.8);
  EXPECT_TRUE(jaws[1].free_when_open);
  EXPECT_EQ(jaws[1].contacts[1], jaw.contacts[1]);
  EXPECT_EQ(jaws[1].normals[0], jaw.normals[0]);
  EXPECT_EQ(jaws[1].quality, 0.75);
  EXPECT_EQ(cups[0].point, cup.point);
  EXPECT_EQ(cups[0].approach, cup.approach);
  EXPECT_EQ(cups[0].quality(), cup.quality());
  EXPECT_EQ(cups[0].rim_height_mm, 0.25);
  for (size_t cut : {size_t{0}, size_t{7}, bytes.size() / 2, bytes.size() - 1})
    EXPECT_THROW(DecodeGrasps(bytes.substr(0, cut), &jaws, &cups), Error) << cut;
  EXPECT_THROW(DecodeGrasps(bytes + "x", &jaws, &cups), Error);
}

// An entry whose bytes changed on disk (a flipped bit, a cut write) is a miss.
TEST(PartCache, DamagedEntriesAreMisses) {
  testing::ScratchDir dir;
  const PartCache cache(dir.path(), "test");
  KeyHasher hasher;
  cache.Start(&hasher, "thing 1");
  const CacheKey key = hasher.Text("input").Key();
  EXPECT_FALSE(cache.Load("thing", key));
  cache.Store("thing", key, "the stored value");
  ASSERT_EQ(cache.Load("thing", key).value_or(""), "the stored value");
  const std::filesystem::path file =
      dir.path() / "thing" / key.Hex().substr(0, 2) / (key.Hex() + ".bin");
  ASSERT_TRUE(std::filesystem::exists(file));
  std::string raw = testing::ReadFile(file);
  raw[raw.size() - 3] ^= 0x10;
  std::ofstream(file, std::ios::binary | std::ios::trunc) << raw;
  EXPECT_FALSE(cache.Load("thing", key));
  raw[raw.size() - 3] ^= 0x10;
  std::ofstream(file, std::ios::binary | std::ios::trunc) << raw.substr(0, raw.size() - 1);
  EXPECT_FALSE(cache.Load("thing", key));
  cache.Store("thing", key, "the stored value");
  EXPECT_EQ(cache.Load("thing", key).value_or(""), "the stored value");
  EXPECT_FALSE(cache.Load("other", key));
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir.path())) {
    EXPECT_EQ(entry.path().string().find(".tmp."), std::string::npos) << entry.path();
  }
}

// Keys separate salts (builds), kinds and how the bytes split into fields.
TEST(PartCache, KeysSeparateBuildsKindsAndFields) {
  const auto key = [](const std::string& salt, const std::string& kind, const std::string& a,
                      const std::string& b) {
    KeyHasher hasher;
    PartCache("/nonexistent", salt).Start(&hasher, kind);
    return hasher.Text(a).Text(b).Key();
  };
  const CacheKey base = key("build 1", "hull 1", "ab", "c");
  EXPECT_EQ(key("build 1", "hull 1", "ab", "c"), base);
  EXPECT_FALSE(key("build 2", "hull 1", "ab", "c") == base);
  EXPECT_FALSE(key("build 1", "hull 2", "ab", "c") == base);
  EXPECT_FALSE(key("build 1", "hull 1", "a", "bc") == base);
  EXPECT_EQ(base.Hex().size(), 32u);
  Mesh m = SampleAssembly().parts[1].mesh;
  const CacheKey mesh_key = KeyHasher().Geometry(m).Key();
  m.positions[5].x() = std::nextafter(m.positions[5].x(), 1e9f);
  EXPECT_FALSE(KeyHasher().Geometry(m).Key() == mesh_key);
}

// A cache that cannot be written warns once and the work goes on.
TEST(PartCache, UnwritableCacheWarnsOnceAndGoesOn) {
  testing::ScratchDir dir;
  std::ofstream(dir / "file") << "not a folder";
  const PartCache cache(dir / "file", "test");
  std::vector<std::string> seen;
  g_seen = &seen;
  const WarningSink previous = SetWarningSink(&Collect);
  KeyHasher hasher;
  const CacheKey key = hasher.Text("x").Key();
  EXPECT_NO_THROW(cache.Store("thing", key, "value"));
  EXPECT_NO_THROW(cache.Store("thing", key, "value"));
  SetWarningSink(previous);
  EXPECT_FALSE(cache.Load("thing", key));
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_NE(seen[0].find("cannot write"), std::string::npos) << seen[0];
}

TEST(PartCache, DefaultDirectoryFollowsTheEnvironment) {
  const char* old = std::getenv("CADSYNTH_CACHE");
  const std::string saved = old ? old : "";
  setenv("CADSYNTH_CACHE", "/tmp/somewhere", 1);
  EXPECT_EQ(PartCache::DefaultDirectory().value_or(""), "/tmp/somewhere");
  setenv("CADSYNTH_CACHE", "off", 1);
  EXPECT_FALSE(PartCache::DefaultDirectory());
  unsetenv("CADSYNTH_CACHE");
  setenv("XDG_CACHE_HOME", "/xdg", 1);
  EXPECT_EQ(PartCache::DefaultDirectory().value_or(""), "/xdg/cadsynth");
  unsetenv("XDG_CACHE_HOME");
  if (const char* home = std::getenv("HOME"); home && *home == '/') {
    EXPECT_EQ(PartCache::DefaultDirectory().value_or(""),
              std::filesystem::path(home) / ".cache" / "cadsynth");
  }
  if (old) setenv("CADSYNTH_CACHE", saved.c_str(), 1);
}

}  // namespace
}  // namespace cadsynth
