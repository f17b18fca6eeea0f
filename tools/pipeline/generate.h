// The `generate` job: RunSpec in, BOP dataset out: prepare (tools/pipeline/prepare.h), plan the
// views and units, render and write every frame, finish. Used by the command line and the tests.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>

#include "dataset/bop.h"
#include "recipes/recipe.h"
#include "render/randomize.h"
#include "render/scene.h"
#include "tools/pipeline/frames.h"
#include "tools/pipeline/prepare.h"
#include "tools/pipeline/shards.h"

namespace cadsynth {

struct GenerateOptions {
  std::filesystem::path output;  // dataset folder to create
  bool overwrite = false;        // replace an existing folder (only once the new one is complete)
  // Render only this shard's units, straight into `output` (a shard tree; see
  // tools/pipeline/shards.h), to be joined by Merge once every shard has finished.
  std::optional<ShardSpec> shard;
  // Called with (frames rendered, frames to render) by this attempt: once with 0 before the first
  // frame, then after each (frames an interrupted run completed do not count); may be empty.
  std::function<void(size_t, size_t)> progress;
  // Receives one line per notable fact (what was read, placement); may be empty.
  std::function<void(const std::string&)> info;
  // The part cache's folder (cad/part_cache.h; PartCache::DefaultDirectory() is the usual one);
  // none: every part is read and analysed afresh. Either way the output is the same.
  std::optional<std::filesystem::path> cache;
  // A cadsynth executable to read CAD and mesh files in child processes (guarded_import.h), so
  // a reader that crashes or hangs on a file ends in an error; empty: read in this process.
  std::filesystem::path reader;
  // Warnings that describe a broken dataset (parts kept outside their container, parts still
  // moving, a camera that sees the scene from inside or touching it) are errors.
  bool strict = false;
  // Progress of the long preparation stages (a pile's simulation), per scene; may be empty.
  StageProgress stage_progress;
};

struct GenerateSummary {
  size_t frames = 0;          // written (a shard: its own, including those of an earlier attempt)
  size_t resumed = 0;         // of these, written by an interrupted earlier run
  size_t skipped_empty = 0;   // views with no object pixel visible (sweep.min_visible_pixels > 0)
  size_t skipped_sparse = 0;  // views with fewer than sweep.min_visible_pixels object pixels
  size_t scenes = 0;
  size_t objects = 0;
  size_t instances = 0;
  double seconds = 0.0;
};

// Reads the files and builds the family variants of every scene, merges repeated shapes into one
// object each, arranges each scene on the floor, renders every view of the sweep per scene and
// writes the BOP dataset (scene i in SPLIT/00000i) plus variants.json. Everything is written into
// a hidden staging folder next to `output` and renamed into place at the end, so a failed run
// leaves no half-written dataset; the same run started again continues from the frames the
// failed one completed (checked against their manifest entries). With options.shard, renders
// that shard's units into `output` directly. Throws Error.
GenerateSummary Generate(const RunSpec& spec, const GenerateOptions& options);
// The same for a run already prepared (options.cache and options.reader are not used: the
// source was prepared with its own). The source's scene renderers are released as each scene is
// finished.
GenerateSummary Generate(const FrameSource& source, const GenerateOptions& options);

// A frame's domain randomisation record (render/randomize.h) as the compact JSON object the
// dataset writes to scene_randomization.json: each draw under its name, in draw order; a number,
// a list of numbers (a rotation's angle and axis) or a name (a preset, a light type).
std::string RandomizationRecord(const std::vector<Drawn>& record);

}  // namespace cadsynth
