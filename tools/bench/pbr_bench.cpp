// Speed and image error of the physically based mode (render.mode: pbr):
//
//   build/bench/cadsynth_bench_pbr [--benchmark_filter=...]
//
// The scenes, materials and lights of recipes/pbr_demo.yaml (the default job's three demo sets
// in steel, aluminium and ABS on a wooden table under two light panels; CADSYNTH_BENCH_RECIPE
// picks another recipe), 640x480, 3 bounces, six views of its sweep (two per scene).
//
//   BM_Pbr/S/T/D   ms per frame (real time) at S samples per pixel with T threads, denoised
//                (render.denoise) when D is 1.
//   BM_PbrError/S/D  with CADSYNTH_BENCH_ERROR=1: the RMS error at S samples per pixel (denoised
//                when D is 1) against a 4,096-sample render of the same pixels (the 160x120
//                centre crop of each view, where the parts are), in 8-bit display values
//                (rmse_8bit) and relative to the mean linear radiance (rel_rmse). The reference
//                takes minutes.
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstdlib>
#include <map>
#include <memory>

#include "render/path_tracer.h"
#include "render/renderer.h"
#include "tools/pipeline/prepare.h"

namespace cadsynth {
namespace {

struct Fixture {
  RunSpec spec;
  PreparedRun run;
  std::vector<SweepView> views;
  Fixture() {
    const char* recipe = std::getenv("CADSYNTH_BENCH_RECIPE");
    spec = LoadRecipe(recipe != nullptr ? recipe : CADSYNTH_SOURCE_DIR "/recipes/pbr_demo.yaml");
    run = Prepare(spec);
    const std::vector<SweepView> all = SampleViews(spec.sampler, spec.sweep);
    const size_t step = std::max<size_t>(1, all.size() / 6);
    for (size_t i = 0; i < all.size() && views.size() < 6; i += step) views.push_back(all[i]);
  }
  size_t SceneFor(size_t i) const { return i % run.scenes.size(); }
  std::unique_ptr<Renderer> Make(size_t scene, int samples, bool denoise = false) const {
    RenderOptions o = spec.render;
    o.denoise = denoise;
    o.mode = RenderOptions::Mode::kPbr;
    o.samples = samples;
    o.bounces = 3;
    o.amodal_masks = false;  // the labels' cost is the fast mode's (render_bench)
    o.hdr = true;
    return std::make_unique<Renderer>(run.parts, run.scenes[scene], o);
  }
  // The 160 x 120 pixels at the centre of view i, as their own camera.
  Camera Crop(size_t i) const {
    Camera c{spec.intrinsics, views[i].world_from_cam};
    c.intrinsics.cx -= (c.intrinsics.width - 160) / 2.0;
    c.intrinsics.cy -= (c.intrinsics.height - 120) / 2.0;
    c.intrinsics.width = 160;
    c.intrinsics.height = 120;
    return c;
  }
};

Fixture& Get() {
  static Fixture fixture;
  return fixture;
}

void BM_Pbr(benchmark::State& state) {
  Fixture& f = Get();
  const int samples = static_cast<int>(state.range(0));
  const tbb::global_control threads(tbb::global_control::max_allowed_parallelism, state.range(1));
  std::vector<std::unique_ptr<Renderer>> renderers;
  const bool denoise = state.range(2) != 0;
  for (size_t s = 0; s < f.run.scenes.size(); ++s) renderers.push_back(f.Make(s, samples, denoise));
  size_t frames = 0;
  for (auto _ : state) {
    for (size_t i = 0; i < f.views.size(); ++i) {
      const Camera camera{f.spec.intrinsics, f.views[i].world_from_cam};
      benchmark::DoNotOptimize(renderers[f.SceneFor(i)]->Render(camera, i));
    }
    frames += f.views.size();
  }
  state.counters["ms_per_frame"] =
      benchmark::Counter(static_cast<double>(frames) * 1e-3,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.SetLabel(std::to_string(samples) + " spp, " + std::to_string(state.range(1)) +
                 " thread(s), 640x480, 3 bounces" + (denoise ? ", denoised" : ""));
}

void BM_PbrError(benchmark::State& state) {
  if (std::getenv("CADSYNTH_BENCH_ERROR") == nullptr) {
    state.SkipWithError("set CADSYNTH_BENCH_ERROR=1 (renders 4,096-spp references: minutes)");
    return;
  }
  Fixture& f = Get();
  const int samples = static_cast<int>(state.range(0));
  const bool denoise = state.range(1) != 0;
  static std::map<size_t, Frame> references;
  for (size_t i = 0; i < f.views.size(); ++i) {
    if (references.count(i) == 0) references[i] = f.Make(f.SceneFor(i), 4096)->Render(f.Crop(i), i);
  }
  double sq8 = 0, sq = 0, mean = 0;
  size_t n = 0;
  for (auto _ : state) {
    for (size_t i = 0; i < f.views.size(); ++i) {
      // Another view number: noise independent of the reference's.
      const Frame frame = f.Make(f.SceneFor(i), samples, denoise)->Render(f.Crop(i), 1000 + i);
      const Frame& ref = references[i];
      for (size_t p = 0; p < frame.rgb.size(); ++p) {
        const double d8 = static_cast<double>(frame.rgb[p]) - ref.rgb[p];
        const double d = static_cast<double>(frame.radiance[p]) - ref.radiance[p];
        sq8 += d8 * d8;
        sq += d * d;
        mean += ref.radiance[p];
        ++n;
      }
    }
  }
  state.counters["rmse_8bit"] = std::sqrt(sq8 / n);
  state.counters["rel_rmse"] = std::sqrt(sq / n) / (mean / n);
  state.SetLabel(std::to_string(samples) + " spp" + (denoise ? " denoised" : "") +
                 " vs 4096 spp, 160x120 centre crops");
}

BENCHMARK(BM_Pbr)
    ->ArgsProduct({{4, 16, 64}, {1, 2}, {0}})
    ->Args({4, 2, 1})
    ->Args({16, 2, 1})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond)
    ->MinTime(1.0);
BENCHMARK(BM_PbrError)->ArgsProduct({{4, 16, 64}, {0, 1}})->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace
}  // namespace cadsynth

BENCHMARK_MAIN();
