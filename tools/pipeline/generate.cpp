#include "tools/pipeline/generate.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <optional>
#include <sstream>
#include <system_error>

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>
#include <nlohmann/json.hpp>

#include "cad/core/error.h"
#include "dataset/acronym.h"
#include "dataset/bop.h"
#include "dataset/file_io.h"
#include "dataset/grasp_labels.h"
#include "dataset/output_formats.h"
#include "dataset/webdataset.h"
#include "render/randomize.h"
#include "render/renderer.h"
#include "tools/pipeline/journal.h"
#include "tools/pipeline/run_record.h"
#include "variants/grasp/scene_grasps.h"

namespace cadsynth {

namespace {

// The objects' grasps as ACRONYM's per-object HDF5 files models/grasps/obj_OBJID.h5.
void WriteGraspFiles(const std::filesystem::path& root, const std::vector<Part>& parts,
                     const GraspSpec& spec, const FrameSource& source) {
  std::filesystem::create_directories(root / "models" / "grasps");
  tbb::parallel_for(size_t{0}, parts.size(), [&](size_t p) {
    char id[16];
    std::snprintf(id, sizeof(id), "%06zu", p + 1);
    AcronymGrasps file;
    file.object_file = std::string("models/obj_") + id + ".ply";
    // ACRONYM names the Franka hand "panda"; a hand of other sizes keeps its own name.
    ParallelJawGripper franka = ParallelJawGripper::Franka();
    franka.name = spec.gripper.name;
    file.gripper = spec.gripper == franka ? "panda" : spec.gripper.name;
    file.gripper_configuration = 0.5e-3 * spec.gripper.max_opening_mm;
    file.friction = spec.sampling.friction;
    file.volume_m3 = parts[p].mass.volume_mm3 * 1e-9;
    file.com_m = parts[p].mass.center_of_mass * 1e-3;
    for (const ParallelJawGrasp& g : source.ObjectJawGrasps()[p]) {
      file.model_from_gripper.push_back(g.model_from_gripper);
      file.width_mm.push_back(g.width_mm);
      file.quality.push_back(g.quality);
      // ACRONYM tries its grasps with the hand fully open (gripper/configuration): a grasp that
      // is free only at the narrower opening it was checked with is a failure there.
      file.success.push_back(g.free_when_open ? 1 : 0);
    }
    if (spec.suction) {
      // The suction wrench assumed this density: the mass is known.
      file.density = spec.suction_sampling.density_kg_m3;
      file.mass_kg = file.density * file.volume_m3;
      file.cup_diameter_mm = spec.cup.diameter_mm;
      file.cup_vacuum_kpa = spec.cup.vacuum_kpa;
      for (const SuctionGrasp& g : source.ObjectSuctionGrasps()[p]) {
        file.suction_points_mm.push_back(g.point);
        file.suction_approaches.push_back(g.approach);
        file.suction_seal.push_back(g.seal);
        file.suction_wrench.push_back(g.wrench);
      }
    }
    WriteAcronymFile(root / "models" / "grasps" / (std::string("obj_") + id + ".h5"), file);
  });
}

}  // namespace

std::string RandomizationRecord(const std::vector<Drawn>& record) {
  // In draw order (nlohmann's ordered_json keeps insertion order).
  nlohmann::ordered_json json = nlohmann::ordered_json::object();
  for (const Drawn& d : record) {
    if (!d.text.empty()) {
      json[d.key] = d.text;
    } else if (d.values.size() == 1) {
      json[d.key] = d.values[0];
    } else {
      json[d.key] = d.values;
    }
  }
  return json.dump();
}

namespace {

// The run's input files (recipe, CAD files), which --overwrite must never delete.
std::vector<std::filesystem::path> RunInputs(const RunSpec& spec) {
  std::vector<std::filesystem::path> inputs;
  if (!spec.recipe.empty()) inputs.push_back(spec.recipe);
  for (const SceneSpec& scene : spec.scenes) {
    for (const PartSource& source : scene.sources) {
      if (source.kind == PartSource::Kind::kFile) inputs.push_back(source.path);
      for (const ParamValues& values : source.variants) {
        const auto file = values.find("file");
        if (file != values.end() && std::holds_alternative<std::string>(file->second))
          inputs.emplace_back(std::get<std::string>(file->second));
      }
    }
  }
  return inputs;
}

// The output folder, checked before any work: it must not exist unless replaced, and may not
// hold the run's inputs.
std::filesystem::path CheckOutput(const RunSpec& spec, const GenerateOptions& options) {
  if (options.output.empty()) throw Error("no output folder given");
  const std::filesystem::path output = std::filesystem::absolute(options.output).lexically_normal();
  std::error_code ec;
  if (!options.shard && std::filesystem::exists(output, ec) && !options.overwrite) {
    throw Error(output.string() + ": already exists (pass --overwrite to replace it)");
  }
  if (options.shard && options.overwrite)
    throw Error("--overwrite does not apply to shards (they share one folder)");
  // Checked before the work, and again when the new dataset replaces the old one.
  if (!options.shard && options.overwrite) CheckReplaceable(output, RunInputs(spec));
  return output;
}

}  // namespace

namespace {
GenerateSummary GenerateFrom(const FrameSource& source, const GenerateOptions& options,
                             std::chrono::steady_clock::time_point start);
}  // namespace

GenerateSummary Generate(const RunSpec& spec, const GenerateOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  CheckOutput(spec, options);
  FrameSourceOptions source_options;
  source_options.info = options.info;
  source_options.cache = options.cache;
  source_options.reader = options.reader;
  source_options.strict = options.strict;
  source_options.stage_progress = options.stage_progress;
  const FrameSource source(spec, source_options);
  return GenerateFrom(source, options, start);  // its times count the preparation too
}

GenerateSummary Generate(const FrameSource& source, const GenerateOptions& options) {
  return GenerateFrom(source, options, std::chrono::steady_clock::now());
}

namespace {

// What GenerateFrom's steps share: the prepared run and the part of it this process renders.
struct Run {
  const FrameSource& source;
  const GenerateOptions& options;
  const RunSpec& spec;
  const PreparedRun& prepared;
  const std::vector<Part>& parts;
  const std::vector<SweepView>& views;
  const std::vector<RigSensor>& sensors;
  const std::optional<ShardSpec>& shard;
  std::vector<BopSensor> bop_sensors;
  bool common = false;  // writes the files every dataset has once

  // Work unit g = scene * views + view; a shard renders the units it owns.
  bool Owns(size_t scene, size_t view) const {
    return !shard || shard->Owns(scene * views.size() + view);
  }
  void Info(const std::string& line) const {
    if (options.info) options.info(line);
  }
};

Run MakeRun(const FrameSource& source, const GenerateOptions& options) {
  const RunSpec& spec = source.spec();
  const PreparedRun& prepared = source.prepared();
  Run run{.source = source,
          .options = options,
          .spec = spec,
          .prepared = prepared,
          .parts = prepared.parts,
          .views = source.views(),
          .sensors = source.sensors(),
          .shard = options.shard};
  for (const RigSensor& sensor : run.sensors) {
    run.bop_sensors.push_back(
        {sensor.name, spec.rig.empty() ? spec.bop.gray_bits : GrayBits(sensor.sensor.image)});
  }
  run.common = !run.shard || run.shard->index == 0;
  return run;
}

// The frames of this attempt: the last pipeline stage counts from many threads (atomics).
struct Counts {
  size_t total = 0;  // the units this run (or shard) owns
  std::atomic<size_t> done{0}, empty_views{0}, sparse_views{0};
  size_t resumed = 0, damaged = 0, frames = 0;
};

size_t OwnedUnits(const Run& run) {
  size_t total_frames = 0;
  for (size_t s = 0; s < run.prepared.scenes.size(); ++s) {
    for (size_t i = 0; i < run.views.size(); ++i) total_frames += run.Owns(s, i);
  }
  return total_frames;
}

// The placement warnings (shard 0 says them); under --strict, a camera inside or touching the
// scene is an error in every shard.
void WarnPlacements(const Run& run, bool strict) {
  for (size_t s = 0; s < run.prepared.scenes.size(); ++s) {
    for (const std::string& warning :
         PlacementWarnings(run.parts, run.prepared.scenes[s].instances, run.sensors[0].intrinsics,
                           run.spec.sweep)) {
      const std::string text = "scene '" + run.prepared.scene_names[s] + "': " + warning;
      if (strict && warning.find(kCameraInsideScene) != std::string::npos)
        throw Error(text + " (an error under --strict)");
      if (run.common) Warn(text);
    }
  }
}

// Where this attempt writes: a single run's staging folder, or a shard's tree (the output itself).
struct Output {
  std::filesystem::path root;
  std::unique_ptr<StagingRun> staging;
  std::unique_ptr<ShardTree> tree;
};

// A single run writes to a hidden staging folder beside the output, renamed into place at the
// end. An interrupted run (killed, disk full) leaves it; the same run started again continues
// from the frames it completed, if its run key (recipe text, parts, views, output options)
// matches. Shards write into the output folder itself and agree on the key there.
Output OpenOutput(const Run& run, const std::filesystem::path& output, const std::string& run_key) {
  Output out;
  if (run.shard) {
    out.root = output;
    out.tree = std::make_unique<ShardTree>(output, *run.shard, run_key);
  } else {
    out.staging = std::make_unique<StagingRun>(output, run_key, run.options.info);
    out.root = out.staging->root();
  }
  return out;
}

void WriteCommonFiles(const Run& run, const std::filesystem::path& root) {
  const RunSpec& spec = run.spec;
  WriteBopCamera(root, run.sensors[0].intrinsics, spec.bop);  // a rig: its first sensor's
  if (!spec.rig.empty()) {
    for (const RigSensor& sensor : run.sensors)
      WriteBopCamera(root, sensor.intrinsics, spec.bop, sensor.name);
  }
  WriteBopModels(root, run.parts, run.prepared.classes);
  WriteModelPoints(root, run.parts, spec.bop);
  if (spec.grasps.enabled && spec.grasps.acronym)
    WriteGraspFiles(root, run.parts, spec.grasps, run.source);
  WriteFileAtomic(root / "variants.json", run.prepared.variants_json);
}

std::vector<BopSceneWriter::CocoCategory> CocoCategories(const Run& run) {
  std::vector<BopSceneWriter::CocoCategory> categories;
  for (size_t p = 0; p < run.parts.size(); ++p) {
    categories.push_back(
        {static_cast<int>(p) + 1, run.parts[p].name, run.prepared.classes[p].name});
  }
  return categories;
}

// What merge needs to know about the run (shard 0 writes it).
void WriteShardRunInfo(const Run& run, const ShardTree& tree,
                       const std::vector<BopSceneWriter::CocoCategory>& categories) {
  ShardRunInfo info;
  info.shards = run.shard->count;
  info.views = run.views.size();
  info.bop = run.spec.bop;
  if (!run.spec.rig.empty()) info.sensors = run.bop_sensors;
  info.obj_ids = run.prepared.obj_ids;
  info.categories = categories;
  info.classes = run.prepared.classes;
  info.recipe_path = run.spec.recipe.string();
  info.recipe_text = run.spec.recipe_text;
  tree.WriteRunInfo(info);
}

// Per scene, the writers of the other output formats and of the grasp labels (none: the scene
// has no grasp labels here), beside the scene's RigSceneWriter.
struct SceneFormats {
  std::vector<std::vector<std::unique_ptr<FrameWriter>>> formats;
  std::vector<std::unique_ptr<GraspLabelWriter>> grasps;
};

// The free grasps of instance `instance` of scene `s` (a pick's part in the step before it),
// for scene_sequence.json: per kind, the best one whose approach comes from above (within 45
// degrees of straight down, as a bin picker reaches in), else the best of any approach.
std::vector<SequenceStep::Grasp> PickGrasps(const Run& run, size_t s, int instance) {
  std::vector<SequenceStep::Grasp> out;
  const SceneGrasps& placed = run.source.PlacedGrasps(s);
  const Eigen::Isometry3d& world_from_model =
      run.prepared.scenes[s].instances[static_cast<size_t>(instance)].world_from_model;
  const auto best = [&](const char* kind, const std::vector<PlacedGrasp>& list, auto tool,
                        auto quality) {
    SequenceStep::Grasp chosen;
    bool from_above = false;
    for (const PlacedGrasp& g : list) {
      if (g.instance != instance || g.approach_blocked) continue;
      const Eigen::Isometry3d world_from_tool = world_from_model * tool(g.grasp);
      const bool above = world_from_tool.linear().col(2).z() < -std::sqrt(0.5);
      const double q = quality(g.grasp);
      if (chosen.index < 0 || (above && !from_above) ||
          (above == from_above && q > chosen.quality)) {
        chosen = {kind, g.grasp, q, world_from_tool};
        from_above = above;
      }
    }
    if (chosen.index >= 0) out.push_back(chosen);
  };
  const int part = run.prepared.scenes[s].instances[static_cast<size_t>(instance)].part;
  if (placed.jaw != nullptr) {
    const std::vector<ParallelJawGrasp>& grasps = (*placed.jaw)[static_cast<size_t>(part)];
    best(
        "parallel_jaw", placed.jaw_placed,
        [&](int g) { return grasps[static_cast<size_t>(g)].model_from_gripper; },
        [&](int g) { return grasps[static_cast<size_t>(g)].quality; });
  }
  if (placed.suction != nullptr) {
    const std::vector<SuctionGrasp>& grasps = (*placed.suction)[static_cast<size_t>(part)];
    best(
        "suction", placed.suction_placed,
        [&](int g) { return ModelFromSuctionTool(grasps[static_cast<size_t>(g)]); },
        [&](int g) { return grasps[static_cast<size_t>(g)].quality(); });
  }
  return out;
}

// scene_sequence.json of scene s (a step of a pick sequence), with the pick's grasps.
void WriteSequence(const Run& run, size_t s, RigSceneWriter* writer) {
  SequenceStep step = *run.prepared.sequence[s];
  if (step.step > 0 && run.spec.grasps.enabled) {
    const std::vector<int>& before = run.prepared.sequence[s - 1]->instance_ids;
    const auto at = std::find(before.begin(), before.end(), step.picked_id);
    step.grasps = PickGrasps(run, s - 1, static_cast<int>(at - before.begin()));
  }
  writer->WriteSequence(step);
}

// Scene s's writers: its RigSceneWriter, appended to `writers`, and its entries of `formats`.
void OpenScene(const Run& run, const std::filesystem::path& root, size_t s,
               const std::vector<BopSceneWriter::CocoCategory>& categories,
               std::vector<std::unique_ptr<RigSceneWriter>>* writers, SceneFormats* formats) {
  const RunSpec& spec = run.spec;
  const PreparedRun& prepared = run.prepared;
  auto& writer = *writers->emplace_back(std::make_unique<RigSceneWriter>(
      root, static_cast<int>(s), spec.bop, prepared.obj_ids[s], run.bop_sensors));
  if (run.common) writer.WriteWorldPoses(prepared.scenes[s].instances);
  if (run.common && prepared.sequence[s]) WriteSequence(run, s, &writer);
  if (run.common && s < prepared.rest.size() && prepared.rest[s])
    writer.WriteRest(*prepared.rest[s]);
  writer.SetCocoCategories(categories);
  FormatScene format_scene{root, static_cast<int>(s), spec.bop, {}};
  for (size_t i = 0; i < prepared.scenes[s].instances.size(); ++i) {
    const Instance& instance = prepared.scenes[s].instances[i];
    format_scene.instances.push_back({prepared.obj_ids[s][i],
                                      prepared.classes[static_cast<size_t>(instance.part)],
                                      instance.name, instance.world_from_model});
  }
  formats->formats.push_back(MakeFrameWriters(format_scene));
  bool renders_here = false;  // a shard places only the grasps of scenes it renders frames of
  for (size_t i = 0; i < run.views.size() && !renders_here; ++i) renders_here = run.Owns(s, i);
  if (spec.grasps.enabled && (spec.grasps.labels.graspnet || spec.grasps.labels.suctionnet) &&
      renders_here) {
    formats->grasps[s] = std::make_unique<GraspLabelWriter>(
        root, static_cast<int>(s), spec.grasps.labels, run.source.PlacedGrasps(s));
  }
}

// The frames of scene s an interrupted attempt wrote: those whose files still match their
// manifest entry count as resumed; the others are forgotten, to be rendered again.
void CheckEarlierFrames(const Run& run, size_t s, RigSceneWriter& writer, Counts* counts) {
  std::vector<int> earlier;
  for (int id : writer.WrittenFrames()) {
    if (id >= 0 && static_cast<size_t>(id) < run.views.size() &&
        run.Owns(s, static_cast<size_t>(id)))
      earlier.push_back(id);
  }
  std::vector<std::string> problems(earlier.size());
  tbb::parallel_for(size_t{0}, earlier.size(),
                    [&](size_t k) { problems[k] = writer.CheckFrame(earlier[k]); });
  for (size_t k = 0; k < earlier.size(); ++k) {
    if (problems[k].empty()) {
      ++counts->resumed;
      continue;
    }
    Warn(problems[k] + ": rendering image " + std::to_string(earlier[k]) + " again");
    writer.ForgetFrame(earlier[k]);
    ++counts->damaged;
  }
}

// Scene s through the TBB pipeline: cast -> encode + write, a bounded number of frames in flight.
// Views showing too little of the scene are skipped (image ids keep their view index).
void RenderScene(const Run& run, size_t s, RigSceneWriter& writer, const SceneFormats& scene,
                 size_t to_render, Counts* counts) {
  std::vector<const FrameWriter*> formats;
  for (const auto& format : scene.formats[s]) formats.push_back(format.get());
  if (scene.grasps[s]) formats.push_back(scene.grasps[s].get());
  size_t next = 0;
  const size_t tokens = 2 * static_cast<size_t>(tbb::this_task_arena::max_concurrency());
  // The scene's acceleration structures first, with every thread (as before FrameSource:
  // also for a scene this shard renders no frame of, so the same errors surface).
  run.source.BuildScene(s);
  using ViewPtr = std::shared_ptr<const RenderedView>;
  tbb::parallel_pipeline(
      tokens,
      tbb::make_filter<void, size_t>(
          tbb::filter_mode::serial_in_order,
          [&](tbb::flow_control& control) -> size_t {
            while (next < run.views.size() &&
                   (!run.Owns(s, next) || writer.HasFrame(static_cast<int>(next)))) {
              ++next;
            }
            if (next >= run.views.size()) {
              control.stop();
              return 0;
            }
            return next++;
          }) &
          tbb::make_filter<size_t, ViewPtr>(tbb::filter_mode::parallel,
                                            [&](size_t i) {
                                              return std::make_shared<const RenderedView>(
                                                  run.source.Render(s * run.views.size() + i));
                                            }) &
          tbb::make_filter<ViewPtr, void>(tbb::filter_mode::parallel, [&](const ViewPtr& view) {
            if (!view->kept) {
              ++(view->visible_pixels == 0 ? counts->empty_views : counts->sparse_views);
            } else {
              std::vector<const Frame*> rig_frames;
              for (const Frame& frame : view->frames) rig_frames.push_back(&frame);
              writer.WriteFrame(static_cast<int>(view->view), rig_frames, formats);
            }
            const size_t n = ++counts->done;
            if (run.options.progress) run.options.progress(n, to_render);
          }));
  run.source.ReleaseScene(s);
  for (int id : writer.WrittenFrames()) counts->frames += run.Owns(s, static_cast<size_t>(id));
}

// The written frames this run (or shard) owns, as webdataset samples, in scene and image order.
std::vector<ArchiveSample> OwnedSamples(
    const Run& run, const std::vector<std::unique_ptr<RigSceneWriter>>& writers) {
  std::vector<ArchiveSample> samples;
  const int views = static_cast<int>(run.views.size());
  for (size_t s = 0; s < writers.size(); ++s) {
    for (int id : writers[s]->WrittenFrames()) {
      if (id < 0 || id >= views || !run.Owns(s, static_cast<size_t>(id))) continue;
      // The split is known while rendering only when no view is skipped (as Run.frames()).
      std::string split;
      if (run.spec.min_visible_pixels <= 0)
        split = run.spec.bop.IsTest(id, views) ? "test" : "train";
      samples.push_back({static_cast<int>(s), id, split});
    }
  }
  return samples;
}

// formats: webdataset. The frames this attempt owns, packed into its archives; a farm task then
// drops its loose copies (merge restores them from the archives).
void PackArchives(const Run& run, const std::filesystem::path& root,
                  const std::vector<std::unique_ptr<RigSceneWriter>>& writers) {
  const std::vector<ArchiveSample> samples = OwnedSamples(run, writers);
  const int shard = run.shard ? run.shard->index : 0;
  const int shards = run.shard ? run.shard->count : 1;
  const ArchiveManifest manifest =
      WriteArchives(root, run.spec.bop, run.bop_sensors, samples, shard, shards);
  run.Info("webdataset: " + std::to_string(manifest.samples) + " samples in " +
           std::to_string(manifest.archives.size()) + " archives (" +
           ManifestPath(root, shard).filename().string() + ")");
  if (run.shard) RemoveArchivedFrames(root, run.spec.bop, run.bop_sensors, samples);
}

// A shard records that it finished (for merge); a single run moves its dataset into place.
void Finish(const Run& run, const Output& out, const std::filesystem::path& output,
            const std::vector<std::filesystem::path>& inputs,
            const std::vector<std::unique_ptr<RigSceneWriter>>& writers, const Counts& counts,
            const std::string& run_key, size_t frames,
            std::chrono::steady_clock::time_point start) {
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const int threads = static_cast<int>(
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  if (run.shard) {
    std::ostringstream marker;
    marker << "{\"shard\": " << run.shard->index << ", \"of\": " << run.shard->count
           << ", \"units\": " << counts.total << ", \"frames\": " << counts.frames
           << ", \"skipped_empty\": " << counts.empty_views
           << ", \"skipped_sparse\": " << counts.sparse_views << ", \"seconds\": " << seconds
           << ", \"threads\": " << threads << ", \"started_utc\": \"" << UtcTime(seconds) << "\"}";
    out.tree->MarkDone(marker.str());
  } else {
    for (const auto& writer : writers) writer->RemoveFragments();
    RunRecord record;
    record.version = CadsynthVersion();
    record.run_key = RunKeyHash(run_key);
    record.recipe_path = run.spec.recipe.string();
    record.recipe_text = run.spec.recipe_text;
    record.started_utc = UtcTime(seconds);
    record.frames = frames;
    record.shards.push_back({0, seconds, frames, threads});
    // Checksumming every file takes a moment: the run's time includes it.
    record.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    WriteDatasetRecords(out.root, record);
    out.staging->Publish(output, run.options.overwrite, inputs);
  }
}

GenerateSummary Summarize(const Run& run, const Counts& counts,
                          std::chrono::steady_clock::time_point start) {
  GenerateSummary summary;
  summary.skipped_empty = counts.empty_views;
  summary.skipped_sparse = counts.sparse_views;
  summary.frames = counts.frames;
  summary.resumed = counts.resumed;
  summary.scenes = run.prepared.scenes.size();
  summary.objects = run.parts.size();
  summary.instances = 0;
  for (const Scene& scene : run.prepared.scenes) summary.instances += scene.instances.size();
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

GenerateSummary GenerateFrom(const FrameSource& source, const GenerateOptions& options,
                             std::chrono::steady_clock::time_point start) {
  const RunSpec& spec = source.spec();
  const std::filesystem::path output = CheckOutput(spec, options);
  const std::vector<std::filesystem::path> inputs = RunInputs(spec);
  const Run run = MakeRun(source, options);
  const PreparedRun& prepared = run.prepared;
  if (run.common || options.strict) WarnPlacements(run, options.strict);
  Counts counts;
  counts.total = OwnedUnits(run);

  const std::string run_key = RunKey(spec, prepared, run.views);
  run.Info("tracing with Embree's " + TracingIsa(spec.render.isa) + " kernels");
  // Grasps: every shard samples them (its frames need them); the common files write them.
  if (spec.grasps.enabled) source.ObjectJawGrasps();
  const Output out = OpenOutput(run, output, run_key);
  // The staging folder (or shard tree) is kept on errors from here on: a rerun resumes from it.
  std::vector<std::unique_ptr<RigSceneWriter>> writers;
  size_t frames = 0;  // in the finished dataset (a single run)
  try {
    if (run.common) WriteCommonFiles(run, out.root);
    const std::vector<BopSceneWriter::CocoCategory> categories = CocoCategories(run);
    if (run.shard && run.shard->index == 0) WriteShardRunInfo(run, *out.tree, categories);

    // Every scene's writers first: frames of an interrupted attempt count when every file still
    // matches their manifest entry; the others are rendered (again).
    // A farm task run again after its archives were complete: their frames back first, so
    // that they count as written (the archives are written again, to the same bytes).
    if (run.shard && spec.bop.webdataset)
      RestoreArchivedFrames(out.root, spec.bop, run.shard->index);
    SceneFormats formats;
    formats.grasps.resize(prepared.scenes.size());
    for (size_t s = 0; s < prepared.scenes.size(); ++s) {
      OpenScene(run, out.root, s, categories, &writers, &formats);
      CheckEarlierFrames(run, s, *writers[s], &counts);
    }
    // Progress counts the frames this attempt renders.
    const size_t to_render = counts.total - counts.resumed;
    if (options.progress) options.progress(0, to_render);

    // Render scene by scene.
    for (size_t s = 0; s < prepared.scenes.size(); ++s)
      RenderScene(run, s, *writers[s], formats, to_render, &counts);
    if (spec.bop.webdataset) PackArchives(run, out.root, writers);
    if (!run.shard) frames = FinishDataset(out.root, spec.bop, writers, prepared.classes);
  } catch (const Error& e) {
    throw Error(std::string(e.what()) + "\n(the complete frames are kept in " + out.root.string() +
                ": the same command continues from them)");
  }
  Finish(run, out, output, inputs, writers, counts, run_key, frames, start);
  if (counts.resumed > 0)
    run.Info("resumed: " + std::to_string(counts.resumed) + " frames were already written");
  if (counts.damaged > 0)
    run.Info("rendered again: " + std::to_string(counts.damaged) +
             " frames whose files did not match the manifest");
  return Summarize(run, counts, start);
}

}  // namespace

}  // namespace cadsynth
