#include "tools/pipeline/shards.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <system_error>

#include <tbb/parallel_for.h>
#include <nlohmann/json.hpp>

#include "cad/core/error.h"
#include "dataset/file_io.h"
#include "dataset/webdataset.h"
#include "tools/pipeline/journal.h"
#include "tools/pipeline/run_record.h"

namespace cadsynth {
namespace {

using Json = nlohmann::ordered_json;
namespace fs = std::filesystem;

fs::path Meta(const fs::path& dir) { return dir / ".shards"; }
std::string ShardFile(int index, int count, const char* ext) {
  return std::to_string(index) + "-of-" + std::to_string(count) + ext;
}

// The output options by their described names (cad/core/schema.h); enums and choice bools by name.
Json OptionsJson(const BopOptions& b) {
  Json j = Json::object();
  BopOptions::Fields(b, [&j](const auto& value, const Field& field) {
    using T = std::decay_t<decltype(value)>;
    if constexpr (std::is_enum_v<T>) {
      j[std::string(field.Name())] = FieldText(value, field);
    } else {
      j[std::string(field.Name())] = value;
    }
  });
  return j;
}

BopOptions OptionsFromJson(const Json& j) {
  BopOptions b;
  BopOptions::Fields(b, [&j](auto& value, const Field& field) {
    using T = std::decay_t<decltype(value)>;
    const Json& v = j.at(std::string(field.Name()));
    if constexpr (std::is_enum_v<T>) {
      const std::string name = v.get<std::string>();
      const auto it = std::find(field.choices.begin(), field.choices.end(), name);
      if (it == field.choices.end())
        throw Error("unknown " + std::string(field.Name()) + " '" + name + "'");
      value = static_cast<T>(it - field.choices.begin());
    } else {
      value = v.get<T>();
    }
  });
  return b;
}

}  // namespace

std::string OutputOptionsJson(const BopOptions& options) { return OptionsJson(options).dump(); }

BopOptions OutputOptionsFromJson(const std::string& text) {
  try {
    return OptionsFromJson(Json::parse(text));
  } catch (const Json::exception& e) {
    throw Error(std::string("output options: ") + e.what());
  }
}

namespace {

ShardRunInfo ReadRunInfo(const fs::path& path) {
  try {
    const Json j = Json::parse(ReadFileText(path));
    ShardRunInfo info;
    info.shards = j.at("shards");
    info.views = j.at("views");
    info.bop = OptionsFromJson(j.at("output"));
    for (const Json& scene : j.at("scenes"))
      info.obj_ids.push_back(scene.at("obj_ids").get<std::vector<int>>());
    for (const Json& o : j.at("objects")) {
      info.categories.push_back({o.at("obj_id"), o.at("name"), o.at("class_name")});
      info.classes.push_back({o.at("class_id"), o.at("class_name")});
    }
    if (j.contains("sensors")) {  // a rig
      for (const Json& sensor : j.at("sensors"))
        info.sensors.push_back({sensor.at("name"), sensor.at("gray_bits")});
    }
    info.recipe_path = j.value("recipe_path", "");
    info.recipe_text = j.value("recipe_text", "");
    if (info.shards < 1 || info.views < 1 || info.obj_ids.empty()) throw Error("impossible counts");
    return info;
  } catch (const Json::exception& e) {
    throw Error(path.string() + ": unreadable: " + e.what());
  } catch (const Error& e) {
    throw Error(path.string() + ": " + e.what());
  }
}

// The shard count written in a run key's last line ("shards N"), or 0.
int ShardsOfKey(const std::string& key) {
  const size_t at = key.rfind("shards ");
  return at == std::string::npos ? 0 : std::atoi(key.c_str() + at + 7);
}

// The rest of the last line of `key` that starts with `prefix` ("" when there is none).
std::string KeyLine(const std::string& key, const std::string& prefix) {
  const size_t at = key.rfind("\n" + prefix);  // the last such line: the recipe text comes first
  if (at == std::string::npos) return "";
  const size_t begin = at + 1 + prefix.size();
  return key.substr(begin, key.find('\n', begin) - begin);
}

// Of two Embree kernel names, the narrower (the one both machines have).
std::string Narrower(const std::string& a, const std::string& b) {
  const std::vector<std::string> order = {"sse2", "sse4.2", "avx", "avx2", "avx512"};
  const auto rank = [&](const std::string& isa) {
    return std::find(order.begin(), order.end(), isa) - order.begin();
  };
  return rank(a) <= rank(b) ? a : b;
}

// An exclusive, non-blocking flock; -1 when another process holds it.
int TryLock(const fs::path& path) {
  const int fd = ::open(path.c_str(), O_CREAT | O_RDWR, 0644);
  if (fd < 0) throw Error(path.string() + ": cannot create lock file: " + std::strerror(errno));
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

}  // namespace

ShardSpec ParseShard(const std::string& text) {
  const size_t slash = text.find('/');
  const auto number = [&](const std::string& part, long* out) {
    char* end = nullptr;
    *out = std::strtol(part.c_str(), &end, 10);
    return !part.empty() && end != part.c_str() && *end == '\0';
  };
  long index = 0, count = 0;
  if (slash == std::string::npos || !number(text.substr(0, slash), &index) ||
      !number(text.substr(slash + 1), &count)) {
    throw Error("--shard takes I/N (shard I of N, counting from 0), got '" + text + "'");
  }
  if (count < 1 || count > ShardSpec::kMaxCount || index < 0 || index >= count) {
    throw Error("--shard " + text + ": I must be at least 0 and less than N (N from 1 to " +
                std::to_string(ShardSpec::kMaxCount) + ")");
  }
  return {static_cast<int>(index), static_cast<int>(count)};
}

namespace {

// One scheduler's reading of the environment: unset, or the shard it names.
struct SchedulerReading {
  bool set = false;
  ShardSpec shard;
  std::string source;
};

// A variable's value as a task index or count: decimal digits only (no sign, no spaces).
std::optional<long> EnvNumber(const std::function<const char*(const char*)>& env,
                              const char* name) {
  const char* value = env(name);
  if (value == nullptr) return std::nullopt;
  const std::string text = value;
  if (text.empty() || text.size() > 9 ||
      text.find_first_not_of("0123456789") != std::string::npos) {
    throw Error("--shard auto: " + std::string(name) + "='" + text +
                "' is not a task index or count (a whole number)");
  }
  return std::stol(text);
}

std::string Assignment(const char* name, long value) {
  return std::string(name) + "=" + std::to_string(value);
}

// Index `index` of `count` from `source`, checked.
SchedulerReading Reading(long index, long count, std::string source) {
  if (count < 1 || count > ShardSpec::kMaxCount) {
    throw Error("--shard auto: " + source + ": the shard count must be from 1 to " +
                std::to_string(ShardSpec::kMaxCount));
  }
  if (index < 0 || index >= count) {
    throw Error("--shard auto: " + source + ": the index must be at least 0 and less than " +
                std::to_string(count));
  }
  return {true, {static_cast<int>(index), static_cast<int>(count)}, std::move(source)};
}

SchedulerReading FromSlurm(const std::function<const char*(const char*)>& env, int shards) {
  const std::optional<long> id = EnvNumber(env, "SLURM_ARRAY_TASK_ID");
  if (!id) return {};
  if (shards > 0) {
    // The ID itself: reruns of some tasks (--array=3,17) keep their shard numbers.
    return Reading(
        *id, shards,
        Assignment("SLURM_ARRAY_TASK_ID", *id) + " of --shards " + std::to_string(shards));
  }
  const std::optional<long> min = EnvNumber(env, "SLURM_ARRAY_TASK_MIN");
  const std::optional<long> max = EnvNumber(env, "SLURM_ARRAY_TASK_MAX");
  if (!min || !max || *max < *min) {
    throw Error(
        "--shard auto: SLURM_ARRAY_TASK_ID is set but SLURM_ARRAY_TASK_MIN and "
        "SLURM_ARRAY_TASK_MAX are not (or MAX < MIN): give the count with --shards N");
  }
  const long count = *max - *min + 1;
  const std::optional<long> tasks = EnvNumber(env, "SLURM_ARRAY_TASK_COUNT");
  if (tasks && *tasks != count) {
    throw Error("--shard auto: the Slurm array " + std::to_string(*min) + "-" +
                std::to_string(*max) +
                " has gaps (SLURM_ARRAY_TASK_COUNT=" + std::to_string(*tasks) +
                "): use a contiguous range, or give the shard count with --shards N (the task "
                "ID is then the shard index)");
  }
  return Reading(*id - *min, count,
                 Assignment("SLURM_ARRAY_TASK_ID", *id) + " of the array " + std::to_string(*min) +
                     "-" + std::to_string(*max));
}

SchedulerReading FromKubernetes(const std::function<const char*(const char*)>& env, int shards) {
  const std::optional<long> index = EnvNumber(env, "JOB_COMPLETION_INDEX");
  if (!index) return {};
  if (shards <= 0) {
    throw Error(
        "--shard auto: JOB_COMPLETION_INDEX is set (a Kubernetes Indexed Job), whose pods "
        "are not told the shard count: give --shards N equal to the Job's "
        "spec.completions");
  }
  return Reading(
      *index, shards,
      Assignment("JOB_COMPLETION_INDEX", *index) + " of --shards " + std::to_string(shards));
}

// A scheduler that sets both the index and the count.
SchedulerReading FromIndexAndCount(const std::function<const char*(const char*)>& env,
                                   const char* index_name, const char* count_name) {
  const std::optional<long> index = EnvNumber(env, index_name);
  if (!index) return {};
  const std::optional<long> count = EnvNumber(env, count_name);
  if (!count) {
    throw Error("--shard auto: " + std::string(index_name) + " is set but " + count_name +
                " is not");
  }
  return Reading(*index, *count,
                 Assignment(index_name, *index) + " of " + Assignment(count_name, *count));
}

}  // namespace

SchedulerShard ShardFromScheduler(const std::function<const char*(const char*)>& env, int shards) {
  if (shards < 0 || shards > ShardSpec::kMaxCount) {
    throw Error("--shards " + std::to_string(shards) + ": the shard count must be from 1 to " +
                std::to_string(ShardSpec::kMaxCount));
  }
  const SchedulerReading readings[] = {
      FromSlurm(env, shards),
      FromKubernetes(env, shards),
      FromIndexAndCount(env, "AWS_BATCH_JOB_ARRAY_INDEX", "AWS_BATCH_JOB_ARRAY_SIZE"),
      FromIndexAndCount(env, "BATCH_TASK_INDEX", "BATCH_TASK_COUNT"),
  };
  const SchedulerReading* found = nullptr;
  for (const SchedulerReading& reading : readings) {
    if (!reading.set) continue;
    if (shards > 0 && reading.shard.count != shards) {
      throw Error("--shard auto: " + reading.source + " but --shards " + std::to_string(shards) +
                  ": give the scheduler's count, or leave --shards out");
    }
    if (found != nullptr &&
        (found->shard.index != reading.shard.index || found->shard.count != reading.shard.count)) {
      throw Error("--shard auto: the schedulers' variables disagree: " + found->source +
                  " is shard " + found->shard.Name() + ", " + reading.source + " is shard " +
                  reading.shard.Name() + "; unset the one that does not belong to this task");
    }
    if (found == nullptr) found = &reading;
  }
  if (found == nullptr) {
    throw Error(
        "--shard auto: no scheduler task index is set (SLURM_ARRAY_TASK_ID, "
        "JOB_COMPLETION_INDEX, AWS_BATCH_JOB_ARRAY_INDEX or BATCH_TASK_INDEX); outside "
        "an array job give the shard as --shard I/N");
  }
  return {found->shard, found->source};
}

ShardTree::ShardTree(const fs::path& dir, ShardSpec shard, const std::string& run_key)
    : dir_(dir), shard_(shard) {
  std::error_code ec;
  // Emptiness before the shard folder: shards starting together create the folder and then its
  // .shards, never anything else first, so a folder seen non-empty and then without .shards
  // holds something else. (The other order raced: .shards missing, then a sibling shard made it,
  // then the folder looked non-empty, and a shard of a new run refused its own folder.)
  if (fs::exists(dir, ec) && !fs::is_empty(dir, ec) && !fs::exists(Meta(dir), ec)) {
    throw Error(dir.string() +
                ": exists and is not a shard folder (a finished dataset?): shards need a new or "
                "empty folder, or the folder their run started");
  }
  CreateFolder(Meta(dir));
  MarkDataset(dir);
  const fs::path lock = Meta(dir) / ShardFile(shard.index, shard.count, ".lock");
  lock_fd_ = TryLock(lock);
  if (lock_fd_ < 0)
    throw Error(dir.string() + ": shard " + shard.Name() + " is already running on this folder");

  try {  // the lock is released if the tree turns out not to be ours
    if (fs::exists(Meta(dir) / "merging", ec)) {
      throw Error(
          dir.string() +
          ": is being merged (.shards/merging): shards can start again once the merge "
          "has failed or finished (a merge that was killed leaves the mark: run merge again)");
    }
    // The first shard to arrive publishes the key: written under a name of its own, then linked
    // (link fails if another shard got there first; it is atomic on NFS as well).
    const std::string key = run_key + "shards " + std::to_string(shard.count) + "\n";
    const fs::path key_path = Meta(dir) / "run_key";
    if (!fs::exists(key_path, ec)) {
      const fs::path mine = Meta(dir) / ShardFile(shard.index, shard.count, ".key");
      WriteFileAtomic(mine, key);
      if (::link(mine.c_str(), key_path.c_str()) != 0 && errno != EEXIST) {
        throw Error(key_path.string() + ": cannot create: " + std::strerror(errno));
      }
      fs::remove(mine, ec);
    }
    const std::string agreed = ReadFileText(key_path);
    if (agreed != key) {
      const std::string theirs = KeyLine(agreed, "trace "), mine = KeyLine(key, "trace ");
      if (theirs != mine) {
        throw Error(dir.string() + ": this machine traces with Embree's " + mine +
                    " kernels, the run started with " + theirs +
                    " ones (the bytes would differ): set render: {isa: " + Narrower(theirs, mine) +
                    "} in the recipe so that every machine uses the same, and start the run again");
      }
      if (KeyLine(agreed, "build ") != KeyLine(key, "build ")) {
        throw Error(
            dir.string() +
            ": this run was started by another build of cadsynth (its bytes "
            "could differ): run every shard with the same executable, or start the run again");
      }
      const int started = ShardsOfKey(agreed);
      if (started != shard.count && agreed.substr(0, agreed.rfind("shards ")) == run_key) {
        throw Error(dir.string() + ": this run was started with " + std::to_string(started) +
                    " shards; this is shard " + shard.Name() + ": use --shard I/" +
                    std::to_string(started));
      }
      throw Error(dir.string() +
                  ": holds shards of a different run (the recipe, its parts, views or output "
                  "options changed since it started): remove the folder or write to another one");
    }
  } catch (...) {
    ::close(lock_fd_);
    lock_fd_ = -1;
    throw;
  }
}

ShardTree::~ShardTree() {
  if (lock_fd_ >= 0) ::close(lock_fd_);
}

void ShardTree::WriteRunInfo(const ShardRunInfo& info) const {
  Json scenes = Json::array(), objects = Json::array();
  for (const std::vector<int>& ids : info.obj_ids) scenes.push_back({{"obj_ids", ids}});
  for (size_t o = 0; o < info.categories.size(); ++o) {
    objects.push_back({{"obj_id", info.categories[o].id},
                       {"name", info.categories[o].name},
                       {"class_id", info.classes.at(o).id},
                       {"class_name", info.classes.at(o).name}});
  }
  Json j = {{"shards", info.shards},
            {"views", info.views},
            {"output", OptionsJson(info.bop)},
            {"scenes", scenes},
            {"objects", objects},
            {"recipe_path", info.recipe_path},
            {"recipe_text", info.recipe_text}};
  if (!info.sensors.empty()) {
    Json sensors = Json::array();
    for (const BopSensor& sensor : info.sensors)
      sensors.push_back({{"name", sensor.name}, {"gray_bits", sensor.gray_bits}});
    j["sensors"] = sensors;
  }
  WriteFileAtomic(Meta(dir_) / "run.json", j.dump(2) + "\n");
}

void ShardTree::MarkDone(const std::string& summary_json) const {
  WriteFileAtomic(Meta(dir_) / ShardFile(shard_.index, shard_.count, ".done"), summary_json + "\n");
}

namespace {

// The run of the shard tree DIR, from the run.json shard 0 writes; throws Error saying why DIR
// cannot be merged when there is none.
ShardRunInfo ReadMergeRun(const fs::path& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw Error(dir.string() + ": no such folder");
  const fs::path meta = Meta(dir);
  if (!fs::exists(meta / "run.json", ec)) {
    if (!fs::exists(meta, ec)) {
      if (fs::exists(dir / "camera.json", ec))
        throw Error(dir.string() + ": already a complete dataset; nothing to merge");
      throw Error(dir.string() +
                  ": not a shard folder (no .shards/): write one with "
                  "cadsynth generate RECIPE --shard I/N -o " +
                  dir.string());
    }
    const int n =
        fs::exists(meta / "run_key", ec) ? ShardsOfKey(ReadFileText(meta / "run_key")) : 0;
    throw Error(dir.string() + ": cannot merge yet: shard 0/" +
                (n > 0 ? std::to_string(n) : std::string("N")) +
                " has not started (it writes .shards/run.json)");
  }
  return ReadRunInfo(meta / "run.json");
}

// An earlier merge completed the dataset, then stopped: only its clean-up is left.
MergeSummary FinishCleanUp(const fs::path& dir, const ShardRunInfo& run,
                           std::chrono::steady_clock::time_point start) {
  std::error_code ec;
  const fs::path meta = Meta(dir);
  MergeSummary summary;
  summary.shards = run.shards;
  summary.scenes = run.obj_ids.size();
  const std::string count = ReadFileText(meta / "merged");
  char* end = nullptr;
  summary.frames = std::strtoul(count.c_str(), &end, 10);
  if (end == count.c_str())
    throw Error((meta / "merged").string() + ": unreadable (expected a frame count)");
  for (size_t s = 0; s < run.obj_ids.size(); ++s) {
    const fs::path scene = dir / run.bop.split / Id6(static_cast<int>(s));
    fs::remove_all(scene / ".fragments", ec);
    for (const BopSensor& sensor : run.sensors)
      fs::remove_all(scene / (".fragments" + sensor.Suffix()), ec);
  }
  fs::remove_all(meta, ec);
  if (ec) throw Error(meta.string() + ": cannot remove: " + ec.message());
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

// What Merge's checks share: the tree, its run, each scene's writer and the frames per shard.
struct MergeTree {
  fs::path dir, meta;
  const ShardRunInfo& run;
  int n = 0;  // shards
  std::vector<std::unique_ptr<RigSceneWriter>> writers;
  std::vector<bool> running;  // per shard: another process holds its lock
  // Frames per shard: written (fragments) and declared (done markers), and its units.
  std::vector<size_t> written, units, declared;
  std::vector<RunRecord::Shard> records;  // per shard, from its done marker (run.json)
  std::string first_start;                // the earliest shard's start (ISO 8601 UTC)
  std::vector<std::string> not_ready;     // why the shards cannot be merged yet
};

// Locks are tried one at a time: a farm may have more shards than a process may open files.
void FindRunningShards(MergeTree* tree) {
  const int n = tree->n;
  tree->running.assign(n, false);
  for (int i = 0; i < n; ++i) {
    const int fd = TryLock(tree->meta / ShardFile(i, n, ".lock"));
    if (fd < 0) {
      tree->running[i] = true;
      tree->not_ready.push_back("shard " + std::to_string(i) + "/" + std::to_string(n) +
                                " is running");
    } else {
      ::close(fd);
    }
  }
}

void OpenSceneWriters(MergeTree* tree) {
  const ShardRunInfo& run = tree->run;
  const std::vector<BopSensor> sensors =
      run.sensors.empty() ? std::vector<BopSensor>{BopSensor{}} : run.sensors;
  for (size_t s = 0; s < run.obj_ids.size(); ++s) {
    tree->writers.push_back(std::make_unique<RigSceneWriter>(tree->dir, static_cast<int>(s),
                                                             run.bop, run.obj_ids[s], sensors));
    tree->writers.back()->SetCocoCategories(run.categories);
  }
}

void CountWrittenFrames(MergeTree* tree) {
  const ShardRunInfo& run = tree->run;
  const int n = tree->n;
  tree->written.assign(n, 0);
  tree->units.assign(n, 0);
  for (size_t s = 0; s < tree->writers.size(); ++s) {
    for (size_t v = 0; v < run.views; ++v) ++tree->units[(s * run.views + v) % n];
    for (int id : tree->writers[s]->WrittenFrames()) {
      if (id >= 0 && static_cast<size_t>(id) < run.views) ++tree->written[(s * run.views + id) % n];
    }
  }
}

// Each finished shard's frame count from its done marker; a shard without one is not ready.
void ReadDoneMarkers(MergeTree* tree) {
  const int n = tree->n;
  tree->declared.assign(n, 0);
  for (int i = 0; i < n; ++i) {
    const fs::path marker = tree->meta / ShardFile(i, n, ".done");
    if (tree->running[i]) continue;
    std::error_code ec;
    if (!fs::exists(marker, ec)) {
      const std::string name = "shard " + std::to_string(i) + "/" + std::to_string(n);
      if (tree->written[i] == 0) {
        tree->not_ready.push_back(name + " has not started");
      } else {
        tree->not_ready.push_back(name + " has not finished (" + std::to_string(tree->written[i]) +
                                  " of " + std::to_string(tree->units[i]) + " views done)");
      }
      continue;
    }
    try {
      const Json done = Json::parse(ReadFileText(marker));
      tree->declared[i] = done.at("frames").get<size_t>();
      tree->records.push_back(
          {i, done.value("seconds", 0.0), tree->declared[i], done.value("threads", 0)});
      const std::string started = done.value("started_utc", "");
      if (!started.empty() && (tree->first_start.empty() || started < tree->first_start))
        tree->first_start = started;
    } catch (const Json::exception&) {
      tree->not_ready.push_back(marker.string() + ": unreadable");
    }
  }
}

// run.json and the manifest of the merged dataset: the run key without its shard count (the
// key of the same run in one process), the shards' times from their done markers.
void WriteMergedRecords(const MergeTree& tree, size_t frames,
                        std::chrono::steady_clock::time_point start) {
  const std::string key = ReadFileText(tree.meta / "run_key");
  RunRecord record;
  record.version = CadsynthVersion();
  record.run_key = RunKeyHash(key.substr(0, key.rfind("shards ")));
  record.recipe_path = tree.run.recipe_path;
  record.recipe_text = tree.run.recipe_text;
  record.frames = frames;
  record.shards = tree.records;
  const double merge_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  record.started_utc = tree.first_start.empty() ? UtcTime(merge_seconds) : tree.first_start;
  // From the first shard's start to the end of the merge (unknown start: the merge alone).
  record.seconds = merge_seconds;
  if (!tree.first_start.empty()) {
    std::tm tm{};
    if (strptime(tree.first_start.c_str(), "%Y-%m-%dT%H:%M:%SZ", &tm) != nullptr)
      record.seconds = std::max(merge_seconds, std::difftime(std::time(nullptr), timegm(&tm)));
  }
  WriteDatasetRecords(tree.dir, record);
}

void ThrowUnlessReady(const MergeTree& tree) {
  const std::vector<std::string>& not_ready = tree.not_ready;
  if (not_ready.empty()) return;
  std::string list;
  const size_t shown = std::min<size_t>(not_ready.size(), 8);
  for (size_t k = 0; k < shown; ++k) list += (k ? "; " : "") + not_ready[k];
  if (not_ready.size() > shown)
    list += "; and " + std::to_string(not_ready.size() - shown) + " more";
  throw Error(tree.dir.string() + ": cannot merge yet: " + list);
}

// Every frame's files against its manifest entry, in parallel, and each shard's frames against
// its done marker. Throws Error naming the shards to run again (their done markers removed, the
// damaged frames forgotten: they re-render them).
void CheckFrames(MergeTree* tree) {
  const ShardRunInfo& run = tree->run;
  const int n = tree->n;
  const auto& writers = tree->writers;
  std::vector<std::pair<size_t, int>> frames;
  for (size_t s = 0; s < writers.size(); ++s) {
    for (int id : writers[s]->WrittenFrames()) frames.push_back({s, id});
  }
  std::vector<std::string> problems(frames.size());
  tbb::parallel_for(size_t{0}, frames.size(), [&](size_t k) {
    problems[k] = writers[frames[k].first]->CheckFrame(frames[k].second);
  });
  std::set<int> rerun;
  std::vector<std::string> damaged;
  for (size_t k = 0; k < frames.size(); ++k) {
    if (problems[k].empty()) continue;
    const int owner = static_cast<int>((frames[k].first * run.views + frames[k].second) % n);
    writers[frames[k].first]->ForgetFrame(frames[k].second);
    rerun.insert(owner);
    damaged.push_back(problems[k]);
  }
  for (int i = 0; i < n; ++i) {
    if (tree->written[i] != tree->declared[i] && !rerun.count(i)) {
      rerun.insert(i);
      damaged.push_back("shard " + std::to_string(i) + "/" + std::to_string(n) + " reported " +
                        std::to_string(tree->declared[i]) + " frames, the folder holds " +
                        std::to_string(tree->written[i]));
    }
  }
  if (rerun.empty()) return;
  std::error_code ec;
  std::string shards_text;
  for (int i : rerun) {
    fs::remove(tree->meta / ShardFile(i, n, ".done"), ec);
    shards_text += (shards_text.empty() ? "" : ", ") + std::to_string(i) + "/" + std::to_string(n);
  }
  std::string list;
  for (size_t k = 0; k < std::min<size_t>(damaged.size(), 5); ++k) list += "\n  " + damaged[k];
  if (damaged.size() > 5) list += "\n  and " + std::to_string(damaged.size() - 5) + " more";
  throw Error(tree->dir.string() + ": " + std::to_string(damaged.size()) +
              " damaged or missing frame(s):" + list + "\nrun shard(s) " + shards_text +
              " again (they re-render what is missing), then merge");
}

}  // namespace

MergeSummary Merge(const fs::path& dir_in,
                   const std::function<void(const std::string&)>& info_sink) {
  const auto start = std::chrono::steady_clock::now();
  const auto info = [&](const std::string& line) {
    if (info_sink) info_sink(line);
  };
  const fs::path dir = fs::absolute(dir_in).lexically_normal();
  const ShardRunInfo run = ReadMergeRun(dir);
  const fs::path meta = Meta(dir);
  const int n = run.shards;
  std::error_code ec;
  if (fs::exists(meta / "merged", ec)) return FinishCleanUp(dir, run, start);

  // No shard may run while merging: the "merging" mark keeps new shards from starting (they look
  // for it once they hold their lock), and every shard lock must be free after it is written.
  const fs::path merging = meta / "merging";
  WriteFileAtomic(merging, "merge\n");
  struct Unmark {  // removed unless the merge completes (then all of .shards goes)
    fs::path path;
    ~Unmark() {
      std::error_code ignored;
      if (!path.empty()) fs::remove(path, ignored);
    }
  } unmark{merging};
  MergeTree tree{.dir = dir, .meta = meta, .run = run, .n = n};
  FindRunningShards(&tree);
  // formats: webdataset: the tasks kept their frames only in their archives; back into the
  // tree first (checked against the manifests), unless a shard still runs (refused below).
  if (std::none_of(tree.running.begin(), tree.running.end(), [](bool r) { return r; })) {
    const size_t restored = RestoreArchivedFrames(dir, run.bop);
    if (restored > 0) info("restored " + std::to_string(restored) + " frames from webdataset/");
  }
  OpenSceneWriters(&tree);
  CountWrittenFrames(&tree);
  ReadDoneMarkers(&tree);
  ThrowUnlessReady(tree);
  CheckFrames(&tree);

  // What a single process does at its end, in the same order: the same bytes.
  const size_t scenes = run.obj_ids.size();
  const size_t frame_count = FinishDataset(dir, run.bop, tree.writers, run.classes);
  WriteMergedRecords(tree, frame_count, start);
  // From here the dataset is complete: a merge interrupted while cleaning up only cleans up.
  WriteFileAtomic(meta / "merged", std::to_string(frame_count) + "\n");
  for (const auto& writer : tree.writers) writer->RemoveFragments();
  unmark.path.clear();
  fs::remove_all(meta, ec);
  if (ec) throw Error(meta.string() + ": cannot remove: " + ec.message());
  info("merged " + std::to_string(n) + " shard(s): " + std::to_string(frame_count) + " frames in " +
       std::to_string(scenes) + " scene(s)");

  MergeSummary summary;
  summary.shards = n;
  summary.scenes = scenes;
  summary.frames = frame_count;
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

}  // namespace cadsynth
