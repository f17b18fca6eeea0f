// Grasp labels' speed (issue 19): antipodal and suction grasps sampled and checked per second for
// a gear, a bolt and the reference paper's casing, and one scene's grasps placed and filtered in
// a pile of 60 bolts in a tote (once per scene; a frame then only transforms and writes them).
//
//   build/bench/cadsynth_bench_grasp [--benchmark_filter=...]
//
// The casing comes from the shared test data (CADSYNTH_TEST_DATA); without it its benchmarks
// are skipped.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <string>
#include <vector>

#include "recipes/recipe.h"
#include "tools/pipeline/prepare.h"
#include "variants/grasp/parallel_jaw.h"
#include "variants/grasp/scene_grasps.h"
#include "variants/grasp/suction.h"

namespace cadsynth {
namespace {

const std::filesystem::path kCasing =
    std::filesystem::path(CADSYNTH_TEST_DATA) / "mesh/seed_speed_reducer/bottom_casing.STL";

// 0: a 24-tooth spur gear (module 2, 10 mm wide, 8 mm bore), 1: an M16 x 60 bolt, 2: the
// paper's bottom casing (when the test data is there).
const std::vector<Part>& Parts() {
  static const std::vector<Part> parts = [] {
    std::string text =
        "parts:\n"
        "  - {family: spur_gear, params: {teeth: 24, module: 2 mm, face_width: 10 mm, bore: 8 "
        "mm}}\n"
        "  - {family: hex_bolt, params: {size: M16, length: 60 mm}}\n";
    if (std::filesystem::exists(kCasing)) text += "  - {file: " + kCasing.string() + ", unit: m}\n";
    return Prepare(ParseRecipe(text, "grasp_bench.yaml", ".")).parts;
  }();
  return parts;
}

void Antipodal(benchmark::State& state) {
  const size_t p = static_cast<size_t>(state.range(0));
  if (p >= Parts().size()) return state.SkipWithError("no casing: the test data is not there");
  AntipodalOptions o;  // 2,000 points, 8 approaches, the Franka's pad depth
  size_t grasps = 0;
  for (auto _ : state) {
    grasps = SampleAntipodalGrasps(Parts()[p], ParallelJawGripper::Franka(), o).size();
    benchmark::DoNotOptimize(grasps);
  }
  state.SetLabel(Parts()[p].name + ", " + std::to_string(Parts()[p].mesh.triangles.size()) +
                 " triangles, " + std::to_string(grasps) + " grasps kept");
  state.counters["grasps/s"] = benchmark::Counter(static_cast<double>(grasps) * state.iterations(),
                                                  benchmark::Counter::kIsRate);
  state.counters["checked/s"] =
      benchmark::Counter(static_cast<double>(o.samples) * o.approaches * state.iterations(),
                         benchmark::Counter::kIsRate);
}
BENCHMARK(Antipodal)->DenseRange(0, 2)->Unit(benchmark::kMillisecond);

void Suction(benchmark::State& state) {
  const size_t p = static_cast<size_t>(state.range(0));
  if (p >= Parts().size()) return state.SkipWithError("no casing: the test data is not there");
  SuctionOptions o;  // 2,000 points, a 20 mm cup of 16 rim points
  size_t grasps = 0;
  for (auto _ : state) {
    grasps = SampleSuctionGrasps(Parts()[p], SuctionCup{}, o).size();
    benchmark::DoNotOptimize(grasps);
  }
  state.SetLabel(Parts()[p].name + ", " + std::to_string(grasps) + " grasps kept");
  state.counters["grasps/s"] = benchmark::Counter(static_cast<double>(grasps) * state.iterations(),
                                                  benchmark::Counter::kIsRate);
  state.counters["checked/s"] = benchmark::Counter(
      static_cast<double>(o.samples) * state.iterations(), benchmark::Counter::kIsRate);
}
BENCHMARK(Suction)->DenseRange(0, 2)->Unit(benchmark::kMillisecond);

// 60 M16 x 60 bolts dropped into a tote (recipes/bin_picking.yaml's first scene); every
// instance's grasps (the bolt's own, sampled once) placed and checked against the floor, the
// tote and the other 59.
void PlaceInPile(benchmark::State& state) {
  static const PreparedRun pile = Prepare(ParseRecipe(
      "scenes:\n"
      "  - name: pile\n"
      "    parts: [{family: hex_bolt, params: {size: M16, length: 60 mm}}]\n"
      "    layout: pile\n"
      "    copies: 60\n"
      "    seed: 1\n"
      "    container: {type: tote, inner: [355 mm, 265 mm], height: 150 mm, wall: 6 mm,\n"
      "                floor: 6 mm, corner_radius: 15 mm}\n"
      "    physics: {density: 7850, friction: 0.7, restitution: 0.1}\n",
      "pile.yaml", "."));
  const Scene& scene = pile.scenes[0];
  AntipodalOptions o;
  o.depths_mm = {3, 8.8, 20};
  const std::vector<std::vector<ParallelJawGrasp>> jaw = {
      SampleAntipodalGrasps(pile.parts[0], ParallelJawGripper::Franka(), o)};
  const std::vector<std::vector<SuctionGrasp>> suction = {
      SampleSuctionGrasps(pile.parts[0], SuctionCup{}, SuctionOptions{})};
  GraspObstacles obstacles;
  obstacles.floor = scene.floor;
  for (const Scene::Fixture& f : scene.fixtures) obstacles.fixtures.push_back(&f.mesh);
  for (const Instance& i : scene.instances)
    obstacles.instances.push_back({&pile.parts[0].mesh, i.world_from_model, 0});
  size_t kept = 0;
  for (auto _ : state) {
    kept = PlaceParallelJawGrasps(obstacles, jaw, ParallelJawGripper::Franka(), {}).size() +
           PlaceSuctionGrasps(obstacles, suction, SuctionCup{}, {}).size();
    benchmark::DoNotOptimize(kept);
  }
  const size_t placed = scene.instances.size() * (jaw[0].size() + suction[0].size());
  state.SetLabel(std::to_string(scene.instances.size()) + " bolts, " + std::to_string(placed) +
                 " grasps placed, " + std::to_string(kept) + " free");
  state.counters["placed/s"] = benchmark::Counter(static_cast<double>(placed) * state.iterations(),
                                                  benchmark::Counter::kIsRate);
}
BENCHMARK(PlaceInPile)->Unit(benchmark::kSecond)->Iterations(2);

}  // namespace
}  // namespace cadsynth

BENCHMARK_MAIN();
