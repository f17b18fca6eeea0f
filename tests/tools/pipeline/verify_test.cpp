// `cadsynth verify` and `cadsynth report`'s data on datasets the pipeline wrote: every check
// passes on a run, a rig and a merged farm run, and each kind of damage (a flipped mask pixel, a
// wrong box, a truncated PNG, a moved instance, a changed image byte, a wrong diameter) fails
// with the file and the reason, also where the manifest was written again after the damage (so
// that the content checks, not the checksums, must find it).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <string>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "tests/image_support.h"

#include "cad/core/error.h"
#include "dataset/file_io.h"
#include "dataset/manifest.h"
#include "dataset/verify.h"
#include "tests/test_support.h"
#include "tests/tools/pipeline/small_job.h"
#include "tools/pipeline/report.h"
#include "tools/pipeline/run_record.h"
#include "tools/pipeline/shards.h"

namespace cadsynth {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;
using testing::RunJob;
using testing::ScratchDir;
using testing::SmallJob;

Json ReadJson(const fs::path& path) { return Json::parse(ReadFileText(path)); }
void WriteJson(const fs::path& path, const Json& j) { WriteFileAtomic(path, j.dump()); }

// Every problem as "FILE: REASON" lines, for messages and searches.
std::string Problems(const VerifyReport& report) {
  std::string text;
  for (const auto& p : report.problems) text += p.file + ": " + p.reason + "\n";
  return text;
}

const VerifyReport::Check& CheckOf(const VerifyReport& report, const std::string& name) {
  for (const auto& c : report.checks) {
    if (c.name == name) return c;
  }
  throw std::runtime_error("no check " + name);
}

// The manifest as a run writes it, listing the files as they are now.
void RewriteManifest(const fs::path& root) {
  DatasetManifest m = ReadManifest(root);
  m.files = ListDatasetFiles(root);
  WriteManifest(root, m);
}

TEST(Verify, ARunPassesEveryCheck) {
  ScratchDir dir;
  RunJob(SmallJob(), dir / "out");
  const VerifyReport report = VerifyDataset(dir / "out");
  EXPECT_TRUE(report.passed()) << Problems(report);
  EXPECT_EQ(report.images, 6u);
  EXPECT_EQ(report.instances, 30u);  // five parts in each scene
  EXPECT_GT(CheckOf(report, "manifest").checked, 60u);
  EXPECT_EQ(CheckOf(report, "gt_info").checked, report.instances);
  EXPECT_GT(CheckOf(report, "coco").checked, 0u);
  EXPECT_EQ(CheckOf(report, "models_info").checked, 13u);
  EXPECT_GT(CheckOf(report, "recast").checked, 6u * 20);
  EXPECT_EQ(report.Verdict().rfind("PASS: 6 images", 0), 0u) << report.Verdict();
  // The certificate names the run it checked.
  const Json certificate = Json::parse(report.CertificateJson());
  EXPECT_EQ(certificate["verdict"], "pass");
  EXPECT_EQ(certificate["run_key"], ReadManifest(dir / "out").run_key);
  EXPECT_EQ(certificate["run_key"].get<std::string>().size(), 32u);
}

struct Damage {
  std::string what;
  std::function<void(const fs::path&)> apply;
  std::string file, reason;  // a problem names this file and holds this text
};

TEST(Verify, EachDamageFailsWithTheFileAndTheReason) {
  ScratchDir dir;
  RunJob(SmallJob(), dir / "clean");
  const fs::path scene = fs::path("train") / "000001";
  const std::vector<Damage> damages = {
      {"a flipped mask pixel",
       [&](const fs::path& root) {
         const fs::path path = root / scene / "mask_visib" / "000000_000001.png";
         cv::Mat mask = testing::Imread(path.string(), cv::IMREAD_UNCHANGED);
         cv::Point on;
         for (int v = 0; v < mask.rows && on.x == 0; ++v) {
           for (int u = 0; u < mask.cols; ++u) {
             if (mask.at<uint8_t>(v, u) != 0) on = {u, v};
           }
         }
         mask.at<uint8_t>(on) = 0;  // the last visible pixel of the first visible row goes
         testing::Imwrite(path.string(), mask);
       },
       (scene / "scene_gt_info.json").string(), "px_count_visib is"},
      {"the same pixel, seen by COCO",
       [&](const fs::path& root) {
         const fs::path path = root / scene / "mask_visib" / "000000_000001.png";
         cv::Mat mask = testing::Imread(path.string(), cv::IMREAD_UNCHANGED);
         for (int v = 0; v < mask.rows; ++v) {
           for (int u = 0; u < mask.cols; ++u) {
             if (mask.at<uint8_t>(v, u) != 0) {
               mask.at<uint8_t>(v, u) = 0;
               testing::Imwrite(path.string(), mask);
               return;
             }
           }
         }
       },
       (scene / "scene_gt_coco.json").string(), "its RLE differs from mask_visib in 1 pixels"},
      {"a wrong box",
       [&](const fs::path& root) {
         Json info = ReadJson(root / scene / "scene_gt_info.json");
         info["1"][2]["bbox_visib"][2] = info["1"][2]["bbox_visib"][2].get<int>() + 1;
         WriteJson(root / scene / "scene_gt_info.json", info);
       },
       (scene / "scene_gt_info.json").string(), "image 1 instance 2: bbox_visib is"},
      {"a truncated PNG",
       [&](const fs::path& root) {
         const fs::path path = root / scene / "mask" / "000001_000000.png";
         const std::string bytes = ReadFileText(path);
         WriteFileAtomic(path, bytes.substr(0, bytes.size() / 2));
       },
       (scene / "mask" / "000001_000000.png").string(), "truncated"},
      {"a moved instance",
       [&](const fs::path& root) {
         Json gt = ReadJson(root / scene / "scene_gt.json");
         Json& t = gt["0"][0]["cam_t_m2c"];
         t[2] = t[2].get<double>() + 5.0;  // 5 mm farther
         WriteJson(root / scene / "scene_gt.json", gt);
       },
       (scene / "scene_gt.json").string(), "image 0 pixel"},
      {"a wrong diameter",
       [&](const fs::path& root) {
         Json info = ReadJson(root / "models" / "models_info.json");
         info["3"]["diameter"] = info["3"]["diameter"].get<double>() + 0.5;
         WriteJson(root / "models" / "models_info.json", info);
       },
       "models/models_info.json", "obj 3: diameter is"},
  };
  for (const Damage& damage : damages) {
    SCOPED_TRACE(damage.what);
    const fs::path root = dir / "damaged";
    fs::remove_all(root);
    fs::copy(dir / "clean", root, fs::copy_options::recursive);
    damage.apply(root);
    // Against the manifest the run wrote: the checksum and the content both fail.
    VerifyReport report = VerifyDataset(root);
    EXPECT_FALSE(report.passed());
    EXPECT_GE(CheckOf(report, "manifest").failed, 1u) << Problems(report);
    // With a manifest written again over the damage, the content checks alone find it.
    RewriteManifest(root);
    report = VerifyDataset(root);
    EXPECT_FALSE(report.passed()) << report.Verdict();
    bool found = false;
    for (const auto& p : report.problems)
      found |= p.file == damage.file && p.reason.find(damage.reason) != std::string::npos;
    EXPECT_TRUE(found) << "expected " << damage.file << ": ..." << damage.reason << " in\n"
                       << Problems(report);
    EXPECT_EQ(CheckOf(report, "manifest").failed, 0u);
    EXPECT_EQ(report.Verdict().rfind("FAIL: ", 0), 0u) << report.Verdict();
  }

  // A changed byte of a colour image: only the checksum can tell.
  const fs::path root = dir / "damaged";
  fs::remove_all(root);
  fs::copy(dir / "clean", root, fs::copy_options::recursive);
  const fs::path rgb = root / scene / "rgb" / "000000.png";
  std::string bytes = ReadFileText(rgb);
  bytes[bytes.size() / 2] ^= 1;
  WriteFileAtomic(rgb, bytes);
  const VerifyReport report = VerifyDataset(root);
  ASSERT_EQ(report.problem_count, 1u) << Problems(report);
  EXPECT_EQ(report.problems[0].file, (scene / "rgb" / "000000.png").string());
  EXPECT_EQ(report.problems[0].reason, "checksum differs from the manifest");
  // A file the manifest does not list is noted, not failed.
  WriteFileAtomic(dir / "clean" / "notes.txt", "mine");
  const VerifyReport noted = VerifyDataset(dir / "clean");
  EXPECT_TRUE(noted.passed()) << Problems(noted);
  ASSERT_EQ(noted.notes.size(), 1u);
  EXPECT_NE(noted.notes[0].find("notes.txt"), std::string::npos) << noted.notes[0];
}

TEST(Verify, ARigAndAMergedFarmRunPassAndReportTheirRuns) {
  ScratchDir dir;
  const RunSpec spec = testing::SmallRigFarmJob();
  for (int i : {1, 0}) RunJob(spec, dir / "farm", ShardSpec{i, 2});
  EXPECT_EQ(Merge(dir / "farm").frames, 12u);
  const VerifyReport report = VerifyDataset(dir / "farm");
  EXPECT_TRUE(report.passed()) << Problems(report);
  EXPECT_EQ(report.images, 24u);  // 12 views, two sensors
  EXPECT_GT(CheckOf(report, "recast").checked, 24u * 20);

  // run.json: both shards, their frames adding up to the run's.
  const std::optional<RunRecord> run = ReadRunRecord(dir / "farm");
  ASSERT_TRUE(run);
  ASSERT_EQ(run->shards.size(), 2u);
  EXPECT_EQ(run->shards[0].frames + run->shards[1].frames, 12u);
  EXPECT_EQ(run->frames, 12u);
  EXPECT_EQ(run->run_key, ReadManifest(dir / "farm").run_key);

  // The report's data: both sensors' images, each object's views counted once (the first
  // sensor's), the extremes in the gallery as JPEG, the verifier's certificate once written.
  WriteFileAtomic(dir / "farm" / kCertificateFile, report.CertificateJson());
  const Json data = Json::parse(ReportData(dir / "farm"));
  ASSERT_EQ(data["sensors"].size(), 2u);
  EXPECT_EQ(data["sensors"][0]["name"], "a");
  EXPECT_EQ(data["sensors"][1]["name"], "b");
  EXPECT_EQ(data["sensors"][0]["images"], 12);
  EXPECT_EQ(data["sensors"][1]["width"], 120);
  EXPECT_EQ(data["run"]["shards"].size(), 2u);
  EXPECT_EQ(data["run"]["frames"], 12);
  size_t views = 0, instances = 0;
  for (const Json& o : data["objects"]) {
    instances += o["instances"].get<size_t>();
    for (const Json& row : o["coverage"]["counts"]) {
      for (const Json& n : row) views += n.get<size_t>();
    }
    EXPECT_LE(o["visible"].get<size_t>(), o["instances"].get<size_t>());
  }
  EXPECT_EQ(instances, report.instances / 2);  // one sensor's
  size_t visible = 0;
  for (const Json& o : data["objects"]) visible += o["visible"].get<size_t>();
  EXPECT_EQ(views, visible);
  ASSERT_GE(data["gallery"].size(), 3u);
  EXPECT_EQ(data["gallery"][0]["title"], "most occluded");
  EXPECT_EQ(data["gallery"][0]["image"].get<std::string>().rfind("data:image/jpeg;base64,/9j/", 0),
            0u);
  // Each sensor's own extremes: sensor a's first, then b's (the grey camera).
  std::map<std::string, int> per_sensor;
  std::string last;
  for (const Json& g : data["gallery"]) {
    const std::string sensor = g["sensor"];
    if (sensor != last) {
      EXPECT_EQ(per_sensor.count(sensor), 0u) << "sensors in turn";
    }
    ++per_sensor[sensor];
    last = sensor;
  }
  EXPECT_GE(per_sensor["a"], 3);
  EXPECT_GE(per_sensor["b"], 3);
  EXPECT_EQ(data["gallery"][0]["sensor"], "a");
  EXPECT_EQ(data["verify"]["verdict"], "pass");
}

TEST(Report, ViewsAreFoldedByTheObjectsSymmetries) {
  // The default job's gears have 18 and more teeth (discrete symmetries): every view of a gear
  // lands in one fundamental region, so its coverage map fills a sector of at most 360 / 18
  // degrees of azimuth (two bins of 10 degrees); the carrier (2-fold) may use half the circle.
  ScratchDir dir;
  RunJob(SmallJob({0.0, 0.7, 1.4, 2.1, 2.8, 3.5, 4.2, 4.9, 5.6}), dir / "out");
  const Json data = Json::parse(ReportData(dir / "out"));
  bool checked = false;
  for (const Json& o : data["objects"]) {
    if (o["name"] != "sun_z18") continue;
    checked = true;
    EXPECT_EQ(o["symmetry"], "discrete (35)");
    std::set<int> columns;
    const Json& counts = o["coverage"]["counts"];
    for (const Json& row : counts) {
      for (size_t x = 0; x < row.size(); ++x) {
        if (row[x].get<int>() > 0) columns.insert(static_cast<int>(x));
      }
    }
    EXPECT_LE(columns.size(), 3u) << o["coverage"].dump();
    EXPECT_EQ(o["visible"], 9);
  }
  EXPECT_TRUE(checked);
}

// The key of the report's randomisation entry `key`.
const Json& DrawEntry(const Json& data, const std::string& key) {
  for (const Json& k : data["randomization"]) {
    if (k["key"] == key) return k;
  }
  static const Json none;
  ADD_FAILURE() << "no randomisation entry " << key;
  return none;
}

TEST(Report, RandomisedDrawsAreTestedAgainstTheRecipe) {
  ScratchDir dir;
  std::ofstream(dir / "r.yaml") << R"(scenes:
  - name: crank
    parts: [{family: slider_crank}]
camera: {width: 48, height: 36, hfov: 60}
sweep: {sampler: random, count: 40, pitch: {from: 40, to: 80, step: 1},
        yaw: {from: 0, to: 359, step: 1}, radius: {from: 0.5 m, to: 0.7 m, step: 0.01 m}}
render: {mode: pbr, samples: 1, bounces: 1}
randomize:
  seed: 5
  parts:
    - {name: "*", preset: {choice: [steel, abs, brass]}}
  lights: {count: {choice: [1, 2, 3]}, type: {choice: [rect, point]},
           power: {log_uniform: [15, 120]}}
  camera: {exposure: {normal: [0, 0.4]}}
  distractors: {count: {uniform: [2, 4]}}
)";
  RunJob(LoadRecipe(dir / "r.yaml"), dir / "out");
  Json data = Json::parse(ReportData(dir / "out"));
  EXPECT_FALSE(data.contains("randomization_note")) << data["randomization_note"];
  // Every quantity the recipe asked for is tested, and the seeded draws agree with it.
  size_t tested = 0;
  for (const Json& k : data["randomization"]) {
    if (k["asked"].is_null()) continue;
    ++tested;
    ASSERT_TRUE(k["check"].is_object()) << k.dump();
    EXPECT_TRUE(k["check"]["agrees"].get<bool>()) << k.dump();
  }
  EXPECT_GE(tested, 6u);  // presets, light count, type, power, exposure, distractor count
  const Json& power = DrawEntry(data, "light.*.power");
  EXPECT_EQ(power["asked"], "{log_uniform: [15, 120]}");
  EXPECT_EQ(power["check"]["test"], "Kolmogorov-Smirnov");
  EXPECT_EQ(power["per"], "frame");
  // The expected counts over the histogram's bins: all draws lie in [15, 120].
  double expected = 0;
  for (const Json& e : power["expected"]) expected += e.get<double>();
  EXPECT_NEAR(expected, power["samples"].get<double>(), 1e-6 * expected);
  // Distractors are drawn once per scene: one scene, one draw (not one per frame).
  EXPECT_EQ(DrawEntry(data, "distractor.count")["per"], "scene");
  EXPECT_EQ(DrawEntry(data, "distractor.count")["samples"], 1);
  EXPECT_EQ(DrawEntry(data, "part.*.preset")["check"]["test"], "chi-square");

  // Draws that are not what the recipe asked for: every light at 100 W, a preset never offered,
  // and light counts of 30, 5 and 5 in 40 frames (expected 40 / 3 each: chi-square
  // (16.67^2 + 2 x 8.33^2) / 13.33 = 31.25 on 2 degrees of freedom, p = exp(-31.25 / 2)).
  const fs::path draws_file = dir / "out" / "train" / "000000" / "scene_randomization.json";
  Json draws = Json::parse(ReadFileText(draws_file));
  int frame = 0;
  for (Json& record : draws) {
    for (auto it = record.begin(); it != record.end(); ++it) {
      const std::string& key = it.key();
      if (key.ends_with(".power")) it.value() = 100.0;
      if (frame == 0 && key.starts_with("part.") && key.ends_with(".preset")) it.value() = "gold";
    }
    record["light.count"] = frame < 30 ? 1.0 : frame < 35 ? 2.0 : 3.0;
    ++frame;
  }
  ASSERT_EQ(frame, 40);
  WriteFileAtomic(draws_file, draws.dump());
  data = Json::parse(ReportData(dir / "out"));
  EXPECT_FALSE(DrawEntry(data, "light.*.power")["check"]["agrees"].get<bool>());
  EXPECT_LT(DrawEntry(data, "light.*.power")["check"]["p_value"].get<double>(), 1e-6);
  EXPECT_FALSE(DrawEntry(data, "part.*.preset")["check"]["agrees"].get<bool>());
  const Json& count = DrawEntry(data, "light.count")["check"];
  EXPECT_NEAR(count["statistic"].get<double>(), 31.25, 1e-9);
  EXPECT_NEAR(count["p_value"].get<double>(), std::exp(-31.25 / 2), 1e-12);
  EXPECT_FALSE(count["agrees"].get<bool>());
  EXPECT_TRUE(DrawEntry(data, "camera.exposure")["check"]["agrees"].get<bool>());

  // A recipe that cannot be read again (run.json edited): the draws are shown, not compared.
  Json run = Json::parse(ReadFileText(dir / "out" / "run.json"));
  run["recipe_text"] = "scenes: [";
  WriteFileAtomic(dir / "out" / "run.json", run.dump());
  data = Json::parse(ReportData(dir / "out"));
  EXPECT_NE(data.value("randomization_note", "").find("could not be read again"),
            std::string::npos);
  EXPECT_TRUE(DrawEntry(data, "light.*.power")["check"].is_null());
}

TEST(Report, APythonWithoutMatplotlibIsOneMessageWithTheFixAndNoPage) {
  ScratchDir dir;
  RunJob(SmallJob(), dir / "out");
  ReportOptions options;
  options.python = "/bin/false";  // exits 1 on `-c "import numpy, matplotlib"`
  try {
    WriteReport(dir / "out", dir / "page.html", options);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("apt install python3-matplotlib"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(fs::exists(dir / "page.html"));
  // An output folder that is not there: named before any work.
  try {
    WriteReport(dir / "out", dir / "missing" / "page.html");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("page.html: cannot write: no folder"), std::string::npos)
        << e.what();
  }
  // Not a dataset: one message naming the folder.
  try {
    WriteReport(dir / "nothing", dir / "page.html", options);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("nothing: no such folder"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace cadsynth
