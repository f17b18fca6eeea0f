// The dataset's own records, written last by a run or a merge, so that any copy of a dataset can
// be checked (`cadsynth verify`) and described (`cadsynth report`):
//   DIR/manifest.json  every file of the dataset (path relative to DIR, size, CRC-32), sorted by
//                      path, with the cadsynth version, the run key's hash and the frame count.
//                      Written last: a dataset with a manifest is complete. Byte for byte the
//                      same for any thread count and shard count.
//   DIR/run.json       how the run went (time, threads, shards; tools/pipeline/run_record.h):
//                      the one file that differs between runs of one recipe.
// The manifest leaves out the files about the dataset (itself, run.json and what verify and
// report write into DIR: verify.json, report.html) and hidden files (the marker, fragments).
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "dataset/file_io.h"

namespace cadsynth {

inline constexpr const char* kManifestFile = "manifest.json";
inline constexpr const char* kRunRecordFile = "run.json";
inline constexpr const char* kCertificateFile = "verify.json";
inline constexpr const char* kReportFile = "report.html";

struct DatasetManifest {
  std::string version;  // of the cadsynth that wrote the dataset
  std::string run_key;  // hex XXH3-128 of the run key (journal.h RunKey) but its build line
  size_t frames = 0;    // images per sensor, over all scenes
  std::vector<FileRecord> files;  // sorted by path
};

// Whether `relative` (a path under the dataset root) is one the manifest lists: not hidden (no
// component starting with '.') and not one of the files about the dataset named above.
bool IsDatasetContent(const std::filesystem::path& relative);

// Every content file under `root` with its size and CRC-32 (read in parallel), sorted by path.
// Throws Error naming a file that cannot be read.
std::vector<FileRecord> ListDatasetFiles(const std::filesystem::path& root);

// Writes ROOT/manifest.json (atomically): one file per line.
void WriteManifest(const std::filesystem::path& root, const DatasetManifest& manifest);

// Reads ROOT/manifest.json; throws Error naming it (and the line) when it is missing or damaged.
DatasetManifest ReadManifest(const std::filesystem::path& root);

}  // namespace cadsynth
