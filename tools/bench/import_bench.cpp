// Import plus tessellation of real assemblies, with 1 and 2 threads; symmetry detection and gear
// recognition of every part of the shared STEP assemblies (one thread, the parts one by one).
//
//   build/tools/bench/cadsynth_bench_import [--benchmark_...]
//
// Reads the files from $CADSYNTH_TEST_DATA or ../shared/data next to the source tree; a missing
// file is reported as a skipped benchmark. Counters: parts, instances, triangles.
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <cstdlib>
#include <filesystem>

#include <chrono>

#include "cad/core/error.h"
#include "cad/gear_recognition.h"
#include "cad/import.h"
#include "cad/symmetry.h"

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

const char* const kAssemblies[] = {"step/assemblies/as1-oc-214.stp",
                                   "step/assemblies/as1_motor.step",
                                   "step/assemblies/rotor_pump_pm4-ec-203.stp",
                                   "step/assemblies/eight_cyl.stp",
                                   "step/assemblies/digital_microscope_onshape.step",
                                   "step/assemblies/dm1-id-214.stp"};

// Per part, as `generate` and `inspect` do it: DetectSymmetries with the B-rep's axes, the
// B-rep's surface-to-surface check, then RecognizePartGear. Counters: parts, the mean and the
// slowest part (ms), parts with symmetries, gears recognised.
void BM_SymmetriesAndGears(benchmark::State& state) {
  const std::filesystem::path file = DataDir() / kAssemblies[state.range(0)];
  if (!std::filesystem::exists(file)) {
    state.SkipWithError(("missing " + file.string()).c_str());
    return;
  }
  cadsynth::SetWarningSink([](const std::string&) {});
  const cadsynth::Assembly a = cadsynth::ImportCad(file, cadsynth::ImportOptions{});
  double slowest = 0, total = 0;
  size_t symmetric = 0, gears = 0, runs = 0;
  for (auto _ : state) {
    symmetric = gears = 0;
    for (const cadsynth::Part& p : a.parts) {
      if (p.mesh.triangles.empty()) continue;
      const auto start = std::chrono::steady_clock::now();
      cadsynth::DetectedSymmetries d =
          cadsynth::DetectSymmetries(p.mesh, cadsynth::PartSymmetryOptions(p));
      cadsynth::CompareBrepFaces(p, &d);
      gears += cadsynth::RecognizePartGear(p, d).has_value();
      const double ms =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
              .count();
      slowest = std::max(slowest, ms);
      total += ms;
      symmetric += !d.symmetries.empty();
    }
    ++runs;
  }
  state.SetLabel(file.filename().string());
  state.counters["parts"] = static_cast<double>(a.parts.size());
  state.counters["ms_per_part"] = total / std::max<size_t>(1, runs * a.parts.size());
  state.counters["slowest_ms"] = slowest;
  state.counters["symmetric"] = static_cast<double>(symmetric);
  state.counters["gears"] = static_cast<double>(gears);
}
BENCHMARK(BM_SymmetriesAndGears)
    ->DenseRange(0, 5)
    ->ArgNames({"file"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
