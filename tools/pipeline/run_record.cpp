#include "tools/pipeline/run_record.h"

#include <chrono>
#include <ctime>

#include <nlohmann/json.hpp>

#include "cad/core/error.h"
#include "cad/part_cache.h"
#include "dataset/bop_read.h"
#include "dataset/file_io.h"
#include "dataset/manifest.h"

namespace cadsynth {

namespace fs = std::filesystem;
using Json = nlohmann::json;

const char* CadsynthVersion() { return CADSYNTH_VERSION; }

std::string RunKeyHash(const std::string& run_key) {
  // Without its "build SIZE CRC" line (journal.cpp RunKey): two builds of one source write the
  // same bytes, and so the same manifest (the container check compares them).
  std::string key = run_key;
  const size_t build = key.rfind("\nbuild ");  // the last line; a recipe holds none after it
  if (build != std::string::npos) {
    const size_t end = key.find('\n', build + 1);
    key.erase(build + 1, end == std::string::npos ? std::string::npos : end - build);
  }
  KeyHasher hasher;
  hasher.Bytes(key.data(), key.size());
  return hasher.Key().Hex();
}

std::string UtcTime(double seconds_ago) {
  const auto when = std::chrono::system_clock::now() -
                    std::chrono::duration_cast<std::chrono::system_clock::duration>(
                        std::chrono::duration<double>(seconds_ago));
  const std::time_t t = std::chrono::system_clock::to_time_t(when);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return text;
}

void WriteDatasetRecords(const fs::path& root, const RunRecord& record) {
  Json shards = Json::array();
  for (const RunRecord::Shard& s : record.shards)
    shards.push_back(
        {{"index", s.index}, {"seconds", s.seconds}, {"frames", s.frames}, {"threads", s.threads}});
  const Json run = {{"version", record.version},         {"run_key", record.run_key},
                    {"recipe_path", record.recipe_path}, {"recipe_text", record.recipe_text},
                    {"started_utc", record.started_utc}, {"seconds", record.seconds},
                    {"frames", record.frames},           {"shards", shards}};
  WriteFileAtomic(root / kRunRecordFile, run.dump(2) + "\n");
  DatasetManifest manifest;
  manifest.version = record.version;
  manifest.run_key = record.run_key;
  manifest.frames = record.frames;
  manifest.files = ListDatasetFiles(root);
  WriteManifest(root, manifest);
}

std::optional<RunRecord> ReadRunRecord(const fs::path& root) {
  const fs::path path = root / kRunRecordFile;
  std::error_code ec;
  if (!fs::exists(path, ec)) return std::nullopt;
  const std::string text = ReadFileText(path);
  RunRecord r;
  try {
    const Json j = Json::parse(text);
    r.version = j.at("version").get<std::string>();
    r.run_key = j.at("run_key").get<std::string>();
    r.recipe_path = j.at("recipe_path").get<std::string>();
    r.recipe_text = j.at("recipe_text").get<std::string>();
    r.started_utc = j.at("started_utc").get<std::string>();
    r.seconds = j.at("seconds").get<double>();
    r.frames = j.at("frames").get<size_t>();
    for (const Json& s : j.at("shards"))
      r.shards.push_back({s.at("index").get<int>(), s.at("seconds").get<double>(),
                          s.at("frames").get<size_t>(), s.at("threads").get<int>()});
  } catch (const Json::exception& e) {
    throw Error(JsonErrorMessage(path.string(), text, e));
  }
  return r;
}

}  // namespace cadsynth
