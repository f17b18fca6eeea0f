// formats: webdataset in whole runs: archives that hold every frame (bounded, with their manifest's
// SHA-256), farm tasks that keep their frames only in archives, retried tasks that write the same
// archive bytes, and merge restoring the BOP folders of one process from the archives.
#include "dataset/webdataset.h"

#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cad/core/error.h"
#include "dataset/tar_archive.h"
#include "tests/test_support.h"
#include "tests/tools/pipeline/small_job.h"
#include "tools/pipeline/generate.h"
#include "tools/pipeline/shards.h"

namespace cadsynth {
namespace {

using testing::ExpectSameTree;
using testing::ReadFile;
using testing::ReadTree;
using testing::RunJob;
using testing::ScratchDir;

// The farm tests' job (12 units, every output format) with archives of at most 3 samples.
RunSpec ArchiveSpec() {
  RunSpec spec = testing::SmallFarmJob();
  spec.bop.webdataset = true;
  spec.bop.archive_samples = 3;
  return spec;
}

// Archive name -> bytes, of ROOT/webdataset.
std::map<std::string, std::string> Archives(const std::filesystem::path& root) {
  std::map<std::string, std::string> archives;
  for (const auto& [name, bytes] : ReadTree(ArchiveFolder(root))) {
    if (name.size() > 4 && name.substr(name.size() - 4) == ".tar") archives[name] = bytes;
  }
  return archives;
}

// The archives' members: sample key -> member names after the key, in archive order.
std::map<std::string, std::vector<std::string>> Samples(const std::filesystem::path& root) {
  std::map<std::string, std::vector<std::string>> samples;
  for (const ArchiveManifest& manifest : ReadArchiveManifests(root)) {
    for (const ArchiveRecord& record : manifest.archives) {
      ReadTar(ArchiveFolder(root) / record.file, [&](const std::string& name, std::string&&) {
        const size_t dot = name.find('.');
        samples[name.substr(0, dot)].push_back(name.substr(dot + 1));
        return true;
      });
    }
  }
  return samples;
}

TEST(Webdataset, AWholeRunArchivesEveryFrameWithItsBopFilesAndManifest) {
  ScratchDir dir;
  EXPECT_EQ(RunJob(ArchiveSpec(), dir / "out").frames, 12u);
  const std::vector<ArchiveManifest> manifests = ReadArchiveManifests(dir / "out");
  ASSERT_EQ(manifests.size(), 1u);
  const ArchiveManifest& m = manifests[0];
  EXPECT_EQ(m.shard, 0);
  EXPECT_EQ(m.shards, 1);
  EXPECT_EQ(m.samples, 12u);
  ASSERT_EQ(m.archives.size(), 4u);  // 12 samples, at most 3 per archive
  for (const ArchiveRecord& record : m.archives) {
    const std::filesystem::path path = ArchiveFolder(dir / "out") / record.file;
    EXPECT_EQ(record.samples, 3u);
    EXPECT_EQ(std::filesystem::file_size(path), record.bytes);
    EXPECT_EQ(FileSha256(path), record.sha256);
  }
  EXPECT_EQ(m.archives[0].file, "shard-000000-0000.tar");
  EXPECT_EQ(m.archives[0].first_key, "000000_000000");
  EXPECT_EQ(m.archives[3].last_key, "000002_000003");

  const auto samples = Samples(dir / "out");
  ASSERT_EQ(samples.size(), 12u);
  const std::vector<std::string>& s = samples.at("000001_000002");
  const std::set<std::string> names(s.begin(), s.end());
  EXPECT_EQ(names.size(), s.size()) << "a member name repeats";
  for (const char* name : {"cadsynth.json", "camera.json", "gt.json", "gt_info.json", "rgb.png",
                           "depth.png", "mask_000000.png", "mask_visib_000000.png", "split.txt"}) {
    EXPECT_TRUE(names.count(name)) << name;
  }
  // Each member holds the file it names: the BOP image, byte for byte, and its fragment's entries.
  const std::filesystem::path scene = dir / "out" / "train" / "000001";
  std::map<std::string, std::string> members;
  ReadTar(ArchiveFolder(dir / "out") / "shard-000000-0002.tar",
          [&](const std::string& name, std::string&& bytes) {
            members[name] = bytes;
            return true;
          });
  EXPECT_EQ(members.at("000001_000002.rgb.png"), ReadFile(scene / "rgb" / "000002.png"));
  EXPECT_EQ(members.at("000001_000002.mask_visib_000000.png"),
            ReadFile(scene / "mask_visib" / "000002_000000.png"));
  EXPECT_EQ(members.at("000001_000002.split.txt"),
            ArchiveSpec().bop.IsTest(2, 4) ? "test" : "train");
  const std::string camera = members.at("000001_000002.camera.json");
  EXPECT_NE(camera.find("\"cam_K\""), std::string::npos) << camera;
  EXPECT_NE(camera.find("\"depth_scale\""), std::string::npos) << camera;
}

// The archives are cut per task (a farm's differ from one process's) and the dataset's
// manifest lists them: both go before two trees are compared.
void DropArchives(const std::filesystem::path& root) {
  std::filesystem::remove_all(ArchiveFolder(root));
  const std::filesystem::path manifest = root / "manifest.json";
  std::istringstream lines(ReadFile(manifest));
  std::string kept;
  for (std::string line; std::getline(lines, line);) {
    if (line.find("\"webdataset/") == std::string::npos) kept += line + "\n";
  }
  std::ofstream(manifest, std::ios::binary) << kept;
}

TEST(Webdataset, FarmTasksKeepOnlyArchivesAndMergeRestoresOneProcessesBytes) {
  ScratchDir dir;
  const RunSpec spec = ArchiveSpec();
  RunJob(spec, dir / "whole");
  for (int i : {2, 0, 1}) RunJob(spec, dir / "tree", ShardSpec{i, 3});
  // No frame of any task is left loose: scene folders hold only what merge will fill in.
  for (const auto& [name, bytes] : ReadTree(dir / "tree" / "train")) {
    EXPECT_EQ(name.find("rgb/"), std::string::npos) << name;
    EXPECT_EQ(name.find(".fragments"), std::string::npos) << name;
  }
  const std::vector<ArchiveManifest> manifests = ReadArchiveManifests(dir / "tree");
  ASSERT_EQ(manifests.size(), 3u);
  size_t samples = 0;
  for (const ArchiveManifest& m : manifests) {
    EXPECT_EQ(m.shards, 3);
    EXPECT_EQ(m.samples, 4u);  // units g with g % 3 == shard
    samples += m.samples;
  }
  EXPECT_EQ(samples, 12u);
  // Task 1 owns units 1, 4, 7, 10: scene 0 image 1, scene 1 images 0 and 3, scene 2 image 2.
  const auto task1 = Samples(dir / "tree");
  EXPECT_TRUE(task1.count("000001_000000"));
  EXPECT_EQ(manifests[1].archives[0].first_key, "000000_000001");
  EXPECT_EQ(manifests[1].archives[1].last_key, "000002_000002");

  // A retried task writes the same archive bytes: run again on the same tree (its frames come
  // back from its archives), and from scratch in another tree.
  const auto first = Archives(dir / "tree");
  RunJob(spec, dir / "tree", ShardSpec{1, 3});
  RunJob(spec, dir / "retry", ShardSpec{1, 3});
  const auto again = Archives(dir / "tree");
  const auto retry = Archives(dir / "retry");
  EXPECT_EQ(first, again);
  ASSERT_EQ(retry.size(), 2u);
  for (const auto& [name, bytes] : retry) EXPECT_EQ(bytes, first.at(name)) << name;

  // Merge: the BOP folders of one process (the archives stay, as every task wrote them).
  EXPECT_EQ(Merge(dir / "tree").frames, 12u);
  EXPECT_EQ(Archives(dir / "tree"), first);
  DropArchives(dir / "whole");
  DropArchives(dir / "tree");
  ExpectSameTree(dir / "whole", dir / "tree");
}

TEST(Webdataset, ARigsSensorsShareASampleAndMergeBack) {
  ScratchDir dir;
  RunSpec spec = ArchiveSpec();
  RigSensor a{"a", spec.intrinsics, {}};
  RigSensor b{"b", Intrinsics{120, 90, 100.0, 100.0, 59.5, 44.5}, {}};
  b.sensor.image = SensorOptions::Image::kGray;
  b.rig_from_cam.translation() = Eigen::Vector3d(50, 0, 0);
  spec.rig = {a, b};
  RunJob(spec, dir / "whole");
  for (int i : {1, 0}) RunJob(spec, dir / "tree", ShardSpec{i, 2});
  const auto samples = Samples(dir / "tree");
  ASSERT_EQ(samples.size(), 12u);
  const std::vector<std::string>& s = samples.at("000000_000000");
  const std::set<std::string> names(s.begin(), s.end());
  for (const char* name : {"cadsynth_a.json", "cadsynth_b.json", "gt_b.json", "rgb_a.png",
                           "gray_b.png", "depth_b.png", "mask_visib_b_000000.png"}) {
    EXPECT_TRUE(names.count(name)) << name;
  }
  Merge(dir / "tree");
  DropArchives(dir / "whole");
  DropArchives(dir / "tree");
  ExpectSameTree(dir / "whole", dir / "tree");
}

TEST(Webdataset, MergeRefusesADamagedArchiveNamingIt) {
  ScratchDir dir;
  const RunSpec spec = ArchiveSpec();
  for (int i : {0, 1}) RunJob(spec, dir / "tree", ShardSpec{i, 2});
  const std::filesystem::path archive = ArchiveFolder(dir / "tree") / "shard-000001-0001.tar";
  std::string bytes = ReadFile(archive);
  bytes[1000] ^= 1;
  std::ofstream(archive, std::ios::binary) << bytes;
  try {
    Merge(dir / "tree");
    ADD_FAILURE() << "merged a damaged archive";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("shard-000001-0001.tar: damaged"), std::string::npos)
        << e.what();
  }
  // The task run again writes it anew; then the merge goes through.
  std::filesystem::remove(archive);
  std::filesystem::remove(ManifestPath(dir / "tree", 1));
  RunJob(spec, dir / "tree", ShardSpec{1, 2});
  EXPECT_EQ(Merge(dir / "tree").frames, 12u);
}

TEST(Webdataset, ArchivesAreBoundedInSize) {
  ScratchDir dir;
  RunSpec spec = ArchiveSpec();
  spec.bop.archive_samples = 1000;
  spec.bop.archive_megabytes = 1;
  spec.intrinsics = Intrinsics{640, 480, 525.0, 525.0, 319.5, 239.5};
  spec.sweep.yaw_rad = {0.0, 1.0, 2.0, 3.0};
  RunJob(spec, dir / "out");
  const ArchiveManifest m = ReadArchiveManifests(dir / "out").at(0);
  EXPECT_GT(m.archives.size(), 1u);
  for (const ArchiveRecord& record : m.archives) EXPECT_LE(record.bytes, uint64_t{1} << 20);
}

}  // namespace
}  // namespace cadsynth
