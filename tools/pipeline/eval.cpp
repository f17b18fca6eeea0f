#include "tools/pipeline/eval.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include <tbb/parallel_for.h>
#include <nlohmann/json.hpp>

#include "cad/core/error.h"
#include "dataset/bop.h"
#include "dataset/bop_read.h"
#include "dataset/file_io.h"
#include "dataset/point_cloud.h"
#include "dataset/pose_metrics.h"

namespace cadsynth {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

constexpr double kAucMaxMm = 100.0;  // 0.1 m, as PoseCNN and PVN3D

struct Model {
  std::string name;
  bool symmetric = false;
  double diameter = 0;
  std::vector<Eigen::Vector3f> points;
  std::vector<Eigen::Isometry3d> symmetry_poses;  // for MSSD
};

struct Estimate {
  double score;
  Eigen::Isometry3d pose;
};

using ImageKey = std::pair<int, int>;  // scene, image
using Estimates = std::map<std::pair<ImageKey, int>, std::vector<Estimate>>;

// The estimates of RESULTS grouped per (image, object).
Estimates ReadResults(const fs::path& path) {
  Estimates out;
  for (const BopEstimate& e : ParseBopResults(ReadFileText(path), path.string()))
    out[{{e.scene_id, e.im_id}, e.obj_id}].push_back({e.score, e.cam_from_model});
  return out;
}

void Score(ObjectScores* s, const std::vector<double>& add_s, const std::vector<double>& add_or_s,
           const std::vector<double>& mssd, const std::vector<double>& diameters) {
  double mssd_sum = 0;
  int mssd_count = 0;
  for (double e : mssd) {
    if (std::isfinite(e)) mssd_sum += e, ++mssd_count;
  }
  s->mean_mssd_mm = mssd_count ? mssd_sum / mssd_count : std::numeric_limits<double>::quiet_NaN();
  s->ar_mssd = AverageRecallMssd(mssd, diameters);
  s->instances = static_cast<int>(add_s.size());
  double sum = 0;
  int hits = 0;
  for (size_t i = 0; i < add_or_s.size(); ++i) {
    if (!std::isfinite(add_or_s[i])) continue;
    ++s->estimated;
    sum += add_or_s[i];
    if (add_or_s[i] < 0.1 * diameters[i]) ++hits;
  }
  s->mean_error_mm = s->estimated ? sum / s->estimated : std::numeric_limits<double>::quiet_NaN();
  s->within_10pct = s->instances ? static_cast<double>(hits) / s->instances : 0.0;
  s->auc_adds = AccuracyAuc(add_s, kAucMaxMm);
  s->auc_add_or_s = AccuracyAuc(add_or_s, kAucMaxMm);
}

// The models of DATASET by obj_id: models_info.json, names from models_cad.json and the point
// clouds in models/points/.
std::map<int, Model> ReadModels(const fs::path& dataset) {
  const fs::path info_file = dataset / "models" / "models_info.json";
  const fs::path cad_file = dataset / "models" / "models_cad.json";
  Json cad = Json::object();
  if (fs::exists(cad_file)) {
    const std::string text = ReadFileText(cad_file);
    try {
      cad = Json::parse(text);
    } catch (const Json::exception& e) {
      throw Error(JsonErrorMessage(cad_file.string(), text, e));
    }
  }
  std::map<int, Model> models;
  for (const BopModelInfo& info : ParseModelsInfo(ReadFileText(info_file), info_file.string())) {
    Model m;
    m.diameter = info.diameter;
    m.symmetric = info.symmetric;
    m.symmetry_poses = info.symmetry_poses;
    const std::string key = std::to_string(info.obj_id);
    m.name = "obj_" + key;
    if (cad.is_object() && cad.contains(key) && cad[key].is_object() && cad[key].contains("name") &&
        cad[key]["name"].is_string()) {
      m.name = cad[key]["name"].get<std::string>();
    }
    std::ostringstream file;
    file << "obj_" << std::setw(6) << std::setfill('0') << info.obj_id << ".ply";
    const fs::path cloud = dataset / "models" / "points" / file.str();
    if (!fs::exists(cloud)) {
      throw Error(cloud.string() +
                  ": missing; eval needs the model clouds (generate with output.model_points > 0)");
    }
    m.points = DecodePointPly(ReadFileText(cloud), cloud.string());
    models[info.obj_id] = std::move(m);
  }
  return models;
}

// The images splits/test.txt lists (scene, image per line).
std::set<ImageKey> ReadTestImages(const fs::path& test_list) {
  std::set<ImageKey> test_images;
  std::istringstream in(ReadFileText(test_list));
  int scene, image;
  while (in >> scene >> image) test_images.insert({scene, image});
  if (!in.eof()) throw Error(test_list.string() + ": expected 'scene_id image_id' per line");
  if (test_images.empty())
    throw Error(test_list.string() + ": the test split is empty (see output.test_every)");
  return test_images;
}

struct TruthInstance {
  ImageKey image;
  int obj_id;
  Eigen::Isometry3d pose;
};

struct Truth {
  std::vector<TruthInstance> instances;
  std::set<ImageKey> images;  // the evaluated images
};

// Ground truth of the evaluated images (`test_images`; none: every image of `sensor`), grouped like
// the estimates.
Truth ReadTruth(const fs::path& dataset, const std::string& sensor,
                const std::map<int, Model>& models,
                const std::optional<std::set<ImageKey>>& test_images) {
  Truth truth;
  const fs::path root = FindSceneFolder(dataset, sensor);
  for (const auto& scene_dir : fs::directory_iterator(root)) {
    const fs::path gt_file =
        scene_dir.path() / ("scene_gt" + (sensor.empty() ? "" : "_" + sensor) + ".json");
    if (!fs::exists(gt_file)) continue;
    const auto scene = ParseBopId(scene_dir.path().filename().string());
    if (!scene) continue;  // not a scene folder (BOP names them 000000, 000001, ...)
    for (const auto& [im, list] : ParseSceneGt(ReadFileText(gt_file), gt_file.string())) {
      const ImageKey key{*scene, im};
      if (test_images && !test_images->count(key)) continue;
      truth.images.insert(key);
      for (const BopGroundTruth& gt : list) {
        if (!models.count(gt.obj_id))
          throw Error(gt_file.string() + ": obj_id " + std::to_string(gt.obj_id) + " has no model");
        truth.instances.push_back({key, gt.obj_id, gt.cam_from_model});
      }
    }
  }
  return truth;
}

// Per ground-truth instance, the errors of the estimate matched to it (infinite: none).
struct Errors {
  std::vector<double> add_s, add_or_s, mssd;
};

// Match estimates to instances: per (image, object), best score first, each to the unmatched
// instance it is closest to (by ADD(-S)). Counts the estimates left over (or for other images)
// in `report`.
Errors Match(const Truth& truth, const std::map<int, Model>& models, const Estimates& estimates,
             EvalReport* report) {
  const std::vector<TruthInstance>& instances = truth.instances;
  std::map<std::pair<ImageKey, int>, std::vector<size_t>> groups;
  for (size_t i = 0; i < instances.size(); ++i)
    groups[{instances[i].image, instances[i].obj_id}].push_back(i);
  const double inf = std::numeric_limits<double>::infinity();
  Errors errors{std::vector<double>(instances.size(), inf),
                std::vector<double>(instances.size(), inf),
                std::vector<double>(instances.size(), inf)};
  std::vector<std::pair<std::pair<ImageKey, int>, std::vector<size_t>>> work(groups.begin(),
                                                                             groups.end());
  std::vector<int> surplus(work.size(), 0);
  tbb::parallel_for(size_t{0}, work.size(), [&](size_t g) {
    const auto& [key, members] = work[g];
    auto found = estimates.find(key);
    if (found == estimates.end()) return;
    std::vector<Estimate> list = found->second;
    std::stable_sort(list.begin(), list.end(),
                     [](const Estimate& a, const Estimate& b) { return a.score > b.score; });
    const Model& model = models.at(key.second);
    std::vector<bool> taken(members.size(), false);
    for (const Estimate& e : list) {
      int best = -1;
      double best_error = inf, best_add_s = inf;
      for (size_t m = 0; m < members.size(); ++m) {
        if (taken[m]) continue;
        const Eigen::Isometry3d& gt = instances[members[m]].pose;
        const double s = AddSError(model.points, e.pose, gt);
        const double err = model.symmetric ? s : AddError(model.points, e.pose, gt);
        if (err < best_error) best = static_cast<int>(m), best_error = err, best_add_s = s;
      }
      if (best < 0) {
        ++surplus[g];
        continue;
      }
      taken[best] = true;
      errors.add_or_s[members[best]] = best_error;
      errors.add_s[members[best]] = best_add_s;
      errors.mssd[members[best]] =
          MssdError(model.points, e.pose, instances[members[best]].pose, model.symmetry_poses);
    }
  });
  for (const auto& [key, list] : estimates) {
    if (truth.images.count(key.first) && !groups.count(key))
      report->unmatched_estimates += static_cast<int>(list.size());
    if (!truth.images.count(key.first)) report->ignored_estimates += static_cast<int>(list.size());
  }
  for (int s : surplus) report->unmatched_estimates += s;
  return errors;
}

// Scores per object and overall.
void ScoreAll(const std::map<int, Model>& models, const std::vector<TruthInstance>& truth,
              const Errors& errors, EvalReport* report) {
  std::vector<double> all_diam;
  for (const TruthInstance& t : truth) all_diam.push_back(models.at(t.obj_id).diameter);
  for (const auto& [obj, model] : models) {
    std::vector<double> a, b, m, d;
    for (size_t i = 0; i < truth.size(); ++i) {
      if (truth[i].obj_id != obj) continue;
      a.push_back(errors.add_s[i]), b.push_back(errors.add_or_s[i]), m.push_back(errors.mssd[i]);
      d.push_back(model.diameter);
    }
    if (a.empty()) continue;
    ObjectScores s;
    s.obj_id = obj;
    s.name = model.name;
    s.symmetric = model.symmetric;
    s.diameter_mm = model.diameter;
    Score(&s, a, b, m, d);
    report->objects.push_back(s);
  }
  report->overall.name = "all";
  Score(&report->overall, errors.add_s, errors.add_or_s, errors.mssd, all_diam);
}

}  // namespace

EvalReport Evaluate(const fs::path& dataset, const fs::path& results, const std::string& sensor) {
  if (!fs::is_directory(dataset)) throw Error(dataset.string() + ": no such dataset folder");
  const std::map<int, Model> models = ReadModels(dataset);
  const Estimates estimates = ReadResults(results);

  // Which images: splits/test.txt if present, else all.
  EvalReport report;
  std::optional<std::set<ImageKey>> test_images;
  const fs::path test_list = dataset / "splits" / "test.txt";
  if (fs::exists(test_list)) {
    test_images = ReadTestImages(test_list);
    report.images = "test split (" + test_list.string() + ")";
  } else {
    report.images = "all images (no splits/test.txt)";
  }

  const Truth truth = ReadTruth(dataset, sensor, models, test_images);
  report.image_count = static_cast<int>(truth.images.size());
  if (truth.instances.empty())
    throw Error(dataset.string() + ": no ground-truth instances to evaluate");
  const Errors errors = Match(truth, models, estimates, &report);
  ScoreAll(models, truth.instances, errors, &report);
  return report;
}

std::string EvalTable(const EvalReport& report) {
  std::ostringstream out;
  out << "evaluated: " << report.images << ", " << report.image_count << " images\n";
  out << std::left << std::setw(8) << "obj_id" << std::setw(22) << "name" << std::right
      << std::setw(5) << "sym" << std::setw(11) << "diam mm" << std::setw(11) << "found"
      << std::setw(13) << "ADD(-S) mm" << std::setw(10) << "<10% d" << std::setw(11) << "AUC ADD-S"
      << std::setw(13) << "AUC ADD(-S)" << std::setw(10) << "MSSD mm" << std::setw(9) << "AR MSSD"
      << "\n";
  const auto row = [&](const ObjectScores& s) {
    out << std::left << std::setw(8) << (s.obj_id ? std::to_string(s.obj_id) : "") << std::setw(22)
        << s.name << std::right << std::setw(5) << (s.obj_id ? (s.symmetric ? "yes" : "no") : "")
        << std::setw(11) << std::fixed << std::setprecision(1);
    if (s.obj_id) {
      out << s.diameter_mm;
    } else {
      out << "";
    }
    out << std::setw(11) << (std::to_string(s.estimated) + "/" + std::to_string(s.instances))
        << std::setw(13) << std::setprecision(2) << s.mean_error_mm << std::setw(9)
        << std::setprecision(1) << 100 * s.within_10pct << "%" << std::setw(10) << 100 * s.auc_adds
        << "%" << std::setw(12) << 100 * s.auc_add_or_s << "%" << std::setw(10)
        << std::setprecision(2) << s.mean_mssd_mm << std::setw(8) << std::setprecision(1)
        << 100 * s.ar_mssd << "%\n";
  };
  for (const ObjectScores& s : report.objects) row(s);
  row(report.overall);
  if (report.unmatched_estimates)
    out << report.unmatched_estimates << " estimates matched no ground-truth instance\n";
  if (report.ignored_estimates)
    out << report.ignored_estimates << " estimates for images outside the evaluated set ignored\n";
  return out.str();
}

std::string EvalJson(const EvalReport& report) {
  const auto scores = [](const ObjectScores& s) {
    Json j = {{"instances", s.instances},
              {"estimated", s.estimated},
              {"mean_error_mm", std::isfinite(s.mean_error_mm) ? Json(s.mean_error_mm) : Json()},
              {"within_10pct_diameter", s.within_10pct},
              {"auc_adds", s.auc_adds},
              {"auc_add_or_s", s.auc_add_or_s},
              {"mean_mssd_mm", std::isfinite(s.mean_mssd_mm) ? Json(s.mean_mssd_mm) : Json()},
              {"ar_mssd", s.ar_mssd}};
    if (s.obj_id) {
      j["obj_id"] = s.obj_id;
      j["name"] = s.name;
      j["symmetric"] = s.symmetric;
      j["diameter_mm"] = s.diameter_mm;
    }
    return j;
  };
  Json objects = Json::array();
  for (const ObjectScores& s : report.objects) objects.push_back(scores(s));
  return Json{{"images", report.images},
              {"image_count", report.image_count},
              {"unmatched_estimates", report.unmatched_estimates},
              {"ignored_estimates", report.ignored_estimates},
              {"auc_max_threshold_mm", kAucMaxMm},
              {"objects", objects},
              {"overall", scores(report.overall)}}
             .dump(2) +
         "\n";
}

void WriteEvalJson(const fs::path& path, const EvalReport& report) {
  WriteFileAtomic(path, EvalJson(report));
}

}  // namespace cadsynth
