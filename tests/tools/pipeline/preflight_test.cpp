// A new user's first hour (issue 49): impossible scenes refused before any simulation or
// rendering, with the recipe line and the reason; what becomes of parts that leave the tote;
// --strict; progress during a pile's simulation; piles read back from the part cache.
#include <sys/stat.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

#include "cad/core/error.h"
#include "cad/part_cache.h"
#include "recipes/recipe.h"
#include "tests/test_support.h"
#include "tools/pipeline/generate.h"
#include "tools/pipeline/prepare.h"
#include "tools/pipeline/progress.h"
#include "tools/pipeline/shards.h"

namespace cadsynth {
namespace {

std::string PrepareError(const std::string& recipe, const PrepareControls& controls = {}) {
  testing::ScratchDir dir;
  try {
    const RunSpec spec = ParseRecipe(recipe, "r.yaml", dir.path());
    Prepare(spec, {}, nullptr, nullptr, controls);
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

std::string RecipeError(const std::string& recipe) {
  try {
    ParseRecipe(recipe, "r.yaml", ".");
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

bool Has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// A peg 20 mm across and 50 mm long: its thinnest width is 20 mm, its diagonal
// sqrt(20^2 + 50^2) = 53.9 mm.
const char* const kPegPile =
    "scenes:\n  - name: bin\n    parts: [{family: round_peg, params: {diameter: 20 mm, length: "
    "50 mm}}]\n    layout: pile\n";

// Pre-flight: a part wider than the tote's inside, or longer than its inner diagonal, is refused
// at the container's line; so are more parts than the tote could hold at the densest random
// packing, at the copies' line. All before any simulation (no progress line comes).
TEST(Preflight, PartsThatCannotFitTheToteAreRefusedWithTheirLine) {
  std::atomic<int> progress{0};
  PrepareControls controls;
  controls.progress = [&](const StageReport& report) {
    if (report.stage == "pile") ++progress;
  };
  controls.progress_interval_s = 0;
  // 15 mm between the walls: the 20 mm peg cannot lie in any orientation.
  const std::string narrow = PrepareError(
      std::string(kPegPile) +
          "    copies: 3\n    container: {type: tote, inner: [80 mm, 15 mm], height: 60 mm, "
          "corner_radius: 5 mm}\n",
      controls);
  EXPECT_TRUE(Has(narrow, "r.yaml:6:16: scene 'bin': part 'round_peg")) << narrow;
  EXPECT_TRUE(Has(narrow, "20 mm across at its thinnest")) << narrow;
  EXPECT_TRUE(Has(narrow, "cannot lie between the walls")) << narrow;
  // 30 x 25 x 10 mm: an inner diagonal of 40.3 mm, shorter than the 53.9 mm peg.
  const std::string short_tote = PrepareError(
      std::string(kPegPile) +
          "    copies: 3\n    container: {type: tote, inner: [30 mm, 25 mm], height: 10 mm, "
          "corner_radius: 5 mm}\n",
      controls);
  EXPECT_TRUE(Has(short_tote, "54 mm long, longer than the tote's inner diagonal (40 mm"))
      << short_tote;
  // 500 pegs (15.7 cm3 each: 7,854 cm3) in 200 x 150 x 100 mm (3,000 cm3, 1,920 at 64 %).
  const std::string crowded = PrepareError(
      std::string(kPegPile) +
          "    copies: 500\n    container: {type: tote, inner: [200 mm, 150 mm], height: 100 "
          "mm}\n",
      controls);
  EXPECT_TRUE(Has(crowded,
                  "r.yaml:5:13: scene 'bin': 500 parts of 7854 cm3 of solid cannot fit "
                  "a tote of 3000 cm3"))
      << crowded;
  EXPECT_TRUE(Has(crowded, "here 1920 cm3")) << crowded;
  EXPECT_EQ(progress, 0);  // refused before the simulation started
  // 100 pegs (1,571 cm3) fit the 1,920: no refusal before the drop.
  PrepareControls none;
  const std::string fits = PrepareError(
      std::string(kPegPile) +
          "    copies: 100\n    container: {type: tote, inner: [200 mm, 150 mm], height: 100 "
          "mm}\n    settle_time: 0.01\n",
      none);
  EXPECT_FALSE(Has(fits, "cannot fit")) << fits;
}

// A sweep whose cameras sit inside the tote (50 mm above the target, the rim 156 mm high) is
// refused before the drop; a camera inside an arranged part is refused before rendering.
TEST(Preflight, CamerasInsideTheToteOrAPartAreRefused) {
  const std::string in_tote = PrepareError(
      std::string(kPegPile) +
      "    copies: 2\n    container: {type: tote, inner: [200 mm, 150 mm], height: 150 mm}\n"
      "sweep: {yaw: 0, pitch: 90, radius: 50 mm}\n");
  EXPECT_TRUE(Has(in_tote,
                  "sweep: view 0 of scene 'bin' puts the camera at (0, 0, 50) mm, "
                  "inside the tote"))
      << in_tote;
  const std::string in_part = PrepareError(
      "parts: [{family: round_peg, params: {diameter: 3000 mm, length: 3000 mm}}]\n"
      "scene: {layout: single}\nsweep: {yaw: 0, pitch: 45, radius: 650 mm}\n");
  EXPECT_TRUE(Has(in_part,
                  "sweep: view 0 of scene 'scene' puts the camera inside part "
                  "'round_peg"))
      << in_part;
  EXPECT_TRUE(Has(in_part, "(3000 mm long), 650 mm from the target")) << in_part;
}

// Bare numbers where metres are meant, and densities in g/cm3: refused at the number, saying
// what it was read as and what was likely meant.
TEST(Preflight, ImplausibleBareNumbersAndDensitiesAreRefusedAtTheNumber) {
  EXPECT_EQ(RecipeError("sweep:\n  radius: {from: 0.8, to: 0.95, step: 0.05}\n"),
            "r.yaml:2:18: sweep.radius: 0.8 is read as 0.8 mm (a bare number is millimetres): did "
            "you mean '0.8 m'? Give the unit");
  EXPECT_EQ(RecipeError(std::string(kPegPile) + "    container: {type: tote, inner: [0.4, 0.3]}\n"),
            "r.yaml:5:37: scenes[0].container.inner: 0.4 is read as 0.4 mm (a bare number is "
            "millimetres): did you mean '0.4 m'? Give the unit");
  EXPECT_EQ(RecipeError(std::string(kPegPile) + "    physics: {density: 7.85}\n"),
            "r.yaml:5:24: scenes[0].physics.density: 7.85 is read as kg/m3, lighter than any "
            "solid part (steel is 7850, aluminium 2700, ABS 1050): did you mean 7850 (7.85 "
            "g/cm3)?");
  EXPECT_TRUE(Has(RecipeError(std::string(kPegPile) + "    physics: {density: 80000}\n"),
                  "denser than any material"));
  // With units, or in the millimetres' range: accepted.
  EXPECT_EQ(RecipeError("sweep:\n  radius: {from: 0.8 m, to: 0.95 m, step: 0.05 m}\n"),
            "(no error)");
  EXPECT_EQ(RecipeError("sweep:\n  radius: [650, 900]\n"), "(no error)");
  EXPECT_EQ(RecipeError(std::string(kPegPile) + "    physics: {density: [2700, 7850]}\n"),
            "(no error)");
}

// A range error points at the offending key, not at the section holding it.
TEST(Preflight, RangeErrorsPointAtTheOffendingKey) {
  EXPECT_EQ(RecipeError(std::string(kPegPile) + "    copies: -3\n"),
            "r.yaml:5:13: scenes[0].copies: copies must be 1 to 10000");
  EXPECT_EQ(RecipeError(std::string(kPegPile) + "    settle_time: 900\n"),
            "r.yaml:5:18: scenes[0].settle_time: settle_time must lie in (0, 600] s");
}

// A pile whose parts are still moving when settle_time runs out: a warning, and with --strict
// an error saying so.
TEST(Preflight, StrictMakesAPileStillMovingAnError) {
  const std::string recipe =
      std::string(kPegPile) +
      "    copies: 6\n    settle_time: 0.05\n"
      "    container: {type: tote, inner: [200 mm, 150 mm], height: 100 mm}\n";
  testing::ScratchDir dir;
  const RunSpec spec = ParseRecipe(recipe, "r.yaml", dir.path());
  WarningCapture capture;
  const PreparedRun run = Prepare(spec);
  const std::vector<std::string> warnings = capture.Take();
  ASSERT_FALSE(warnings.empty());
  EXPECT_TRUE(Has(warnings[0], "still moving after settle_time")) << warnings[0];
  PrepareControls strict;
  strict.strict = true;
  const std::string error = PrepareError(recipe, strict);
  EXPECT_TRUE(Has(error, "scene 'bin': 6 parts (#0 'round_peg")) << error;
  EXPECT_TRUE(Has(error, "still moving after settle_time (0.05 s, simulated)")) << error;
  EXPECT_TRUE(Has(error, "(an error under --strict)")) << error;
}

// The pile's progress: lines while it is simulated, in order, each within settle_time, saying how
// many bodies move; the JSON mode's lines carry the same numbers. A second Prepare with the same
// part cache reads the pile instead of simulating it (no progress at all) and gives the same
// poses bit for bit, as does a run without a cache.
TEST(Preflight, PileProgressComesWhileItIsSimulatedAndNotWhenItIsCached) {
  testing::ScratchDir dir;
  const RunSpec spec =
      ParseRecipe(std::string(kPegPile) +
                      "    copies: 12\n    seed: 2\n"
                      "    container: {type: tote, inner: [160 mm, 120 mm], height: 80 mm}\n",
                  "r.yaml", dir.path());
  std::mutex mutex;
  std::vector<double> times;
  std::vector<std::string> details, shapes;
  PrepareControls controls;
  controls.progress_interval_s = 0;
  controls.progress = [&](const StageReport& report) {
    std::lock_guard<std::mutex> lock(mutex);
    if (report.stage == "collision_shapes") {  // the peg's: one piece, its hull
      shapes.push_back(report.detail);
      EXPECT_EQ(report.total, 1.0);
      return;
    }
    EXPECT_EQ(report.scene, "bin");
    EXPECT_EQ(report.total, 10.0);
    times.push_back(report.done);
    details.push_back(report.detail);
  };

  PartCache cache(dir / "cache", "test");
  const PreparedRun cold = Prepare(spec, {}, &cache, nullptr, controls);
  ASSERT_GE(times.size(), 2u);
  for (size_t k = 1; k < times.size(); ++k) EXPECT_GT(times[k], times[k - 1]);
  EXPECT_LE(times.back(), 10.0);
  EXPECT_TRUE(Has(details[0], " of 12 bodies moving")) << details[0];
  ASSERT_EQ(shapes.size(), 1u);
  EXPECT_TRUE(Has(shapes[0], "'round_peg")) << shapes[0];
  // A cylinder is its hull; the hull of its mesh (an inscribed prism) holds a little less than
  // the exact cylinder's volume.
  EXPECT_TRUE(Has(shapes[0], "': its hull, 0.99")) << shapes[0];
  EXPECT_TRUE(Has(shapes[0], "x its volume in ")) << shapes[0];
  EXPECT_TRUE(std::filesystem::exists(dir / "cache" / "pile"));

  times.clear();
  const PreparedRun warm = Prepare(spec, {}, &cache, nullptr, controls);
  EXPECT_TRUE(times.empty()) << "the pile was simulated again";
  const PreparedRun none = Prepare(spec);
  ASSERT_EQ(cold.scenes[0].instances.size(), 12u);
  ASSERT_EQ(warm.scenes[0].instances.size(), 12u);
  ASSERT_EQ(none.scenes[0].instances.size(), 12u);
  for (size_t i = 0; i < 12; ++i) {
    EXPECT_EQ(warm.scenes[0].instances[i].world_from_model.matrix(),
              cold.scenes[0].instances[i].world_from_model.matrix());
    EXPECT_EQ(none.scenes[0].instances[i].world_from_model.matrix(),
              cold.scenes[0].instances[i].world_from_model.matrix());
  }

  // The JSON mode: one object per line, the stage and its numbers.
  char* buffer = nullptr;
  size_t size = 0;
  std::FILE* out = open_memstream(&buffer, &size);
  {
    ProgressReporter reporter(ProgressReporter::Mode::kJson, out);
    reporter.SetShard("1/4");
    reporter.Stage({"pile", "bin", 2.5, 10.0, "7 of 12 bodies moving"});
  }
  std::fclose(out);
  const std::string text(buffer, size);
  std::free(buffer);
  const auto j = nlohmann::json::parse(text);
  EXPECT_EQ(j["shard"], "1/4");
  EXPECT_EQ(j["stage"], "pile");
  EXPECT_EQ(j["scene"], "bin");
  EXPECT_DOUBLE_EQ(j["done"].get<double>(), 2.5);
  EXPECT_DOUBLE_EQ(j["total"].get<double>(), 10.0);
  EXPECT_EQ(j["detail"], "7 of 12 bodies moving");
}

// Eight bouncy pegs dropped from 250 mm into a 12 mm deep tray: some of them (three, #4, #5 and
// #7, with seed 1) end on the floor beside it. remove (the default) takes them out, keep labels
// them where they lie (an error under --strict), redrop drops them again onto the pile and takes
// out what still lands outside; the warning names them every time.
TEST(Preflight, PartsOutsideTheToteAreRemovedKeptOrDroppedAgain) {
  const auto recipe = [](const std::string& mode) {
    return std::string(kPegPile) +
           "    copies: 8\n    seed: 1\n    drop_height: 250 mm\n"
           "    container: {type: tote, inner: [140 mm, 120 mm], height: 12 mm}\n"
           "    physics: {restitution: 0.9, friction: 0.2}\n" +
           (mode.empty() ? "" : "    out_of_container: " + mode + "\n");
  };
  const auto inside = [](const Instance& instance) {
    const Eigen::Vector3d t = instance.world_from_model.translation();
    return std::abs(t.x()) <= 70.0 && std::abs(t.y()) <= 60.0;
  };
  const auto prepare = [&](const std::string& mode, std::string* warning) {
    testing::ScratchDir dir;
    const RunSpec spec = ParseRecipe(recipe(mode), "r.yaml", dir.path());
    WarningCapture capture;
    PreparedRun run = Prepare(spec);
    const std::vector<std::string> warnings = capture.Take();
    *warning = warnings.empty() ? "" : warnings[0];
    return run;
  };
  std::string warning;
  const PreparedRun keep = prepare("keep", &warning);
  ASSERT_EQ(keep.scenes[0].instances.size(), 8u);
  std::vector<Instance> kept_inside;
  std::vector<size_t> outside;
  for (size_t i = 0; i < 8; ++i) {
    if (inside(keep.scenes[0].instances[i])) {
      kept_inside.push_back(keep.scenes[0].instances[i]);
    } else {
      outside.push_back(i);
    }
  }
  ASSERT_GE(outside.size(), 1u);
  ASSERT_LT(outside.size(), 8u);
  const std::string count = std::to_string(outside.size()) + " parts of 8 ended outside the tote";
  EXPECT_TRUE(
      Has(warning, "scene 'bin': " + count + " (#" + std::to_string(outside[0]) + " 'round_peg'"))
      << warning;
  EXPECT_TRUE(Has(warning, "kept where they lie, drawn and labelled")) << warning;
  const PreparedRun removed = prepare("", &warning);  // the default
  EXPECT_TRUE(Has(warning, "taken out of the scene, neither drawn nor labelled")) << warning;
  ASSERT_EQ(removed.scenes[0].instances.size(), kept_inside.size());
  for (size_t i = 0; i < kept_inside.size(); ++i) {  // the same pile without those outside
    EXPECT_EQ(removed.scenes[0].instances[i].world_from_model.matrix(),
              kept_inside[i].world_from_model.matrix())
        << i;
  }
  const PreparedRun redropped = prepare("redrop", &warning);
  EXPECT_TRUE(Has(warning, "dropped again (out_of_container: redrop)")) << warning;
  EXPECT_GE(redropped.scenes[0].instances.size(), 6u);
  for (const Instance& instance : redropped.scenes[0].instances) EXPECT_TRUE(inside(instance));
  PrepareControls strict;
  strict.strict = true;
  const std::string error = PrepareError(recipe("keep"), strict);
  EXPECT_TRUE(Has(error, "scene 'bin': " + count)) << error;
  EXPECT_TRUE(Has(error, "(an error under --strict)")) << error;
}

// A material rule that matches no part says so at its line, and names the parts it could have
// matched.
TEST(Preflight, AMaterialRuleMatchingNoPartNamesItsLineAndTheParts) {
  testing::ScratchDir dir;
  const RunSpec spec = ParseRecipe(
      "scenes:\n  - name: s\n    parts: [{family: hex_nut}, {family: washer}]\n"
      "    layout: row\nrender: {mode: pbr}\nmaterials:\n"
      "  assign:\n    - {name: 'bolt*', preset: steel}\n",
      "r.yaml", dir.path());
  WarningCapture capture;
  Prepare(spec);
  const std::vector<std::string> warnings = capture.Take();
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_TRUE(Has(warnings[0], "r.yaml:8:7: materials.assign[0] (name 'bolt*') matches no part"))
      << warnings[0];
  EXPECT_TRUE(Has(warnings[0], "the parts are 'hex_nut")) << warnings[0];
  EXPECT_TRUE(Has(warnings[0], "(family hex_nut), 'washer")) << warnings[0];
}

// Prepare once per farm: the first shard simulates the pile and places the scene's grasps and
// stores both in the part cache; the second shard reads them (it stores nothing again: the
// entries keep their inodes, where a store renames a new file into place). The merged farm run
// is the same bytes as a run without any cache.
TEST(Preflight, ASecondShardReadsThePileAndItsGraspsFromTheCache) {
  testing::ScratchDir dir;
  const RunSpec spec =
      ParseRecipe(std::string(kPegPile) +
                      "    copies: 10\n    seed: 3\n"
                      "    container: {type: tote, inner: [160 mm, 120 mm], height: 80 mm}\n"
                      "camera: {width: 160, height: 120, fx: 150, fy: 150, cx: 79.5, cy: 59.5}\n"
                      "sweep: {yaw: [0, 120, 240], pitch: 80, radius: 600 mm}\n"
                      "grasps: {gripper: franka, suction: {diameter: 10 mm}}\n",
                  "r.yaml", dir.path());
  GenerateOptions plain;
  plain.output = dir / "plain";
  Generate(spec, plain);

  // Each entry of a kind of the cache, by its inode.
  const auto entries = [&](const std::string& kind) {
    std::map<std::string, ino_t> found;
    if (!std::filesystem::exists(dir / "cache" / kind)) return found;
    for (const auto& e : std::filesystem::recursive_directory_iterator(dir / "cache" / kind)) {
      struct stat st {};
      if (e.is_regular_file() && ::stat(e.path().c_str(), &st) == 0) found[e.path()] = st.st_ino;
    }
    return found;
  };
  std::map<std::string, ino_t> piles, grasps;
  for (int shard = 0; shard < 2; ++shard) {
    GenerateOptions options;
    options.output = dir / "farm";
    options.shard = ShardSpec{shard, 2};
    options.cache = dir / "cache";
    Generate(spec, options);
    if (shard == 0) {
      piles = entries("pile");
      grasps = entries("scene_grasps");
      EXPECT_EQ(piles.size(), 1u);
      EXPECT_EQ(grasps.size(), 1u);
    }
  }
  EXPECT_EQ(entries("pile"), piles) << "the second shard simulated the pile again";
  EXPECT_EQ(entries("scene_grasps"), grasps) << "the second shard placed the grasps again";
  Merge(dir / "farm");
  testing::ExpectSameTree(dir / "plain", dir / "farm");
}

}  // namespace
}  // namespace cadsynth
