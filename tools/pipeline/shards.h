// Farm runs: one recipe's work split into shards that write into one output tree, and the merge
// that turns the tree into the dataset a single process writes.
//
// Work units are fixed by the recipe alone: unit g = scene * views + view (views in the order the
// sweep lists them); shard I of N renders the units with g % N == I. Every unit's camera comes
// from the recipe (seeded samplers draw all views up front), so a unit renders the same bytes in
// any shard, on any machine, with any thread count.
//
//   DIR/.shards/run_key      what every shard must agree on (recipe, parts, views, options, N)
//   DIR/.shards/run.json     what merge needs: output options, scenes, obj_ids, classes (shard 0)
//   DIR/.shards/I-of-N.lock  held while shard I runs (and by merge)
//   DIR/.shards/I-of-N.done  shard I rendered all of its units: counts and seconds
//
// Shard 0 writes the files common to the dataset (camera.json, models/, variants.json,
// scene_gt_world.json); every shard writes its frames' images and JSON fragments (the manifest:
// annotations and every file with size and CRC-32) into the scene folders.
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "dataset/bop.h"

namespace cadsynth {

struct ShardSpec {
  static constexpr int kMaxCount = 1000000;  // the most shards a run is cut into
  int index = 0;
  int count = 1;
  bool Owns(size_t unit) const {
    return unit % static_cast<size_t>(count) == static_cast<size_t>(index);
  }
  std::string Name() const { return std::to_string(index) + "/" + std::to_string(count); }
};

// "I/N" with 0 <= I < N; throws Error saying what is wrong otherwise.
ShardSpec ParseShard(const std::string& text);

// `--shard auto`: the shard this process is, from the task index its scheduler sets.
//   Slurm array        SLURM_ARRAY_TASK_ID, less SLURM_ARRAY_TASK_MIN, of the array's range
//                      (MIN..MAX, which must be contiguous); with `shards`, the ID itself of N
//   Kubernetes         JOB_COMPLETION_INDEX of an Indexed Job; the count is `shards` (pods are
//                      not told the Job's completions)
//   AWS Batch array    AWS_BATCH_JOB_ARRAY_INDEX of AWS_BATCH_JOB_ARRAY_SIZE
//   Google Cloud Batch BATCH_TASK_INDEX of BATCH_TASK_COUNT
// `shards` is `--shards N` (0: not given); a count a scheduler sets must equal it. Throws Error
// naming the variables when none is set, one is not a number or out of range, or two of them (or
// a scheduler and `shards`) disagree. `env` looks a variable up (nullptr: unset); std::getenv.
struct SchedulerShard {
  ShardSpec shard;
  std::string source;  // where it came from: "JOB_COMPLETION_INDEX=3 of --shards 8"
};
SchedulerShard ShardFromScheduler(const std::function<const char*(const char*)>& env, int shards);

// What merge needs to know about a run, without the CAD: written by shard 0 before rendering.
struct ShardRunInfo {
  int shards = 1;
  size_t views = 0;
  BopOptions bop;
  std::vector<std::vector<int>> obj_ids;                 // per scene, obj_id of each instance
  std::vector<BopSceneWriter::CocoCategory> categories;  // per object (id = obj_id)
  std::vector<ObjectClass> classes;                      // per object
  std::vector<BopSensor> sensors;                        // a rig's sensors; empty: one camera
  std::string recipe_path, recipe_text;                  // for run.json (run_record.h)
};

// The output options as the shard file holds them (JSON, each option by its described name) and
// back; throws Error on a missing or unknown value.
std::string OutputOptionsJson(const BopOptions& options);
BopOptions OutputOptionsFromJson(const std::string& text);

// One shard's hold on the output tree: creates DIR/.shards, agrees the run key with the other
// shards (the first to arrive writes it; a different key is an error naming what to do), and
// locks the shard. Throws Error when DIR is not a shard tree of the same run.
class ShardTree {
 public:
  ShardTree(const std::filesystem::path& dir, ShardSpec shard, const std::string& run_key);
  ~ShardTree();
  ShardTree(const ShardTree&) = delete;
  ShardTree& operator=(const ShardTree&) = delete;

  void WriteRunInfo(const ShardRunInfo& info) const;
  // Records that this shard finished: `summary_json` is one JSON object (counts, seconds).
  void MarkDone(const std::string& summary_json) const;

 private:
  std::filesystem::path dir_;
  ShardSpec shard_;
  int lock_fd_ = -1;
};

struct MergeSummary {
  int shards = 0;
  size_t scenes = 0;
  size_t frames = 0;
  double seconds = 0.0;
};

// Joins the shards in DIR into the dataset a single process would have written (byte for byte):
// checks every shard has finished and none is running, checks every frame's files against the
// manifest, then writes the scene files, splits and merged COCO files and removes the shard
// bookkeeping. Throws Error naming the shards that have not finished, or the damaged files (whose
// frames it forgets, so that running their shards again re-renders them).
MergeSummary Merge(const std::filesystem::path& dir,
                   const std::function<void(const std::string&)>& info = {});

}  // namespace cadsynth
