// The labels of a generated dataset read back the way bop_toolkit reads them: every box and count
// of scene_gt_info.json recomputed from the written mask PNGs as calc_gt_info.py computes them,
// every COCO annotation as calc_gt_coco.py writes it, in both visibility modes.
#include <fstream>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "tests/image_support.h"

#include <gtest/gtest.h>

#include "dataset/coco.h"
#include "tests/json_support.h"
#include "tests/test_support.h"
#include "tools/pipeline/generate.h"

namespace cadsynth {
namespace {

using nlohmann::json;
using testing::ScratchDir;

using testing::ReadJson;

// The default job at 320 x 240: straight down and oblique views, so that parts of the
// slider-crank and the gearbox touch, hide each other and leave the image.
std::filesystem::path Generated(const ScratchDir& dir, const std::string& name,
                                BopOptions::Visibility visibility) {
  RunSpec spec = DefaultRunSpec();
  spec.intrinsics = Intrinsics{320, 240, 262.5, 262.5, 159.5, 119.5};
  spec.sweep.yaw_rad = {0.0, 2.0};
  spec.sweep.pitch_rad = {0.5, M_PI / 2};
  spec.sweep.radius_mm = {450.0, 650.0};
  spec.bop.test_every = 2;
  spec.bop.model_points = 100;
  spec.bop.visibility = visibility;
  // The slider-crank on its most probable face, upside down under its base plate: its links
  // hide completely in some views (invisible instances, -1 boxes).
  spec.scenes[1].arrangement.pose = PoseMode::kStable;
  GenerateOptions options;
  options.output = dir / name;
  Generate(spec, options);
  return options.output;
}

// bop_toolkit's misc.calc_2d_bbox of the nonzero pixels: [x, y, max - min, max - min]; -1s if none.
json Box(const cv::Mat& mask, int* count) {
  int u0 = mask.cols, v0 = mask.rows, u1 = -1, v1 = -1;
  *count = 0;
  for (int v = 0; v < mask.rows; ++v) {
    for (int u = 0; u < mask.cols; ++u) {
      if (mask.at<uint8_t>(v, u) == 0) continue;
      ++*count;
      u0 = std::min(u0, u), v0 = std::min(v0, v), u1 = std::max(u1, u), v1 = std::max(v1, v);
    }
  }
  return u1 < 0 ? json::array({-1, -1, -1, -1}) : json::array({u0, v0, u1 - u0, v1 - v0});
}

struct Totals {
  long instances = 0, invisible = 0, visible_pixels = 0;
};

// Checks one dataset against its masks; returns its visible instances and pixels, and every
// image's visible masks by (scene, image, instance) name.
Totals CheckAgainstMasks(const std::filesystem::path& root, bool exact,
                         std::map<std::string, cv::Mat>* visible) {
  Totals totals;
  for (int scene = 0; scene < 3; ++scene) {
    const std::filesystem::path dir = root / "train" / ("00000" + std::to_string(scene));
    const json gt_info = ReadJson(dir / "scene_gt_info.json");
    const json coco = ReadJson(dir / "scene_gt_coco.json");
    std::map<std::pair<int, int>, json> annotations;
    for (const json& a : coco["annotations"])
      annotations[{a["image_id"].get<int>(), a["inst_id"].get<int>()}] = a;
    for (const auto& [im, list] : gt_info.items()) {
      cv::Mat owner;  // exact mode: which instance claimed each pixel
      for (size_t i = 0; i < list.size(); ++i) {
        const std::string name =
            std::string(6 - im.size(), '0') + im + "_00000" + std::to_string(i) + ".png";
        SCOPED_TRACE(dir.string() + " " + name);
        const cv::Mat mask = testing::Imread((dir / "mask" / name).string(), cv::IMREAD_UNCHANGED);
        const cv::Mat mask_visib =
            testing::Imread((dir / "mask_visib" / name).string(), cv::IMREAD_UNCHANGED);
        if (owner.empty()) owner = cv::Mat::zeros(mask.size(), CV_8UC1);
        const json& info = list[i];
        int visib_count = 0, full_count = 0;
        const json visib_box = Box(mask_visib, &visib_count), full_box = Box(mask, &full_count);
        ++totals.instances;
        totals.visible_pixels += visib_count;
        (*visible)[dir.filename().string() + "/" + name] = mask_visib;
        EXPECT_EQ(info["px_count_visib"], visib_count);
        EXPECT_EQ(info["bbox_visib"], visib_box);
        EXPECT_DOUBLE_EQ(info["visib_fract"].get<double>(),
                         info["px_count_all"] > 0
                             ? static_cast<double>(visib_count) / info["px_count_all"].get<int>()
                             : 0);
        if (visib_count == 0) {
          ++totals.invisible;
          EXPECT_EQ(info["bbox_obj"], json::array({-1, -1, -1, -1}));
          EXPECT_EQ(annotations.count({std::stoi(im), static_cast<int>(i)}), 0u);
          continue;
        }
        // bbox_obj is the 3x canvas box: the in-image mask's where the box lies inside the image.
        const json& b = info["bbox_obj"];
        const bool inside = b[0] >= 0 && b[1] >= 0 &&
                            b[0].get<int>() + b[2].get<int>() < mask.cols &&
                            b[1].get<int>() + b[3].get<int>() < mask.rows;
        if (inside) {
          EXPECT_EQ(b, full_box);
          EXPECT_EQ(info["px_count_all"], full_count);
        } else {
          EXPECT_LE(b[0].get<int>(), full_box[0].get<int>());
          EXPECT_GT(info["px_count_all"].get<int>(), full_count);
        }
        int outside = 0, shared = 0;  // visible pixels outside the full silhouette; claimed twice
        for (int v = 0; v < mask.rows; ++v) {
          for (int u = 0; u < mask.cols; ++u) {
            if (mask_visib.at<uint8_t>(v, u) == 0) continue;
            outside += mask.at<uint8_t>(v, u) == 0;
            if (exact) {
              shared += owner.at<uint8_t>(v, u) != 0;
              owner.at<uint8_t>(v, u) = static_cast<uint8_t>(i + 1);
            }
          }
        }
        EXPECT_EQ(outside, 0);
        EXPECT_EQ(shared, 0);
        // COCO as calc_gt_coco.py: the visible mask, the amodal box (COCO's width + 1), ignore.
        const auto found = annotations.find({std::stoi(im), static_cast<int>(i)});
        if (found == annotations.end()) {
          ADD_FAILURE() << "no COCO annotation for a visible instance";
          continue;
        }
        const json& a = found->second;
        EXPECT_EQ(a["area"], visib_count);
        EXPECT_EQ(a["bbox"], json::array({full_box[0], full_box[1], full_box[2].get<int>() + 1,
                                          full_box[3].get<int>() + 1}));
        EXPECT_EQ(a["ignore"], info["visib_fract"].get<double>() < 0.1);
        const std::vector<uint8_t> decoded =
            DecodeRle(RleMask{mask.rows, mask.cols,
                              DecompressRleCounts(a["segmentation"]["counts"].get<std::string>())});
        int differ = 0;
        for (int p = 0; p < mask.rows * mask.cols; ++p)
          differ += (decoded[p] != 0) != (mask_visib.data[p] != 0);
        EXPECT_EQ(differ, 0);
      }
    }
  }
  return totals;
}

TEST(Labels, BoxesCountsAndCocoEqualBopToolkitsFromTheWrittenMasks) {
  ScratchDir dir;
  std::map<std::string, cv::Mat> exact_masks, bop19_masks;
  const Totals exact = CheckAgainstMasks(Generated(dir, "exact", BopOptions::Visibility::kExact),
                                         true, &exact_masks);
  const Totals bop19 = CheckAgainstMasks(Generated(dir, "bop19", BopOptions::Visibility::kBop19),
                                         false, &bop19_masks);
  EXPECT_EQ(exact.instances, bop19.instances);
  EXPECT_GT(exact.invisible, 0);  // some instances hide completely: their boxes are -1
  // bop19 keeps every front-most pixel and adds those of touching parts less than 15 mm behind.
  ASSERT_EQ(exact_masks.size(), bop19_masks.size());
  for (const auto& [name, mask] : exact_masks) {
    const cv::Mat& wider = bop19_masks.at(name);
    for (int p = 0; p < mask.rows * mask.cols; ++p) {
      ASSERT_TRUE(mask.data[p] == 0 || wider.data[p] != 0) << name;
    }
  }
  EXPECT_GT(bop19.visible_pixels, exact.visible_pixels);
}

}  // namespace
}  // namespace cadsynth
