// Farm runs through the command line: shard processes running at the same time on one folder,
// merge, and a disk that fills up in the middle of a run.
#include <sys/mount.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "dataset/file_io.h"
#include "tests/test_support.h"
#include "tests/tools/cli_support.h"

namespace {

using cadsynth::testing::Cadsynth;
using cadsynth::testing::CliRun;
using cadsynth::testing::ExpectSameTree;
using cadsynth::testing::ReadTree;
using cadsynth::testing::ScratchDir;

// The default job's three scenes at 320x240, 12 views each.
void WriteSmallRecipe(const ScratchDir& dir) {
  std::ofstream(dir / "r.yaml")
      << "camera: {preset: kinect_v1, width: 320, height: 240, fx: 262.5, fy: 262.5,\n"
         "         cx: 159.5, cy: 119.5}\n"
         "sweep: {yaw: {from: 0, to: 330, step: 30}, pitch: [40], radius: 0.8 m}\n"
         "output: {formats: [bop, coco, paper, pvn3d, grasp]}\n";
}

TEST(Farm, ShardProcessesAtTheSameTimeMergeToTheSingleRun) {
  ScratchDir dir;
  WriteSmallRecipe(dir);
  ASSERT_EQ(Cadsynth("generate r.yaml -o whole --quiet", dir).code, 0);
  std::vector<std::thread> shards;
  std::vector<CliRun> runs(3);
  for (int i = 0; i < 3; ++i) {
    shards.emplace_back([&, i] {
      runs[i] = Cadsynth(
          "generate r.yaml --shard " + std::to_string(i) + "/3 --threads 1 -o tree --progress=json",
          dir, std::to_string(i));
    });
  }
  for (std::thread& t : shards) t.join();
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(runs[i].code, 0) << runs[i].err;
    EXPECT_NE(runs[i].out.find("as shard " + std::to_string(i) + "/3"), std::string::npos)
        << runs[i].out;
    EXPECT_NE(runs[i].err.find("\"done\":12,\"total\":12"), std::string::npos)
        << runs[i].err;  // 36 units / 3
  }
  const CliRun merge = Cadsynth("merge tree", dir);
  ASSERT_EQ(merge.code, 0) << merge.err;
  EXPECT_NE(merge.out.find("merged 3 shards"), std::string::npos) << merge.out;
  ExpectSameTree(dir / "whole", dir / "tree");
  const CliRun again = Cadsynth("merge tree", dir);
  EXPECT_EQ(again.code, 1);
  EXPECT_NE(again.err.find("nothing to merge"), std::string::npos);
}

TEST(Farm, MergeOfAnUnfinishedTreeIsOneLineNamingTheShards) {
  ScratchDir dir;
  WriteSmallRecipe(dir);
  ASSERT_EQ(Cadsynth("generate r.yaml --shard 0/4 -o tree --quiet", dir).code, 0);
  const CliRun merge = Cadsynth("merge tree", dir);
  EXPECT_EQ(merge.code, 1);
  EXPECT_EQ(merge.err,
            "error: " + (dir / "tree").string() +
                ": cannot merge yet: shard 1/4 has not started; shard 2/4 has not started; "
                "shard 3/4 has not started\n");
  EXPECT_EQ(Cadsynth("merge", dir).code, 2);
  EXPECT_EQ(Cadsynth("generate r.yaml --shard 2 -o tree", dir).code, 2);
  EXPECT_EQ(Cadsynth("generate r.yaml --shard 0/4 --overwrite -o tree", dir).code, 1);
}

// A small tmpfs mounted for the test (needs root or CAP_SYS_ADMIN), unmounted at the end.
class SmallDisk {
 public:
  SmallDisk(const std::filesystem::path& where, size_t bytes) : where_(where) {
    std::filesystem::create_directories(where);
    const std::string size = "size=" + std::to_string(bytes);
    if (::mount("tmpfs", where.c_str(), "tmpfs", 0, size.c_str()) != 0) {
      why_ = std::strerror(errno);
    } else {
      mounted_ = true;
    }
  }
  ~SmallDisk() {
    if (mounted_) ::umount2(where_.c_str(), MNT_DETACH);
  }
  bool mounted() const { return mounted_; }
  const std::string& why() const { return why_; }
  bool Grow(size_t bytes) const {
    const std::string size = "size=" + std::to_string(bytes);
    return ::mount("tmpfs", where_.c_str(), "tmpfs", MS_REMOUNT, size.c_str()) == 0;
  }

 private:
  std::filesystem::path where_;
  bool mounted_ = false;
  std::string why_;
};

size_t TreeBytes(const std::filesystem::path& root) {
  size_t total = 0;
  for (const auto& [name, bytes] : ReadTree(root))
    total += bytes.size() + 4096;  // a block per file, roughly
  return total;
}

// Every frame of an interrupted run whose fragment exists: are its files all as the manifest says?
size_t CheckCompleteFrames(const std::filesystem::path& root) {
  size_t frames = 0;
  for (const auto& scene : std::filesystem::directory_iterator(root / "train")) {
    if (!std::filesystem::exists(scene.path() / ".fragments")) continue;
    for (const auto& fragment : std::filesystem::directory_iterator(scene.path() / ".fragments")) {
      if (fragment.path().extension() != ".json") continue;
      std::ifstream in(fragment.path());
      std::string line;
      for (int n = 0; n < 5; ++n) std::getline(in, line);
      const auto manifest = nlohmann::json::parse(line);
      EXPECT_FALSE(manifest.at("files").empty()) << fragment.path();
      for (const auto& file : manifest.at("files")) {
        const cadsynth::FileRecord record{file.at(0), file.at(1), file.at(2)};
        EXPECT_EQ(cadsynth::CheckFile(root, record), "") << record.path;
      }
      ++frames;
    }
  }
  return frames;
}

TEST(Farm, AFullDiskIsOneClearErrorAndTheRunResumesOnceThereIsRoom) {
  ScratchDir dir;
  WriteSmallRecipe(dir);
  ASSERT_EQ(Cadsynth("generate r.yaml -o whole --quiet", dir).code, 0);
  const size_t needed = TreeBytes(dir / "whole");
  SmallDisk disk(dir / "disk", needed / 2);
  if (!disk.mounted())
    GTEST_SKIP() << "cannot mount a small tmpfs to fill (needs root): " << disk.why();

  const CliRun full = Cadsynth("generate r.yaml -o disk/out --quiet", dir);
  EXPECT_EQ(full.code, 1);
  EXPECT_NE(full.err.find("No space left on device"), std::string::npos) << full.err;
  EXPECT_NE(full.err.find((dir / "disk").string()), std::string::npos)
      << "the error names the file: " << full.err;
  size_t errors = 0;  // one error line (placement warnings may come before it)
  for (size_t at = full.err.find("error:"); at != std::string::npos;
       at = full.err.find("error:", at + 1))
    ++errors;
  EXPECT_EQ(errors, 1u) << full.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "disk" / "out"));
  // What was complete stays complete.
  const size_t complete = CheckCompleteFrames(dir / "disk" / ".out.partial");
  EXPECT_GT(complete, 0u);
  EXPECT_LT(complete, 36u);

  ASSERT_TRUE(disk.Grow(needed * 3));
  const CliRun resumed = Cadsynth("generate r.yaml -o disk/out", dir);
  ASSERT_EQ(resumed.code, 0) << resumed.err;
  EXPECT_NE(resumed.out.find("resumed: " + std::to_string(complete) + " frames"), std::string::npos)
      << resumed.out;
  ExpectSameTree(dir / "whole", dir / "disk" / "out");
}

}  // namespace
