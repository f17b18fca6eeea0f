#include "tools/pipeline/report.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <regex>
#include <set>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "cad/core/error.h"
#include "dataset/bop_read.h"
#include "dataset/file_io.h"
#include "dataset/manifest.h"
#include "dataset/preview.h"
#include "recipes/recipe.h"
#include "render/randomize.h"
#include "tools/pipeline/run_record.h"

extern char** environ;

namespace cadsynth {

namespace fs = std::filesystem;
using Json = nlohmann::json;

namespace {

constexpr double kDeg = 180.0 / std::numbers::pi;

// A histogram of `values` over [lo, hi] in `bins` equal bins (geometric ones with `log`, lo > 0).
Json Hist(const std::vector<double>& values, double lo, double hi, int bins,
          const std::string& label, bool log = false) {
  if (!(hi > lo)) hi = lo + 1;
  std::vector<double> edges(bins + 1);
  for (int k = 0; k <= bins; ++k) {
    const double f = static_cast<double>(k) / bins;
    edges[k] = log ? lo * std::pow(hi / lo, f) : lo + (hi - lo) * f;
  }
  std::vector<size_t> counts(bins, 0);
  for (double v : values) {
    if (!std::isfinite(v)) continue;
    const double f =
        log ? std::log(std::max(v, lo) / lo) / std::log(hi / lo) : (v - lo) / (hi - lo);
    counts[std::min(static_cast<int>(std::clamp(f, 0.0, 1.0) * bins), bins - 1)]++;
  }
  return {{"edges", edges}, {"counts", counts}, {"label", label}, {"log", log}};
}

// Over the values' own range (widened to whole numbers for counts).
Json AutoHist(const std::vector<double>& values, int bins, const std::string& label,
              bool whole = false) {
  if (values.empty()) return Hist({}, 0, 1, bins, label);
  auto [lo, hi] = std::minmax_element(values.begin(), values.end());
  double a = *lo, b = *hi;
  if (whole) {
    a -= 0.5, b += 0.5;
    bins = std::clamp(static_cast<int>(b - a), 1, bins);
  }
  if (b - a < 1e-9) a -= 0.5, b += 0.5;
  return Hist(values, a, b, bins, label);
}

Json ReadJson(const fs::path& path, const std::string& origin) {
  const std::string text = ReadFileText(path);
  try {
    return Json::parse(text);
  } catch (const Json::exception& e) {
    throw Error(JsonErrorMessage(origin, text, e));
  }
}

std::optional<Json> ReadJsonIfThere(const fs::path& root, const std::string& relative) {
  std::error_code ec;
  if (!fs::exists(root / relative, ec)) return std::nullopt;
  return ReadJson(root / relative, relative);
}

struct ObjectStats {
  int obj_id = 0;
  std::string name, symmetry = "none";
  double diameter = 0;
  Eigen::AlignedBox3d box;
  std::vector<Eigen::Isometry3d> symmetries{Eigen::Isometry3d::Identity()};
  size_t instances = 0, visible = 0, targets = 0;
  std::vector<double> azimuth, elevation, inplane, distance, visib_fract, px_visib;
};

// Among the poses the object cannot be told from (pose * S for each symmetry S), the one that
// puts the camera (at -R^T t in the model frame) nearest a fixed generic direction: each view
// lands in one fundamental region of the symmetry group, so the coverage map is folded.
void AddView(ObjectStats* o, const Eigen::Isometry3d& cam_from_model, double visib, size_t px) {
  static const Eigen::Vector3d kGeneric = Eigen::Vector3d(0.8, 0.5, 0.33).normalized();
  const Eigen::Vector3d camera = cam_from_model.inverse().translation();
  const Eigen::Isometry3d* best = &o->symmetries[0];
  double best_dot = -2;
  Eigen::Vector3d folded = camera;
  for (const Eigen::Isometry3d& s : o->symmetries) {
    const Eigen::Vector3d c = s.inverse() * camera;
    const double dot = c.normalized().dot(kGeneric);
    if (dot > best_dot + 1e-12) best_dot = dot, best = &s, folded = c;
  }
  const double r = folded.norm();
  if (r <= 0) return;
  o->azimuth.push_back(std::atan2(folded.y(), folded.x()) * kDeg);
  o->elevation.push_back(std::asin(std::clamp(folded.z() / r, -1.0, 1.0)) * kDeg);
  // In-plane rotation: the angle, about the line of sight, from the image's up (-y) to the
  // model's z axis (its x axis when z points along the line of sight), of the folded pose.
  const Eigen::Matrix3d rotation = cam_from_model.linear() * best->linear();
  const Eigen::Vector3d sight = cam_from_model.translation().normalized();
  const auto across = [&](const Eigen::Vector3d& a) { return a - a.dot(sight) * sight; };
  Eigen::Vector3d axis = across(rotation.col(2));
  if (axis.norm() < 0.2) axis = across(rotation.col(0));
  const Eigen::Vector3d up = across(Eigen::Vector3d(0, -1, 0));
  o->inplane.push_back(std::atan2(sight.dot(up.cross(axis)), up.dot(axis)) * kDeg);
  o->distance.push_back(cam_from_model.translation().norm());
  o->visib_fract.push_back(visib);
  o->px_visib.push_back(static_cast<double>(px));
}

struct ImageStats {
  int scene_id = 0, im_id = 0;
  int instances = 0, visible = 0;
  double occlusion = 0;              // mean 1 - visib_fract over instances
  double z_min = 0, z_max = 0;       // nearest / farthest model box corner of a visible instance
  size_t px_visible = 0;             // object pixels
  size_t smallest = 0, largest = 0;  // visible pixels of its least and most visible instance
};

struct SensorStats {
  std::string name, split;
  int width = 0, height = 0;
  std::vector<ImageStats> images;
};

// The symmetry text of a models_info entry: "discrete (36)", "continuous (z)", "none".
std::string SymmetryText(const Json& entry) {
  std::vector<std::string> parts;
  if (entry.contains("symmetries_discrete"))
    parts.push_back("discrete (" + std::to_string(entry["symmetries_discrete"].size()) + ")");
  if (entry.contains("symmetries_continuous")) {
    for (const Json& c : entry["symmetries_continuous"]) {
      const std::vector<double> a = c.at("axis");
      const char* name = std::abs(a.at(2)) > 0.99   ? "z"
                         : std::abs(a.at(1)) > 0.99 ? "y"
                         : std::abs(a.at(0)) > 0.99 ? "x"
                                                    : "axis";
      parts.push_back(std::string("continuous (") + name + ")");
    }
  }
  if (parts.empty()) return "none";
  std::string text = parts[0];
  for (size_t k = 1; k < parts.size(); ++k) text += ", " + parts[k];
  return text;
}

std::map<int, ObjectStats> ReadObjects(const fs::path& root) {
  const std::string origin = "models/models_info.json";
  const std::string text = ReadFileText(root / origin);
  const Json info = ReadJson(root / origin, origin);
  std::map<int, ObjectStats> objects;
  for (const BopModelInfo& m : ParseModelsInfo(text, origin)) {
    ObjectStats& o = objects[m.obj_id];
    o.obj_id = m.obj_id;
    o.diameter = m.diameter;
    o.name = "obj_" + std::to_string(m.obj_id);
    if (!m.symmetry_poses.empty()) o.symmetries = m.symmetry_poses;
    const Json& e = info.at(std::to_string(m.obj_id));
    o.symmetry = SymmetryText(e);
    const Eigen::Vector3d min(e.value("min_x", 0.0), e.value("min_y", 0.0), e.value("min_z", 0.0));
    const Eigen::Vector3d size(e.value("size_x", 0.0), e.value("size_y", 0.0),
                               e.value("size_z", 0.0));
    o.box = Eigen::AlignedBox3d(min, min + size);
  }
  if (const auto cad = ReadJsonIfThere(root, "models/models_cad.json")) {
    for (const auto& [key, value] : cad->items()) {
      const std::optional<int> id = ParseBopId(key);
      if (id && objects.count(*id) && value.contains("name"))
        objects[*id].name = value["name"].get<std::string>();
    }
  }
  return objects;
}

Eigen::Isometry3d Pose(const Json& g) {
  const std::vector<double> r = g.at("cam_R_m2c"), t = g.at("cam_t_m2c");
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  for (int a = 0; a < 9; ++a) pose.linear()(a / 3, a % 3) = r.at(a);
  pose.translation() = Eigen::Vector3d(t.at(0), t.at(1), t.at(2));
  return pose;
}

// The statistics of every image of every sensor, and each object's views (first sensor only:
// a rig's sensors see the same instances).
std::vector<SensorStats> ReadImages(const fs::path& root, std::map<int, ObjectStats>* objects) {
  std::map<std::string, SensorStats> sensors;
  std::string first_sensor;
  bool any = false;
  for (const BopSceneFolder& scene : FindBopScenes(root)) {
    const std::string s = scene.suffix + ".json";
    if (!any) first_sensor = scene.suffix, any = true;
    SensorStats& stats = sensors[scene.suffix];
    stats.name = scene.suffix.empty() ? "" : scene.suffix.substr(1);
    if (stats.split.empty()) stats.split = scene.split;
    const std::string gt_rel = scene.Relative("scene_gt" + s);
    const std::string info_rel = scene.Relative("scene_gt_info" + s);
    const Json gt = ReadJson(root / gt_rel, gt_rel), info = ReadJson(root / info_rel, info_rel);
    try {
      for (const auto& [key, instances] : gt.items()) {
        const std::optional<int> id = ParseBopId(key);
        if (!id) throw Error(gt_rel + ": \"" + key + "\" is not an image id");
        ImageStats image;
        image.scene_id = scene.scene_id;
        image.im_id = *id;
        const Json& infos = info.at(key);
        double occlusion = 0;
        bool seen = false;
        for (size_t i = 0; i < instances.size(); ++i) {
          const Json& g = instances[i];
          const Json& gi = infos.at(i);
          const int obj_id = g.at("obj_id");
          const double visib = gi.at("visib_fract");
          const size_t px = gi.at("px_count_visib");
          const Eigen::Isometry3d pose = Pose(g);
          ++image.instances;
          occlusion += 1 - visib;
          const auto object = objects->find(obj_id);
          if (px > 0) {
            ++image.visible;
            image.px_visible += px;
            image.smallest = image.visible == 1 ? px : std::min(image.smallest, px);
            image.largest = std::max(image.largest, px);
            if (object != objects->end()) {
              for (int c = 0; c < 8; ++c) {
                const double z = (pose * object->second.box.corner(
                                             static_cast<Eigen::AlignedBox3d::CornerType>(c)))
                                     .z();
                image.z_min = seen ? std::min(image.z_min, z) : z;
                image.z_max = seen ? std::max(image.z_max, z) : z;
                seen = true;
              }
            }
          }
          if (scene.suffix == first_sensor && object != objects->end()) {
            ++object->second.instances;
            if (px > 0) {
              ++object->second.visible;
              AddView(&object->second, pose, visib, px);
            }
          }
        }
        if (image.instances > 0) image.occlusion = occlusion / image.instances;
        stats.images.push_back(image);
      }
    } catch (const Json::exception& e) {
      throw Error(JsonErrorMessage(gt_rel + " / " + info_rel, "", e));
    }
  }
  std::vector<SensorStats> out;
  for (auto& [suffix, stats] : sensors) {
    if (const auto camera = ReadJsonIfThere(root, "camera" + suffix + ".json")) {
      stats.width = camera->value("width", 0);
      stats.height = camera->value("height", 0);
    }
    std::sort(stats.images.begin(), stats.images.end(), [](const auto& a, const auto& b) {
      return std::tie(a.scene_id, a.im_id) < std::tie(b.scene_id, b.im_id);
    });
    out.push_back(std::move(stats));
  }
  // The first sensor first: the objects' views are its.
  std::stable_partition(out.begin(), out.end(), [&](const SensorStats& s) {
    return (s.name.empty() ? "" : "_" + s.name) == first_sensor;
  });
  return out;
}

Json SensorJson(const SensorStats& s, int sparse_percent) {
  std::vector<double> instances, visible, occlusion, z_min, z_max;
  size_t empty = 0, sparse = 0;
  Json examples = Json::array();
  const size_t threshold =
      static_cast<size_t>(static_cast<double>(s.width) * s.height * sparse_percent / 100.0);
  for (const ImageStats& im : s.images) {
    instances.push_back(im.instances);
    visible.push_back(im.visible);
    if (im.instances > 0) occlusion.push_back(im.occlusion);
    if (im.visible > 0) z_min.push_back(im.z_min), z_max.push_back(im.z_max);
    if (im.visible == 0) {
      ++empty;
      if (examples.size() < 50)
        examples.push_back("scene " + std::to_string(im.scene_id) + " image " +
                           std::to_string(im.im_id));
    } else if (im.px_visible < threshold) {
      ++sparse;
    }
  }
  // Nearest and farthest share their edges, so the two can be compared.
  std::vector<double> both = z_min;
  both.insert(both.end(), z_max.begin(), z_max.end());
  double lo = 0, hi = 1;
  if (!both.empty()) {
    lo = *std::min_element(both.begin(), both.end());
    hi = *std::max_element(both.begin(), both.end());
  }
  return {
      {"name", s.name},
      {"images", s.images.size()},
      {"width", s.width},
      {"height", s.height},
      {"instances_per_image", AutoHist(instances, 40, "instances per image", true)},
      {"visible_instances_per_image", AutoHist(visible, 40, "visible instances per image", true)},
      {"occlusion_per_image", Hist(occlusion, 0, 1, 20, "mean occluded fraction per image")},
      {"depth_min_mm", Hist(z_min, lo, hi, 30, "nearest object depth (mm, model boxes)")},
      {"depth_max_mm", Hist(z_max, lo, hi, 30, "farthest object depth (mm, model boxes)")},
      {"empty_images", empty},
      {"sparse_images", sparse},
      {"sparse_threshold_px", threshold},
      {"empty_examples", examples}};
}

Json ObjectJson(const ObjectStats& o, int image_pixels) {
  Json coverage = {{"x_label", "azimuth of the camera (deg, model frame, folded)"},
                   {"y_label", "elevation (deg)"}};
  constexpr int kAz = 36, kEl = 18;
  std::vector<double> x_edges(kAz + 1), y_edges(kEl + 1);
  for (int k = 0; k <= kAz; ++k) x_edges[k] = -180.0 + 360.0 * k / kAz;
  for (int k = 0; k <= kEl; ++k) y_edges[k] = -90.0 + 180.0 * k / kEl;
  std::vector<std::vector<size_t>> counts(kEl, std::vector<size_t>(kAz, 0));
  for (size_t k = 0; k < o.azimuth.size(); ++k) {
    const int x = std::clamp(static_cast<int>((o.azimuth[k] + 180.0) / 360.0 * kAz), 0, kAz - 1);
    const int y = std::clamp(static_cast<int>((o.elevation[k] + 90.0) / 180.0 * kEl), 0, kEl - 1);
    ++counts[y][x];
  }
  coverage["x_edges"] = x_edges;
  coverage["y_edges"] = y_edges;
  coverage["counts"] = counts;
  return {{"obj_id", o.obj_id},
          {"name", o.name},
          {"diameter_mm", o.diameter},
          {"symmetry", o.symmetry},
          {"instances", o.instances},
          {"visible", o.visible},
          {"targets", o.targets},
          {"coverage", coverage},
          {"inplane_deg", Hist(o.inplane, -180, 180, 36, "in-plane rotation (deg)")},
          {"distance_mm", AutoHist(o.distance, 30, "distance (mm)")},
          {"visib_fract", Hist(o.visib_fract, 0, 1, 20, "visible fraction")},
          {"px_count_visib",
           Hist(o.px_visib, 1, std::max(2, image_pixels), 30, "visible pixels", true)}};
}

// What the recipe asked for one randomised quantity (a folded draw key, "part.*.roughness"): a
// number's distribution, or names picked equally likely, drawn per frame or once per scene.
struct AskedDraw {
  std::string text;                    // as a recipe writes it
  std::optional<Distribution> number;  // a number's distribution
  std::vector<std::string> names;      // or the names picked from
  bool per_scene = false;
  bool operator==(const AskedDraw&) const = default;
};
// Per folded key, the distinct things asked (several where rules or scenes differ).
using AskedDraws = std::map<std::string, std::vector<AskedDraw>>;

void AddAsked(AskedDraws* asked, const std::string& key, AskedDraw a) {
  std::vector<AskedDraw>& list = (*asked)[key];
  if (std::find(list.begin(), list.end(), a) == list.end()) list.push_back(std::move(a));
}

AskedDraw AskedNumber(const Distribution& d, bool per_scene) {
  return {d.Text(), d, {}, per_scene};
}

AskedDraw AskedNames(const std::vector<std::string>& names, bool per_scene) {
  std::string text = "{choice: [";
  for (size_t i = 0; i < names.size(); ++i) text += (i ? ", " : "") + names[i];
  return {text + "]}", std::nullopt, names, per_scene};
}

// A material randomisation's keys under `prefix` ("part.*", "floor", "fixture.*").
void AddAskedMaterial(AskedDraws* asked, const std::string& prefix, const MaterialRandomization& m,
                      bool per_scene) {
  if (!m.preset_names.empty())
    AddAsked(asked, prefix + ".preset", AskedNames(m.preset_names, per_scene));
  if (!m.texture_names.empty())
    AddAsked(asked, prefix + ".texture", AskedNames(m.texture_names, per_scene));
  const std::pair<const char*, const std::optional<Distribution>*> numbers[] = {
      {"hue", &m.hue},
      {"saturation", &m.saturation},
      {"value", &m.value},
      {"metallic", &m.metallic},
      {"roughness", &m.roughness},
      {"specular", &m.specular},
      {"texture_scale", &m.texture_scale}};
  for (const auto& [name, d] : numbers) {
    if (*d) AddAsked(asked, prefix + "." + name, AskedNumber(**d, per_scene));
  }
}

// The draw keys (folded as RandomizationJson folds them) of one scene's randomisation, with what
// the recipe asked for each: render/randomize.cpp names them as it draws.
void AddAskedScene(AskedDraws* asked, const RandomizeSpec& spec) {
  const Randomization& r = spec.draws;
  const auto scene = [](DrawPer per) { return per == DrawPer::kScene; };
  for (const PartRandomization& p : r.parts)
    AddAskedMaterial(asked, p.per_instance ? "instance.*" : "part.*", p.material, scene(p.per));
  if (r.floor) AddAskedMaterial(asked, "floor", *r.floor, scene(r.floor_per));
  if (r.fixtures) AddAskedMaterial(asked, "fixture.*", *r.fixtures, scene(r.fixtures_per));
  if (r.lights) {
    const LightRandomization& l = *r.lights;
    const bool per = scene(r.lights_per);
    AddAsked(asked, "light.count", AskedNumber(l.count, per));
    std::vector<std::string> kinds;
    for (LightSource::Kind k : l.kinds) kinds.push_back(LightKindName(k));
    AddAsked(asked, "light.*.type", AskedNames(kinds, per));
    const std::pair<const char*, const Distribution*> numbers[] = {
        {"elevation", &l.elevation_deg},   {"azimuth", &l.azimuth_deg},
        {"distance", &l.distance_mm},      {"power", &l.power},
        {"temperature", &l.temperature_k}, {"size", &l.size_mm}};
    for (const auto& [name, d] : numbers)
      AddAsked(asked, std::string("light.*.") + name, AskedNumber(*d, per));
  }
  if (r.environment) {
    const EnvironmentRandomization& e = *r.environment;
    const bool per = scene(r.environment_per);
    if (e.images) AddAsked(asked, "environment.image", AskedNames(e.images->names, per));
    if (e.strength) AddAsked(asked, "environment.strength", AskedNumber(*e.strength, per));
    if (e.rotation_deg) AddAsked(asked, "environment.rotation", AskedNumber(*e.rotation_deg, per));
    if (e.temperature_k)
      AddAsked(asked, "environment.temperature", AskedNumber(*e.temperature_k, per));
  }
  if (r.background)
    AddAsked(asked, "background", AskedNames(r.background->images.names, scene(r.background_per)));
  if (r.camera) {
    const CameraRandomization& c = *r.camera;
    const std::pair<const char*, const std::optional<Distribution>*> numbers[] = {
        {"exposure", &c.exposure},
        {"white_balance", &c.white_balance_k},
        {"noise_gain", &c.noise_gain},
        {"focus_distance", &c.focus_distance_mm},
        {"f_number", &c.f_number},
        {"rotation[0]", &c.rotation_deg},  // recorded with its axis: [angle, x, y, z]
        {"translation[0]", &c.translation_mm}};
    for (const auto& [name, d] : numbers) {
      if (*d) AddAsked(asked, std::string("camera.") + name, AskedNumber(**d, false));
    }
  }
  if (r.distractors) {
    const DistractorRandomization& d = *r.distractors;
    AddAsked(asked, "distractor.count", AskedNumber(d.count, true));
    AddAsked(asked, "distractor.*.size[0]", AskedNumber(d.size_mm, true));
    if (d.material) AddAskedMaterial(asked, "distractor.*", *d.material, scene(d.material_per));
  }
}

// What the dataset's recipe (run.json's text, read again) asked for each randomised quantity;
// empty without a recipe or a randomisation. `note` says why when the recipe cannot be read again
// (a file it names is gone).
AskedDraws ReadAsked(const fs::path& root, std::string* note) {
  AskedDraws asked;
  const std::optional<RunRecord> run = ReadRunRecord(root);
  if (!run || run->recipe_text.empty()) return asked;
  try {
    const fs::path path = run->recipe_path;
    const RunSpec spec = ParseRecipe(run->recipe_text, path.string(), path.parent_path());
    for (const SceneSpec& scene : spec.scenes)
      AddAskedScene(&asked, scene.randomize ? *scene.randomize : spec.randomize);
    if (spec.scenes.empty()) AddAskedScene(&asked, spec.randomize);
  } catch (const Error& e) {
    *note = std::string(
                "the recipe in run.json could not be read again, so the draws are not "
                "compared with it: ") +
            e.what();
    asked.clear();
  }
  return asked;
}

// The regularised upper incomplete gamma function Q(a, x) (a series below a + 1, Lentz's
// continued fraction above): the chi-square test's p-value is Q(dof / 2, statistic / 2).
double GammaQ(double a, double x) {
  if (x <= 0) return 1.0;
  const double front = std::exp(-x + a * std::log(x) - std::lgamma(a));
  if (x < a + 1) {
    double term = 1 / a, sum = term;
    for (int n = 1; n < 1000 && std::abs(term) > std::abs(sum) * 1e-15; ++n) {
      term *= x / (a + n);
      sum += term;
    }
    return std::clamp(1 - sum * front, 0.0, 1.0);
  }
  constexpr double kTiny = 1e-300;
  double b = x + 1 - a, c = 1 / kTiny, d = 1 / b, h = d;
  for (int i = 1; i < 1000; ++i) {
    const double an = -i * (i - a);
    b += 2;
    d = an * d + b;
    d = std::abs(d) < kTiny ? kTiny : d;
    c = b + an / c;
    c = std::abs(c) < kTiny ? kTiny : c;
    d = 1 / d;
    h *= d * c;
    if (std::abs(d * c - 1) < 1e-15) break;
  }
  return std::clamp(front * h, 0.0, 1.0);
}

// The Kolmogorov-Smirnov test's p-value for statistic D on n samples (Stephens' correction of
// the asymptotic Kolmogorov distribution, good from n = 5 on).
double KolmogorovP(double d, size_t n) {
  const double sn = std::sqrt(static_cast<double>(n));
  const double lambda = (sn + 0.12 + 0.11 / sn) * d;
  if (lambda < 0.2) return 1.0;
  double sum = 0, sign = 1;
  for (int j = 1; j <= 100; ++j, sign = -sign) {
    const double term = sign * 2 * std::exp(-2.0 * j * j * lambda * lambda);
    sum += term;
    if (std::abs(term) < 1e-12) break;
  }
  return std::clamp(sum, 0.0, 1.0);
}

// P(X < x) for a number's distribution (a choice: the share of its values below x).
double CdfBelow(const Distribution& d, double x) {
  using Kind = Distribution::Kind;
  switch (d.kind) {
    case Kind::kFixed:
      return x > d.a ? 1.0 : 0.0;
    case Kind::kUniform:
      return d.b > d.a ? std::clamp((x - d.a) / (d.b - d.a), 0.0, 1.0) : (x > d.a ? 1.0 : 0.0);
    case Kind::kLogUniform:
      return x <= d.a ? 0.0 : std::clamp(std::log(x / d.a) / std::log(d.b / d.a), 0.0, 1.0);
    case Kind::kNormal:
      return d.b > 0 ? 0.5 * std::erfc(-(x - d.a) / (d.b * std::numbers::sqrt2))
                     : (x > d.a ? 1.0 : 0.0);
    case Kind::kChoice: {
      if (d.values.empty()) return 0.0;
      const auto below =
          std::count_if(d.values.begin(), d.values.end(), [&](double v) { return v < x; });
      return static_cast<double>(below) / static_cast<double>(d.values.size());
    }
  }
  return 0.0;
}

// A goodness-of-fit test of the draws against what was asked: Kolmogorov-Smirnov for a
// continuous distribution, chi-square for a choice (of numbers or names), equality for a fixed
// value. Draws agree with the recipe unless p < 0.001 (draws are seeded, so a check that passes
// passes every time). Null when nothing was asked or nothing was drawn.
constexpr double kAgreeP = 1e-3;

Json CheckAgainst(const AskedDraw& asked, std::vector<double> numbers,
                  const std::map<std::string, size_t>& names) {
  Json check;
  const auto result = [&](const char* test, double statistic, double p, size_t n) {
    check = {{"test", test},
             {"statistic", statistic},
             {"p_value", p},
             {"samples", n},
             {"agrees", p >= kAgreeP}};
  };
  const auto chi_square = [&](const std::vector<double>& counts, size_t n) {
    const double expected = static_cast<double>(n) / static_cast<double>(counts.size());
    double x2 = 0;
    for (double c : counts) x2 += (c - expected) * (c - expected) / expected;
    result("chi-square", x2, counts.size() < 2 ? 1.0 : GammaQ(0.5 * (counts.size() - 1), 0.5 * x2),
           n);
  };
  if (!asked.names.empty()) {
    size_t n = 0, other = 0;
    std::vector<double> counts;
    for (const std::string& name : asked.names) {
      const auto it = names.find(name);
      counts.push_back(it == names.end() ? 0.0 : static_cast<double>(it->second));
    }
    for (const auto& [name, c] : names) {
      n += c;
      if (std::find(asked.names.begin(), asked.names.end(), name) == asked.names.end()) other += c;
    }
    if (n == 0) return nullptr;
    if (other > 0)
      result("chi-square", std::numeric_limits<double>::infinity(), 0.0, n);
    else
      chi_square(counts, n);
    return check;
  }
  if (!asked.number || numbers.empty()) return nullptr;
  const Distribution& d = *asked.number;
  const size_t n = numbers.size();
  if (d.kind == Distribution::Kind::kFixed) {
    const bool all = std::all_of(numbers.begin(), numbers.end(), [&](double v) {
      return std::abs(v - d.a) <= 1e-9 * std::max(1.0, std::abs(d.a));
    });
    result("equality", all ? 0.0 : 1.0, all ? 1.0 : 0.0, n);
  } else if (d.kind == Distribution::Kind::kChoice) {
    std::vector<double> counts(d.values.size(), 0.0);
    size_t other = 0;
    for (double v : numbers) {
      const auto it = std::find_if(d.values.begin(), d.values.end(), [&](double c) {
        return std::abs(v - c) <= 1e-9 * std::max(1.0, std::abs(c));
      });
      if (it == d.values.end())
        ++other;
      else
        ++counts[static_cast<size_t>(it - d.values.begin())];
    }
    if (other > 0)
      result("chi-square", std::numeric_limits<double>::infinity(), 0.0, n);
    else
      chi_square(counts, n);
  } else {
    std::sort(numbers.begin(), numbers.end());
    double dmax = 0;
    for (size_t i = 0; i < n; ++i) {
      const double f = CdfBelow(d, std::nextafter(numbers[i], HUGE_VAL));
      dmax = std::max({dmax, f - static_cast<double>(i) / n, static_cast<double>(i + 1) / n - f});
    }
    result("Kolmogorov-Smirnov", dmax, KolmogorovP(dmax, n), n);
  }
  return check;
}

// Expected counts in a histogram's bins ([e_k, e_k+1), the last closed) for n draws of `d`.
std::vector<double> ExpectedCounts(const Distribution& d, const Json& hist, size_t n) {
  const std::vector<double> edges = hist.at("edges").get<std::vector<double>>();
  std::vector<double> out;
  for (size_t k = 0; k + 1 < edges.size(); ++k) {
    const double hi = k + 2 == edges.size() ? std::nextafter(edges[k + 1], HUGE_VAL) : edges[k + 1];
    out.push_back(static_cast<double>(n) * (CdfBelow(d, hi) - CdfBelow(d, edges[k])));
  }
  return out;
}

// A histogram of a quantity's draws over their range and, where the recipe asked for a
// distribution, over its support too (a normal's mean +- 4 sigma; a choice's values, a bin each
// when they are whole numbers), so that a part of the asked range never drawn shows.
Json DrawHist(const std::vector<double>& values, const std::string& key, const AskedDraw* asked) {
  if (asked == nullptr || !asked->number || values.empty()) return AutoHist(values, 20, key);
  const Distribution& d = *asked->number;
  auto [lo, hi] = std::minmax_element(values.begin(), values.end());
  double a = *lo, b = *hi;
  int bins = 20;
  if (d.kind == Distribution::Kind::kNormal) {
    a = std::min(a, d.a - 4 * d.b), b = std::max(b, d.a + 4 * d.b);
  } else if (d.kind == Distribution::Kind::kChoice && !d.values.empty()) {
    const auto [vlo, vhi] = std::minmax_element(d.values.begin(), d.values.end());
    a = std::min(a, *vlo), b = std::max(b, *vhi);
    const bool whole =
        std::all_of(d.values.begin(), d.values.end(), [](double v) { return v == std::round(v); });
    if (whole && b - a < 20) a -= 0.5, b += 0.5, bins = static_cast<int>(b - a);
  } else {
    a = std::min(a, d.Lowest()), b = std::max(b, d.Highest());
  }
  if (b - a < 1e-9) a -= 0.5, b += 0.5;
  return Hist(values, a, b, bins, key);
}

// scene_randomization*.json of the first sensor: each drawn key with its index ("part.3.hue")
// folded to "part.*.hue"; numbers as histograms, anything else as choices. With what the recipe
// asked (ReadAsked), a quantity drawn once per scene is counted once per scene, and the draws are
// tested against it (CheckAgainst) and the expected counts given beside the drawn ones.
Json RandomizationJson(const fs::path& root, const std::string& suffix, std::string* note) {
  const AskedDraws asked = ReadAsked(root, note);
  const auto asked_of = [&](const std::string& key) -> const AskedDraw* {
    const auto it = asked.find(key);
    return it != asked.end() && it->second.size() == 1 ? &it->second[0] : nullptr;
  };
  std::map<std::string, std::vector<double>> numbers;
  std::map<std::string, std::map<std::string, size_t>> choices;
  static const std::regex index(R"(\.\d+(?=\.|$))");
  for (const BopSceneFolder& scene : FindBopScenes(root)) {
    if (scene.suffix != suffix) continue;
    const auto draws =
        ReadJsonIfThere(root, scene.Relative("scene_randomization" + suffix + ".json"));
    if (!draws) continue;
    bool first = true;
    for (const auto& [im, record] : draws->items()) {
      if (!record.is_object()) continue;
      for (const auto& [key, value] : record.items()) {
        const std::string folded = std::regex_replace(key, index, ".*");
        // A list's first value (a one-value list is written as a number: a sphere's one size
        // among boxes' three).
        const bool listed = value.is_array() || (value.is_number() && !asked.count(folded) &&
                                                 asked.count(folded + "[0]"));
        const std::string name = listed ? folded + "[0]" : folded;
        const AskedDraw* a = asked_of(name);
        if (!first && a != nullptr && a->per_scene) continue;  // the scene's one draw
        if (value.is_number()) {
          numbers[name].push_back(value.get<double>());
        } else if (value.is_array() && !value.empty() && value[0].is_number()) {
          numbers[name].push_back(value[0].get<double>());
        } else if (value.is_string()) {
          ++choices[folded][value.get<std::string>()];
        } else if (value.is_boolean()) {
          ++choices[folded][value.get<bool>() ? "true" : "false"];
        }
      }
      first = false;
    }
  }
  const auto asked_text = [&](const std::string& key) -> Json {
    const auto it = asked.find(key);
    if (it == asked.end()) return nullptr;
    std::string text;
    for (const AskedDraw& a : it->second) text += (text.empty() ? "" : " or ") + a.text;
    return text;
  };
  const auto per = [&](const std::string& key) -> Json {
    const AskedDraw* a = asked_of(key);
    return a == nullptr ? Json(nullptr) : Json(a->per_scene ? "scene" : "frame");
  };
  Json out = Json::array();
  for (const auto& [key, values] : numbers) {
    if (choices.count(key)) continue;
    Json entry = {{"key", key},
                  {"kind", "number"},
                  {"hist", DrawHist(values, key, asked_of(key))},
                  {"asked", asked_text(key)},
                  {"per", per(key)},
                  {"samples", values.size()},
                  {"check", nullptr},
                  {"expected", nullptr}};
    if (const AskedDraw* a = asked_of(key)) {
      entry["check"] = CheckAgainst(*a, values, {});
      if (a->number) entry["expected"] = ExpectedCounts(*a->number, entry["hist"], values.size());
    }
    out.push_back(std::move(entry));
  }
  for (auto [key, counts] : choices) {
    size_t n = 0;
    for (const auto& [name, c] : counts) n += c;
    Json entry = {{"key", key},   {"kind", "choice"}, {"asked", asked_text(key)}, {"per", per(key)},
                  {"samples", n}, {"check", nullptr}, {"expected", nullptr}};
    if (const AskedDraw* a = asked_of(key); a != nullptr && !a->names.empty()) {
      entry["check"] = CheckAgainst(*a, {}, counts);
      for (const std::string& name : a->names) counts.emplace(name, 0);  // never drawn: 0
      Json expected = Json::object();
      for (const auto& [name, c] : counts) {
        const bool listed = std::find(a->names.begin(), a->names.end(), name) != a->names.end();
        expected[name] = listed ? static_cast<double>(n) / a->names.size() : 0.0;
      }
      entry["expected"] = expected;
    }
    entry["counts"] = counts;
    out.push_back(std::move(entry));
  }
  return out;
}

// The row count of a 2-D float32 .npy file and its rows (numpy's format 1.0 / 2.0 header).
std::vector<std::vector<float>> ReadNpyRows(const fs::path& path) {
  const std::string bytes = ReadFileText(path);
  if (bytes.size() < 12 || bytes.compare(0, 6, "\x93NUMPY") != 0)
    throw Error(path.string() + ": not a .npy file");
  const bool v1 = bytes[6] == 1;
  const size_t header_len = v1 ? static_cast<uint8_t>(bytes[8]) | static_cast<uint8_t>(bytes[9])
                                                                      << 8
                               : static_cast<size_t>(static_cast<uint8_t>(bytes[8])) |
                                     static_cast<size_t>(static_cast<uint8_t>(bytes[9])) << 8 |
                                     static_cast<size_t>(static_cast<uint8_t>(bytes[10])) << 16;
  const size_t start = (v1 ? 10 : 12) + header_len;
  const std::string header = bytes.substr(v1 ? 10 : 12, header_len);
  static const std::regex shape(R"('shape':\s*\((\d+),\s*(\d+)\))");
  std::smatch m;
  if (header.find("'<f4'") == std::string::npos || !std::regex_search(header, m, shape))
    throw Error(path.string() + ": expected a 2-D float32 array");
  const size_t rows = std::stoul(m[1]), cols = std::stoul(m[2]);
  if (bytes.size() < start + rows * cols * 4) throw Error(path.string() + ": truncated");
  std::vector<std::vector<float>> out(rows, std::vector<float>(cols));
  for (size_t r = 0; r < rows && cols > 0; ++r)
    std::memcpy(out[r].data(), bytes.data() + start + r * cols * 4, cols * 4);
  return out;
}

// graspnet/ and suctionnet/ labels: per object the free grasps (approach not blocked) over all
// frames, and per frame their count.
Json GraspsJson(const fs::path& root) {
  std::error_code ec;
  const bool jaw = fs::is_directory(root / "graspnet", ec),
             cup = fs::is_directory(root / "suctionnet", ec);
  if (!jaw && !cup) return nullptr;
  std::map<int, std::array<size_t, 2>> per_object;
  std::array<std::vector<double>, 2> per_frame;
  const char* folders[2] = {"graspnet", "suctionnet"};
  for (int kind = 0; kind < 2; ++kind) {
    const fs::path folder = root / folders[kind];
    if (!fs::is_directory(folder, ec)) continue;
    std::vector<fs::path> files;
    for (const auto& e : fs::recursive_directory_iterator(folder, ec)) {
      if (e.path().string().ends_with("_labels.npy")) files.push_back(e.path());
    }
    std::sort(files.begin(), files.end());
    for (const fs::path& file : files) {
      size_t free = 0;
      for (const std::vector<float>& row : ReadNpyRows(file)) {
        if (row.size() < 3 || row[2] != 0) continue;  // instance, obj_id, approach blocked
        ++free;
        ++per_object[static_cast<int>(row[1])][kind];
      }
      per_frame[kind].push_back(static_cast<double>(free));
    }
  }
  Json objects = Json::array();
  for (const auto& [obj_id, n] : per_object)
    objects.push_back({{"obj_id", obj_id}, {"parallel_jaw", n[0]}, {"suction", n[1]}});
  return {{"per_object", objects},
          {"per_frame",
           {{"parallel_jaw", AutoHist(per_frame[0], 30, "free parallel-jaw grasps per frame")},
            {"suction", AutoHist(per_frame[1], 30, "free suction grasps per frame")}}}};
}

// Median of `v` (0 when empty).
double Median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Physics: how piles and dropped parts came to rest (scene_physics.json, a row per scene, with a
// summary), and pick sequences (scene_sequence.json, a row per step). Null when there are none.
Json PhysicsJson(const fs::path& root) {
  constexpr size_t kListed = 200;  // rows per table (piles not at rest first)
  Json rest_rows = Json::array(), moving_rows = Json::array(), step_rows = Json::array();
  std::vector<double> settle;
  size_t piles = 0, at_rest = 0, removed = 0, kept = 0;
  std::set<std::pair<std::string, int>> done;
  std::map<int, Json> shape_rows;  // by obj_id: the shape it was simulated as (one per run)
  for (const BopSceneFolder& scene : FindBopScenes(root)) {
    if (!done.insert({scene.split, scene.scene_id}).second) continue;
    if (const auto rest = ReadJsonIfThere(root, scene.Relative("scene_physics.json"))) {
      ++piles;
      for (const Json& shape : rest->value("collision_shapes", Json::array())) {
        const int pieces = shape.value("pieces", 0);
        const double ratio = shape.value("volume_ratio", 0.0);
        shape_rows.emplace(
            shape.value("obj_id", 0),
            Json{shape.value("obj_id", 0),
                 shape.value("decomposed", false) ? std::to_string(pieces) + " convex pieces"
                                                  : std::string("its convex hull"),
                 ratio > 0 ? Json(std::round(ratio * 1000) / 1000) : Json("unknown (open mesh)"),
                 shape.value("timed_out", false) ? "yes: the hull instead" : "no"});
      }
      const bool still = rest->value("at_rest", true);
      at_rest += still ? 1 : 0;
      const double seconds = rest->value("settle_seconds", 0.0);
      settle.push_back(seconds);
      removed += rest->value("removed_outside", 0);
      kept += rest->value("kept_outside", Json::array()).size();
      Json row = {scene.scene_id,
                  rest->value("kind", ""),
                  rest->value("parts_dropped", 0),
                  still ? "yes" : "no",
                  seconds,
                  rest->value("settle_time", 0.0),
                  rest->value("restless", Json::array()).size(),
                  rest->value("removed_outside", 0),
                  rest->value("kept_outside", Json::array()).size(),
                  rest->value("distractors", 0)};
      (still ? rest_rows : moving_rows).push_back(std::move(row));
    }
    const auto step = ReadJsonIfThere(root, scene.Relative("scene_sequence.json"));
    if (!step) continue;
    size_t freed = 0;
    double moved = 0;
    for (const Json& i : step->value("instances", Json::array())) {
      freed += i.value("freed", false) ? 1 : 0;
      moved = std::max(moved, i.value("moved_mm", 0.0));
    }
    const Json pick = step->value("pick", Json());
    step_rows.push_back(
        {scene.scene_id, step->value("step", 0), pick.is_object() ? pick.value("obj_id", 0) : 0,
         pick.is_object() ? pick.value("settle_seconds", 0.0) : 0.0,
         pick.is_object() ? pick.value("restless", Json::array()).size() : 0, freed, moved});
  }
  if (piles == 0 && step_rows.empty()) return nullptr;
  Json tables = Json::array();
  if (piles > 0) {
    Json rows = moving_rows;
    for (Json& r : rest_rows) rows.push_back(std::move(r));
    const size_t total = rows.size();
    if (rows.size() > kListed) rows.erase(rows.begin() + kListed, rows.end());
    char summary[300];
    std::snprintf(summary, sizeof summary,
                  "%zu of %zu piles and drops at rest; simulated settle time median %.2f s, "
                  "longest %.2f s; %zu parts taken out (outside the container), %zu kept outside",
                  at_rest, piles, Median(settle), *std::max_element(settle.begin(), settle.end()),
                  removed, kept);
    tables.push_back({{"title", "Piles and dropped parts"},
                      {"summary", summary},
                      {"columns",
                       {"scene", "kind", "parts dropped", "at rest", "settle time (s, simulated)",
                        "settle_time (s)", "still moving", "taken out (outside)", "kept outside",
                        "distractors"}},
                      {"rows", rows},
                      {"more", total - rows.size()},
                      {"settle_seconds", AutoHist(settle, 20, "simulated settle time (s)")}});
  }
  if (!shape_rows.empty()) {
    Json rows = Json::array();
    for (auto& [obj_id, row] : shape_rows) rows.push_back(std::move(row));
    tables.push_back(
        {{"title", "Collision shapes"},
         {"summary",
          "what each object was simulated as; the volume of its pieces over its own volume is the "
          "shape's quality: 1 is exact, above 1 the pieces fill concavities (parts lie on air "
          "there)"},
         {"columns",
          {"obj_id", "simulated as", "pieces' volume / part's", "decomposition out of time"}},
         {"rows", rows},
         {"more", 0}});
  }
  if (!step_rows.empty()) {
    const size_t total = step_rows.size();
    if (step_rows.size() > kListed) step_rows.erase(step_rows.begin() + kListed, step_rows.end());
    tables.push_back({{"title", "Pick sequences"},
                      {"columns",
                       {"scene", "step", "picked obj_id", "settle time (s, simulated)",
                        "still moving", "freed by the pick", "largest move (mm)"}},
                      {"rows", step_rows},
                      {"more", total - step_rows.size()}});
  }
  return {{"tables", tables}};
}

std::string Base64(const std::string& bytes) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (size_t i = 0; i < bytes.size(); i += 3) {
    uint32_t n = static_cast<uint8_t>(bytes[i]) << 16;
    if (i + 1 < bytes.size()) n |= static_cast<uint8_t>(bytes[i + 1]) << 8;
    if (i + 2 < bytes.size()) n |= static_cast<uint8_t>(bytes[i + 2]);
    out += kAlphabet[(n >> 18) & 63];
    out += kAlphabet[(n >> 12) & 63];
    out += i + 1 < bytes.size() ? kAlphabet[(n >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? kAlphabet[n & 63] : '=';
  }
  return out;
}

// The frames that show the extremes of a sensor's images: the most occluded, the one with
// the smallest and the largest visible instance, the most crowded, and the first.
Json GalleryJson(const fs::path& root, const SensorStats& s, const ReportOptions& options) {
  Json gallery = Json::array();
  if (s.images.empty() || options.gallery <= 0) return gallery;
  struct Pick {
    std::string title;
    const ImageStats* image;
  };
  std::vector<Pick> picks;
  const auto best = [&](const std::string& title, auto better) {
    const ImageStats* chosen = nullptr;
    for (const ImageStats& im : s.images) {
      if (im.visible > 0 && (chosen == nullptr || better(im, *chosen))) chosen = &im;
    }
    if (chosen) picks.push_back({title, chosen});
  };
  best("most occluded", [](const auto& a, const auto& b) { return a.occlusion > b.occlusion; });
  best("smallest instance", [](const auto& a, const auto& b) { return a.smallest < b.smallest; });
  best("largest instance", [](const auto& a, const auto& b) { return a.largest > b.largest; });
  best("most instances in view",
       [](const auto& a, const auto& b) { return a.visible > b.visible; });
  best("least occluded", [](const auto& a, const auto& b) { return a.occlusion < b.occlusion; });
  picks.push_back({"first frame", &s.images.front()});
  picks.push_back({"middle frame", &s.images[s.images.size() / 2]});
  std::set<std::pair<int, int>> shown;
  for (const Pick& p : picks) {
    if (static_cast<int>(gallery.size()) >= options.gallery) break;
    if (!shown.insert({p.image->scene_id, p.image->im_id}).second) continue;
    PreviewOptions preview;
    preview.frames = {{p.image->scene_id, p.image->im_id}};
    preview.split = s.split;
    preview.sensor = s.name;
    preview.panel_width = options.panel_width;
    preview.jpeg_quality = 82;
    const std::string jpeg = RenderPreview(root, preview);
    char caption[200];
    std::snprintf(caption, sizeof caption,
                  "scene %d image %d: %d of %d instances visible, mean occluded fraction %.2f, "
                  "visible pixels of an instance %zu to %zu",
                  p.image->scene_id, p.image->im_id, p.image->visible, p.image->instances,
                  p.image->occlusion, p.image->smallest, p.image->largest);
    gallery.push_back({{"title", p.title},
                       {"caption", caption},
                       {"scene_id", p.image->scene_id},
                       {"im_id", p.image->im_id},
                       {"sensor", s.name},
                       {"image", "data:image/jpeg;base64," + Base64(jpeg)}});
  }
  return gallery;
}

Json RunJson(const fs::path& root, size_t scenes, size_t objects, size_t instances) {
  Json run = {{"scenes", scenes}, {"objects", objects}, {"instances", instances}};
  std::error_code ec;
  if (fs::exists(root / kManifestFile, ec)) {
    const DatasetManifest m = ReadManifest(root);
    uint64_t bytes = 0;
    for (const FileRecord& f : m.files) bytes += f.size;
    run["files"] = m.files.size();
    run["bytes"] = bytes;
    run["frames"] = m.frames;
    run["version"] = m.version;
    run["run_key"] = m.run_key;
  }
  if (const std::optional<RunRecord> r = ReadRunRecord(root)) {
    run["recipe_path"] = r->recipe_path.empty() ? "(the built-in default job)" : r->recipe_path;
    run["recipe_text"] = r->recipe_text;
    run["started_utc"] = r->started_utc;
    run["seconds"] = r->seconds;
    run["frames"] = r->frames;
    Json shards = Json::array();
    int threads = 0;
    for (const RunRecord::Shard& s : r->shards) {
      shards.push_back({{"index", s.index}, {"seconds", s.seconds}, {"frames", s.frames}});
      threads = std::max(threads, s.threads);
    }
    run["shards"] = shards;
    run["threads"] = threads;
  }
  // Images per split, from splits/*.txt (one "scene_id im_id" per line).
  Json splits = Json::object();
  for (const char* split : {"train", "test"}) {
    const fs::path list = root / "splits" / (std::string(split) + ".txt");
    if (!fs::exists(list, ec)) continue;
    const std::string text = ReadFileText(list);
    splits[split] = std::count(text.begin(), text.end(), '\n');
  }
  run["splits"] = splits;
  return run;
}

// The verifier's certificate (DATASET/verify.json) when it is of this dataset's run.
Json VerifyJson(const fs::path& root, const std::string& run_key) {
  const auto certificate = ReadJsonIfThere(root, kCertificateFile);
  if (!certificate || certificate->value("run_key", "") != run_key) return nullptr;
  return *certificate;
}

}  // namespace

std::string ReportData(const fs::path& root, const ReportOptions& options) {
  std::error_code ec;
  if (!fs::is_directory(root, ec)) throw Error(root.string() + ": no such folder");
  if (FindBopScenes(root).empty())
    throw Error(root.string() + ": not a BOP dataset (no SPLIT/NNNNNN/scene_camera.json)");
  std::map<int, ObjectStats> objects = ReadObjects(root);
  const std::vector<SensorStats> sensors = ReadImages(root, &objects);
  for (const char* name : {"test_targets_bop19.json", "test_targets_multiview_bop25.json"}) {
    const auto targets = ReadJsonIfThere(root, name);
    if (!targets || !targets->is_array()) continue;
    for (const Json& t : *targets) {
      const auto o = objects.find(t.value("obj_id", -1));
      if (o != objects.end()) o->second.targets += t.value("inst_count", 0);
    }
    break;
  }
  const int image_pixels = sensors.empty() ? 1 : sensors[0].width * sensors[0].height;
  Json objects_json = Json::array();
  size_t instances = 0;
  for (const auto& [id, o] : objects) {
    objects_json.push_back(ObjectJson(o, image_pixels));
    instances += o.instances;
  }
  Json sensors_json = Json::array();
  std::set<std::pair<std::string, int>> scenes;
  for (const SensorStats& s : sensors) {
    sensors_json.push_back(SensorJson(s, options.sparse_percent));
    for (const ImageStats& im : s.images) scenes.insert({s.split, im.scene_id});
  }
  std::string randomization_note;
  Json data = {{"report_data", 1},
               {"title", "cadsynth report: " + root.filename().string()},
               {"dataset", fs::absolute(root).lexically_normal().string()},
               {"generated_by", std::string("cadsynth ") + CadsynthVersion()},
               {"run", RunJson(root, scenes.size(), objects.size(), instances)},
               {"sensors", sensors_json},
               {"objects", objects_json},
               {"randomization",
                RandomizationJson(
                    root, sensors.empty() || sensors[0].name.empty() ? "" : "_" + sensors[0].name,
                    &randomization_note)},
               {"grasps", GraspsJson(root)},
               {"physics", PhysicsJson(root)},
               {"gallery", Json::array()}};
  // Every sensor's extremes (a rig's sensors see the scene differently: a grey or depth camera
  // beside the colour one).
  for (const SensorStats& s : sensors) {
    for (Json& entry : GalleryJson(root, s, options)) data["gallery"].push_back(std::move(entry));
  }
  data["verify"] = VerifyJson(root, data["run"].value("run_key", ""));
  if (!randomization_note.empty()) data["randomization_note"] = randomization_note;
  return data.dump() + "\n";
}

namespace {

// Runs `argv` (argv[0] looked up on the PATH) with `extra_env` added; returns its exit status
// (-1: it could not be started or was killed).
int Spawn(const std::vector<std::string>& argv, const std::vector<std::string>& extra_env,
          bool quiet) {
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  std::vector<std::string> env_text(extra_env);
  for (char** e = environ; *e != nullptr; ++e) env_text.push_back(*e);
  std::vector<char*> env;
  for (const std::string& e : env_text) env.push_back(const_cast<char*>(e.c_str()));
  env.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (quiet) {
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
  }
  pid_t pid = 0;
  const int started = posix_spawnp(&pid, args[0], &actions, nullptr, args.data(), env.data());
  posix_spawn_file_actions_destroy(&actions);
  if (started != 0) return -1;
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return -1;
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string ChoosePython(const ReportOptions& options) {
  if (!options.python.empty()) return options.python;
  if (const char* env = std::getenv("CADSYNTH_PYTHON"); env != nullptr && *env != '\0') return env;
  std::error_code ec;
  // Debian's python3 is the one its python3-matplotlib is for (before pyenv shims on the PATH).
  if (fs::exists("/usr/bin/python3", ec)) return "/usr/bin/python3";
  return "python3";
}

}  // namespace

void WriteReport(const fs::path& root, const fs::path& output, const ReportOptions& options) {
  std::error_code ec;
  const fs::path folder = fs::absolute(output).parent_path();
  if (!fs::is_directory(folder, ec))
    throw Error(output.string() + ": cannot write: no folder " + folder.string());
  const std::string data = ReportData(root, options);
  const std::string python = ChoosePython(options);
  const fs::path work = fs::temp_directory_path() / ("cadsynth-report-" + std::to_string(getpid()));
  struct Remove {
    fs::path path;
    ~Remove() {
      std::error_code ignored;
      fs::remove_all(path, ignored);
    }
  } remove{work};
  CreateFolder(work);
  WriteFileAtomic(work / "report_data.json", data);
  WriteFileAtomic(work / "report.py", kReportScript);
  const std::vector<std::string> env = {"MPLCONFIGDIR=" + (work / "matplotlib").string()};
  if (Spawn({python, "-c", "import numpy, matplotlib"}, env, true) != 0) {
    throw Error("report: " + python +
                " cannot import numpy and matplotlib, which draw the report's plots: install "
                "them (apt install python3-matplotlib) or set CADSYNTH_PYTHON to a Python that "
                "has them");
  }
  const fs::path absolute = fs::absolute(output);
  const int status = Spawn({python, (work / "report.py").string(),
                            (work / "report_data.json").string(), absolute.string()},
                           env, false);
  if (status != 0)
    throw Error("report: " + python + " report.py failed (exit " + std::to_string(status) +
                ") writing " + output.string());
}

}  // namespace cadsynth
