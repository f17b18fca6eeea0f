// The command line as a user meets it: exit codes, one clear error line, nothing half-written.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <random>
#include <sstream>
#include <thread>

#include <gtest/gtest.h>

#include "tests/test_support.h"
#include "tests/tools/cli_support.h"

namespace {

using cadsynth::testing::Cadsynth;
using cadsynth::testing::CliRun;
using cadsynth::testing::ScratchDir;

size_t Lines(const std::string& text) { return std::count(text.begin(), text.end(), '\n'); }

TEST(Cli, HelpVersionAndUsageErrors) {
  ScratchDir dir;
  EXPECT_EQ(Cadsynth("--help", dir).code, 0);
  EXPECT_NE(Cadsynth("--help", dir).out.find("cadsynth generate"), std::string::npos);
  EXPECT_EQ(Cadsynth("--version", dir).code, 0);
  const CliRun bad = Cadsynth("frobnicate", dir);
  EXPECT_EQ(bad.code, 2);
  EXPECT_EQ(bad.err.rfind("error: unknown command 'frobnicate'", 0), 0u);
  EXPECT_EQ(Cadsynth("generate --threads zero", dir).code, 2);
  EXPECT_EQ(Cadsynth("generate --progress=fancy", dir).code, 2);
  EXPECT_EQ(Cadsynth("generate --progressx", dir).err,
            "error: unknown option '--progressx'\n(run 'cadsynth generate --help' for usage)\n");
  EXPECT_EQ(Cadsynth("merge", dir).err,
            "error: DIR is required\n(run 'cadsynth merge --help' for usage)\n");
  const CliRun shards = Cadsynth("generate --shard 1/4 --shards 4 -o out", dir);
  EXPECT_EQ(shards.code, 2);
  EXPECT_NE(shards.err.find("--shards N goes with --shard auto"), std::string::npos) << shards.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out"));
}

// Every subcommand describes its own options.
TEST(Cli, EverySubcommandHasHelp) {
  ScratchDir dir;
  const std::map<std::string, std::vector<std::string>> options = {
      {"generate",
       {"--output", "--overwrite", "--shard", "--shards", "--threads", "--progress", "--quiet"}},
      {"merge", {"DIR"}},
      {"inspect", {"FILE", "--json", "--unit", "--encoding", "--deflection"}},
      {"variants", {"RECIPE", "--export-step", "--overwrite"}},
      {"eval", {"DATASET", "RESULTS", "--json"}},
      {"preview", {"DATASET", "--output", "--count", "--frames", "--width"}},
      {"sensor-test", {"SENSOR", "--list", "--distances", "--tilts", "--material", "--check"}},
  };
  for (const auto& [command, names] : options) {
    for (const char* flag : {"--help", "-h"}) {
      const CliRun run = Cadsynth(command + " " + flag, dir);
      EXPECT_EQ(run.code, 0) << command << " " << flag << ": " << run.err;
      EXPECT_NE(run.out.find("Usage: cadsynth " + command), std::string::npos) << run.out;
      for (const std::string& name : names)
        EXPECT_NE(run.out.find(name), std::string::npos) << command << ": " << name;
    }
  }
  EXPECT_NE(Cadsynth("--help", dir).out.find("cadsynth COMMAND --help"), std::string::npos);
}

TEST(Cli, MissingRecipeIsOneLineAndNoOutput) {
  ScratchDir dir;
  const CliRun run = Cadsynth("generate missing.yaml -o out", dir);
  EXPECT_EQ(run.code, 1);
  EXPECT_EQ(run.err, "error: missing.yaml: no such recipe file\n");
  EXPECT_FALSE(std::filesystem::exists(dir / "out"));
}

TEST(Cli, UnknownKeyNamesFileLineAndColumn) {
  ScratchDir dir;
  std::ofstream(dir / "r.yaml") << "sweep:\n  yaw: [0, 90]\n  pich: 30\n";
  const CliRun run = Cadsynth("generate r.yaml -o out", dir);
  EXPECT_EQ(run.code, 1);
  EXPECT_EQ(run.err, "error: r.yaml:3:3: unknown key 'sweep.pich' (did you mean 'pitch'?)\n");
  EXPECT_FALSE(std::filesystem::exists(dir / "out"));
}

TEST(Cli, FileThatIsNotStepFailsCleanly) {
  ScratchDir dir;
  std::ofstream(dir / "notes.stp") << "shopping list: bolts, nuts\n";
  std::ofstream(dir / "r.yaml")
      << "parts:\n  - file: notes.stp\nsweep: {yaw: 0, pitch: 45, radius: 1 m}\n";
  const CliRun run = Cadsynth("generate r.yaml -o out", dir);
  EXPECT_EQ(run.code, 1);
  EXPECT_EQ(Lines(run.err), 1u) << run.err;
  EXPECT_NE(run.err.find("r.yaml:2:11: "), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("notes.stp: not a readable STEP file"), std::string::npos) << run.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out"));
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), {}), 2);
}

TEST(Cli, CorruptedSharedStepFailsCleanly) {
  CADSYNTH_REQUIRE_DATA(file, "step/awkward/bug32314_corrupted.stp");
  ScratchDir dir;
  std::ofstream(dir / "r.yaml") << "parts:\n  - file: " << file.string()
                                << "\nsweep: {yaw: 0, pitch: 45, radius: 1 m}\n";
  const CliRun run = Cadsynth("generate r.yaml -o out", dir);
  EXPECT_EQ(run.code, 1);
  EXPECT_EQ(Lines(run.err), 1u) << run.err;
  EXPECT_NE(run.err.find(file.string()), std::string::npos) << run.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out"));
}

TEST(Cli, GenerateWithoutArgumentsWritesTheDefaultDataset) {
  ScratchDir dir;
  const CliRun run = Cadsynth("generate --quiet", dir);
  ASSERT_EQ(run.code, 0) << run.err;
  EXPECT_NE(run.out.find("wrote 432 frames (3 scenes) of 13 objects"), std::string::npos)
      << run.out;
  EXPECT_TRUE(
      std::filesystem::exists(dir / "cadsynth_dataset" / "train" / "000002" / "scene_gt.json"));
  EXPECT_TRUE(std::filesystem::exists(dir / "cadsynth_dataset" / "train" / "000000" / "rgb" /
                                      "000143.png"));
  const CliRun again = Cadsynth("generate --quiet", dir);
  EXPECT_EQ(again.code, 1);
  EXPECT_NE(again.err.find("already exists (pass --overwrite"), std::string::npos);
}

TEST(Cli, EvalAndPreviewErrorsAreOneLine) {
  ScratchDir dir;
  EXPECT_EQ(Cadsynth("eval only_one_arg", dir).code, 2);
  std::ofstream(dir / "r.csv") << "0,0,1,0.9,1 0 0 0 1 0 0 0 1,0 0 500,-1\n";
  const CliRun run = Cadsynth("eval nowhere r.csv --json scores.json", dir);
  EXPECT_EQ(run.code, 1);
  EXPECT_EQ(run.err, "error: nowhere: no such dataset folder\n");
  EXPECT_FALSE(std::filesystem::exists(dir / "scores.json"));
  EXPECT_EQ(Cadsynth("preview nowhere --frames 0-1", dir).code, 2);
  const CliRun preview = Cadsynth("preview nowhere -o sheet.png", dir);
  EXPECT_EQ(preview.code, 1);
  EXPECT_EQ(Lines(preview.err), 1u) << preview.err;
  EXPECT_NE(preview.err.find("nowhere: no such dataset folder"), std::string::npos) << preview.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "sheet.png"));
}

TEST(Cli, SensorTestReportsAndRefuses) {
  ScratchDir dir;
  const CliRun list = Cadsynth("sensor-test --list", dir);
  EXPECT_EQ(list.code, 0);
  EXPECT_NE(list.out.find("realsense_d435: "), std::string::npos) << list.out;
  const CliRun unknown = Cadsynth("sensor-test kinect_v9 -o out", dir);
  EXPECT_EQ(unknown.code, 2);
  EXPECT_EQ(
      unknown.err.rfind("error: no sensor preset called 'kinect_v9' (presets: kinect_v1, ", 0), 0u)
      << unknown.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out"));
  // A recipe whose camera has exact depth has nothing to test; one with a sensor is measured.
  std::ofstream(dir / "ideal.yaml") << "camera: {preset: kinect_v1}\n";
  const CliRun ideal = Cadsynth("sensor-test ideal.yaml", dir);
  EXPECT_EQ(ideal.code, 1);
  EXPECT_EQ(ideal.err, "error: ideal.yaml: camera.depth is ideal (exact depth): nothing to test\n");
  std::ofstream(dir / "sl.yaml") << "camera: {preset: kinect_v1, depth: structured_light}\n";
  const CliRun run =
      Cadsynth("sensor-test sl.yaml --distances 1000 --frames 2 --step 0 -o out --check", dir);
  EXPECT_EQ(run.code, 0) << run.err;
  EXPECT_NE(run.out.find("plane test of sl.yaml: 640 x 480"), std::string::npos) << run.out;
  EXPECT_TRUE(std::filesystem::exists(dir / "out" / "sensor_test.svg"));
  std::ifstream json(dir / "out" / "sensor_test.json");
  std::stringstream text;
  text << json.rdbuf();
  EXPECT_NE(text.str().find("\"fill_rate\": 1.0"), std::string::npos) << text.str();
  EXPECT_EQ(Cadsynth("sensor-test kinect_v1 --frames 1", dir).code, 2);  // out of range
}

// Kill a run three times at random moments (SIGKILL), start it again each time: the finished
// dataset has the same files, byte for byte, as a run that was never interrupted.
TEST(Cli, KilledRunsResumeToTheSameBytes) {
  ScratchDir dir;
  std::ofstream(dir / "r.yaml")
      << "camera: {preset: kinect_v1, width: 320, height: 240, fx: 262.5, fy: 262.5,\n"
         "         cx: 159.5, cy: 119.5}\n"
         "sweep: {yaw: {from: 0, to: 350, step: 10}, pitch: [20, 50, 80], radius: 0.8 m}\n"
         "output: {formats: [bop, coco, paper, grasp]}\n";
  ASSERT_EQ(Cadsynth("generate r.yaml -o whole --quiet", dir).code, 0);

  std::mt19937 rng(std::random_device{}());
  std::uniform_int_distribution<int> delay_ms(100, 700);
  int interrupted = 0;
  for (int attempt = 0; attempt < 3; ++attempt) {
    std::cout << std::flush;  // the child must not inherit unwritten output
    std::fflush(stdout);
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      ::chdir(dir.path().c_str());
      ::freopen("/dev/null", "w", stdout);
      ::freopen("/dev/null", "w", stderr);
      ::execl(CADSYNTH_EXE, CADSYNTH_EXE, "generate", "r.yaml", "-o", "resumed", "--quiet",
              static_cast<char*>(nullptr));
      ::_exit(127);
    }
    const int ms = delay_ms(rng);
    std::this_thread::sleep_for(std::chrono::milliseconds(ms));
    ::kill(child, SIGKILL);
    int status = 0;
    ::waitpid(child, &status, 0);
    if (WIFSIGNALED(status)) {
      ++interrupted;
      std::cout << "killed after " << ms << " ms\n";
    }
    if (std::filesystem::exists(dir / "resumed")) break;  // it finished before the kill
  }
  if (!std::filesystem::exists(dir / "resumed")) {
    const CliRun last = Cadsynth("generate r.yaml -o resumed --quiet", dir);
    ASSERT_EQ(last.code, 0) << last.err;
  }
  EXPECT_GE(interrupted, 1);
  cadsynth::testing::ExpectSameTree(dir / "whole", dir / "resumed");
  for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    EXPECT_EQ(entry.path().filename().string().find(".partial"), std::string::npos) << entry.path();
  }
}

}  // namespace

namespace {

// A message quoting a 5 MB name was printed whole; the line keeps its start and end.
TEST(Cli, HugeNamesInErrorsAreShortened) {
  ScratchDir dir;
  std::ofstream(dir / "r.yaml") << "parts: [{family: " << std::string(5 << 20, 'x') << "}]\n";
  const CliRun run = Cadsynth("generate r.yaml -o out", dir);
  EXPECT_EQ(run.code, 1);
  EXPECT_LT(run.err.size(), 2200u);
  EXPECT_EQ(run.err.rfind("error: r.yaml:1:", 0), 0u) << run.err.substr(0, 200);
  EXPECT_NE(run.err.find("characters left out"), std::string::npos);
}

}  // namespace
