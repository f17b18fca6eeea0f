// The run journal of a single-process run: its key, its lock and its staging folder. A run writes
// into a hidden staging folder beside the output (DIR/../.NAME.partial) and renames it into place
// at the end, so a failed run leaves no half-written dataset; the same run started again finds
// its key there and continues from the frames it completed (each frame's manifest entry, written
// last, lists its files with size and CRC-32: dataset/bop.h). Shards agree on the same key in a
// shard tree instead (tools/pipeline/shards.h).
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "dataset/bop.h"
#include "render/camera.h"
#include "tools/pipeline/prepare.h"

namespace cadsynth {

// The size and CRC-32 of the running executable, read once ("unknown" where it cannot be read):
// run keys and the part cache hold it, so results of another build are never mixed in.
const std::string& BuildId();

// What must match for a run to continue an interrupted one (and for shards to join): the recipe
// file's text, the CAD files' bytes, the parts and their variants, every view, the image size,
// every output and render option (each by its described name, cad/core/schema.h), the kernels and
// this build of cadsynth.
std::string RunKey(const RunSpec& spec, const PreparedRun& prepared,
                   const std::vector<SweepView>& views);

// One run at a time per output: an exclusive lock (flock) on STAGING.lock beside the staging
// folder. Throws Error when another run holds it.
class RunLock {
 public:
  explicit RunLock(const std::filesystem::path& staging);
  ~RunLock() { Release(); }
  RunLock(const RunLock&) = delete;
  RunLock& operator=(const RunLock&) = delete;
  void Release();

 private:
  std::string path_;
  int fd_ = -1;
};

// Every dataset folder cadsynth writes holds this file; `--overwrite` replaces only such folders.
inline constexpr const char* kDatasetMarker = ".cadsynth_dataset";
// Writes the marker into `folder`.
void MarkDataset(const std::filesystem::path& folder);
// Throws Error unless `output` may be replaced by --overwrite: a folder cadsynth wrote (its marker,
// or variants.json for datasets written before the marker), holding no shard tree (shards may be
// writing into it) and none of `inputs` (the recipe, CAD files).
void CheckReplaceable(const std::filesystem::path& output,
                      const std::vector<std::filesystem::path>& inputs);

// The staging folder of a run writing `output`: locked, and started afresh unless it holds an
// interrupted run with the same key (then the run continues in it).
class StagingRun {
 public:
  StagingRun(const std::filesystem::path& output, const std::string& run_key,
             const std::function<void(const std::string&)>& info);
  ~StagingRun();
  const std::filesystem::path& root() const { return root_; }
  // Moves the finished dataset to `output` (replacing an old one only with `overwrite`, only if
  // CheckReplaceable(output, inputs) allows it, and only once the new one is complete) and
  // releases the lock.
  void Publish(const std::filesystem::path& output, bool overwrite,
               const std::vector<std::filesystem::path>& inputs = {});

 private:
  std::filesystem::path root_;
  std::unique_ptr<RunLock> lock_;
};

// The finish stage, as a single run and merge both end (so both write the same bytes): each
// scene's JSON files from its frames' fragments in image order, the splits and test targets, and
// the merged COCO files. The fragments stay until the caller removes them (a run interrupted
// here finishes again). Returns the number of frames.
size_t FinishDataset(const std::filesystem::path& root, const BopOptions& options,
                     const std::vector<std::unique_ptr<RigSceneWriter>>& writers,
                     const std::vector<ObjectClass>& classes);

}  // namespace cadsynth
