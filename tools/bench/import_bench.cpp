// Import plus tessellation of real assemblies, with 1 and 2 threads.
//
//   build/tools/bench/cadsynth_bench_import [--benchmark_...]
//
// Reads the files from $CADSYNTH_TEST_DATA or ../shared/data next to the source tree; a missing
// file is reported as a skipped benchmark. Counters: parts, instances, triangles.
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <cstdlib>
#include <filesystem>

#include "cad/error.h"
#include "cad/import.h"

namespace {

const char* const kFiles[] = {"step/assemblies/as1_motor.step",
                              "step/assemblies/rotor_pump_pm4-ec-203.stp"};

std::filesystem::path DataDir() {
  if (const char* env = std::getenv("CADSYNTH_TEST_DATA")) return env;
  return CADSYNTH_TEST_DATA;
}

void BM_ImportAndTessellate(benchmark::State& state) {
  const std::filesystem::path file = DataDir() / kFiles[state.range(0)];
  if (!std::filesystem::exists(file)) {
    state.SkipWithError(("missing " + file.string()).c_str());
    return;
  }
  const tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                                    static_cast<size_t>(state.range(1)));
  cadsynth::SetWarningSink([](const std::string&) {});
  size_t triangles = 0, parts = 0, instances = 0;
  for (auto _ : state) {
    const cadsynth::Assembly a = cadsynth::ImportCad(file, cadsynth::ImportOptions{});
    triangles = 0;
    for (const cadsynth::Part& p : a.parts) triangles += p.mesh.num_triangles();
    parts = a.parts.size();
    instances = a.instances.size();
  }
  state.SetLabel(file.filename().string() + ", " + std::to_string(state.range(1)) + " thread(s)");
  state.counters["parts"] = static_cast<double>(parts);
  state.counters["instances"] = static_cast<double>(instances);
  state.counters["triangles"] = static_cast<double>(triangles);
}
BENCHMARK(BM_ImportAndTessellate)
    ->ArgsProduct({{0, 1}, {1, 2}})
    ->ArgNames({"file", "threads"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(2.0);

}  // namespace

BENCHMARK_MAIN();
