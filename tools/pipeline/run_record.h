// DIR/run.json: how the run that wrote a dataset went (the recipe, when, how long, on how many
// threads and shards), for `cadsynth report`; and the dataset's manifest (dataset/manifest.h),
// written after it as the last file of a run or a merge.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace cadsynth {

struct RunRecord {
  std::string version;                   // cadsynth's
  std::string run_key;                   // RunKeyHash of the run key
  std::string recipe_path, recipe_text;  // empty: the built-in default job
  std::string started_utc;               // ISO 8601, e.g. 2026-12-02T14:25:48Z
  double seconds = 0;                    // wall time to the end of the merge / run
  size_t frames = 0;
  struct Shard {
    int index = 0;
    double seconds = 0;  // the shard's own wall time
    size_t frames = 0;
    int threads = 0;
  };
  std::vector<Shard> shards;  // one for a single run
};

// The cadsynth version this build writes into its records.
const char* CadsynthVersion();

// Hex XXH3-128 of a run key's text (journal.h RunKey; a shard tree's key without its shard
// count), leaving out the key's build line: another build of the same source that writes the
// same bytes writes the same manifest.
std::string RunKeyHash(const std::string& run_key);

// The current time as ISO 8601 UTC, `seconds_ago` earlier.
std::string UtcTime(double seconds_ago = 0);

// Writes ROOT/run.json, then ROOT/manifest.json listing every content file under ROOT (read and
// checksummed: call it when the dataset is otherwise complete).
void WriteDatasetRecords(const std::filesystem::path& root, const RunRecord& record);

// ROOT/run.json; nothing when there is none. Throws Error naming a damaged one.
std::optional<RunRecord> ReadRunRecord(const std::filesystem::path& root);

}  // namespace cadsynth
