#include "tools/pipeline/prepare.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>

#include <gtest/gtest.h>

#include "cad/core/error.h"
#include "cad/part_cache.h"
#include "tests/test_support.h"

namespace cadsynth {
namespace {

// The default job's three demo sets: objects shared by the scenes, one obj_id per instance,
// every instance resting on the floor (z >= 0, touching it).
TEST(Prepare, DefaultJobScenesObjectsAndClasses) {
  const RunSpec spec = DefaultRunSpec();
  const PreparedRun run = Prepare(spec);
  EXPECT_EQ(run.parts.size(), 13u);
  EXPECT_EQ(run.classes.size(), run.parts.size());
  ASSERT_EQ(run.scenes.size(), 3u);
  ASSERT_EQ(run.obj_ids.size(), 3u);
  size_t instances = 0;
  for (size_t s = 0; s < 3; ++s) {
    SCOPED_TRACE(s);
    ASSERT_EQ(run.obj_ids[s].size(), run.scenes[s].instances.size());
    double lowest = 1e300;
    for (size_t i = 0; i < run.scenes[s].instances.size(); ++i) {
      const Instance& instance = run.scenes[s].instances[i];
      EXPECT_EQ(run.obj_ids[s][i], instance.part + 1);
      for (const Eigen::Vector3f& p : run.parts[instance.part].mesh.positions) {
        lowest = std::min(lowest, (instance.world_from_model * p.cast<double>()).z());
      }
    }
    EXPECT_NEAR(lowest, 0.0, 1e-3);  // resting on the floor
    instances += run.scenes[s].instances.size();
  }
  EXPECT_EQ(instances, 15u);
  EXPECT_NE(run.variants_json.find("\"variants\""), std::string::npos);
}

TEST(Prepare, PlacementWarningsSayWhenTheSceneIsTooLargeOrTooSmall) {
  const RunSpec spec = DefaultRunSpec();
  const PreparedRun run = Prepare(spec);
  SweepOptions near = spec.sweep;
  near.radius_mm = {30.0};  // inside the scene (it reaches 48 mm from the target)
  const auto warnings =
      PlacementWarnings(run.parts, run.scenes[0].instances, spec.intrinsics, near);
  ASSERT_FALSE(warnings.empty());
  EXPECT_NE(warnings[0].find("beyond the nearest camera radius"), std::string::npos) << warnings[0];
  EXPECT_TRUE(
      PlacementWarnings(run.parts, run.scenes[0].instances, spec.intrinsics, spec.sweep).empty());
}

std::vector<std::string>* g_seen = nullptr;
void Collect(const std::string& message) { g_seen->push_back(message); }

// An open mesh (a tetrahedron missing a face) warns when read; a gear family variant.
RunSpec CacheSpec(const std::filesystem::path& stl) {
  std::ofstream out(stl);
  out << "solid open\n";
  const char* facets[] = {"0 0 0  0 10 0  10 0 0", "0 0 0  10 0 0  0 0 10",
                          "0 0 0  0 0 10  0 10 0"};
  for (const char* f : facets) {
    std::istringstream in(f);
    double v[9];
    for (double& x : v) in >> x;
    out << "facet normal 0 0 0\nouter loop\n";
    for (int k = 0; k < 3; ++k)
      out << "vertex " << v[3 * k] << " " << v[3 * k + 1] << " " << v[3 * k + 2] << "\n";
    out << "endloop\nendfacet\n";
  }
  out << "endsolid open\n";
  out.close();
  RunSpec spec = DefaultRunSpec();
  spec.scenes.resize(1);
  PartSource file;
  file.path = stl;
  spec.scenes[0].sources.insert(spec.scenes[0].sources.begin(), file);
  return spec;
}

// The part cache gives the bits a run without it gives, and the same warnings in the same order,
// whether it is empty (cold) or full (warm); a warm run finds every entry it needs.
TEST(Prepare, PartCacheGivesTheSameParts) {
  testing::ScratchDir dir;
  const RunSpec spec = CacheSpec(dir / "open.stl");
  std::vector<std::string> seen;
  g_seen = &seen;
  const WarningSink previous = SetWarningSink(&Collect);
  const PreparedRun plain = Prepare(spec);
  const std::vector<std::string> plain_warnings = seen;
  const PartCache cache(dir / "cache", "test build");
  seen.clear();
  const PreparedRun cold = Prepare(spec, {}, &cache);
  const std::vector<std::string> cold_warnings = seen;
  size_t entries = 0;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir / "cache"))
    entries += e.is_regular_file();
  seen.clear();
  const PreparedRun warm = Prepare(spec, {}, &cache);
  const std::vector<std::string> warm_warnings = seen;
  SetWarningSink(previous);
  size_t entries_after = 0;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir / "cache"))
    entries_after += e.is_regular_file();
  EXPECT_EQ(entries_after, entries);            // nothing new to store
  EXPECT_GE(entries, 2u * plain.parts.size());  // an import or variant and a hull per part
  ASSERT_FALSE(plain_warnings.empty());
  EXPECT_NE(plain_warnings[0].find("not closed"), std::string::npos) << plain_warnings[0];
  EXPECT_EQ(cold_warnings, plain_warnings);
  EXPECT_EQ(warm_warnings, plain_warnings);
  for (const PreparedRun* run : {&cold, &warm}) {
    ASSERT_EQ(run->parts.size(), plain.parts.size());
    for (size_t p = 0; p < plain.parts.size(); ++p) {
      SCOPED_TRACE(plain.parts[p].name);
      const Part& a = plain.parts[p];
      const Part& b = run->parts[p];
      EXPECT_EQ(b.name, a.name);
      ASSERT_EQ(b.mesh.positions.size(), a.mesh.positions.size());
      EXPECT_TRUE(
          std::equal(a.mesh.positions.begin(), a.mesh.positions.end(), b.mesh.positions.begin()));
      EXPECT_TRUE(std::equal(a.mesh.normals.begin(), a.mesh.normals.end(), b.mesh.normals.begin()));
      EXPECT_EQ(b.mass.volume_mm3, a.mass.volume_mm3);
      ASSERT_EQ(b.symmetries.discrete.size(), a.symmetries.discrete.size());
      for (size_t k = 0; k < a.symmetries.discrete.size(); ++k)
        EXPECT_EQ(b.symmetries.discrete[k].matrix(), a.symmetries.discrete[k].matrix());
      EXPECT_EQ(b.symmetries.continuous.size(), a.symmetries.continuous.size());
      ASSERT_EQ(b.hull != nullptr, a.hull != nullptr);
      // The same corners and diameter (CGAL may split a planar facet into other triangles from
      // one call to the next; the poses use the facets' outlines, not their triangles).
      if (a.hull) {
        EXPECT_TRUE(a.hull->vertices == b.hull->vertices);
        EXPECT_EQ(b.hull->diameter, a.hull->diameter);
      }
    }
    ASSERT_EQ(run->scenes.size(), plain.scenes.size());
    for (size_t s = 0; s < plain.scenes.size(); ++s) {
      ASSERT_EQ(run->scenes[s].instances.size(), plain.scenes[s].instances.size());
      for (size_t i = 0; i < plain.scenes[s].instances.size(); ++i) {
        EXPECT_EQ(run->scenes[s].instances[i].world_from_model.matrix(),
                  plain.scenes[s].instances[i].world_from_model.matrix());
      }
    }
    EXPECT_EQ(run->variants_json, plain.variants_json);
  }
}

// The symmetries of an imported part are detected once: the next run reads them from the part
// cache (here an entry replaced by other symmetries, which the run then reports as the part's).
TEST(Prepare, ImportedPartsSymmetriesComeFromThePartCache) {
  testing::ScratchDir dir;
  const RunSpec spec = CacheSpec(dir / "open.stl");
  const PartCache cache(dir / "cache", "test build");
  const PreparedRun cold = Prepare(spec, {}, &cache);
  const auto found = std::find_if(cold.parts.begin(), cold.parts.end(),
                                  [](const Part& p) { return p.name == "open"; });
  ASSERT_NE(found, cold.parts.end());
  // Three right-angled faces about a corner: 3-fold about the diagonal (1, 1, 1).
  ASSERT_EQ(found->symmetries.discrete.size(), 2u);
  EXPECT_TRUE(found->symmetries.continuous.empty());
  std::vector<std::filesystem::path> entries;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir / "cache" / "symmetry"))
    if (e.is_regular_file()) entries.push_back(e.path());
  ASSERT_EQ(entries.size(), 1u);  // the only part whose symmetries are detected
  const std::string hex = entries[0].stem().string();
  ASSERT_EQ(hex.size(), 32u);
  const CacheKey key{std::stoull(hex.substr(0, 16), nullptr, 16),
                     std::stoull(hex.substr(16), nullptr, 16)};
  DetectedSymmetries other;
  other.symmetries.continuous.push_back({Eigen::Vector3d::UnitX(), Eigen::Vector3d(1, 2, 3)});
  other.continuous_deviation_mm = {0.001};
  other.axes.push_back({Eigen::Vector3d::UnitX(), 0});
  other.tolerance_mm = 0.05;
  cache.Store("symmetry", key, EncodeDetectedSymmetries(other, {}));
  const PreparedRun warm = Prepare(spec, {}, &cache);
  const auto read = std::find_if(warm.parts.begin(), warm.parts.end(),
                                 [](const Part& p) { return p.name == "open"; });
  ASSERT_NE(read, warm.parts.end());
  EXPECT_TRUE(read->symmetries.discrete.empty());
  ASSERT_EQ(read->symmetries.continuous.size(), 1u);
  EXPECT_EQ(read->symmetries.continuous[0].offset, Eigen::Vector3d(1, 2, 3));
}

// An entry damaged on disk is computed again, with the same result.
TEST(Prepare, DamagedCacheEntriesAreRebuilt) {
  testing::ScratchDir dir;
  const RunSpec spec = CacheSpec(dir / "open.stl");
  const PartCache cache(dir / "cache", "test build");
  const PreparedRun cold = Prepare(spec, {}, &cache);
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir / "cache")) {
    if (!e.is_regular_file()) continue;
    std::string raw = testing::ReadFile(e.path());
    raw.resize(raw.size() / 2);
    std::ofstream(e.path(), std::ios::binary | std::ios::trunc) << raw;
  }
  const PreparedRun again = Prepare(spec, {}, &cache);
  ASSERT_EQ(again.parts.size(), cold.parts.size());
  for (size_t p = 0; p < cold.parts.size(); ++p) {
    EXPECT_TRUE(std::equal(cold.parts[p].mesh.positions.begin(), cold.parts[p].mesh.positions.end(),
                           again.parts[p].mesh.positions.begin()));
  }
  EXPECT_EQ(again.variants_json, cold.variants_json);
}

void WriteAsciiStl(const std::filesystem::path& path,
                   const std::vector<std::array<Eigen::Vector3d, 3>>& triangles) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path);
  out << "solid s\n";
  for (const auto& t : triangles) {
    out << "facet normal 0 0 0\nouter loop\n";
    for (const auto& v : t) out << "vertex " << v.x() << " " << v.y() << " " << v.z() << "\n";
    out << "endloop\nendfacet\n";
  }
  out << "endsolid s\n";
}

std::vector<std::array<Eigen::Vector3d, 3>> Tetrahedron(double s) {
  const Eigen::Vector3d a(0, 0, 0), b(s, 0, 0), c(0, s, 0), d(0, 0, s);
  return {{a, c, b}, {a, b, d}, {a, d, c}, {b, c, d}};  // outward
}

// Two different parts of one name (exporters call every body "SOLID") become two names, so COCO
// gets distinct categories; a flat sheet (no volume) lies in the floor instead of failing.
TEST(Prepare, SameNamesMadeUniqueAndFlatSheetsLieFlat) {
  testing::ScratchDir dir;
  WriteAsciiStl(dir / "a" / "part.stl", Tetrahedron(10));
  WriteAsciiStl(dir / "b" / "part.stl", Tetrahedron(20));
  std::vector<std::array<Eigen::Vector3d, 3>> octagon;
  const auto corner = [](int i) {
    return Eigen::Vector3d(10 * std::cos(i * M_PI / 4), 10 * std::sin(i * M_PI / 4), 3);
  };
  for (int i = 1; i + 1 < 8; ++i) octagon.push_back({corner(0), corner(i), corner(i + 1)});
  WriteAsciiStl(dir / "sheet.stl", octagon);
  RunSpec spec = DefaultRunSpec();
  spec.scenes.resize(1);
  spec.scenes[0].sources.clear();
  for (const char* file : {"a/part.stl", "b/part.stl", "sheet.stl"})
    spec.scenes[0].sources.push_back(
        PartSource{.kind = PartSource::Kind::kFile, .path = dir / file});
  spec.scenes[0].arrangement.layout = Layout::kRow;
  std::vector<std::string> seen;
  g_seen = &seen;
  const WarningSink previous = SetWarningSink(&Collect);
  const PreparedRun run = Prepare(spec);
  SetWarningSink(previous);
  ASSERT_EQ(run.parts.size(), 3u);
  EXPECT_EQ(run.parts[0].name, "part");
  EXPECT_EQ(run.parts[1].name, "part_2");
  EXPECT_EQ(run.parts[2].name, "sheet");
  EXPECT_NE(run.classes[0].name, run.classes[1].name);
  const Instance& sheet = run.scenes[0].instances[2];
  ASSERT_EQ(sheet.part, 2);
  for (const Eigen::Vector3f& p : run.parts[2].mesh.positions)
    EXPECT_NEAR((sheet.world_from_model * p.cast<double>()).z(), 0.0, 1e-4);
}

// Image textures by texture coordinates: a part from an OBJ with them takes the rule, a part
// without them is refused with the rule's place in the recipe.
TEST(Prepare, UvProjectionNeedsTextureCoordinates) {
  testing::ScratchDir dir;
  testing::WriteSolidPng(dir / "tile.png", 2, 2, 0x80);
  std::ofstream(dir / "label.obj") << "v -5 -5 0\nv 5 -5 0\nv 5 5 0\nv -5 5 0\nv 0 0 4\n"
                                      "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 0.5\n"
                                      "f 1/1 4/4 3/3 2/2\nf 1/1 2/2 5/5\nf 2/2 3/3 5/5\n"
                                      "f 3/3 4/4 5/5\nf 4/4 1/1 5/5\n";
  const std::string recipe =
      "scenes:\n  - name: s\n    parts: [{file: label.obj}, {family: hex_nut}]\n"
      "render: {mode: pbr}\nmaterials:\n"
      "  assign:\n    - {name: '*', texture: {type: image, file: tile.png, projection: uv}}\n";
  const RunSpec spec = ParseRecipe(recipe, (dir / "r.yaml").string(), dir.path());
  try {
    Prepare(spec);
    ADD_FAILURE() << "expected an error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("r.yaml:7:7: materials.assign[0]: texture projection 'uv', but part "),
              std::string::npos)
        << what;
    EXPECT_NE(what.find("has no texture coordinates"), std::string::npos) << what;
  }
  RunSpec only_obj = ParseRecipe(recipe, (dir / "r.yaml").string(), dir.path());
  only_obj.scenes[0].sources.resize(1);
  const PreparedRun run = Prepare(only_obj);
  ASSERT_EQ(run.parts.size(), 1u);
  EXPECT_TRUE(run.parts[0].mesh.has_uvs());
  EXPECT_EQ(run.scenes[0].instance_material, (std::vector<int>{0}));
}

// A pile scene: its copies rest inside the tote, which comes with the scene as a fixture (seen,
// not annotated); the collision shapes come from the part cache the second time, with the same
// poses.
// Every vertex of every part of `scene` lies inside a 120 x 90 mm container with a 6 mm floor
// (0.5 mm of collision margin allowed).
void ExpectInside120x90Tote(const PreparedRun& run, const Scene& scene) {
  for (const Instance& instance : scene.instances) {
    for (const Eigen::Vector3f& v : run.parts[instance.part].mesh.positions) {
      const Eigen::Vector3d p = instance.world_from_model * v.cast<double>();
      EXPECT_GT(p.z(), 6.0 - 0.5);
      EXPECT_LT(std::abs(p.x()), 60.5);
      EXPECT_LT(std::abs(p.y()), 45.5);
    }
  }
}

TEST(Prepare, PileSceneDropsCopiesIntoItsTote) {
  testing::ScratchDir dir;
  const std::string recipe =
      "scenes:\n  - name: bin\n    parts: [{family: hex_nut}]\n    layout: pile\n"
      "    copies: 12\n    seed: 4\n"
      "    container: {type: tote, inner: [120 mm, 90 mm], height: 60 mm}\n";
  const RunSpec spec = ParseRecipe(recipe, "r.yaml", dir.path());
  PartCache cache(dir / "cache", "test");
  const PreparedRun cold = Prepare(spec, {}, &cache);
  ASSERT_EQ(cold.scenes.size(), 1u);
  const Scene& scene = cold.scenes[0];
  ASSERT_EQ(scene.instances.size(), 12u);
  ASSERT_EQ(scene.fixtures.size(), 1u);
  EXPECT_EQ(scene.fixtures[0].name, "tote");
  EXPECT_NEAR(scene.fixtures[0].mesh.Bounds().sizes().x(), 120 + 2 * 6.0, 1e-3);
  ExpectInside120x90Tote(cold, scene);
  const PreparedRun warm = Prepare(spec, {}, &cache);
  for (size_t i = 0; i < 12; ++i) {
    EXPECT_EQ(warm.scenes[0].instances[i].world_from_model.matrix(),
              scene.instances[i].world_from_model.matrix());
  }
}

// Distractors in a pile fall with the copies: the tote, then one fixture per distractor (a
// family's part and primitives), all inside the tote; the parts (objects) are only the nuts, the
// instances only the copies. Without a cache and with one: the same poses.
TEST(Prepare, PileDistractorsFallWithTheCopiesAndAreFixtures) {
  testing::ScratchDir dir;
  const std::string recipe =
      "scenes:\n  - name: bin\n    parts: [{family: hex_nut}]\n    layout: pile\n"
      "    copies: 8\n    seed: 4\n"
      "    container: {type: tote, inner: [120 mm, 90 mm], height: 60 mm}\n"
      "randomize:\n  seed: 3\n  distractors: {count: 4, size: {uniform: [10 mm, 25 mm]},\n"
      "                objects: [box, cylinder, {family: washer}]}\n";
  const RunSpec spec = ParseRecipe(recipe, "r.yaml", dir.path());
  PartCache cache(dir / "cache", "test");
  const PreparedRun run = Prepare(spec, {}, &cache);
  ASSERT_EQ(run.parts.size(), 1u);
  const Scene& scene = run.scenes[0];
  ASSERT_EQ(scene.instances.size(), 8u);
  ASSERT_EQ(scene.fixtures.size(), 5u);
  EXPECT_EQ(scene.fixtures[0].name, "tote");
  EXPECT_EQ(run.randomization[0].first_distractor, 1u);
  for (size_t f = 1; f < 5; ++f) {
    EXPECT_EQ(scene.fixtures[f].name.rfind("distractor " + std::to_string(f - 1) + " (", 0), 0u)
        << scene.fixtures[f].name;
    const Eigen::AlignedBox3d box = scene.fixtures[f].mesh.Bounds();
    EXPECT_GT(box.min().z(), 6.0 - 0.6) << f;
    EXPECT_LT(std::max(std::abs(box.min().x()), std::abs(box.max().x())), 60.6) << f;
    EXPECT_LT(std::max(std::abs(box.min().y()), std::abs(box.max().y())), 45.6) << f;
  }
  ExpectInside120x90Tote(run, scene);
  const PreparedRun warm = Prepare(spec, {}, &cache);
  for (size_t f = 0; f < 5; ++f) {
    EXPECT_EQ(warm.scenes[0].fixtures[f].mesh.positions, scene.fixtures[f].mesh.positions);
  }
}

// A scene's own distractors replace the recipe's; scenes without inherit them; two family
// entries with other parameters are two objects (not one read twice); a flat layout of files
// and families keeps its parts where the layout put them.
TEST(Prepare, SceneDistractorsOverrideTheRecipesAndSourcesAreTheirOwn) {
  testing::ScratchDir dir;
  const std::string recipe =
      "scenes:\n"
      "  - {name: a, parts: [{family: hex_nut}], layout: row}\n"
      "  - name: b\n"
      "    parts: [{family: hex_nut}]\n"
      "    layout: row\n"
      "    randomize:\n"
      "      distractors: {count: 6, objects: [{family: washer, params: {size: M8}},\n"
      "                                        {family: washer, params: {size: M20}}]}\n"
      "randomize:\n  seed: 2\n  distractors: {count: 2, objects: [sphere]}\n";
  const PreparedRun run = Prepare(ParseRecipe(recipe, "r.yaml", dir.path()));
  ASSERT_EQ(run.scenes.size(), 2u);
  ASSERT_EQ(run.scenes[0].fixtures.size(), 2u);
  for (const auto& f : run.scenes[0].fixtures)
    EXPECT_NE(f.name.find("(sphere)"), std::string::npos);
  ASSERT_EQ(run.scenes[1].fixtures.size(), 6u);
  std::set<double> widths;
  for (const auto& f : run.scenes[1].fixtures) {
    EXPECT_NE(f.name.find("washer"), std::string::npos) << f.name;
    const Eigen::Vector3d size = f.mesh.Bounds().sizes();
    widths.insert(std::round(std::max({size.x(), size.y(), size.z()})));
  }
  EXPECT_EQ(widths.size(), 2u) << "both washers picked, each its own size";
  // The nuts (the only objects) rest as the row puts them, distractors or not.
  const PreparedRun plain = Prepare(ParseRecipe(
      "scenes:\n  - {name: a, parts: [{family: hex_nut}], layout: row}\n", "r.yaml", dir.path()));
  EXPECT_EQ(run.parts.size(), 1u);
  EXPECT_EQ(run.scenes[0].instances[0].world_from_model.matrix(),
            plain.scenes[0].instances[0].world_from_model.matrix());
}

// Physics rules reach the parts they match: a rule for another family leaves the pile as it was;
// a rule for the nuts changes it; a dropped scene puts every copy flat on the floor.
TEST(Prepare, PhysicsRulesMatchTheirPartsAndDroppedPartsLieOnTheFloor) {
  testing::ScratchDir dir;
  const auto poses = [&](const std::string& physics) {
    const std::string recipe =
        "scenes:\n  - name: bin\n    parts: [{family: hex_nut}]\n    layout: pile\n"
        "    copies: 6\n    seed: 2\n" +
        physics;
    const PreparedRun run = Prepare(ParseRecipe(recipe, "r.yaml", dir.path()));
    std::vector<Eigen::Matrix4d> out;
    for (const Instance& i : run.scenes[0].instances) out.push_back(i.world_from_model.matrix());
    return out;
  };
  const auto plain = poses("");
  EXPECT_EQ(poses("    physics: [{family: spur_gear, friction: 0.05}]\n"), plain);
  EXPECT_NE(poses("    physics: [{family: hex_nut, friction: 0.05}]\n"), plain);
  EXPECT_NE(poses("    physics: [{name: '*', friction: [0.1, 0.2]}]\n"), plain);

  const std::string recipe =
      "scenes:\n  - name: fallen\n    parts: [{family: hex_nut}]\n    layout: row\n"
      "    pose: dropped\n    copies: 8\n    seed: 1\n";
  const PreparedRun run = Prepare(ParseRecipe(recipe, "r.yaml", dir.path()));
  ASSERT_EQ(run.scenes[0].instances.size(), 8u);
  EXPECT_TRUE(run.scenes[0].fixtures.empty());
  for (const Instance& i : run.scenes[0].instances)
    EXPECT_NEAR(run.parts[i.part].mesh.Bounds(i.world_from_model).min().z(), 0.0, 1e-9);
}

// A container from a mesh file (container type: file): a tray written as an OBJ, drawn off the
// origin and Y-up; it stands centred on the floor as the scene's fixture, and the nuts lie in it.
TEST(Prepare, ContainerFromAFileHoldsThePile) {
  testing::ScratchDir dir;
  Container tray;
  tray.kind = Container::Kind::kTote;
  tray.inner_mm = {120, 90};
  tray.height_mm = 25;
  tray.corner_radius_mm = 0;
  const Mesh mesh = MakeContainerMesh(tray);
  {
    std::ofstream obj(dir / "tray.obj");
    // Y-up and moved: (x, y, z) -> (x + 500, z, -y).
    for (const Eigen::Vector3f& p : mesh.positions)
      obj << "v " << p.x() + 500 << " " << p.z() << " " << -p.y() << "\n";
    for (const auto& t : mesh.triangles)
      obj << "f " << t[0] + 1 << " " << t[1] + 1 << " " << t[2] + 1 << "\n";
  }
  const std::string recipe =
      "scenes:\n  - name: tray\n    parts: [{family: hex_nut}]\n    layout: pile\n"
      "    copies: 10\n    seed: 3\n"
      "    container: {type: file, file: tray.obj, up: y, friction: 0.6}\n";
  const RunSpec spec = ParseRecipe(recipe, (dir / "r.yaml").string(), dir.path());
  ASSERT_TRUE(spec.scenes[0].container_file.has_value());
  const PreparedRun run = Prepare(spec);
  const Scene& scene = run.scenes[0];
  ASSERT_EQ(scene.fixtures.size(), 1u);
  EXPECT_EQ(scene.fixtures[0].name, "tray.obj");
  const Eigen::AlignedBox3d box = scene.fixtures[0].mesh.Bounds();
  EXPECT_NEAR(box.min().z(), 0.0, 1e-4);
  EXPECT_NEAR(box.max().z(), 31.0, 1e-4);  // floor 6 + height 25: up: y stood it up again
  EXPECT_NEAR(box.center().x(), 0.0, 1e-4);
  EXPECT_NEAR(box.sizes().x(), 132.0, 1e-4);
  ASSERT_EQ(scene.instances.size(), 10u);
  ExpectInside120x90Tote(run, scene);
  EXPECT_THROW(
      {
        try {
          ParseRecipe(
              "scenes:\n  - {parts: [{family: hex_nut}], layout: pile, container: {type: file}}\n",
              "r.yaml", dir.path());
        } catch (const Error& e) {
          EXPECT_STREQ(e.what(),
                       "r.yaml:2:59: scenes[0].container: a container of type file needs a "
                       "'file' (CAD or mesh)");
          throw;
        }
      },
      Error);
  EXPECT_THROW(
      {
        try {
          ParseRecipe(
              "scenes:\n  - {parts: [{family: hex_nut}], layout: pile, container: {type: "
              "file, file: tray.obj, wall: 3 mm}}\n",
              "r.yaml", dir.path());
        } catch (const Error& e) {
          EXPECT_STREQ(e.what(),
                       "r.yaml:2:88: scenes[0].container.wall: goes with type: tote, not file");
          throw;
        }
      },
      Error);
}

}  // namespace
}  // namespace cadsynth
