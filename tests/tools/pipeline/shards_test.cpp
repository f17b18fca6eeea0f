// Farm runs in-process: shards write one tree, merge makes it the single-process dataset; an
// interrupted single run resumes, starts over when the run changed, and re-renders damaged frames.
#include "tools/pipeline/shards.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/resource.h>
#include <unistd.h>

#include <fstream>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cad/core/error.h"
#include "tests/test_support.h"
#include "tests/tools/pipeline/small_job.h"
#include "tools/pipeline/generate.h"

namespace cadsynth {
namespace {

using testing::ExpectSameTree;
using testing::RunJob;
using testing::ScratchDir;
using testing::SmallFarmJob;
using testing::SmallRigFarmJob;

std::string MergeError(const std::filesystem::path& dir) {
  try {
    Merge(dir);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(Shards, ParseShardTakesIOfN) {
  EXPECT_EQ(ParseShard("0/1").index, 0);
  EXPECT_EQ(ParseShard("3/4").index, 3);
  EXPECT_EQ(ParseShard("3/4").count, 4);
  for (const char* bad : {"4/4", "-1/4", "1/0", "1", "a/b", "1/4x", "/4", "1/"}) {
    EXPECT_THROW(ParseShard(bad), Error) << bad;
  }
  const ShardSpec s{1, 3};
  EXPECT_FALSE(s.Owns(0));
  EXPECT_TRUE(s.Owns(1));
  EXPECT_TRUE(s.Owns(4));
}

// A scheduler's environment: the variables set, the rest unset.
class FakeEnvironment {
 public:
  FakeEnvironment(std::map<std::string, std::string> vars) : vars_(std::move(vars)) {}
  std::function<const char*(const char*)> Lookup() const {
    return [this](const char* name) -> const char* {
      const auto it = vars_.find(name);
      return it == vars_.end() ? nullptr : it->second.c_str();
    };
  }

 private:
  std::map<std::string, std::string> vars_;
};

ShardSpec Auto(const std::map<std::string, std::string>& vars, int shards = 0) {
  const FakeEnvironment env(vars);
  return ShardFromScheduler(env.Lookup(), shards).shard;
}

std::string AutoError(const std::map<std::string, std::string>& vars, int shards = 0) {
  try {
    Auto(vars, shards);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(Shards, AutoReadsTheSlurmArrayRange) {
  // sbatch --array=0-3: task 2 is shard 2/4.
  const std::map<std::string, std::string> slurm = {{"SLURM_ARRAY_TASK_ID", "2"},
                                                    {"SLURM_ARRAY_TASK_MIN", "0"},
                                                    {"SLURM_ARRAY_TASK_MAX", "3"},
                                                    {"SLURM_ARRAY_TASK_COUNT", "4"}};
  EXPECT_EQ(Auto(slurm).Name(), "2/4");
  // --array=1-100: task 1 is shard 0, task 100 is shard 99, of 100.
  EXPECT_EQ(Auto({{"SLURM_ARRAY_TASK_ID", "1"},
                  {"SLURM_ARRAY_TASK_MIN", "1"},
                  {"SLURM_ARRAY_TASK_MAX", "100"}})
                .Name(),
            "0/100");
  EXPECT_EQ(Auto({{"SLURM_ARRAY_TASK_ID", "100"},
                  {"SLURM_ARRAY_TASK_MIN", "1"},
                  {"SLURM_ARRAY_TASK_MAX", "100"}})
                .Name(),
            "99/100");
  // A rerun of some tasks (--array=3,17) with the count given: the ID is the index.
  const std::map<std::string, std::string> rerun = {{"SLURM_ARRAY_TASK_ID", "17"},
                                                    {"SLURM_ARRAY_TASK_MIN", "3"},
                                                    {"SLURM_ARRAY_TASK_MAX", "17"},
                                                    {"SLURM_ARRAY_TASK_COUNT", "2"}};
  EXPECT_EQ(Auto(rerun, 100).Name(), "17/100");
  // ... without it, the gaps are an error that says what to do.
  EXPECT_NE(AutoError(rerun).find("has gaps"), std::string::npos) << AutoError(rerun);
  EXPECT_NE(AutoError(rerun).find("--shards N"), std::string::npos);
  EXPECT_NE(AutoError({{"SLURM_ARRAY_TASK_ID", "2"}}).find("SLURM_ARRAY_TASK_MIN"),
            std::string::npos);
  EXPECT_NE(AutoError({{"SLURM_ARRAY_TASK_ID", "100"}}, 100).find("less than 100"),
            std::string::npos);
}

TEST(Shards, AutoReadsKubernetesAwsAndGoogleBatch) {
  EXPECT_EQ(Auto({{"JOB_COMPLETION_INDEX", "7"}}, 8).Name(), "7/8");
  EXPECT_EQ(Auto({{"JOB_COMPLETION_INDEX", "0"}}, 1).Name(), "0/1");
  // Pods are not told the Job's completions.
  EXPECT_NE(AutoError({{"JOB_COMPLETION_INDEX", "7"}}).find("spec.completions"), std::string::npos);
  EXPECT_NE(AutoError({{"JOB_COMPLETION_INDEX", "8"}}, 8).find("less than 8"), std::string::npos);
  EXPECT_EQ(Auto({{"AWS_BATCH_JOB_ARRAY_INDEX", "0"}, {"AWS_BATCH_JOB_ARRAY_SIZE", "10"}}).Name(),
            "0/10");
  EXPECT_EQ(
      Auto({{"AWS_BATCH_JOB_ARRAY_INDEX", "9"}, {"AWS_BATCH_JOB_ARRAY_SIZE", "10"}}, 10).Name(),
      "9/10");
  EXPECT_NE(AutoError({{"AWS_BATCH_JOB_ARRAY_INDEX", "3"}}).find("AWS_BATCH_JOB_ARRAY_SIZE"),
            std::string::npos);
  EXPECT_EQ(Auto({{"BATCH_TASK_INDEX", "4"}, {"BATCH_TASK_COUNT", "5"}}).Name(), "4/5");
  // The count a scheduler sets is the one: --shards must agree with it.
  const std::string mismatch =
      AutoError({{"AWS_BATCH_JOB_ARRAY_INDEX", "3"}, {"AWS_BATCH_JOB_ARRAY_SIZE", "10"}}, 8);
  EXPECT_NE(mismatch.find("AWS_BATCH_JOB_ARRAY_SIZE=10"), std::string::npos) << mismatch;
  EXPECT_NE(mismatch.find("--shards 8"), std::string::npos) << mismatch;
}

TEST(Shards, AutoRefusesNothingGarbageAndDisagreement) {
  const std::string none = AutoError({{"HOME", "/root"}});
  EXPECT_NE(none.find("no scheduler task index"), std::string::npos) << none;
  EXPECT_NE(none.find("--shard I/N"), std::string::npos) << none;
  for (const char* bad : {"", "-1", "3x", " 3", "1e3", "0x10", "99999999999"}) {
    const std::string error = AutoError({{"JOB_COMPLETION_INDEX", bad}}, 8);
    EXPECT_NE(error.find("is not a task index"), std::string::npos) << bad << ": " << error;
  }
  EXPECT_NE(AutoError({{"BATCH_TASK_INDEX", "0"}, {"BATCH_TASK_COUNT", "0"}}).find("from 1"),
            std::string::npos);
  // Two schedulers that agree (a Slurm array inside a Kubernetes pod, say) are one shard ...
  EXPECT_EQ(Auto({{"JOB_COMPLETION_INDEX", "2"},
                  {"SLURM_ARRAY_TASK_ID", "2"},
                  {"SLURM_ARRAY_TASK_MIN", "0"},
                  {"SLURM_ARRAY_TASK_MAX", "3"}},
                 4)
                .Name(),
            "2/4");
  // ... two that disagree are an error naming both.
  const std::string both = AutoError({{"AWS_BATCH_JOB_ARRAY_INDEX", "1"},
                                      {"AWS_BATCH_JOB_ARRAY_SIZE", "4"},
                                      {"BATCH_TASK_INDEX", "2"},
                                      {"BATCH_TASK_COUNT", "4"}});
  EXPECT_NE(both.find("disagree"), std::string::npos) << both;
  EXPECT_NE(both.find("AWS_BATCH_JOB_ARRAY_INDEX=1"), std::string::npos) << both;
  EXPECT_NE(both.find("BATCH_TASK_INDEX=2"), std::string::npos) << both;
}

TEST(Shards, MergedShardsAreByteIdenticalToOneProcess) {
  ScratchDir dir;
  const RunSpec spec = SmallFarmJob();
  const GenerateSummary whole = RunJob(spec, dir / "whole");
  EXPECT_EQ(whole.frames, 12u);
  // Four shards, in no particular order; each renders every 4th unit of scene * views + view.
  size_t frames = 0;
  for (int i : {2, 0, 3, 1}) {
    const GenerateSummary part = RunJob(spec, dir / "tree", ShardSpec{i, 4});
    EXPECT_EQ(part.frames, 3u);
    frames += part.frames;
  }
  EXPECT_EQ(frames, 12u);
  // Shard 1 owns units 1, 5, 9: scene 0 image 1, scene 1 image 1, scene 2 image 1.
  for (const char* scene : {"000000", "000001", "000002"}) {
    EXPECT_TRUE(
        std::filesystem::exists(dir / "tree" / "train" / scene / ".fragments" / "000001.json"));
  }
  const MergeSummary merged = Merge(dir / "tree");
  EXPECT_EQ(merged.shards, 4);
  EXPECT_EQ(merged.frames, 12u);
  EXPECT_EQ(merged.scenes, 3u);
  ExpectSameTree(dir / "whole", dir / "tree");
  EXPECT_FALSE(std::filesystem::exists(dir / "tree" / ".shards"));
  EXPECT_NE(MergeError(dir / "tree").find("already a complete dataset"), std::string::npos);

  // A merge stopped after the dataset was complete (its "merged" mark written) but before the
  // bookkeeping was removed only cleans up when run again.
  RunJob(spec, dir / "again", ShardSpec{0, 1});
  std::filesystem::copy_file(dir / "again" / ".shards" / "run.json", dir / "run.json");
  Merge(dir / "again");
  std::filesystem::create_directories(dir / "again" / ".shards");
  std::filesystem::copy_file(dir / "run.json", dir / "again" / ".shards" / "run.json");
  std::ofstream(dir / "again" / ".shards" / "merged") << "12\n";
  std::filesystem::create_directories(dir / "again" / "train" / "000001" / ".fragments");
  std::ofstream(dir / "again" / "train" / "000001" / ".fragments" / "000000.json") << "stale";
  EXPECT_EQ(Merge(dir / "again").frames, 12u);
  ExpectSameTree(dir / "whole", dir / "again");
}

TEST(Shards, CameraRigShardsMergeToOneProcessesBytes) {
  // Two sensors: the camera with a Kinect v1 depth model, and a grey camera 50 mm to its right.
  // Three shards merge to the bytes of one process; a frame that only one sensor finished (a
  // shard stopped between the sensors) is not written: merge names the shard, which renders it
  // again.
  ScratchDir dir;
  const RunSpec spec = SmallRigFarmJob();
  EXPECT_EQ(RunJob(spec, dir / "whole").frames, 12u);
  for (int i : {1, 2, 0}) RunJob(spec, dir / "tree", ShardSpec{i, 3});
  const std::filesystem::path scene = dir / "tree" / "train" / "000001";
  EXPECT_TRUE(std::filesystem::exists(scene / ".fragments_a" / "000001.json"));
  std::filesystem::remove(scene / ".fragments_b" / "000001.json");  // unit 5: shard 2
  EXPECT_NE(MergeError(dir / "tree").find("run shard(s) 2/3 again"), std::string::npos)
      << MergeError(dir / "tree");
  RunJob(spec, dir / "tree", ShardSpec{2, 3});
  EXPECT_EQ(Merge(dir / "tree").frames, 12u);
  ExpectSameTree(dir / "whole", dir / "tree");
  EXPECT_FALSE(std::filesystem::exists(scene / ".fragments_a"));
  EXPECT_TRUE(std::filesystem::exists(scene / "gray_b" / "000001.png"));
}

TEST(Shards, PhysicallyBasedShardsAreByteIdenticalToOneProcess) {
  // The path tracer's noise depends on (seed, view, pixel) only, and adaptive sampling's stops
  // on the tile's own paths: shards render the same bytes, the linear EXR colour included.
  ScratchDir dir;
  RunSpec spec = SmallFarmJob();
  spec.render.mode = RenderOptions::Mode::kPbr;
  spec.render.samples = 6;
  spec.render.min_samples = 2;
  spec.render.noise_threshold = 0.05;
  spec.render.bounces = 1;
  spec.render.hdr = true;
  Material steel;
  ASSERT_TRUE(MaterialPreset("steel", &steel));
  spec.material_rules.push_back({"*", "", "", steel});
  RunJob(spec, dir / "whole");
  for (int i : {1, 0, 2}) RunJob(spec, dir / "tree", ShardSpec{i, 3});
  Merge(dir / "tree");
  ExpectSameTree(dir / "whole", dir / "tree");
  EXPECT_TRUE(
      std::filesystem::exists(dir / "whole" / "train" / "000001" / "rgb_hdr" / "000002.exr"));
}

// The small farm with materials, lights, camera jitter and distractors randomised.
RunSpec RandomizedFarmSpec() {
  RunSpec spec = SmallFarmJob();
  spec.render.mode = RenderOptions::Mode::kPbr;
  spec.render.samples = 1;
  spec.render.bounces = 1;
  spec.randomize.draws.seed = 5;
  PartRandomization p;
  p.material.roughness = Distribution::Uniform(0, 1);
  spec.randomize.draws.parts = {p};
  spec.randomize.part_rules = {RandomizeRule{"*", "", "", ""}};
  spec.randomize.draws.lights = LightRandomization{};
  spec.randomize.draws.camera = CameraRandomization{};
  spec.randomize.draws.camera->rotation_deg = Distribution::Uniform(0, 1);
  // Distractors in the benchmark's grid only (its parts are convex enough for one hull each:
  // the gears' convex decompositions would take seconds per run without a part cache).
  RandomizeSpec grid = spec.randomize;
  grid.draws.distractors = DistractorRandomization{};
  grid.draws.distractors->count = Distribution::Uniform(1, 3);
  grid.draws.distractors->material = MaterialRandomization{};
  grid.draws.distractors->material->hue = Distribution::Uniform(0, 1);
  for (const auto kind : {DistractorObject::Kind::kBox, DistractorObject::Kind::kCylinder}) {
    DistractorObject object;
    object.kind = kind;
    grid.distractor_objects.push_back(object);
  }
  spec.scenes[2].randomize = grid;
  return spec;
}

TEST(Shards, RandomizedShardsAreByteIdenticalToOneProcess) {
  // Every draw is keyed by (seed, scene, view, quantity): shards draw what one process draws,
  // and merge writes the same scene_randomization.json.
  ScratchDir dir;
  const RunSpec spec = RandomizedFarmSpec();
  RunJob(spec, dir / "whole");
  for (int i : {2, 0, 1}) RunJob(spec, dir / "tree", ShardSpec{i, 3});
  Merge(dir / "tree");
  ExpectSameTree(dir / "whole", dir / "tree");
  EXPECT_TRUE(
      std::filesystem::exists(dir / "whole" / "train" / "000001" / "scene_randomization.json"));
}

TEST(Shards, MergeRefusesUnfinishedAndRunningShardsNamingThem) {
  ScratchDir dir;
  const RunSpec spec = SmallFarmJob();
  EXPECT_NE(MergeError(dir / "tree").find("no such folder"), std::string::npos);
  RunJob(spec, dir / "tree", ShardSpec{1, 3});
  EXPECT_NE(MergeError(dir / "tree").find("shard 0/3 has not started"), std::string::npos);
  RunJob(spec, dir / "tree", ShardSpec{0, 3});
  EXPECT_NE(MergeError(dir / "tree").find("shard 2/3 has not started"), std::string::npos);
  RunJob(spec, dir / "tree", ShardSpec{2, 3});
  // A shard that wrote frames but did not finish (its done marker gone) is counted.
  std::filesystem::remove(dir / "tree" / ".shards" / "2-of-3.done");
  EXPECT_NE(MergeError(dir / "tree").find("shard 2/3 has not finished (4 of 4 views done)"),
            std::string::npos);
  RunJob(spec, dir / "tree", ShardSpec{2, 3});  // resumes: nothing left to render
  // A running shard holds its lock.
  const std::string lock = (dir / "tree" / ".shards" / "1-of-3.lock").string();
  const int fd = ::open(lock.c_str(), O_RDWR);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX | LOCK_NB), 0);
  EXPECT_NE(MergeError(dir / "tree").find("shard 1/3 is running"), std::string::npos);
  EXPECT_THROW(RunJob(spec, dir / "tree", ShardSpec{1, 3}), Error);  // the same shard twice
  ::close(fd);
  // A refused merge takes its "merging" mark back; while the mark is there, shards do not start.
  EXPECT_FALSE(std::filesystem::exists(dir / "tree" / ".shards" / "merging"));
  std::ofstream(dir / "tree" / ".shards" / "merging") << "merge\n";
  try {
    RunJob(spec, dir / "tree", ShardSpec{1, 3});
    ADD_FAILURE() << "a shard started during a merge";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("is being merged"), std::string::npos) << e.what();
  }
  EXPECT_EQ(MergeError(dir / "tree"), "");
}

// Merge checks the shard locks one at a time: a farm may have more shards than a process may
// open files. Twelve shards of one unit each, merged with room for only a few more open files.
TEST(Shards, MergeOpensFewFilesWhateverTheShardCount) {
  ScratchDir dir;
  const RunSpec spec = SmallFarmJob();
  RunJob(spec, dir / "whole");
  for (int i = 0; i < 12; ++i) RunJob(spec, dir / "tree", ShardSpec{i, 12});
  size_t open_files = 0;
  for ([[maybe_unused]] const auto& fd : std::filesystem::directory_iterator("/proc/self/fd"))
    ++open_files;
  rlimit old_limit{};
  ASSERT_EQ(::getrlimit(RLIMIT_NOFILE, &old_limit), 0);
  rlimit tight = old_limit;
  tight.rlim_cur = open_files + 10;  // fewer than the 12 locks the first merge held at once
  ASSERT_EQ(::setrlimit(RLIMIT_NOFILE, &tight), 0);
  const std::string why = MergeError(dir / "tree");
  ::setrlimit(RLIMIT_NOFILE, &old_limit);
  EXPECT_EQ(why, "");
  ExpectSameTree(dir / "whole", dir / "tree");
}

TEST(Shards, DamagedFramesAreNamedAndTheirShardRendersThemAgain) {
  ScratchDir dir;
  const RunSpec spec = SmallFarmJob();
  RunJob(spec, dir / "whole");
  for (int i = 0; i < 2; ++i) RunJob(spec, dir / "tree", ShardSpec{i, 2});
  // Unit 3 (scene 0, image 3) belongs to shard 1: damage its mask, delete its grasp points.
  const std::filesystem::path mask =
      dir / "tree" / "train" / "000000" / "mask_visib" / "000003_000001.png";
  std::ofstream(mask, std::ios::binary | std::ios::app) << "x";
  bool removed = false;
  for (const auto& e : std::filesystem::directory_iterator(dir / "tree" / "grasp" / "000000")) {
    if (!removed && e.path().filename().string().rfind("000003_", 0) == 0)
      removed = std::filesystem::remove(e.path());
  }
  ASSERT_TRUE(removed);
  const std::string why = MergeError(dir / "tree");
  EXPECT_NE(why.find("1 damaged or missing frame(s)"), std::string::npos) << why;
  EXPECT_NE(why.find("000003_000001.png: "), std::string::npos) << why;
  EXPECT_NE(why.find("run shard(s) 1/2 again"), std::string::npos) << why;
  // Until shard 1 runs again, merge still refuses.
  EXPECT_NE(MergeError(dir / "tree").find("shard 1/2 has not finished (5 of 6 views done)"),
            std::string::npos);
  const GenerateSummary again = RunJob(spec, dir / "tree", ShardSpec{1, 2});
  EXPECT_EQ(again.resumed, 5u);
  EXPECT_EQ(again.frames, 6u);
  Merge(dir / "tree");
  ExpectSameTree(dir / "whole", dir / "tree");
}

TEST(Shards, ShardsOfAnotherRunOrCountAreRefused) {
  ScratchDir dir;
  RunSpec spec = SmallFarmJob();
  RunJob(spec, dir / "tree", ShardSpec{0, 3});
  try {
    RunJob(spec, dir / "tree", ShardSpec{1, 2});
    ADD_FAILURE() << "another shard count was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("started with 3 shards"), std::string::npos) << e.what();
  }
  spec.bop.depth_scale = 1.0;
  try {
    RunJob(spec, dir / "tree", ShardSpec{1, 3});
    ADD_FAILURE() << "a changed run was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("different run"), std::string::npos) << e.what();
  }
  // A machine whose CPU gives Embree other kernels than the first shard's, or another build of
  // cadsynth: the key says so, and the message says what to do.
  spec.bop.depth_scale = SmallFarmJob().bop.depth_scale;
  const std::filesystem::path key = dir / "tree" / ".shards" / "run_key";
  const std::string original = testing::ReadFile(key);
  const auto refusal = [&](const std::string& prefix, const std::string& value) {
    const size_t at = original.rfind("\n" + prefix);
    EXPECT_NE(at, std::string::npos) << prefix;
    const std::string text = original.substr(0, at) + "\n" + prefix + value +
                             original.substr(original.find('\n', at + 1));
    std::ofstream(key, std::ios::binary | std::ios::trunc) << text;
    try {
      RunJob(spec, dir / "tree", ShardSpec{1, 3});
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  const std::string kernels = refusal("trace ", "sse2");
  EXPECT_NE(kernels.find("the run started with sse2 ones"), std::string::npos) << kernels;
  EXPECT_NE(kernels.find("set render: {isa: sse2}"), std::string::npos) << kernels;
  const std::string build = refusal("build ", "12-abc");
  EXPECT_NE(build.find("started by another build of cadsynth"), std::string::npos) << build;
  std::ofstream(key, std::ios::binary | std::ios::trunc) << original;
  EXPECT_EQ(RunJob(spec, dir / "tree", ShardSpec{1, 3}).frames, 4u);
  // A finished dataset is not a shard folder.
  RunJob(spec, dir / "whole");
  EXPECT_THROW(RunJob(spec, dir / "whole", ShardSpec{0, 2}), Error);
}

// An error inside the run (here: from the progress callback after 5 frames) stands in for a kill.
void Interrupt(const RunSpec& spec, const std::filesystem::path& out,
               std::vector<std::string>* info = nullptr) {
  GenerateOptions options;
  options.output = out;
  options.progress = [](size_t done, size_t) {
    if (done == 5) throw Error("interrupted on purpose");
  };
  if (info != nullptr) options.info = [info](const std::string& line) { info->push_back(line); };
  EXPECT_THROW(Generate(spec, options), Error);
}

bool Says(const std::vector<std::string>& lines, const std::string& text) {
  for (const std::string& line : lines) {
    if (line.find(text) != std::string::npos) return true;
  }
  return false;
}

TEST(Resume, AChangedRunStartsOverAndADamagedFrameIsRenderedAgain) {
  ScratchDir dir;
  RunSpec spec = SmallFarmJob();
  RunJob(spec, dir / "whole");
  const std::filesystem::path partial = dir / ".out.partial";

  // Interrupted, then resumed unchanged: the completed frames are kept.
  Interrupt(spec, dir / "out");
  ASSERT_TRUE(std::filesystem::exists(partial));
  // Damage one completed frame: truncate its colour image.
  std::vector<std::string> complete;  // frames whose fragment (written last) exists
  for (const auto& e :
       std::filesystem::directory_iterator(partial / "train" / "000000" / ".fragments")) {
    complete.push_back(e.path().stem().string());
  }
  ASSERT_FALSE(complete.empty());
  std::filesystem::resize_file(partial / "train" / "000000" / "rgb" / (complete.front() + ".png"),
                               100);
  std::vector<std::string> info;
  GenerateOptions options;
  options.output = dir / "out";
  options.info = [&](const std::string& line) { info.push_back(line); };
  const GenerateSummary resumed = Generate(spec, options);
  EXPECT_TRUE(Says(info, "resuming the interrupted run")) << ::testing::PrintToString(info);
  EXPECT_TRUE(Says(info, "rendered again: 1 frames")) << ::testing::PrintToString(info);
  EXPECT_GE(resumed.resumed, 1u);
  EXPECT_EQ(resumed.frames, 12u);
  ExpectSameTree(dir / "whole", dir / "out");

  // Interrupted, then started with a changed recipe: the old frames are discarded.
  std::filesystem::remove_all(dir / "out");
  Interrupt(spec, dir / "out");
  spec.bop.depth_scale = 1.0;
  info.clear();
  const GenerateSummary changed = Generate(spec, options);
  EXPECT_TRUE(Says(info, "starting over")) << ::testing::PrintToString(info);
  EXPECT_EQ(changed.resumed, 0u);
  RunJob(spec, dir / "fresh");
  ExpectSameTree(dir / "fresh", dir / "out");
}

// A randomised run (distractors included) interrupted and resumed: the same bytes as one
// uninterrupted run.
TEST(Resume, ARandomizedRunResumesToTheSameBytes) {
  ScratchDir dir;
  const RunSpec spec = RandomizedFarmSpec();
  RunJob(spec, dir / "whole");
  Interrupt(spec, dir / "out");
  std::vector<std::string> info;
  GenerateOptions options;
  options.output = dir / "out";
  options.info = [&](const std::string& line) { info.push_back(line); };
  const GenerateSummary resumed = Generate(spec, options);
  EXPECT_TRUE(Says(info, "resuming the interrupted run")) << ::testing::PrintToString(info);
  EXPECT_GE(resumed.resumed, 1u);
  ExpectSameTree(dir / "whole", dir / "out");
}

}  // namespace
}  // namespace cadsynth
