// Rendering speed on the default job's scenes (the paper's three demo sets) at 640x480, on views
// of the paper's sweep, with 1 and 2 threads:
//
//   build/bench/cadsynth_bench_render
//
//   BM_Cast       primary rays only (16-ray packets), no shading, no amodal masks: Mrays/s
//   BM_Render     everything a frame needs: primary rays, shading with shadow rays, amodal masks
//   BM_Encode     encoding and writing one frame's BOP files (RGB, depth, masks) to /dev/shm
//   BM_EndToEnd   the generate pipeline: render and write every view, frames in flight
//   BM_Sensor     a frame with each depth sensor model (render/sensor.h), 0 ideal, 1 kinect_v1,
//                 2 azure_kinect, 3 structured_light, 4 active_stereo, at 640x480 and 1440x1080
//                 (the Kinect v1's field of view), 2 threads, on every 12th view: what the model
//                 adds to a frame is its time minus ideal's (writing excluded)
//   BM_Distortion a frame (ideal depth) through 0 a pinhole, 1 a lens with OpenCV distortion (its
//                 per-pixel ray table cached by the renderer), 2 the same lens with a new table
//                 every frame (a camera whose K changes), at 640x480 and 1440x1080, 2 threads
// Each reports ms per frame (real time); compare BM_EndToEnd with BM_Cast + BM_Encode.
// CADSYNTH_BENCH_RECIPE=RECIPE.yaml measures that recipe's scenes and views instead.
// CADSYNTH_BENCH_OUT=DIR: BM_EndToEnd writes under DIR/cadsynth_bench_e2e instead of
// /dev/shm/cadsynth_bench_e2e (that folder is removed before and after).
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>

#include "dataset/bop.h"
#include "render/renderer.h"
#include "tools/pipeline/generate.h"

namespace cadsynth {
namespace {

constexpr double kDeg = M_PI / 180.0;

struct Fixture {
  RunSpec spec;
  PreparedRun run;
  std::vector<SweepView> views;  // default: every 37th view of the paper's sweep, 90 views
  std::vector<std::unique_ptr<Renderer>> full, cast;
  Fixture() {
    // CADSYNTH_BENCH_RECIPE=recipe.yaml: that recipe's scenes, camera, every view of its sweep,
    // render and output options (the floor for a whole-process run of the same recipe).
    const char* recipe = std::getenv("CADSYNTH_BENCH_RECIPE");
    spec = recipe != nullptr ? LoadRecipe(recipe) : DefaultRunSpec();
    run = Prepare(spec);
    if (recipe != nullptr) {
      views = SampleViews(spec.sampler, spec.sweep);
    } else {
      spec.intrinsics = Intrinsics::KinectV1();
      SweepOptions sweep;
      for (int y = 0; y <= 360; y += 10) sweep.yaw_rad.push_back(y * kDeg);
      for (int p = 0; p <= 90; p += 10) sweep.pitch_rad.push_back(p * kDeg);
      for (int r = 0; r < 9; ++r) sweep.radius_mm.push_back(650 + 100 * r);
      const std::vector<SweepView> all = ExpandSweep(sweep);
      for (size_t i = 0; i < all.size(); i += 37) views.push_back(all[i]);
    }
    RenderOptions render = spec.render;
    render.amodal_depth = spec.bop.visibility == BopOptions::Visibility::kBop19;
    RenderOptions cast_only = render;
    cast_only.shade = false;
    cast_only.amodal_masks = false;
    for (const Scene& scene : run.scenes) {
      full.push_back(std::make_unique<Renderer>(run.parts, scene, render));
      cast.push_back(std::make_unique<Renderer>(run.parts, scene, cast_only));
    }
  }
  Camera CameraFor(size_t i) const { return Camera{spec.intrinsics, views[i].world_from_cam}; }
  size_t SceneFor(size_t i) const { return i % run.scenes.size(); }
};

Fixture& Get() {
  static Fixture fixture;
  return fixture;
}

void Report(benchmark::State& state, size_t frames) {
  state.counters["ms_per_frame"] =
      benchmark::Counter(static_cast<double>(frames) * 1e-3,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.SetLabel(std::to_string(state.range(0)) + " thread(s)");
}

void BM_Cast(benchmark::State& state) {
  Fixture& f = Get();
  const tbb::global_control threads(tbb::global_control::max_allowed_parallelism, state.range(0));
  size_t frames = 0;
  for (auto _ : state) {
    for (size_t i = 0; i < f.views.size(); ++i)
      benchmark::DoNotOptimize(f.cast[f.SceneFor(i)]->Render(f.CameraFor(i)));
    frames += f.views.size();
  }
  Report(state, frames);
  state.counters["Mrays_per_s"] = benchmark::Counter(static_cast<double>(frames) * 640 * 480 * 1e-6,
                                                     benchmark::Counter::kIsRate);
}

void BM_Render(benchmark::State& state) {
  Fixture& f = Get();
  const tbb::global_control threads(tbb::global_control::max_allowed_parallelism, state.range(0));
  size_t frames = 0;
  for (auto _ : state) {
    for (size_t i = 0; i < f.views.size(); ++i)
      benchmark::DoNotOptimize(f.full[f.SceneFor(i)]->Render(f.CameraFor(i)));
    frames += f.views.size();
  }
  Report(state, frames);
}

void BM_Encode(benchmark::State& state) {
  Fixture& f = Get();
  const tbb::global_control threads(tbb::global_control::max_allowed_parallelism, state.range(0));
  const std::filesystem::path dir = "/dev/shm/cadsynth_bench_encode";
  std::filesystem::remove_all(dir);
  std::vector<Frame> frames;
  for (size_t i = 0; i < f.run.scenes.size(); ++i)
    frames.push_back(f.full[i]->Render(f.CameraFor(i)));
  std::vector<std::unique_ptr<BopSceneWriter>> writers;
  for (size_t s = 0; s < f.run.scenes.size(); ++s) {
    writers.push_back(
        std::make_unique<BopSceneWriter>(dir, static_cast<int>(s), f.spec.bop, f.run.obj_ids[s]));
  }
  size_t count = 0;
  for (auto _ : state) {
    for (size_t s = 0; s < frames.size(); ++s) writers[s]->WriteFrame(0, frames[s]);
    count += frames.size();
  }
  std::filesystem::remove_all(dir);
  Report(state, count);
}

void BM_EndToEnd(benchmark::State& state) {
  Fixture& f = Get();
  const tbb::global_control threads(tbb::global_control::max_allowed_parallelism, state.range(0));
  // Its own folder under CADSYNTH_BENCH_OUT, so that removing it never touches the user's files.
  const char* out = std::getenv("CADSYNTH_BENCH_OUT");
  const std::filesystem::path dir =
      std::filesystem::path(out != nullptr ? out : "/dev/shm") / "cadsynth_bench_e2e";
  std::filesystem::remove_all(dir);
  std::vector<std::unique_ptr<BopSceneWriter>> writers;
  for (size_t s = 0; s < f.run.scenes.size(); ++s) {
    writers.push_back(
        std::make_unique<BopSceneWriter>(dir, static_cast<int>(s), f.spec.bop, f.run.obj_ids[s]));
  }
  size_t frames = 0;
  for (auto _ : state) {
    size_t next = 0;
    using FramePtr = std::shared_ptr<const Frame>;
    tbb::parallel_pipeline(
        2 * static_cast<size_t>(tbb::this_task_arena::max_concurrency()),
        tbb::make_filter<void, size_t>(tbb::filter_mode::serial_in_order,
                                       [&](tbb::flow_control& control) -> size_t {
                                         if (next >= f.views.size()) control.stop();
                                         return next++;
                                       }) &
            tbb::make_filter<size_t, std::pair<size_t, FramePtr>>(
                tbb::filter_mode::parallel,
                [&](size_t i) {
                  return std::make_pair(i, std::make_shared<const Frame>(
                                               f.full[f.SceneFor(i)]->Render(f.CameraFor(i))));
                }) &
            tbb::make_filter<std::pair<size_t, FramePtr>, void>(
                tbb::filter_mode::parallel, [&](const auto& item) {
                  writers[f.SceneFor(item.first)]->WriteFrame(static_cast<int>(item.first),
                                                              *item.second);
                }));
    frames += f.views.size();
  }
  std::filesystem::remove_all(dir);
  Report(state, frames);
}

void BM_Sensor(benchmark::State& state) {
  Fixture& f = Get();
  const tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 2);
  SensorOptions sensor;
  sensor.depth = DepthModel::Defaults(static_cast<DepthModel::Kind>(state.range(0)));
  const int width = static_cast<int>(state.range(1));
  const Intrinsics k = Intrinsics::FromFov(width, width * 3 / 4, 2.0 * std::atan(320.0 / 525.0));
  size_t frames = 0;
  for (auto _ : state) {
    for (size_t i = 0; i < f.views.size(); i += 12) {
      const Camera camera{k, f.views[i].world_from_cam};
      benchmark::DoNotOptimize(f.full[f.SceneFor(i)]->Render(camera, i, sensor));
      ++frames;
    }
  }
  state.counters["ms_per_frame"] =
      benchmark::Counter(static_cast<double>(frames) * 1e-3,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  const char* names[] = {"ideal", "kinect_v1", "azure_kinect", "structured_light", "active_stereo"};
  state.SetLabel(std::string(names[state.range(0)]) + " " + std::to_string(width) + "x" +
                 std::to_string(width * 3 / 4));
}

void BM_Distortion(benchmark::State& state) {
  Fixture& f = Get();
  const tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 2);
  const int width = static_cast<int>(state.range(1));
  Intrinsics k = Intrinsics::FromFov(width, width * 3 / 4, 2.0 * std::atan(320.0 / 525.0));
  if (state.range(0) > 0) k.distortion = Distortion{-0.21, 0.045, 0.0006, -0.0004, 0.0};
  size_t frames = 0;
  for (auto _ : state) {
    for (size_t i = 0; i < f.views.size(); i += 12) {
      if (state.range(0) == 2) k.cx += 1e-6;  // another camera: the table is built again
      const Camera camera{k, f.views[i].world_from_cam};
      benchmark::DoNotOptimize(f.full[f.SceneFor(i)]->Render(camera, i));
      ++frames;
    }
  }
  state.counters["ms_per_frame"] =
      benchmark::Counter(static_cast<double>(frames) * 1e-3,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  const char* names[] = {"pinhole", "distortion", "distortion, new table"};
  state.SetLabel(std::string(names[state.range(0)]) + " " + std::to_string(width) + "x" +
                 std::to_string(width * 3 / 4));
}

BENCHMARK(BM_Cast)->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_Render)->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_Encode)->Arg(1)->UseRealTime()->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_EndToEnd)->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_Sensor)
    ->ArgsProduct({{0, 1, 2, 3, 4}, {640, 1440}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond)
    ->MinTime(1.0);
BENCHMARK(BM_Distortion)
    ->ArgsProduct({{0, 1, 2}, {640, 1440}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond)
    ->MinTime(1.0);

}  // namespace
}  // namespace cadsynth

BENCHMARK_MAIN();
