// Reading a generated dataset back: the schema of every BOP file, eval and preview.
#include "tools/pipeline/eval.h"

#include <fstream>
#include <map>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "tests/image_support.h"

#include <gtest/gtest.h>

#include "cad/core/error.h"
#include "dataset/preview.h"
#include "tests/json_support.h"
#include "tests/test_support.h"
#include "tests/tools/pipeline/small_job.h"
#include "tools/pipeline/generate.h"

namespace cadsynth {
namespace {

using nlohmann::json;
using testing::ScratchDir;

using testing::ReadJson;

// The default job (the paper's three demo sets) at 160 x 120, 2 views, every image a test image.
std::filesystem::path SmallDataset(const ScratchDir& dir) {
  RunSpec spec = testing::SmallJob();
  spec.bop.test_every = 1;
  spec.bop.model_points = 500;
  GenerateOptions options;
  options.output = dir / "data";
  Generate(spec, options);
  return options.output;
}

// Writes the ground truth of every instance as an estimate, moved by `shift` mm along the camera's
// x axis, skipping the instances `skip` says to; returns how many it skipped.
int WriteShiftedTruth(const std::filesystem::path& dataset, const std::filesystem::path& csv,
                      double shift, const std::function<bool(int scene, int im, int obj)>& skip) {
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
        out << "," << gt["cam_t_m2c"][0].get<double>() + shift << " "
            << gt["cam_t_m2c"][1].get<double>() << " " << gt["cam_t_m2c"][2].get<double>()
            << ",-1\n";
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
  const int skipped = WriteShiftedTruth(
      dataset, csv, 10.0, [](int s, int im, int obj) { return s == 0 && im == 0 && obj == 1; });
  ASSERT_EQ(skipped, 1);
  std::ofstream(csv, std::ios::app)
      << "7,0,1,0.5,1 0 0 0 1 0 0 0 1,0 0 500,-1\n"   // no such scene
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
    // MSSD of a pure shift t is |t| = 10 mm whatever the symmetries: the identity gives it, and
    // any other symmetry S moves points by v = R (x - S x), which average to zero over an orbit,
    // so the largest |t + v| is at least |t| (to the sampling of the model cloud).
    EXPECT_NEAR(s.mean_mssd_mm, 10.0, 0.05);
    // BOP's recall: the thresholds 5% to 50% of the diameter that 10 mm is below (none of them
    // within the tolerance of 10 mm for these diameters).
    int below = 0;
    for (int k = 1; k <= 10; ++k) {
      ASSERT_GT(std::abs(0.05 * k * s.diameter_mm - 10.0), 0.05) << k;
      below += 10.0 < 0.05 * k * s.diameter_mm;
    }
    EXPECT_NEAR(s.ar_mssd, below / 10.0 * s.estimated / s.instances, 1e-9);
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
  std::ofstream(csv)
      << "scene_id,im_id,obj_id,score,R,t,time\n0,0,1,0.9,1 0 0 0 1 0 0 0 1,0 0 500,-1\n"
      << "0,0,1,0.9,1 0 0 0 1 0,0 0 500,-1\n";
  try {
    Evaluate(dataset, csv);
    FAIL() << "a short R must be refused";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("results.csv:3: R needs 9"), std::string::npos)
        << e.what();
  }
  std::ofstream(csv) << "0,0,1,0.9,2 0 0 0 1 0 0 0 1,0 0 500,-1\n";
  EXPECT_THROW(Evaluate(dataset, csv), Error);  // not a rotation
  std::ofstream(csv) << "0,0.5,1,0.9,1 0 0 0 1 0 0 0 1,0 0 500,-1\n";
  EXPECT_THROW(Evaluate(dataset, csv), Error);  // not an image id
  EXPECT_THROW(Evaluate(dir / "nowhere", csv), Error);
}

// Every object's projected 3D box encloses the object's full silhouette (bbox_obj of
// scene_gt_info.json): the preview draws the boxes where the objects are.
TEST(Preview, BoxesEncloseTheObjectsAndTheSheetHasARowPerFrame) {
  ScratchDir dir;
  const auto dataset = SmallDataset(dir);
  const json info = ReadJson(dataset / "models" / "models_info.json");
  int checked = 0, visible = 0;
  for (int scene = 0; scene < 3; ++scene) {
    const auto scene_dir = dataset / "train" / ("00000" + std::to_string(scene));
    const json cams = ReadJson(scene_dir / "scene_camera.json"),
               gt = ReadJson(scene_dir / "scene_gt.json"),
               gt_info = ReadJson(scene_dir / "scene_gt_info.json");
    for (const auto& [im, list] : gt.items()) {
      Eigen::Matrix3d k;
      for (int i = 0; i < 9; ++i) k(i / 3, i % 3) = cams[im]["cam_K"][i];
      for (size_t i = 0; i < list.size(); ++i) {
        const json& m = info[std::to_string(list[i]["obj_id"].get<int>())];
        const Eigen::Vector3d lo(m["min_x"], m["min_y"], m["min_z"]),
            size(m["size_x"], m["size_y"], m["size_z"]);
        Eigen::Isometry3d m2c = Eigen::Isometry3d::Identity();
        for (int j = 0; j < 9; ++j) m2c.linear()(j / 3, j % 3) = list[i]["cam_R_m2c"][j];
        for (int j = 0; j < 3; ++j) m2c.translation()(j) = list[i]["cam_t_m2c"][j];
        Eigen::AlignedBox2d projected;
        for (const Eigen::Vector2d& c : ProjectBox(k, m2c, Eigen::AlignedBox3d(lo, lo + size)))
          projected.extend(c);
        const json& b = gt_info[im][i]["bbox_obj"];
        visible += gt_info[im][i]["px_count_visib"].get<int>() > 0;
        if (b[0] == -1) continue;
        // Pixels [x, x + w] x [y, y + h] (bop_toolkit's width = max - min) have their centres
        // inside the projected box.
        EXPECT_LE(projected.min().x(), b[0].get<double>() + 0.5);
        EXPECT_LE(projected.min().y(), b[1].get<double>() + 0.5);
        EXPECT_GE(projected.max().x(), b[0].get<double>() + b[2].get<double>() + 0.5);
        EXPECT_GE(projected.max().y(), b[1].get<double>() + b[3].get<double>() + 0.5);
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, visible);  // every instance that shows has its box
  EXPECT_GT(checked, 15);

  PreviewOptions options;
  options.count = 3;
  options.panel_width = 100;
  std::vector<std::pair<int, int>> shown;
  const std::string png = RenderPreview(dataset, options, &shown);
  EXPECT_EQ(shown,
            (std::vector<std::pair<int, int>>{{0, 0}, {1, 0}, {2, 0}}));  // spread over 6 frames
  const cv::Mat sheet = testing::Imdecode(png, cv::IMREAD_COLOR);
  EXPECT_EQ(sheet.cols, 300);
  EXPECT_EQ(sheet.rows, 3 * 75);  // 160 x 120 images at 100 px wide
  // Against another dataset of the same views: two colour panels per row.
  {
    PreviewOptions versus = options;
    versus.versus = dataset;
    const std::string two = RenderPreview(dataset, versus);
    const cv::Mat pair = testing::Imdecode(two, cv::IMREAD_COLOR);
    EXPECT_EQ(pair.cols, 200);
    EXPECT_EQ(pair.rows, 3 * 75);
    versus.versus = dir / "nowhere";
    EXPECT_THROW(RenderPreview(dataset, versus), Error);
  }
  options.frames = {{1, 7}};
  EXPECT_THROW(RenderPreview(dataset, options), Error);  // no such image
  // The folder of scenes is found whatever its name (output.split).
  std::filesystem::rename(dataset / "train", dataset / "val");
  EXPECT_EQ(
      testing::Imdecode(png, cv::IMREAD_COLOR).size(),
      testing::Imdecode(RenderPreview(dataset, PreviewOptions{.count = 3, .panel_width = 100}),
                        cv::IMREAD_COLOR)
          .size());
}

// A small schema language for the checks below: "int", "number", "string", "bool",
// ["list", N, ITEM] (N = -1: any length), {"each": VALUE} (an object of any keys), or
// {"keys": {NAME: SCHEMA}} (exactly these keys; "?NAME" for optional ones).
void ExpectSchema(const json& value, const json& schema, const std::string& where) {
  if (schema.is_string()) {
    const std::string type = schema;
    const bool ok = type == "int"      ? value.is_number_integer()
                    : type == "number" ? value.is_number()
                    : type == "string" ? value.is_string()
                    : type == "bool"   ? value.is_boolean()
                                       : false;
    EXPECT_TRUE(ok) << where << ": expected " << type << ", got " << value.dump();
  } else if (schema.is_array()) {
    ASSERT_TRUE(value.is_array()) << where << ": expected a list, got "
                                  << value.dump().substr(0, 80);
    if (schema[1] >= 0) {
      EXPECT_EQ(value.size(), schema[1].get<size_t>()) << where;
    }
    for (size_t i = 0; i < value.size(); ++i)
      ExpectSchema(value[i], schema[2], where + "[" + std::to_string(i) + "]");
  } else if (schema.contains("each")) {
    ASSERT_TRUE(value.is_object()) << where;
    for (const auto& [key, item] : value.items())
      ExpectSchema(item, schema["each"], where + "." + key);
  } else {
    ASSERT_TRUE(value.is_object()) << where;
    for (const auto& [name, sub] : schema["keys"].items()) {
      const bool optional = name[0] == '?';
      const std::string key = optional ? name.substr(1) : name;
      if (!value.contains(key)) {
        EXPECT_TRUE(optional) << where << ": missing " << key;
        continue;
      }
      ExpectSchema(value[key], sub, where + "." + key);
    }
    for (const auto& [key, item] : value.items()) {
      EXPECT_TRUE(schema["keys"].contains(key) || schema["keys"].contains("?" + key))
          << where << ": unexpected " << key;
    }
  }
}

// bop_toolkit's docs/bop_datasets_format.md, key by key, on every BOP file of a generated dataset.
TEST(BopSchema, EveryFileHasTheDocumentedKeysAndTypes) {
  ScratchDir dir;
  const auto dataset = SmallDataset(dir);
  const json vec3 = json::array({"list", 3, "number"}), mat3 = json::array({"list", 9, "number"});
  const json box = json::array({"list", 4, "int"});
  ExpectSchema(ReadJson(dataset / "camera.json"),
               {{"keys",
                 {{"cx", "number"},
                  {"cy", "number"},
                  {"fx", "number"},
                  {"fy", "number"},
                  {"height", "int"},
                  {"width", "int"},
                  {"depth_scale", "number"}}}},
               "camera.json");
  const json model = {
      {"keys",
       {{"diameter", "number"},
        {"min_x", "number"},
        {"min_y", "number"},
        {"min_z", "number"},
        {"size_x", "number"},
        {"size_y", "number"},
        {"size_z", "number"},
        {"?symmetries_discrete", json::array({"list", -1, json::array({"list", 16, "number"})})},
        {"?symmetries_continuous",
         json::array({"list", -1, {{"keys", {{"axis", vec3}, {"offset", vec3}}}}})}}}};
  ExpectSchema(ReadJson(dataset / "models" / "models_info.json"), {{"each", model}},
               "models_info.json");
  ExpectSchema(
      ReadJson(dataset / "test_targets_bop19.json"),
      json::array(
          {"list",
           -1,
           {{"keys",
             {{"im_id", "int"}, {"inst_count", "int"}, {"obj_id", "int"}, {"scene_id", "int"}}}}}),
      "test_targets_bop19.json");
  for (int scene = 0; scene < 3; ++scene) {
    const auto scene_dir = dataset / "train" / ("00000" + std::to_string(scene));
    ExpectSchema(ReadJson(scene_dir / "scene_camera.json"),
                 {{"each",
                   {{"keys",
                     {{"cam_K", mat3},
                      {"depth_scale", "number"},
                      {"cam_R_w2c", mat3},
                      {"cam_t_w2c", vec3}}}}}},
                 "scene_camera.json");
    ExpectSchema(
        ReadJson(scene_dir / "scene_gt.json"),
        {{"each",
          json::array(
              {"list",
               -1,
               {{"keys", {{"cam_R_m2c", mat3}, {"cam_t_m2c", vec3}, {"obj_id", "int"}}}}})}},
        "scene_gt.json");
    const json gt_info = ReadJson(scene_dir / "scene_gt_info.json");
    ExpectSchema(gt_info,
                 {{"each", json::array({"list",
                                        -1,
                                        {{"keys",
                                          {{"bbox_obj", box},
                                           {"bbox_visib", box},
                                           {"px_count_all", "int"},
                                           {"px_count_valid", "int"},
                                           {"px_count_visib", "int"},
                                           {"visib_fract", "number"}}}}})}},
                 "scene_gt_info.json");
    for (const auto& [im, list] : gt_info.items()) {
      for (const json& entry : list) {
        EXPECT_GE(entry["visib_fract"].get<double>(), 0.0);
        EXPECT_LE(entry["visib_fract"].get<double>(), 1.0);
        EXPECT_LE(entry["px_count_visib"].get<int>(), entry["px_count_all"].get<int>());
        if (entry["px_count_visib"] == 0) {  // bop_toolkit writes no box for an invisible instance
          EXPECT_EQ(entry["bbox_obj"], json::array({-1, -1, -1, -1}));
          EXPECT_EQ(entry["bbox_visib"], json::array({-1, -1, -1, -1}));
        }
      }
    }
    const json rle = {{"keys", {{"size", json::array({"list", 2, "int"})}, {"counts", "string"}}}};
    ExpectSchema(
        ReadJson(scene_dir / "scene_gt_coco.json"),
        {{"keys",
          {{"annotations", json::array({"list",
                                        -1,
                                        {{"keys",
                                          {{"id", "int"},
                                           {"image_id", "int"},
                                           {"category_id", "int"},
                                           {"iscrowd", "int"},
                                           {"area", "int"},
                                           {"bbox", box},
                                           {"segmentation", rle},
                                           {"width", "int"},
                                           {"height", "int"},
                                           {"ignore", "bool"},
                                           {"inst_id", "int"}}}}})},
           {"categories",
            json::array(
                {"list",
                 -1,
                 {{"keys", {{"id", "int"}, {"name", "string"}, {"supercategory", "string"}}}}})},
           {"images", json::array({"list",
                                   -1,
                                   {{"keys",
                                     {{"id", "int"},
                                      {"file_name", "string"},
                                      {"width", "int"},
                                      {"height", "int"}}}}})},
           {"info", {{"keys", {{"description", "string"}}}}},
           {"licenses", json::array({"list", 0, "int"})}}}},
        "scene_gt_coco.json");
  }
}

}  // namespace
}  // namespace cadsynth
