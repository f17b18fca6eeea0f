#include "recipes/recipe.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <system_error>

#include <yaml-cpp/yaml.h>

#include "cad/error.h"
#include "cad/step.h"
#include "cad/units.h"
#include "recipes/units.h"

namespace cadsynth {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr size_t kMaxSeries = 1000000;

size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] != b[j - 1] ? 1 : 0)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

// Reads one recipe; every failure names name:line:column of the offending node.
class Reader {
 public:
  Reader(std::string name, std::filesystem::path base_dir)
      : name_(std::move(name)), base_dir_(std::move(base_dir)) {}

  std::string Where(const YAML::Node& node) const {
    const YAML::Mark mark = node.Mark();
    if (mark.is_null()) return name_;
    return name_ + ":" + std::to_string(mark.line + 1) + ":" + std::to_string(mark.column + 1);
  }

  [[noreturn]] void Fail(const YAML::Node& node, const std::string& key, const std::string& what) const {
    throw Error(Where(node) + ": " + (key.empty() ? "" : key + ": ") + what);
  }

  // A mapping whose keys must all be in `allowed`.
  void ExpectMap(const YAML::Node& node, const std::string& key,
                 std::initializer_list<const char*> allowed) const {
    if (!node.IsMap()) Fail(node, key, "expected a mapping of keys to values");
    for (auto it = node.begin(); it != node.end(); ++it) {
      const std::string k = it->first.as<std::string>();
      if (std::find_if(allowed.begin(), allowed.end(), [&](const char* a) { return k == a; }) !=
          allowed.end()) {
        continue;
      }
      std::string best;
      size_t best_distance = 3;  // suggest only close matches
      for (const char* a : allowed) {
        const size_t d = EditDistance(k, a);
        if (d < best_distance) {
          best_distance = d;
          best = a;
        }
      }
      std::string what = "unknown key '" + (key.empty() ? k : key + "." + k) + "'";
      if (!best.empty()) what += " (did you mean '" + best + "'?)";
      throw Error(Where(it->first) + ": " + what);
    }
  }

  std::string Scalar(const YAML::Node& node, const std::string& key) const {
    if (!node.IsScalar()) Fail(node, key, "expected a single value");
    return node.Scalar();
  }

  double Number(const YAML::Node& node, const std::string& key) const {
    const std::string text = Scalar(node, key);
    char* end = nullptr;
    const double value = std::strtod(text.c_str(), &end);
    if (end == text.c_str() || *end != '\0' || !std::isfinite(value)) {
      Fail(node, key, "expected a number, got '" + text + "'");
    }
    return value;
  }

  int Integer(const YAML::Node& node, const std::string& key) const {
    const double value = Number(node, key);
    if (value != std::floor(value) || std::abs(value) > 1e9) {
      Fail(node, key, "expected a whole number, got '" + node.Scalar() + "'");
    }
    return static_cast<int>(value);
  }

  bool Bool(const YAML::Node& node, const std::string& key) const {
    const std::string text = Scalar(node, key);
    if (text == "true" || text == "yes" || text == "on") return true;
    if (text == "false" || text == "no" || text == "off") return false;
    Fail(node, key, "expected true or false, got '" + text + "'");
  }

  double Length(const YAML::Node& node, const std::string& key) const {
    std::string why;
    const std::optional<double> mm = ParseLengthMm(Scalar(node, key), &why);
    if (!mm) Fail(node, key, why);
    return *mm;
  }

  double Angle(const YAML::Node& node, const std::string& key) const {
    std::string why;
    const std::optional<double> rad = ParseAngleRad(Scalar(node, key), &why);
    if (!rad) Fail(node, key, why);
    return *rad;
  }

  Eigen::Vector3f Color(const YAML::Node& node, const std::string& key) const {
    if (!node.IsSequence() || node.size() != 3) Fail(node, key, "expected [r, g, b] in 0..1");
    Eigen::Vector3f c;
    for (int i = 0; i < 3; ++i) {
      const double v = Number(node[i], key);
      if (v < 0.0 || v > 1.0) Fail(node[i], key, "colour components lie in 0..1");
      c[i] = static_cast<float>(v);
    }
    return c;
  }

  // One value, a list, or an inclusive range {from, to, step}; `parse` reads one value.
  template <typename Parse>
  std::vector<double> Series(const YAML::Node& node, const std::string& key, Parse parse) const {
    std::vector<double> values;
    if (node.IsScalar()) {
      values.push_back(parse(node, key));
    } else if (node.IsSequence()) {
      for (const YAML::Node& item : node) values.push_back(parse(item, key));
      if (values.empty()) Fail(node, key, "the list is empty");
    } else if (node.IsMap()) {
      ExpectMap(node, key, {"from", "to", "step"});
      for (const char* k : {"from", "to", "step"}) {
        if (!node[k]) Fail(node, key, std::string("a range needs 'from', 'to' and 'step' (no '") + k + "')");
      }
      const double from = parse(node["from"], key + ".from");
      const double to = parse(node["to"], key + ".to");
      const double step = parse(node["step"], key + ".step");
      if (!(step > 0.0)) Fail(node["step"], key + ".step", "step must be positive");
      if (to < from) Fail(node["to"], key + ".to", "'to' must not be less than 'from'");
      const double count = std::floor((to - from) / step + 1e-9) + 1.0;
      if (count > kMaxSeries) Fail(node, key, "range has too many values");
      for (int i = 0; i < static_cast<int>(count); ++i) values.push_back(from + i * step);
    } else {
      Fail(node, key, "expected a value, a list or {from, to, step}");
    }
    return values;
  }

  template <typename Options>
  void Check(const Options& options, const YAML::Node& node, const std::string& key) const {
    std::string why;
    if (!options.Check(&why)) Fail(node, key, why);
  }

  std::filesystem::path ResolvePath(const YAML::Node& node, const std::string& key) const {
    std::filesystem::path path = Scalar(node, key);
    if (path.is_relative()) path = base_dir_ / path;
    path = path.lexically_normal();
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) Fail(node, key, path.string() + ": no such file");
    if (std::filesystem::is_directory(path, ec)) {
      Fail(node, key, path.string() + ": is a folder, not a file");
    }
    return path;
  }

  const std::filesystem::path& base_dir() const { return base_dir_; }

 private:
  std::string name_;
  std::filesystem::path base_dir_;
};

void DetectFormatOrFail(const Reader& r, const YAML::Node& node, const std::string& key,
                       const std::filesystem::path& path) {
  try {
    DetectFormat(path);
  } catch (const Error& e) {
    r.Fail(node, key, e.what());
  }
}

void ReadParts(const Reader& r, const YAML::Node& node, RunSpec* spec) {
  if (!node.IsSequence() || node.size() == 0) {
    r.Fail(node, "parts", "expected a list such as [{file: part.stp}, {builtin: default}]");
  }
  spec->sources.clear();
  for (size_t i = 0; i < node.size(); ++i) {
    const YAML::Node item = node[i];
    const std::string key = "parts[" + std::to_string(i) + "]";
    r.ExpectMap(item, key, {"file", "unit", "encoding", "builtin"});
    if (!item["file"] == !item["builtin"]) r.Fail(item, key, "give exactly one of 'file' or 'builtin'");
    PartSource source;
    if (item["file"]) {
      source.kind = PartSource::Kind::kFile;
      source.path = r.ResolvePath(item["file"], key + ".file");
      source.where = r.Where(item["file"]);
      if (item["unit"]) {
        source.unit = r.Scalar(item["unit"], key + ".unit");
        if (!LengthUnitMm(source.unit)) {
          r.Fail(item["unit"], key + ".unit", "unknown length unit '" + source.unit + "' (use um, mm, cm, m, in or ft)");
        }
      }
      if (item["encoding"]) {
        source.encoding = r.Scalar(item["encoding"], key + ".encoding");
        if (StepCodePage(source.encoding).empty()) {
          r.Fail(item["encoding"], key + ".encoding",
                 "unknown encoding '" + source.encoding + "' (e.g. utf-8, cp1251, cp1252, sjis, gb2312)");
        }
      }
      DetectFormatOrFail(r, item["file"], key + ".file", source.path);
    } else {
      if (item["unit"] || item["encoding"]) r.Fail(item, key, "'unit' and 'encoding' go with 'file'");
      const std::string which = r.Scalar(item["builtin"], key + ".builtin");
      if (which != "default") r.Fail(item["builtin"], key + ".builtin", "the built-in set is 'default'");
      source.kind = PartSource::Kind::kBuiltinDefault;
      source.where = r.Where(item["builtin"]);
    }
    spec->sources.push_back(source);
  }
}

void ReadScene(const Reader& r, const YAML::Node& node, RunSpec* spec) {
  r.ExpectMap(node, "scene", {"layout", "gap"});
  if (node["layout"]) {
    const std::string layout = r.Scalar(node["layout"], "scene.layout");
    if (layout == "assembled") {
      spec->arrangement.layout = Layout::kAssembled;
    } else if (layout == "row") {
      spec->arrangement.layout = Layout::kRow;
    } else {
      r.Fail(node["layout"], "scene.layout", "expected 'assembled' or 'row', got '" + layout + "'");
    }
  }
  if (node["gap"]) spec->arrangement.gap_mm = r.Length(node["gap"], "scene.gap");
  r.Check(spec->arrangement, node, "scene");
}

void ReadClasses(const Reader& r, const YAML::Node& node, RunSpec* spec) {
  r.ExpectMap(node, "classes", {"by", "groups"});
  if (node["by"]) {
    const std::string by = r.Scalar(node["by"], "classes.by");
    if (by == "part") {
      spec->class_by = RunSpec::ClassBy::kPart;
    } else if (by == "assembly") {
      spec->class_by = RunSpec::ClassBy::kAssembly;
    } else {
      r.Fail(node["by"], "classes.by", "expected 'part' or 'assembly', got '" + by + "'");
    }
  }
  if (node["groups"]) {
    const YAML::Node groups = node["groups"];
    if (!groups.IsMap()) r.Fail(groups, "classes.groups", "expected {class name: [name patterns]}");
    for (auto it = groups.begin(); it != groups.end(); ++it) {
      const std::string name = it->first.as<std::string>();
      const std::string key = "classes.groups." + name;
      std::vector<std::string> patterns;
      if (it->second.IsSequence()) {
        for (const YAML::Node& p : it->second) patterns.push_back(r.Scalar(p, key));
      } else {
        patterns.push_back(r.Scalar(it->second, key));
      }
      if (patterns.empty()) r.Fail(it->second, key, "give at least one name pattern");
      spec->class_groups.emplace_back(name, patterns);
    }
  }
}

void ReadTessellation(const Reader& r, const YAML::Node& node, RunSpec* spec) {
  r.ExpectMap(node, "tessellation", {"linear_deflection", "angular_deflection", "crease_angle"});
  if (node["crease_angle"]) {
    spec->crease_angle_rad = r.Angle(node["crease_angle"], "tessellation.crease_angle");
    if (spec->crease_angle_rad < 0.0 || spec->crease_angle_rad > M_PI) {
      r.Fail(node["crease_angle"], "tessellation.crease_angle", "must lie between 0 and 180 degrees");
    }
  }
  if (node["linear_deflection"]) {
    spec->tessellation.linear_deflection_mm =
        r.Length(node["linear_deflection"], "tessellation.linear_deflection");
  }
  if (node["angular_deflection"]) {
    spec->tessellation.angular_deflection_rad =
        r.Angle(node["angular_deflection"], "tessellation.angular_deflection");
  }
  r.Check(spec->tessellation, node, "tessellation");
}

void ReadCamera(const Reader& r, const YAML::Node& node, RunSpec* spec) {
  r.ExpectMap(node, "camera", {"preset", "width", "height", "fx", "fy", "cx", "cy"});
  Intrinsics& k = spec->intrinsics;
  if (node["preset"]) {
    const std::string preset = r.Scalar(node["preset"], "camera.preset");
    if (preset != "kinect_v1") {
      r.Fail(node["preset"], "camera.preset", "unknown preset '" + preset + "' (known: kinect_v1)");
    }
    k = Intrinsics::KinectV1();
  }
  if (node["width"]) k.width = r.Integer(node["width"], "camera.width");
  if (node["height"]) k.height = r.Integer(node["height"], "camera.height");
  if (node["fx"]) k.fx = r.Number(node["fx"], "camera.fx");
  if (node["fy"]) k.fy = r.Number(node["fy"], "camera.fy");
  if (node["cx"]) k.cx = r.Number(node["cx"], "camera.cx");
  if (node["cy"]) k.cy = r.Number(node["cy"], "camera.cy");
  r.Check(k, node, "camera");
}

void ReadSweep(const Reader& r, const YAML::Node& node, RunSpec* spec) {
  r.ExpectMap(node, "sweep", {"yaw", "pitch", "radius", "target"});
  const auto angle = [&](const YAML::Node& n, const std::string& k) { return r.Angle(n, k); };
  const auto length = [&](const YAML::Node& n, const std::string& k) { return r.Length(n, k); };
  SweepOptions& s = spec->sweep;
  if (node["yaw"]) s.yaw_rad = r.Series(node["yaw"], "sweep.yaw", angle);
  if (node["pitch"]) s.pitch_rad = r.Series(node["pitch"], "sweep.pitch", angle);
  if (node["radius"]) s.radius_mm = r.Series(node["radius"], "sweep.radius", length);
  if (node["target"]) {
    const YAML::Node t = node["target"];
    if (!t.IsSequence() || t.size() != 3) r.Fail(t, "sweep.target", "expected [x, y, z]");
    for (int i = 0; i < 3; ++i) s.target[i] = r.Length(t[i], "sweep.target");
  }
  r.Check(s, node, "sweep");
}

void ReadRender(const Reader& r, const YAML::Node& node, RunSpec* spec) {
  r.ExpectMap(node, "render", {"background", "floor", "floor_color", "ambient", "light_direction",
                               "light_intensity", "colors"});
  if (node["colors"]) {
    const std::string colors = r.Scalar(node["colors"], "render.colors");
    if (colors != "cad" && colors != "palette") {
      r.Fail(node["colors"], "render.colors", "expected 'cad' or 'palette', got '" + colors + "'");
    }
    spec->cad_colors = colors == "cad";
  }
  Scene& look = spec->look;
  if (node["background"]) look.background_color = r.Color(node["background"], "render.background");
  if (node["floor"]) look.floor = r.Bool(node["floor"], "render.floor");
  if (node["floor_color"]) look.floor_color = r.Color(node["floor_color"], "render.floor_color");
  if (node["ambient"]) look.ambient = static_cast<float>(r.Number(node["ambient"], "render.ambient"));
  if (node["light_intensity"]) {
    look.light_intensity =
        static_cast<float>(r.Number(node["light_intensity"], "render.light_intensity"));
  }
  if (node["light_direction"]) {
    const YAML::Node d = node["light_direction"];
    if (!d.IsSequence() || d.size() != 3) r.Fail(d, "render.light_direction", "expected [x, y, z]");
    for (int i = 0; i < 3; ++i) look.light_direction[i] = r.Number(d[i], "render.light_direction");
    if (look.light_direction.norm() == 0.0) {
      r.Fail(d, "render.light_direction", "the direction must not be zero");
    }
  }
  if (look.ambient < 0.0f || look.light_intensity < 0.0f) {
    r.Fail(node, "render", "ambient and light_intensity must not be negative");
  }
}

void ReadOutput(const Reader& r, const YAML::Node& node, RunSpec* spec) {
  r.ExpectMap(node, "output", {"dir", "depth_scale", "split"});
  if (node["dir"]) {
    std::filesystem::path dir = r.Scalar(node["dir"], "output.dir");
    spec->output = (dir.is_relative() ? r.base_dir() / dir : dir).lexically_normal();
  }
  if (node["depth_scale"]) spec->bop.depth_scale = r.Number(node["depth_scale"], "output.depth_scale");
  if (node["split"]) spec->bop.split = r.Scalar(node["split"], "output.split");
  r.Check(spec->bop, node, "output");
}

}  // namespace

RunSpec DefaultRunSpec() {
  RunSpec spec;
  spec.sources = {PartSource{}};
  spec.arrangement.layout = Layout::kRow;
  for (int yaw = 0; yaw < 360; yaw += 30) spec.sweep.yaw_rad.push_back(yaw * kDeg);
  for (int pitch = 15; pitch <= 75; pitch += 20) spec.sweep.pitch_rad.push_back(pitch * kDeg);
  spec.sweep.radius_mm = {650.0, 1050.0, 1450.0};
  return spec;
}

RunSpec ParseRecipe(const std::string& text, const std::string& name,
                    const std::filesystem::path& base_dir) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw Error(name + ":" + std::to_string(e.mark.line + 1) + ":" +
                std::to_string(e.mark.column + 1) + ": not valid YAML: " + e.msg);
  }
  if (!root.IsMap()) throw Error(name + ": a recipe is a mapping of sections (parts, sweep, ...)");

  const Reader r(name, base_dir);
  RunSpec spec = DefaultRunSpec();
  // A recipe's assemblies stay as designed; the built-in set (no 'parts') lies side by side.
  spec.arrangement.layout = root["parts"] ? Layout::kAssembled : Layout::kRow;
  try {
    r.ExpectMap(root, "", {"parts", "classes", "scene", "tessellation", "camera", "sweep", "render",
                           "output"});
    if (root["parts"]) ReadParts(r, root["parts"], &spec);
    if (root["classes"]) ReadClasses(r, root["classes"], &spec);
    if (root["scene"]) ReadScene(r, root["scene"], &spec);
    if (root["tessellation"]) ReadTessellation(r, root["tessellation"], &spec);
    if (root["camera"]) ReadCamera(r, root["camera"], &spec);
    if (root["sweep"]) ReadSweep(r, root["sweep"], &spec);
    if (root["render"]) ReadRender(r, root["render"], &spec);
    if (root["output"]) ReadOutput(r, root["output"], &spec);
  } catch (const YAML::Exception& e) {
    throw Error(name + ":" + std::to_string(e.mark.line + 1) + ":" +
                std::to_string(e.mark.column + 1) + ": " + e.msg);
  }
  return spec;
}

RunSpec LoadRecipe(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw Error(path.string() + ": no such recipe file");
  if (std::filesystem::is_directory(path, ec)) throw Error(path.string() + ": is a folder, not a recipe");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path.string() + ": cannot open the recipe");
  std::ostringstream text;
  text << in.rdbuf();
  const std::filesystem::path base = std::filesystem::absolute(path, ec).parent_path();
  RunSpec spec = ParseRecipe(text.str(), path.string(), base);
  spec.recipe = path;
  return spec;
}

}  // namespace cadsynth
