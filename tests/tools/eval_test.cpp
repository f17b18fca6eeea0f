#include "tools/eval.h"

#include <fstream>
#include <map>

#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

#include "cad/error.h"
#include "tests/test_support.h"
#include "tools/generate.h"

namespace cadsynth {
namespace {

using nlohmann::json;
using testing::ScratchDir;

// The default job (the paper's three demo sets) at 160 x 120, 2 views, every image a test image.
std::filesystem::path SmallDataset(const ScratchDir& dir) {
  RunSpec spec = DefaultRunSpec();
  spec.intrinsics = Intrinsics{160, 120, 131.25, 131.25, 79.5, 59.5};
  spec.sweep.yaw_rad = {0.0, 2.0};
  spec.sweep.pitch_rad = {0.6};
  spec.sweep.radius_mm = {700.0};
  spec.bop.test_every = 1;
  spec.bop.model_points = 500;
  GenerateOptions options;
  options.output = dir / "data";
  Generate(spec, options);
  return options.output;
}

// Writes the ground truth of every instance as an estimate, moved by `shift` mm along the camera's
// x axis, skipping the instances `skip` says to; returns how many it skipped.
int WriteShiftedTruth(const std::filesystem::path& dataset, const std::filesystem::path& csv, double shift,
                      const std::function<bool(int scene, int im, int obj)>& skip) {
  std::ofstream out(csv);
  out << "scene_id,im_id,obj_id,score,R,t,time\n";
  int skipped = 0;
  for (int scene = 0; scene < 3; ++scene) {
    char name[16];
    std::snprintf(name, sizeof(name), "%06d", scene);
    std::ifstream in(dataset / "train" / name / "scene_gt.json");
    const json scene_gt = json::parse(in);
    for (const auto& [im, list] : scene_gt.items()) {
      for (const json& gt : list) {
        const int obj = gt["obj_id"];
        if (skip(scene, std::stoi(im), obj)) {
          ++skipped;
          continue;
        }
        out << scene << "," << im << "," << obj << ",0.9,";
        for (int i = 0; i < 9; ++i) out << (i ? " " : "") << gt["cam_R_m2c"][i].get<double>();
        out << "," << gt["cam_t_m2c"][0].get<double>() + shift << " " << gt["cam_t_m2c"][1].get<double>() << " "
            << gt["cam_t_m2c"][2].get<double>() << ",-1\n";
      }
    }
  }
  return skipped;
}

TEST(Eval, ShiftedTruthScoresAsWorkedOutByHand) {
  ScratchDir dir;
  const auto dataset = SmallDataset(dir);
  const auto csv = dir / "results.csv";
  // Drop obj 1 in scene 0, image 0 (the sun gear: a symmetric part).
  const int skipped = WriteShiftedTruth(dataset, csv, 10.0, [](int s, int im, int obj) { return s == 0 && im == 0 && obj == 1; });
  ASSERT_EQ(skipped, 1);
  std::ofstream(csv, std::ios::app) << "7,0,1,0.5,1 0 0 0 1 0 0 0 1,0 0 500,-1\n"   // no such scene
                                    << "0,0,5,0.5,1 0 0 0 1 0 0 0 1,0 0 500,-1\n";  // no such object there

  const EvalReport report = Evaluate(dataset, csv);
  EXPECT_EQ(report.image_count, 6);
  EXPECT_EQ(report.ignored_estimates, 1);
  EXPECT_EQ(report.unmatched_estimates, 1);
  ASSERT_EQ(report.objects.size(), 13u);
  EXPECT_EQ(report.overall.instances, 2 * 15);
  EXPECT_EQ(report.overall.estimated, 2 * 15 - 1);
  for (const ObjectScores& s : report.objects) {
    SCOPED_TRACE(s.name);
    EXPECT_EQ(s.instances, s.name == "planet_z18" ? 6 : 2);  // three planets, two views
    if (s.symmetric) {
      EXPECT_LE(s.mean_error_mm, 10.0 + 1e-6);  // ADD-S never exceeds the shift
    } else {
      EXPECT_NEAR(s.mean_error_mm, 10.0, 1e-3);  // ADD of a pure translation is its length
      EXPECT_NEAR(s.auc_add_or_s, 0.9, 1e-5);    // (100 - 10) / 100
    }
    // 10 mm passes the paper's test where the diameter exceeds 100 mm (ADD-S may pass more often).
    const double passes = s.diameter_mm * 0.1 > 10.0 ? double(s.estimated) / s.instances : 0.0;
    if (s.symmetric) {
      EXPECT_GE(s.within_10pct, passes);
    } else {
      EXPECT_DOUBLE_EQ(s.within_10pct, passes);
    }
  }
  EXPECT_EQ(report.objects[0].estimated, 1);  // the dropped one is a miss
  const json j = json::parse(EvalJson(report));
  EXPECT_EQ(j["overall"]["instances"], 30);
  EXPECT_EQ(j["objects"].size(), 13u);
}

TEST(Eval, BadResultsNameTheFileAndLine) {
  ScratchDir dir;
  const auto dataset = SmallDataset(dir);
  const auto csv = dir / "results.csv";
  std::ofstream(csv) << "scene_id,im_id,obj_id,score,R,t,time\n0,0,1,0.9,1 0 0 0 1 0 0 0 1,0 0 500,-1\n"
                     << "0,0,1,0.9,1 0 0 0 1 0,0 0 500,-1\n";
  try {
    Evaluate(dataset, csv);
    FAIL() << "a short R must be refused";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("results.csv:3: R needs 9"), std::string::npos) << e.what();
  }
  std::ofstream(csv) << "0,0,1,0.9,2 0 0 0 1 0 0 0 1,0 0 500,-1\n";
  EXPECT_THROW(Evaluate(dataset, csv), Error);  // not a rotation
  EXPECT_THROW(Evaluate(dir / "nowhere", csv), Error);
}

}  // namespace
}  // namespace cadsynth
