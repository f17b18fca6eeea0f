// The `eval` command: scores pose estimates (BOP results CSV) against a cadsynth dataset.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace cadsynth {

struct ObjectScores {
  int obj_id = 0;  // 0: all objects together
  std::string name;
  bool symmetric = false;  // ADD(-S) below means ADD-S for symmetric objects, ADD otherwise
  double diameter_mm = 0;
  int instances = 0;         // ground-truth instances evaluated
  int estimated = 0;         // of those, matched to an estimate (the rest count as misses)
  double mean_error_mm = 0;  // ADD(-S) over the matched instances (NaN if none)
  double within_10pct = 0;   // share with ADD(-S) < 10% of the diameter (the paper's Table II)
  double auc_adds = 0;       // area under the accuracy curve up to 100 mm, with ADD-S for all
  double auc_add_or_s = 0;   // same with ADD(-S)
  double mean_mssd_mm = 0;   // BOP's MSSD over the matched instances (NaN if none)
  double ar_mssd = 0;        // BOP's average recall of MSSD (thresholds 5% to 50% of diameter)
};

struct EvalReport {
  std::string images;  // which images were evaluated, in words
  int image_count = 0;
  int ignored_estimates = 0;  // estimates for images outside the evaluated set (e.g. train images)
  int unmatched_estimates = 0;  // more estimates of an object in an image than instances
  std::vector<ObjectScores> objects;
  ObjectScores overall;
};

// Reads DATASET's models (models_info.json, models_cad.json, models/points/), ground truth
// (SPLIT/*/scene_gt.json) and, when present, splits/test.txt: only those test images are
// evaluated, else every image. RESULTS is a BOP results CSV
// (scene_id,im_id,obj_id,score,R,t,time; R row-major, t in mm). Every ground-truth instance of an
// evaluated image counts; estimates are matched per (image, object) in decreasing score, each to
// the unmatched instance with the smallest error. A multi-sensor dataset's estimates are for one
// `sensor` (its cam_from_model, scene_gt_SENSOR.json). Throws Error naming the file and line.
EvalReport Evaluate(const std::filesystem::path& dataset, const std::filesystem::path& results,
                    const std::string& sensor = "");

std::string EvalTable(const EvalReport& report);
std::string EvalJson(const EvalReport& report);
void WriteEvalJson(const std::filesystem::path& path, const EvalReport& report);  // atomically

}  // namespace cadsynth
