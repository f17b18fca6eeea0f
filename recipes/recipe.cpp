#include "recipes/recipe.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include <yaml-cpp/yaml.h>

#include "cad/core/error.h"
#include "cad/core/random.h"
#include "cad/core/schema.h"
#include "cad/core/units.h"
#include "cad/core/util.h"
#include "cad/step.h"
#include "dataset/output_formats.h"
#include "recipes/recipe_schema.h"
#include "recipes/units.h"
#include "render/image.h"
#include "variants/families.h"

namespace cadsynth {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr size_t kMaxSeries = 1000000;

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

  [[noreturn]] void Fail(const YAML::Node& node, const std::string& key,
                         const std::string& what) const {
    throw Error(Where(node) + ": " + (key.empty() ? "" : key + ": ") + what);
  }

  // A mapping whose keys must all be in `allowed`: the syntax of a kind of value ({from, to,
  // step}, {choice: [...]}); a section's keys come from the recipe's tree (ExpectKeys).
  void ExpectMap(const YAML::Node& node, const std::string& key,
                 std::initializer_list<const char*> allowed) const {
    if (!node.IsMap()) Fail(node, key, "expected a mapping of keys to values");
    const std::vector<std::string> names(allowed.begin(), allowed.end());
    for (auto it = node.begin(); it != node.end(); ++it) {
      const std::string k = it->first.as<std::string>();
      if (std::find(names.begin(), names.end(), k) == names.end())
        FailUnknownKey(it->first, key, k, names);
    }
  }

  // A mapping whose keys are all keys of the described section `schema` (recipes/recipe_schema.h);
  // in a section with a tag (a light's `type`), a key that goes with other values of it is
  // refused too.
  void ExpectKeys(const YAML::Node& node, const std::string& key, const Key& schema) const {
    if (!node.IsMap()) Fail(node, key, "expected a mapping of keys to values");
    std::string tag_value = schema.tag_default;
    if (!schema.tag.empty() && node[schema.tag] && node[schema.tag].IsScalar())
      tag_value = node[schema.tag].Scalar();
    for (auto it = node.begin(); it != node.end(); ++it) {
      const std::string k = it->first.as<std::string>();
      const Key* known = schema.Find(k);
      const std::string at = key.empty() ? k : key + "." + k;
      if (known == nullptr) {
        std::vector<std::string> names;
        for (const Key& child : schema.keys) names.push_back(child.name);
        FailUnknownKey(it->first, key, k, names);
      }
      if (!known->only_with.empty() && !tag_value.empty() &&
          std::find(known->only_with.begin(), known->only_with.end(), tag_value) ==
              known->only_with.end()) {
        std::string with;
        for (const std::string& t : known->only_with) with += (with.empty() ? "" : " or ") + t;
        throw Error(Where(it->first) + ": " + at + ": goes with " + schema.tag + ": " + with +
                    ", not " + tag_value);
      }
    }
  }

  // "unknown key 'SECTION.KEY' (did you mean 'NEAREST'?)" at the key.
  [[noreturn]] void FailUnknownKey(const YAML::Node& at, const std::string& section,
                                   const std::string& k,
                                   const std::vector<std::string>& names) const {
    const std::string best = NearestName(k, names);
    std::string what = "unknown key '" + (section.empty() ? k : section + "." + k) + "'";
    if (!best.empty()) what += " (did you mean '" + best + "'?)";
    throw Error(Where(at) + ": " + what);
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

  // A colour of the physically based mode, as Blender's Python and its colour fields take it:
  // [r, g, b] is linear (scene-linear Rec. 709, what bpy's default_value and BlenderProc's
  // set_principled_shader_value hold), "#RRGGBB" is sRGB-encoded (Blender's Hex field, a web or
  // paint colour) and is decoded to linear.
  Eigen::Vector3f LinearColor(const YAML::Node& node, const std::string& key) const {
    if (node.IsNull())  // `color: #E7E7E7` unquoted: YAML reads a comment
      Fail(node, key, "no colour; quote a hex colour (\"#RRGGBB\"), or give [r, g, b]");
    if (!node.IsScalar()) return Color(node, key);
    const std::string text = node.Scalar();
    const bool hex = text.size() == 7 && text[0] == '#' &&
                     text.find_first_not_of("0123456789abcdefABCDEF", 1) == std::string::npos;
    if (!hex)
      Fail(node, key, "expected linear [r, g, b] in 0..1 or an sRGB hex colour \"#RRGGBB\"");
    Eigen::Vector3f c;
    for (int i = 0; i < 3; ++i) {
      const int byte = std::stoi(text.substr(1 + 2 * i, 2), nullptr, 16);
      c[i] = SrgbToLinear(static_cast<float>(byte) / 255.0f);
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
        if (!node[k])
          Fail(node, key, std::string("a range needs 'from', 'to' and 'step' (no '") + k + "')");
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

// "spur_gear, ring_gear, ...": for unknown-family messages.
std::string KnownFamilies() {
  std::vector<std::string> names;
  for (const FamilyInfo& f : Families()) names.push_back(f.name);
  return JoinNames(names);
}

void DetectFormatOrFail(const Reader& r, const YAML::Node& node, const std::string& key,
                        const std::filesystem::path& path) {
  try {
    DetectFormat(path);
  } catch (const Error& e) {
    r.Fail(node, key, e.what());
  }
}

// One value of a family parameter, by its kind.
ParamValue ReadParam(const Reader& r, const YAML::Node& node, const std::string& key,
                     const FamilyParam& p) {
  switch (p.kind) {
    case FamilyParam::Kind::kLength:
      return r.Length(node, key);
    case FamilyParam::Kind::kAngle:
      return r.Angle(node, key);
    case FamilyParam::Kind::kCount:
      return double(r.Integer(node, key));
    case FamilyParam::Kind::kNumber:
      return r.Number(node, key);
    case FamilyParam::Kind::kText:
      if (p.name == "file") return r.ResolvePath(node, key).string();
      return r.Scalar(node, key);
  }
  return 0.0;
}

const FamilyParam& Param(const Reader& r, const FamilyInfo& family, const YAML::Node& key_node,
                         const std::string& where) {
  const std::string name = key_node.as<std::string>();
  if (const FamilyParam* p = family.Find(name)) return *p;
  try {
    CompleteParams(family, {{name, 0.0}});
  } catch (const Error& e) {
    r.Fail(key_node, where, e.what());
  }
  r.Fail(key_node, where, "unknown parameter '" + name + "'");
}

// Values of one parameter for a grid: a value, a list, or an inclusive range.
std::vector<ParamValue> ReadSeries(const Reader& r, const YAML::Node& node, const std::string& key,
                                   const FamilyParam& p) {
  std::vector<ParamValue> values;
  if (p.kind == FamilyParam::Kind::kText) {
    if (node.IsSequence()) {
      for (const YAML::Node& item : node) values.push_back(ReadParam(r, item, key, p));
    } else {
      values.push_back(ReadParam(r, node, key, p));
    }
    if (values.empty()) r.Fail(node, key, "the list is empty");
    return values;
  }
  const auto one = [&](const YAML::Node& n, const std::string& k) {
    return std::get<double>(ReadParam(r, n, k, p));
  };
  for (double v : r.Series(node, key, one))
    values.push_back(p.kind == FamilyParam::Kind::kCount ? std::round(v) : v);
  return values;
}

void ReadFamily(const Reader& r, const YAML::Node& item, const std::string& key,
                PartSource* source) {
  source->kind = PartSource::Kind::kFamily;
  source->family = r.Scalar(item["family"], key + ".family");
  source->where = r.Where(item["family"]);
  const FamilyInfo* family = FindFamily(source->family);
  if (family == nullptr) {
    r.Fail(item["family"], key + ".family",
           "unknown family '" + source->family + "' (known: " + KnownFamilies() + ")");
  }
  ParamValues fixed;
  if (item["params"]) {
    const YAML::Node params = item["params"];
    if (!params.IsMap()) r.Fail(params, key + ".params", "expected {parameter: value}");
    for (auto it = params.begin(); it != params.end(); ++it) {
      const FamilyParam& p = Param(r, *family, it->first, key + ".params");
      fixed[p.name] = ReadParam(r, it->second, key + ".params." + p.name, p);
    }
  }
  if (item["grid"] && item["random"]) r.Fail(item, key, "give 'grid' or 'random', not both");
  std::vector<ParamValues> variants = {fixed};
  if (item["grid"]) {
    const YAML::Node grid = item["grid"];
    if (!grid.IsMap()) r.Fail(grid, key + ".grid", "expected {parameter: values}");
    // Nested loops over the family's parameters in their own order, the last varying fastest.
    std::map<std::string, std::vector<ParamValue>> axes;
    for (auto it = grid.begin(); it != grid.end(); ++it) {
      const FamilyParam& p = Param(r, *family, it->first, key + ".grid");
      axes[p.name] = ReadSeries(r, it->second, key + ".grid." + p.name, p);
    }
    for (const FamilyParam& p : family->params) {
      const auto axis = axes.find(p.name);
      if (axis == axes.end()) continue;
      std::vector<ParamValues> next;
      for (const ParamValues& v : variants) {
        for (const ParamValue& value : axis->second) {
          ParamValues w = v;
          w[p.name] = value;
          next.push_back(std::move(w));
        }
      }
      variants = std::move(next);
      if (variants.size() > 100000) r.Fail(grid, key + ".grid", "more than 100000 variants");
    }
  } else if (item["random"]) {
    const YAML::Node random = item["random"];
    r.ExpectKeys(random, key + ".random", SchemaAt("parts[].random"));
    if (!random["count"] || !random["params"])
      r.Fail(random, key + ".random", "give 'count' and 'params'");
    const int count = r.Integer(random["count"], key + ".random.count");
    if (count < 1 || count > 100000)
      r.Fail(random["count"], key + ".random.count", "count must be 1 to 100000");
    const uint64_t seed =
        random["seed"] ? static_cast<uint64_t>(r.Integer(random["seed"], key + ".random.seed")) : 0;
    const YAML::Node params = random["params"];
    if (!params.IsMap())
      r.Fail(params, key + ".random.params", "expected {parameter: {from, to} or [choices]}");
    // Each parameter draws from its own stream (its index in the family), variant by variant.
    struct Draw {
      const FamilyParam* param;
      std::string stream;               // family.param.NAME (cad/core/random.h)
      std::vector<ParamValue> choices;  // a list: pick one
      double from = 0, to = 0;          // a range
    };
    std::vector<Draw> draws;
    for (auto it = params.begin(); it != params.end(); ++it) {
      const FamilyParam& p = Param(r, *family, it->first, key + ".random.params");
      const std::string k = key + ".random.params." + p.name;
      Draw d{&p, std::string(streams::kFamilyParam.name) + "." + p.name, {}, 0, 0};
      if (it->second.IsMap()) {
        r.ExpectMap(it->second, k, {"from", "to"});
        if (!it->second["from"] || !it->second["to"] || p.kind == FamilyParam::Kind::kText) {
          r.Fail(it->second, k,
                 "a random range needs 'from' and 'to' (text parameters take a list)");
        }
        d.from = std::get<double>(ReadParam(r, it->second["from"], k + ".from", p));
        d.to = std::get<double>(ReadParam(r, it->second["to"], k + ".to", p));
        if (d.to < d.from) r.Fail(it->second["to"], k + ".to", "'to' must not be less than 'from'");
      } else {
        d.choices = ReadSeries(r, it->second, k, p);
      }
      draws.push_back(std::move(d));
    }
    variants.clear();
    for (int v = 0; v < count; ++v) {
      ParamValues w = fixed;
      for (const Draw& d : draws) {
        const double u = UniformDraw(seed, d.stream, static_cast<uint64_t>(v));
        if (!d.choices.empty()) {
          w[d.param->name] =
              d.choices[std::min(d.choices.size() - 1, static_cast<size_t>(u * d.choices.size()))];
        } else if (d.param->kind == FamilyParam::Kind::kCount) {
          w[d.param->name] = std::floor(d.from + u * (d.to - d.from + 1));
        } else {
          w[d.param->name] = d.from + u * (d.to - d.from);
        }
      }
      variants.push_back(std::move(w));
    }
  }
  for (ParamValues& v : variants) v = CompleteParams(*family, v);
  source->variants = std::move(variants);
  if (item["class"]) {
    const std::string c = r.Scalar(item["class"], key + ".class");
    if (c != "variant" && c != "family")
      r.Fail(item["class"], key + ".class", "expected 'variant' or 'family', got '" + c + "'");
    source->one_class = c == "family";
  }
}

// `up`: the axis a file's designer drew as up (x, y, z, -x, -y, -z), turned to +z.
void ReadUp(const Reader& r, const YAML::Node& item, const std::string& key, PartSource* source) {
  if (!item["up"]) return;
  const std::string up = r.Scalar(item["up"], key + ".up");
  const double quarter = M_PI / 2;
  const std::map<std::string, Eigen::Matrix3d> turns = {
      {"z", Eigen::Matrix3d::Identity()},
      {"-z", Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()).toRotationMatrix()},
      {"y", Eigen::AngleAxisd(quarter, Eigen::Vector3d::UnitX()).toRotationMatrix()},
      {"-y", Eigen::AngleAxisd(-quarter, Eigen::Vector3d::UnitX()).toRotationMatrix()},
      {"x", Eigen::AngleAxisd(-quarter, Eigen::Vector3d::UnitY()).toRotationMatrix()},
      {"-x", Eigen::AngleAxisd(quarter, Eigen::Vector3d::UnitY()).toRotationMatrix()}};
  const auto it = turns.find(up);
  if (it == turns.end())
    r.Fail(item["up"], key + ".up", "expected x, y, z, -x, -y or -z, got '" + up + "'");
  source->z_from_up = it->second;
}

// A file source's `file` (which must exist and have a known format), `unit` and `encoding`.
void ReadFileSource(const Reader& r, const YAML::Node& item, const std::string& key,
                    PartSource* source) {
  source->kind = PartSource::Kind::kFile;
  source->path = r.ResolvePath(item["file"], key + ".file");
  source->where = r.Where(item["file"]);
  if (item["unit"]) {
    source->unit = r.Scalar(item["unit"], key + ".unit");
    if (!LengthUnitMm(source->unit)) {
      r.Fail(item["unit"], key + ".unit",
             "unknown length unit '" + source->unit + "' (use um, mm, cm, m, in or ft)");
    }
  }
  if (item["encoding"]) {
    source->encoding = r.Scalar(item["encoding"], key + ".encoding");
    if (StepCodePage(source->encoding).empty()) {
      r.Fail(
          item["encoding"], key + ".encoding",
          "unknown encoding '" + source->encoding + "' (e.g. utf-8, cp1251, cp1252, sjis, gb2312)");
    }
  }
  DetectFormatOrFail(r, item["file"], key + ".file", source->path);
}

Eigen::Vector3d Triple(const Reader& r, const YAML::Node& node, const std::string& key,
                       bool length);

std::vector<PartSource> ReadParts(const Reader& r, const YAML::Node& node,
                                  const std::string& where) {
  if (!node.IsSequence() || node.size() == 0) {
    r.Fail(node, where, "expected a list such as [{file: part.stp}, {family: spur_gear}]");
  }
  std::vector<PartSource> sources;
  for (size_t i = 0; i < node.size(); ++i) {
    const YAML::Node item = node[i];
    const std::string key = where + "[" + std::to_string(i) + "]";
    r.ExpectKeys(item, key, SchemaAt("parts[]"));
    if (!item["file"] == !item["family"])
      r.Fail(item, key, "give exactly one of 'file' or 'family'");
    PartSource source;
    ReadUp(r, item, key, &source);
    if (const YAML::Node n = item["symmetry"]; n && n.IsSequence()) {
      if (!item["file"])
        r.Fail(n, key + ".symmetry", "a list goes with 'file' (families declare theirs)");
      if (n.size() == 0) r.Fail(n, key + ".symmetry", "an empty list: write 'none'");
      for (size_t k = 0; k < n.size(); ++k) {
        const YAML::Node e = n[k];
        const std::string at = key + ".symmetry[" + std::to_string(k) + "]";
        r.ExpectKeys(e, at, SchemaAt("parts[].symmetry[]"));
        if (!e["axis"]) r.Fail(e, at, "give the 'axis' to turn about, e.g. [0, 0, 1]");
        PartSource::GivenSymmetry g;
        g.where = r.Where(e);
        g.axis = Triple(r, e["axis"], at + ".axis", false);
        if (!(g.axis.norm() > 0)) r.Fail(e["axis"], at + ".axis", "must not be zero");
        g.axis.normalize();
        const bool continuous = e["continuous"] && r.Bool(e["continuous"], at + ".continuous");
        if (continuous == static_cast<bool>(e["order"]))
          r.Fail(e, at, "give 'order: n' (an n-fold turn) or 'continuous: true'");
        if (e["order"]) {
          g.order = r.Integer(e["order"], at + ".order");
          if (g.order < 2 || g.order > 360)
            r.Fail(e["order"], at + ".order", "must be 2 to 360 (2: a half-turn, a flip)");
        }
        if (e["through"]) g.through = Triple(r, e["through"], at + ".through", true);
        source.given_symmetries.push_back(g);
      }
      source.detect_symmetry = false;
    } else if (n) {
      const std::string policy = r.Scalar(n, key + ".symmetry");
      if (policy != "auto" && policy != "none")
        r.Fail(n, key + ".symmetry",
               "expected auto, none or a list of {axis, order | continuous}, got '" + policy + "'");
      source.detect_symmetry = policy == "auto";
    }
    if (const YAML::Node n = item["symmetry_tolerance"]) {
      source.symmetry_tolerance_mm = r.Length(n, key + ".symmetry_tolerance");
      if (!(source.symmetry_tolerance_mm > 0 && source.symmetry_tolerance_mm <= 1000))
        r.Fail(n, key + ".symmetry_tolerance", "must lie in (0, 1000] mm");
    }
    if (item["file"]) {
      for (const char* k : {"params", "grid", "random", "class"}) {
        if (item[k]) r.Fail(item[k], key + "." + k, "goes with 'family', not 'file'");
      }
      ReadFileSource(r, item, key, &source);
    } else {
      if (item["unit"] || item["encoding"])
        r.Fail(item, key, "'unit' and 'encoding' go with 'file' (the scaled family has its own)");
      ReadFamily(r, item, key, &source);
    }
    sources.push_back(std::move(source));
  }
  return sources;
}

// A distribution of one number: a value (fixed), or {uniform: [low, high]},
// {normal: [mean, sigma]}, {log_uniform: [low, high]} or {choice: [a, b, ...]}; `parse` reads
// one number (lengths with their units).
template <typename Parse>
Distribution ReadDistribution(const Reader& r, const YAML::Node& node, const std::string& key,
                              Parse parse) {
  Distribution d;
  if (node.IsScalar()) {
    d = Distribution::Fixed(parse(node, key));
  } else {
    static const std::vector<std::string> kinds = {"uniform", "normal", "log_uniform", "choice"};
    if (!node.IsMap() || node.size() != 1) {
      r.Fail(node, key,
             "expected a value or one of {uniform: [low, high]}, {normal: [mean, sigma]}, "
             "{log_uniform: [low, high]}, {choice: [...]}");
    }
    const YAML::Node name_node = node.begin()->first;
    const std::string name = name_node.as<std::string>();
    const YAML::Node list = node.begin()->second;
    const auto it = std::find(kinds.begin(), kinds.end(), name);
    if (it == kinds.end()) {
      const std::string best = NearestName(name, kinds);
      r.Fail(name_node, key,
             "unknown distribution '" + name + "'" +
                 (best.empty() ? "" : " (did you mean '" + best + "'?)") +
                 "; known: uniform, normal, log_uniform, choice");
    }
    if (!list.IsSequence()) r.Fail(list, key + "." + name, "expected a list");
    if (name == "choice") {
      d.kind = Distribution::Kind::kChoice;
      for (const YAML::Node& v : list) d.values.push_back(parse(v, key + ".choice"));
    } else {
      if (list.size() != 2)
        r.Fail(list, key + "." + name,
               name == "normal" ? "expected [mean, sigma]" : "expected [low, high]");
      d.kind = name == "uniform"  ? Distribution::Kind::kUniform
               : name == "normal" ? Distribution::Kind::kNormal
                                  : Distribution::Kind::kLogUniform;
      d.a = parse(list[0], key + "." + name);
      d.b = parse(list[1], key + "." + name);
    }
  }
  std::string why;
  if (!d.Check(&why)) r.Fail(node, key, why);
  return d;
}

// The value of the choice `text` among `field`'s choices (an enum's values or a bool's false and
// true, in order); false if it is none of them.
template <typename T>
bool Choose(const Field& field, const std::string& text, T* value) {
  for (size_t i = 0; i < field.choices.size(); ++i) {
    if (text == field.choices[i]) {
      *value = static_cast<T>(i);
      return true;
    }
  }
  return false;
}

// A number against its field's range (Field::range).
void CheckRange(const Reader& r, const YAML::Node& node, const std::string& key, Range range,
                double value) {
  switch (range) {
    case Range::kAny:
      return;
    case Range::kUnit:
      if (!(value >= 0 && value <= 1))
        r.Fail(node, key, "must lie in [0, 1], got " + node.Scalar());
      return;
    case Range::kNonNegative:
      if (value < 0) r.Fail(node, key, "must not be negative");
      return;
    case Range::kPositive:
      if (!(value > 0)) r.Fail(node, key, "must be positive");
      return;
  }
}

// One described field (cad/core/schema.h) from the recipe, by its kind.
template <typename T>
void ReadField(const Reader& r, const YAML::Node& node, const std::string& key, const Field& field,
               T* value) {
  if constexpr (IsOptional<T>::value) {  // set by its key
    typename T::value_type set{};
    ReadField(r, node, key, field, &set);
    *value = std::move(set);
  } else if constexpr (std::is_same_v<T, Distribution>) {  // of numbers or of lengths
    if (field.kind == "distribution_length") {
      *value = ReadDistribution(
          r, node, key, [&r](const YAML::Node& n, const std::string& k) { return r.Length(n, k); });
    } else {
      *value = ReadDistribution(
          r, node, key, [&r](const YAML::Node& n, const std::string& k) { return r.Number(n, k); });
    }
  } else if constexpr (std::is_enum_v<T> || std::is_same_v<T, bool>) {
    if (field.kind == "choice") {
      const std::string text = r.Scalar(node, key);
      if (Choose(field, text, value)) return;
      std::string known;
      for (size_t i = 0; i < field.choices.size(); ++i) {
        known += (i == 0                          ? "'"
                  : i + 1 == field.choices.size() ? " or '"
                                                  : ", '") +
                 std::string(field.choices[i]) + "'";
      }
      r.Fail(node, key, "expected " + known + ", got '" + text + "'");
    } else if constexpr (std::is_same_v<T, bool>) {
      *value = r.Bool(node, key);
    }
  } else if constexpr (std::is_same_v<T, std::string>) {
    *value = r.Scalar(node, key);
  } else if constexpr (std::is_same_v<T, std::filesystem::path>) {  // "path"
    *value = r.ResolvePath(node, key);
  } else if constexpr (IsFixedVector<T>::value) {  // "(linear_)color", "vector3" or "length3"
    if constexpr (std::is_same_v<T, Eigen::Vector3f>) {
      if (field.kind == "linear_color") {
        *value = r.LinearColor(node, key);
        return;
      }
      if (field.kind == "color") {  // sRGB [r, g, b], as given
        *value = r.Color(node, key);
        return;
      }
    }
    if constexpr (T::RowsAtCompileTime == 3) {
      *value = Triple(r, node, key, field.kind == "length3").cast<typename T::Scalar>();
      if (field.kind == "degrees3") *value *= static_cast<typename T::Scalar>(kDeg);
    } else {  // (a pair of lengths, [length, width], has its own message: read by hand)
      constexpr int n = T::RowsAtCompileTime;
      if (!node.IsSequence() || node.size() != n)
        r.Fail(node, key, "expected a list of " + std::to_string(n) + " values");
      for (int i = 0; i < n; ++i)
        (*value)[i] = field.kind == "lengths" ? r.Length(node[i], key) : r.Number(node[i], key);
    }
  } else if constexpr (std::is_same_v<T, std::vector<double>>) {  // "lengths" or numbers
    if (!node.IsSequence() || node.size() == 0) r.Fail(node, key, "expected a list of values");
    value->clear();
    for (const YAML::Node& item : node)
      value->push_back(field.kind == "lengths" ? r.Length(item, key) : r.Number(item, key));
  } else if constexpr (IsVector<T>::value) {
    // "names" (presets, light types): read by hand (Field::by_hand), each against its own table.
    throw std::logic_error(key + ": a list of names is read by hand");
  } else if constexpr (std::is_floating_point_v<T>) {
    const double number = field.kind == "length"  ? r.Length(node, key)
                          : field.kind == "angle" ? r.Angle(node, key)
                                                  : r.Number(node, key);
    CheckRange(r, node, key, field.range, number);
    *value = static_cast<T>(field.kind == "milliseconds" ? number / 1000.0 : number);
  } else if constexpr (std::is_same_v<T, uint64_t>) {
    const int n = r.Integer(node, key);
    if (n < 0) r.Fail(node, key, "must not be negative");
    CheckRange(r, node, key, field.range, n);
    *value = static_cast<uint64_t>(n);
  } else {
    *value = r.Integer(node, key);
    CheckRange(r, node, key, field.range, *value);
  }
}

// The described field of `Options` whose recipe key (or, without one, internal name) is `key`
// (for a key read by hand).
template <typename Options>
Field FieldOf(std::string_view key) {
  const Options defaults{};
  Field found;
  Options::Fields(defaults, [&](const auto&, const Field& field) {
    if (field.Name() == key) found = field;
  });
  return found;
}

// A choice read by hand (a tag): its value, or "unknown WHAT 'TEXT' (known: KNOWN)".
template <typename T>
T ReadKnown(const Reader& r, const YAML::Node& node, const std::string& key, const Field& field,
            const std::string& what, std::vector<std::string> known = {}) {
  const std::string text = r.Scalar(node, key);
  T value{};
  if (Choose(field, text, &value)) return value;
  if (known.empty()) known.assign(field.choices.begin(), field.choices.end());
  r.Fail(node, key, "unknown " + what + " '" + text + "' (known: " + JoinNames(known) + ")");
}

// Every described field of `options` that the recipe section `node` gives, except those read by
// hand (a section may hold the fields of several structs, and keys read elsewhere).
template <typename Options>
void ReadDescribed(const Reader& r, const YAML::Node& node, const std::string& section,
                   Options* options) {
  Options::Fields(*options, [&](auto& value, const Field& field) {
    if (field.key.empty() || field.by_hand || !node[std::string(field.key)]) return;
    ReadField(r, node[std::string(field.key)], section + "." + std::string(field.key), field,
              &value);
  });
}

// The same, after checking that every key of the section is a key of its `schema`.
template <typename Options>
void ReadFields(const Reader& r, const YAML::Node& node, const std::string& section,
                Options* options, const Key& schema) {
  r.ExpectKeys(node, section, schema);
  ReadDescribed(r, node, section, options);
}

void ReadClasses(const Reader& r, const YAML::Node& node, RunSpec* spec) {
  r.ExpectKeys(node, "classes", SchemaAt("classes"));
  if (node["by"]) ReadField(r, node["by"], "classes.by", FieldOf<RunSpec>("by"), &spec->class_by);
  if (node["groups"]) {
    const YAML::Node groups = node["groups"];
    if (!groups.IsMap()) r.Fail(groups, "classes.groups", "expected {class name: [name patterns]}");
    for (auto it = groups.begin(); it != groups.end(); ++it) {
      const std::string name = it->first.as<std::string>();
      const std::string key = "classes.groups." + name;
      std::vector<std::string> patterns;
      // A copy: the iterator's value is a temporary, and a range-for over its member would read
      // it after its end (AddressSanitizer: stack-use-after-scope).
      const YAML::Node value = it->second;
      if (value.IsSequence()) {
        for (const YAML::Node& p : value) patterns.push_back(r.Scalar(p, key));
      } else {
        patterns.push_back(r.Scalar(value, key));
      }
      if (patterns.empty()) r.Fail(value, key, "give at least one name pattern");
      spec->class_groups.emplace_back(name, patterns);
    }
  }
}

Material ReadMaterial(const Reader& r, const YAML::Node& node, const std::string& key,
                      const Key& schema);

// Which parts a rule is for (MaterialRule, PhysicsRule): `name`, `family` and `file` patterns, at
// least one given; a family without glob characters must exist.
template <typename Rule>
void ReadPartPatterns(const Reader& r, const YAML::Node& item, const std::string& key, Rule* rule) {
  if (item["name"]) rule->name = r.Scalar(item["name"], key + ".name");
  if (item["family"]) {
    rule->family = r.Scalar(item["family"], key + ".family");
    if (FindFamily(rule->family) == nullptr &&
        rule->family.find_first_of("*?[") == std::string::npos) {
      r.Fail(item["family"], key + ".family",
             "unknown family '" + rule->family + "' (known: " + KnownFamilies() + ")");
    }
  }
  if (item["file"]) rule->file = r.Scalar(item["file"], key + ".file");
  if (rule->name.empty() && rule->family.empty() && rule->file.empty())
    r.Fail(item, key, "say which parts: 'name', 'family' or 'file' (a pattern)");
}

// How a part or a container behaves in contact: density (kg/m3), friction, restitution; each a
// number or, where `ranges`, [low, high] drawn per scene.
void ReadPhysics(const Reader& r, const YAML::Node& node, const std::string& key, PhysicsDraw* d,
                 const Key& schema, bool ranges) {
  r.ExpectKeys(node, key, schema);
  // Each described field (PhysicsMaterial::Fields) into both ends, the high end's found by its
  // place among the fields.
  std::vector<double*> high;
  PhysicsMaterial::Fields(d->high,
                          [&high](double& value, const Field&) { high.push_back(&value); });
  size_t i = 0;
  PhysicsMaterial::Fields(d->low, [&](double& low, const Field& field) {
    double& hi = *high[i++];
    const YAML::Node v = node[std::string(field.key)];
    if (!v) return;
    const std::string at = key + "." + std::string(field.key);
    if (v.IsSequence()) {
      if (!ranges) r.Fail(v, at, "expected a number (a container's is not drawn)");
      if (v.size() != 2) r.Fail(v, at, "expected a number or a range [low, high]");
      ReadField(r, v[0], at, field, &low);
      ReadField(r, v[1], at, field, &hi);
      if (low > hi) r.Fail(v, at, "the range's low end exceeds its high end");
    } else {
      ReadField(r, v, at, field, &low);
      hi = low;
    }
  });
  r.Check(*d, node, key);
}

// A pile's container: {type: tote | floor | file, inner: [x, y], height, wall, floor,
// corner_radius (tote), file, unit, encoding, up (file), color, material, friction, restitution}.
void ReadContainer(const Reader& r, const YAML::Node& node, const std::string& key,
                   SceneSpec* scene) {
  Container& c = scene->arrangement.container;
  PhysicsDraw material(c.material);
  ReadPhysics(r, node, key, &material, SchemaAt("scene.container"), false);  // a mapping
  c.material = material.low;
  if (!node["type"]) r.Fail(node, key, "a container needs a 'type': tote, floor or file");
  // (A file's mesh is read with the parts: prepare.)
  c.kind = ReadKnown<Container::Kind>(r, node["type"], key + ".type", FieldOf<Container>("type"),
                                      "container");
  // (Keys of another type were refused by ReadPhysics' ExpectKeys: Key::only_with.)
  if (c.kind == Container::Kind::kMesh) {
    if (!node["file"]) r.Fail(node, key, "a container of type file needs a 'file' (CAD or mesh)");
    PartSource source;
    ReadUp(r, node, key, &source);
    ReadFileSource(r, node, key, &source);
    scene->container_file = std::move(source);
  }
  if (const YAML::Node inner = node["inner"]) {
    if (!inner.IsSequence() || inner.size() != 2)
      r.Fail(inner, key + ".inner", "expected [length, width], e.g. [355 mm, 265 mm]");
    c.inner_mm = {r.Length(inner[0], key + ".inner"), r.Length(inner[1], key + ".inner")};
  }
  ReadDescribed(r, node, key, &c);
  if (node["color"]) scene->container_color = r.Color(node["color"], key + ".color");
  if (node["material"])
    scene->container_material =
        ReadMaterial(r, node["material"], key + ".material", SchemaAt("scene.container.material"));
  std::string why;
  if (!(c.kind == Container::Kind::kMesh ? c.material.Check(&why) : c.Check(&why)))
    r.Fail(node, key, why);
}

// A scene's arrangement keys (ArrangementOptions::Fields) and a pile's `container` and
// `physics`; `schema` is the section's (the root `scene`, or an entry of `scenes` with its own
// keys, read elsewhere).
void ReadLayout(const Reader& r, const YAML::Node& node, const std::string& key, SceneSpec* scene,
                const Key& schema) {
  ReadFields(r, node, key, &scene->arrangement, schema);
  const bool pile = scene->arrangement.layout == Layout::kPile;
  const bool dropped = pile || scene->arrangement.pose == PoseMode::kDropped;
  if (node["container"] && !pile)
    r.Fail(node["container"], key + ".container", "only a pile (layout: pile) has one");
  if (node["physics"] && !dropped) {
    r.Fail(node["physics"], key + ".physics",
           "only a pile (layout: pile) or dropped parts (pose: dropped) have physics");
  }
  if (node["container"]) ReadContainer(r, node["container"], key + ".container", scene);
  if (const YAML::Node physics = node["physics"]; physics && physics.IsSequence()) {
    // Rules: the first whose patterns match a part gives its physics.
    for (size_t i = 0; i < physics.size(); ++i) {
      const std::string at = key + ".physics[" + std::to_string(i) + "]";
      PhysicsRule rule;
      rule.where = r.Where(physics[i]);
      rule.physics = scene->arrangement.physics;
      ReadPhysics(r, physics[i], at, &rule.physics, SchemaAt("scene.physics"), true);
      ReadPartPatterns(r, physics[i], at, &rule);
      scene->physics_rules.push_back(std::move(rule));
    }
  } else if (physics) {
    // One map for every part: rules (name, family, file) go in a list.
    for (const char* k : {"name", "family", "file"}) {
      if (physics.IsMap() && physics[k])
        r.Fail(physics[k], key + ".physics." + k,
               "a rule's pattern: give the rules as a list, [{" + std::string(k) + ": ..., ...}]");
    }
    ReadPhysics(r, physics, key + ".physics", &scene->arrangement.physics,
                SchemaAt("scene.physics"), true);
  }
  r.Check(scene->arrangement, node, key);
}

SceneSpec ReadSceneEntry(const Reader& r, const YAML::Node& node, const std::string& key) {
  r.ExpectKeys(node, key, SchemaAt("scenes[]"));
  if (!node["parts"]) r.Fail(node, key, "a scene needs 'parts'");
  SceneSpec scene;
  // (`randomize` is read once the recipe's own is known.)
  ReadLayout(r, node, key, &scene, SchemaAt("scenes[]"));
  scene.name = node["name"] ? r.Scalar(node["name"], key + ".name") : key;
  scene.sources = ReadParts(r, node["parts"], key + ".parts");
  return scene;
}

void ReadTessellation(const Reader& r, const YAML::Node& node, RunSpec* spec) {
  ReadFields(r, node, "tessellation", &spec->tessellation, SchemaAt("tessellation"));
  if (node["crease_angle"]) {
    ReadField(r, node["crease_angle"], "tessellation.crease_angle",
              FieldOf<RunSpec>("crease_angle"), &spec->crease_angle_rad);
    if (spec->crease_angle_rad < 0.0 || spec->crease_angle_rad > M_PI) {
      r.Fail(node["crease_angle"], "tessellation.crease_angle",
             "must lie between 0 and 180 degrees");
    }
  }
  r.Check(spec->tessellation, node, "tessellation");
}

Eigen::Vector3d Triple(const Reader& r, const YAML::Node& node, const std::string& key,
                       bool length) {
  if (!node.IsSequence() || node.size() != 3) r.Fail(node, key, "expected [x, y, z]");
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) v[i] = length ? r.Length(node[i], key) : r.Number(node[i], key);
  return v;
}

// A camera's keys (`camera:`, or an entry of `cameras:` with its `other` keys read elsewhere).
void ReadCamera(const Reader& r, const YAML::Node& node, const std::string& key, Intrinsics* kp,
                SensorOptions* sensor, const Key& schema) {
  r.ExpectKeys(node, key, schema);
  Intrinsics& k = *kp;
  if (node["preset"]) {
    const std::string preset = r.Scalar(node["preset"], key + ".preset");
    const CameraPreset* found = FindCameraPreset(preset);
    if (found == nullptr) {
      std::string known;
      for (const CameraPreset& p : CameraPresets())
        known += (known.empty() ? "" : ", ") + std::string(p.name);
      r.Fail(node["preset"], key + ".preset",
             "unknown preset '" + preset + "' (known: " + known + ")");
    }
    k = found->intrinsics;
    if (found->gray) sensor->image = SensorOptions::Image::kGray;
  }
  ReadDescribed(r, node, key, &k);
  // A field of view in place of fx, fy, cx and cy: from the width and the height.
  if (node["hfov"]) {
    const double hfov = r.Angle(node["hfov"], key + ".hfov");
    if (!(hfov > 0 && hfov < M_PI))
      r.Fail(node["hfov"], key + ".hfov", "must lie between 0 and 180 degrees");
    if (node["fx"] || node["fy"] || node["cx"] || node["cy"])
      r.Fail(node["hfov"], key + ".hfov", "give hfov or fx/fy/cx/cy, not both");
    k = Intrinsics::FromFov(k.width, k.height, hfov);
  }
  if (const YAML::Node distortion = node["distortion"]) {
    ReadFields(r, distortion, key + ".distortion", &k.distortion, SchemaAt("camera.distortion"));
    r.Check(k, distortion, key + ".distortion");
  }
  r.Check(k, node, key);
  if (const YAML::Node lens = node["lens"]) {
    ReadFields(r, lens, key + ".lens", &sensor->lens, SchemaAt("camera.lens"));
    if (!lens["focal_length"])
      r.Fail(lens, key + ".lens", "give the lens's 'focal_length' (with f_number: the aperture)");
    r.Check(sensor->lens, lens, key + ".lens");
  }
  // motion: the camera's velocities in its own frame while the shutter is open.
  if (const YAML::Node motion = node["motion"]) {
    const std::string at = key + ".motion";
    r.ExpectKeys(motion, at, SchemaAt("camera.motion"));
    if (!motion["exposure_ms"])
      r.Fail(motion, at, "give 'exposure_ms', how long the shutter is open");
    ReadDescribed(r, motion, at, &sensor->motion);
    r.Check(sensor->motion, motion, at);
  }
  ReadDescribed(r, node, key, sensor);  // the image
  if (const YAML::Node imager = node["imager"]) {
    ReadFields(r, imager, key + ".imager", &sensor->imager, SchemaAt("camera.imager"));
    r.Check(sensor->imager, imager, key + ".imager");
  }
  // depth: a model's name, or {model: NAME, KEY: VALUE...} overriding the model's defaults.
  if (const YAML::Node depth = node["depth"]) {
    const YAML::Node model = depth.IsMap() ? depth["model"] : depth;
    if (!model) r.Fail(depth, key + ".depth", "give the sensor's 'model'");
    const std::string model_key = depth.IsMap() ? key + ".depth.model" : key + ".depth";
    DepthModel m;
    DepthModel::Fields(m, [&](auto& value, const Field& field) {
      if constexpr (std::is_enum_v<std::decay_t<decltype(value)>>) {
        if (field.key == "model") ReadField(r, model, model_key, field, &value);
      }
    });
    m = DepthModel::Defaults(m.kind);
    if (depth.IsMap()) ReadFields(r, depth, key + ".depth", &m, SchemaAt("camera.depth"));
    r.Check(m, depth, key + ".depth");
    sensor->depth = m;
  }
}

void ReadSweep(const Reader& r, const YAML::Node& node, RunSpec* spec) {
  r.ExpectKeys(node, "sweep", SchemaAt("sweep"));
  // Each axis a series (the recipe's own syntax); the target, the sampler and the jitter described.
  const auto angle = [&](const YAML::Node& n, const std::string& k) { return r.Angle(n, k); };
  const auto length = [&](const YAML::Node& n, const std::string& k) { return r.Length(n, k); };
  SweepOptions& s = spec->sweep;
  if (node["yaw"]) s.yaw_rad = r.Series(node["yaw"], "sweep.yaw", angle);
  if (node["pitch"]) s.pitch_rad = r.Series(node["pitch"], "sweep.pitch", angle);
  if (node["radius"]) s.radius_mm = r.Series(node["radius"], "sweep.radius", length);
  ReadDescribed(r, node, "sweep", &s);
  r.Check(s, node, "sweep");
  ViewSampler& v = spec->sampler;
  ReadDescribed(r, node, "sweep", &v);
  ReadDescribed(r, node, "sweep", spec);  // min_visible_pixels (RunSpec's own)
  // Fibonacci and random views fill the band between the lowest and highest pitch; random radii the
  // range between the smallest and largest radius.
  v.min_pitch_rad = *std::min_element(s.pitch_rad.begin(), s.pitch_rad.end());
  v.max_pitch_rad = *std::max_element(s.pitch_rad.begin(), s.pitch_rad.end());
  v.min_radius_mm = *std::min_element(s.radius_mm.begin(), s.radius_mm.end());
  v.max_radius_mm = *std::max_element(s.radius_mm.begin(), s.radius_mm.end());
  r.Check(v, node, "sweep");
}

// `cameras:`, a rig: a list of cameras with names, the first one the rig's frame (the sweep
// places it) and the others fixed to it by `position` and `look_at` or `rotation`.
void ReadCameras(const Reader& r, const YAML::Node& node, RunSpec* spec) {
  constexpr size_t kMaxSensors = 16;
  if (!node.IsSequence() || node.size() == 0)
    r.Fail(node, "cameras", "expected a list of cameras (a rig), each with a 'name'");
  if (node.size() > kMaxSensors)
    r.Fail(node, "cameras", "at most " + std::to_string(kMaxSensors) + " cameras in a rig");
  spec->rig.clear();
  for (size_t i = 0; i < node.size(); ++i) {
    const YAML::Node entry = node[i];
    const std::string key = "cameras[" + std::to_string(i) + "]";
    RigSensor sensor;
    sensor.where = r.Where(entry);
    ReadCamera(r, entry, key, &sensor.intrinsics, &sensor.sensor, SchemaAt("cameras[]"));
    if (i > 0 && entry["motion"]) {
      r.Fail(entry["motion"], key + ".motion",
             "the rig moves as one: give its motion on the first camera (the rig's frame)");
    }
    if (!entry["name"]) r.Fail(entry, key, "a rig's camera needs a 'name' (e.g. xyz, realsense)");
    sensor.name = r.Scalar(entry["name"], key + ".name");
    // BOP appends the name to folder names (rgb_NAME/): lower-case letters and digits only.
    const bool plain = !sensor.name.empty() && sensor.name.size() <= 32 &&
                       std::all_of(sensor.name.begin(), sensor.name.end(), [](char c) {
                         return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9');
                       });
    if (!plain) {
      r.Fail(
          entry["name"], key + ".name",
          "'" + sensor.name + "': use 1-32 lower-case letters and digits (BOP writes rgb_NAME/)");
    }
    // scene_gt_NAME.json must not read as BOP's scene_gt_info.json, scene_gt_coco.json or our
    // scene_gt_world.json.
    for (const char* taken : {"info", "coco", "world"}) {
      if (sensor.name.rfind(taken, 0) == 0) {
        r.Fail(entry["name"], key + ".name",
               "'" + sensor.name +
                   "': names starting with info, coco or world would make scene_gt_NAME.json "
                   "look like BOP's scene_gt_info.json and its kin");
      }
    }
    for (const RigSensor& earlier : spec->rig) {
      if (earlier.name == sensor.name)
        r.Fail(entry["name"], key + ".name", "'" + sensor.name + "' names two cameras");
    }
    if (i == 0) {
      for (const char* pose : {"position", "look_at", "rotation"}) {
        if (entry[pose]) {
          r.Fail(entry[pose], key + "." + pose,
                 "the first camera is the rig's frame (the sweep places it): give the others' "
                 "poses relative to it");
        }
      }
    }
    Eigen::Vector3d position = Eigen::Vector3d::Zero();
    if (entry["position"]) position = Triple(r, entry["position"], key + ".position", true);
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
    if (entry["look_at"] && entry["rotation"])
      r.Fail(entry["rotation"], key + ".rotation", "give 'look_at' or 'rotation', not both");
    if (entry["look_at"]) {
      // z towards the point; x along the rig's y (down) x z, so the image does not roll.
      const Eigen::Vector3d at = Triple(r, entry["look_at"], key + ".look_at", true);
      const Eigen::Vector3d z = (at - position).normalized();
      const Eigen::Vector3d x = Eigen::Vector3d::UnitY().cross(z);
      if (!((at - position).norm() > 1e-9) || x.norm() < 1e-6) {
        r.Fail(entry["look_at"], key + ".look_at",
               "must lie away from the camera and not straight above or below it (the rig's y)");
      }
      rotation.col(0) = x.normalized();
      rotation.col(2) = z;
      rotation.col(1) = z.cross(rotation.col(0));
    } else if (const YAML::Node rot = entry["rotation"]) {
      if (!rot.IsSequence() || rot.size() != 9) {
        r.Fail(rot, key + ".rotation",
               "expected the 9 numbers of rig_R_cam, row-major (the camera's axes as columns)");
      }
      for (int k = 0; k < 9; ++k) rotation(k / 3, k % 3) = r.Number(rot[k], key + ".rotation");
      if ((rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).norm() > 1e-4 ||
          rotation.determinant() < 0) {
        r.Fail(rot, key + ".rotation", "is not a rotation (orthonormal, determinant 1, to 1e-4)");
      }
      // Calibration files print 6-8 digits: the nearest exact rotation.
      const Eigen::JacobiSVD<Eigen::Matrix3d> svd(rotation,
                                                  Eigen::ComputeFullU | Eigen::ComputeFullV);
      rotation = svd.matrixU() * svd.matrixV().transpose();
    }
    sensor.rig_from_cam.linear() = rotation;
    sensor.rig_from_cam.translation() = position;
    // The rig's motion, as each camera on it sees it.
    if (i > 0) sensor.sensor.motion = spec->rig[0].sensor.motion.Seen(sensor.rig_from_cam);
    spec->rig.push_back(std::move(sensor));
  }
  spec->intrinsics = spec->rig[0].intrinsics;
  spec->sensor = spec->rig[0].sensor;
}

void ReadRender(const Reader& r, const YAML::Node& node, RunSpec* spec) {
  ReadFields(r, node, "render", &spec->render, SchemaAt("render"));
  // The fast mode's look (Scene::Fields) and its lights (Scene::Light::Fields).
  Scene& look = spec->look;
  ReadDescribed(r, node, "render", &look);
  if (node["lights"]) {
    const YAML::Node lights = node["lights"];
    if (!lights.IsSequence())
      r.Fail(lights, "render.lights",
             "expected a list of {direction: [x, y, z]} or {position: [x, y, z]}");
    look.lights.clear();
    for (size_t i = 0; i < lights.size(); ++i) {
      const std::string key = "render.lights[" + std::to_string(i) + "]";
      r.ExpectKeys(lights[i], key, SchemaAt("render.lights[]"));
      if (!lights[i]["direction"] == !lights[i]["position"])
        r.Fail(lights[i], key, "give a direction or a position");
      Scene::Light light;
      ReadDescribed(r, lights[i], key, &light);
      light.kind =
          lights[i]["direction"] ? Scene::Light::Kind::kDirectional : Scene::Light::Kind::kPoint;
      if (light.kind == Scene::Light::Kind::kDirectional && light.direction.norm() == 0)
        r.Fail(lights[i]["direction"], key + ".direction", "the direction must not be zero");
      look.lights.push_back(light);
    }
  }
  if (node["colors"]) {
    // A bool's choices (RunSpec::Fields) are false first; the message names cad first.
    const std::string colors = r.Scalar(node["colors"], "render.colors");
    if (!Choose(FieldOf<RunSpec>("colors"), colors, &spec->cad_colors))
      r.Fail(node["colors"], "render.colors", "expected 'cad' or 'palette', got '" + colors + "'");
  }
  r.Check(spec->render, node, "render");
}

// A texture's keys over `texture` (a preset's, or none): its type first (a new type starts from
// that type's defaults), the described keys, then an image's pixels and projection.
void ReadTexture(const Reader& r, const YAML::Node& t, const std::string& key, Texture* texture) {
  const Field type = FieldOf<Texture>("type");
  // The message lists the patterns, then none.
  std::vector<std::string> known(type.choices.begin() + 1, type.choices.end());
  known.emplace_back(type.choices[0]);
  const auto kind = ReadKnown<Texture::Kind>(r, t["type"], key + ".type", type, "texture", known);
  if (kind != texture->kind) *texture = Texture{};
  texture->kind = kind;
  ReadDescribed(r, t, key, texture);
  if (t["seed"]) texture->seed = static_cast<uint64_t>(r.Integer(t["seed"], key + ".seed"));
  if (texture->kind == Texture::Kind::kImage) {
    if (!t["file"]) r.Fail(t, key, "an image texture needs a 'file'");
    try {
      texture->pixels = LoadLinearImage(texture->image);
    } catch (const Error& e) {
      r.Fail(t["file"], key + ".file", e.what());
    }
    if (const YAML::Node p = t["projection"]) {
      texture->projection = ReadKnown<Texture::Projection>(
          r, p, key + ".projection", FieldOf<Texture>("projection"), "projection");
    }
  } else if (t["file"]) {
    r.Fail(t["file"], key + ".file", "only an image texture reads a file");
  } else if (t["projection"]) {
    r.Fail(t["projection"], key + ".projection",
           "only an image texture is projected (procedural ones are solid)");
  }
}

// A material: a preset, then the keys that change it, and a texture.
Material ReadMaterial(const Reader& r, const YAML::Node& node, const std::string& key,
                      const Key& schema) {
  r.ExpectKeys(node, key, schema);
  Material m;
  if (node["preset"]) {
    const std::string name = r.Scalar(node["preset"], key + ".preset");
    if (!MaterialPreset(name, &m)) {
      const std::string known = JoinNames(MaterialPresetNames());
      const std::string best = NearestName(name, MaterialPresetNames());
      r.Fail(node["preset"], key + ".preset",
             "unknown material '" + name + "'" +
                 (best.empty() ? "" : " (did you mean '" + best + "'?)") + "; known: " + known);
    }
  }
  if (const YAML::Node c = node["base_color"]) {
    if (c.IsScalar() && c.Scalar() == "cad") {
      m.base_from_part = true;
    } else {
      m.surface.base_color = r.LinearColor(c, key + ".base_color");
      m.base_from_part = false;
    }
  }
  ReadDescribed(r, node, key, &m.surface);
  ReadDescribed(r, node, key, &m);
  if (const YAML::Node t = node["texture"]) {
    const std::string tkey = key + ".texture";
    if (t.IsScalar() && t.Scalar() == "none") {
      m.texture = Texture{};
    } else {
      if (!t.IsMap() || !t["type"]) r.Fail(t, tkey, "a texture needs a 'type'");
      r.ExpectKeys(t, tkey, SchemaAt("materials.floor.texture"));
      ReadTexture(r, t, tkey, &m.texture);
    }
  }
  r.Check(m, node, key);
  return m;
}

void ReadMaterials(const Reader& r, const YAML::Node& node, RunSpec* spec) {
  r.ExpectKeys(node, "materials", SchemaAt("materials"));
  if (node["floor"]) {
    spec->look.floor_material =
        ReadMaterial(r, node["floor"], "materials.floor", SchemaAt("materials.floor"));
    if (spec->look.floor_material.texture.projection == Texture::Projection::kUv)
      r.Fail(node["floor"], "materials.floor",
             "the floor has no texture coordinates: use projection 'triplanar' (or 'auto')");
  }
  if (node["default"])
    spec->default_material =
        ReadMaterial(r, node["default"], "materials.default", SchemaAt("materials.default"));
  if (const YAML::Node assign = node["assign"]) {
    if (!assign.IsSequence())
      r.Fail(assign, "materials.assign",
             "expected a list of {name|family|file: pattern, preset: ..., ...}");
    for (size_t i = 0; i < assign.size(); ++i) {
      const std::string key = "materials.assign[" + std::to_string(i) + "]";
      const YAML::Node item = assign[i];
      MaterialRule rule;
      rule.where = r.Where(item);
      rule.material = ReadMaterial(r, item, key, SchemaAt("materials.assign[]"));
      ReadPartPatterns(r, item, key, &rule);
      spec->material_rules.push_back(std::move(rule));
    }
  }
}

// A direction as [x, y, z], or towards a `target` point from `position`.
Eigen::Vector3d ReadAim(const Reader& r, const YAML::Node& node, const std::string& key,
                        const Eigen::Vector3d& position, const Eigen::Vector3d& fallback) {
  if (node["direction"] && node["target"])
    r.Fail(node["target"], key + ".target", "give 'direction' or 'target', not both");
  if (node["direction"]) {
    const Eigen::Vector3d d = Triple(r, node["direction"], key + ".direction", false);
    if (d.norm() == 0) r.Fail(node["direction"], key + ".direction", "must not be zero");
    return d;
  }
  if (node["target"]) {
    const Eigen::Vector3d d = Triple(r, node["target"], key + ".target", true) - position;
    if (d.norm() == 0) r.Fail(node["target"], key + ".target", "is the light's own position");
    return d;
  }
  return fallback;
}

LightSource ReadLightSource(const Reader& r, const YAML::Node& node, const std::string& key) {
  if (!node.IsMap()) r.Fail(node, key, "expected a mapping of keys to values");
  if (!node["type"]) r.Fail(node, key, "a light needs a 'type': point, spot, rect, disc or sun");
  LightSource l;
  using K = LightSource::Kind;
  l.kind = ReadKnown<K>(r, node["type"], key + ".type", FieldOf<LightSource>("type"), "light");
  if (l.kind == K::kSun && node["power"])
    r.Fail(node["power"], key + ".power", "a sun's is 'strength' (irradiance, W/m2, as Blender's)");
  if (l.kind != K::kSun && node["strength"])
    r.Fail(node["strength"], key + ".strength", "this light's is 'power' (W, as Blender's)");
  r.ExpectKeys(node, key, SchemaAt("lighting.lights[]"));
  ReadDescribed(r, node, key, &l);
  if (l.kind != K::kPoint) l.direction = ReadAim(r, node, key, l.position, l.direction);
  // The sun's power is its `strength` (irradiance), as in Blender.
  const char* amount = l.kind == K::kSun ? "strength" : "power";
  if (!node[amount]) {
    r.Fail(node, key,
           l.kind == K::kSun ? "a sun needs a 'strength' (irradiance, W/m2, as Blender's)"
                             : "a light needs a 'power' (W, as Blender's)");
  }
  ReadField(r, node[amount], key + "." + amount, FieldOf<LightSource>("power"), &l.power);
  if (l.kind == K::kDisc && !node["radius"]) r.Fail(node, key, "a disc light needs a 'radius'");
  if (const YAML::Node size = node["size"]) {
    if (size.IsScalar()) {
      l.size_x_mm = l.size_y_mm = r.Length(size, key + ".size");
    } else if (size.IsSequence() && size.size() == 2) {
      l.size_x_mm = r.Length(size[0], key + ".size");
      l.size_y_mm = r.Length(size[1], key + ".size");
    } else {
      r.Fail(size, key + ".size", "expected a length or [x, y]");
    }
  }
  r.Check(l, node, key);
  return l;
}

void ReadLighting(const Reader& r, const YAML::Node& node, RunSpec* spec) {
  r.ExpectKeys(node, "lighting", SchemaAt("lighting"));
  if (const YAML::Node lights = node["lights"]) {
    if (!lights.IsSequence())
      r.Fail(lights, "lighting.lights", "expected a list of {type: point|spot|rect|disc|sun, ...}");
    spec->look.light_sources.clear();
    for (size_t i = 0; i < lights.size(); ++i) {
      spec->look.light_sources.push_back(
          ReadLightSource(r, lights[i], "lighting.lights[" + std::to_string(i) + "]"));
    }
  }
  if (const YAML::Node env = node["environment"]) {
    const std::string key = "lighting.environment";
    Environment& e = spec->look.environment;
    if (!env.IsMap()) r.Fail(env, key, "expected a mapping of keys to values");
    e.kind = env["type"] ? ReadKnown<Environment::Kind>(r, env["type"], key + ".type",
                                                        FieldOf<Environment>("type"), "environment")
                         : Environment::Kind::kUniform;
    r.ExpectKeys(env, key, SchemaAt("lighting.environment"));
    if (e.kind == Environment::Kind::kImage && !env["file"])
      r.Fail(env, key, "an image environment needs a 'file' (HDR, EXR, ...)");
    // Colours are linear radiance multipliers (Blender's world colour).
    ReadDescribed(r, env, key, &e);
    if (env["file"]) {
      try {
        e.pixels = LoadLinearImage(e.image);
      } catch (const Error& err) {
        r.Fail(env["file"], key + ".file", err.what());
      }
    }
    r.Check(e, env, key);
  }
}

// A list of names, or one name, or {choice: [names]}: what is picked from, equally likely.
std::vector<std::pair<YAML::Node, std::string>> ReadNameChoice(const Reader& r,
                                                               const YAML::Node& node,
                                                               const std::string& key) {
  std::vector<std::pair<YAML::Node, std::string>> names;
  YAML::Node list = node;
  if (node.IsMap()) {
    r.ExpectMap(node, key, {"choice"});
    list = node["choice"];
  }
  if (list.IsScalar()) {
    names.emplace_back(list, r.Scalar(list, key));
  } else if (list.IsSequence() && list.size() > 0) {
    for (const YAML::Node& n : list) names.emplace_back(n, r.Scalar(n, key));
  } else {
    r.Fail(node, key, "expected a name, or {choice: [names]} (not empty)");
  }
  return names;
}

// Every PNG, JPEG, EXR and HDR image in the folder `node` names (relative to the recipe), sorted
// by name so that picks do not depend on the file system, read once.
ImageChoice ReadImageFolder(const Reader& r, const YAML::Node& node, const std::string& key) {
  std::filesystem::path folder = r.Scalar(node, key);
  if (folder.is_relative()) folder = r.base_dir() / folder;
  folder = folder.lexically_normal();
  std::error_code ec;
  if (!std::filesystem::is_directory(folder, ec))
    r.Fail(node, key, folder.string() + ": no such folder");
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(folder, ec)) {
    std::string ext = entry.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (entry.is_regular_file() &&
        (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".exr" || ext == ".hdr")) {
      files.push_back(entry.path());
    }
  }
  if (files.empty())
    r.Fail(node, key, folder.string() + ": no PNG, JPEG, EXR or HDR images in the folder");
  std::sort(files.begin(), files.end());
  ImageChoice images;
  for (const std::filesystem::path& file : files) {
    try {
      images.pixels.push_back(LoadLinearImage(file));
    } catch (const Error& e) {
      r.Fail(node, key, e.what());
    }
    images.files.push_back(file);
    images.names.push_back(file.filename().string());
  }
  return images;
}

// A material's randomisation (parts, floor, fixtures, distractors): presets picked by name,
// textures from a folder, the described distributions, and its group's `per` (`per_field`).
MaterialRandomization ReadMaterialRandomization(const Reader& r, const YAML::Node& node,
                                                const std::string& key, const Key& schema,
                                                const Field& per_field, DrawPer* per) {
  r.ExpectKeys(node, key, schema);
  MaterialRandomization m;
  if (const YAML::Node p = node["preset"]) {
    for (const auto& [n, name] : ReadNameChoice(r, p, key + ".preset")) {
      Material preset;
      if (!MaterialPreset(name, &preset)) {
        const std::string best = NearestName(name, MaterialPresetNames());
        r.Fail(n, key + ".preset",
               "unknown material '" + name + "'" +
                   (best.empty() ? "" : " (did you mean '" + best + "'?)"));
      }
      m.presets.push_back(preset);
      m.preset_names.push_back(name);
    }
  }
  if (const YAML::Node t = node["textures"]) {
    // Every image in a folder, projected triplanarly in tiles of `scale` (meshes with texture
    // coordinates use them).
    const std::string at = key + ".textures";
    r.ExpectKeys(t, at, SchemaAt("randomize.floor.textures"));
    if (!t["folder"]) r.Fail(t, at, "give the 'folder' of images to pick from");
    const ImageChoice images = ReadImageFolder(r, t["folder"], at + ".folder");
    Texture texture;
    texture.kind = Texture::Kind::kImage;
    texture.scale_mm = 200.0;
    if (t["scale"])
      ReadField(r, t["scale"], at + ".scale", FieldOf<Texture>("scale"), &texture.scale_mm);
    for (size_t i = 0; i < images.files.size(); ++i) {
      texture.image = images.files[i];
      texture.pixels = images.pixels[i];
      m.textures.push_back(texture);
      m.texture_names.push_back(images.names[i]);
    }
  }
  ReadDescribed(r, node, key, &m);
  if (node["per"]) ReadField(r, node["per"], key + ".per", per_field, per);
  std::string why;
  if (!m.Check(&why)) r.Fail(node, key, why);
  return m;
}

// `randomize.distractors:`: how many, what (primitives, files, folders, families), how large, and
// their materials.
void ReadDistractors(const Reader& r, const YAML::Node& n, const std::string& at,
                     RandomizeSpec* spec) {
  r.ExpectKeys(n, at, SchemaAt("randomize.distractors"));
  DistractorRandomization d;
  ReadDescribed(r, n, at, &d);
  if (n["material"]) {
    d.material = ReadMaterialRandomization(
        r, n["material"], at + ".material", SchemaAt("randomize.distractors.material"),
        FieldOf<DistractorRandomization>("material_per"), &d.material_per);
  }
  std::vector<DistractorObject> objects;
  if (const YAML::Node list = n["objects"]) {
    if (!list.IsSequence() || list.size() == 0) {
      r.Fail(list, at + ".objects",
             "expected a list such as [box, cylinder, {file: part.stl}, {folder: clutter/}, "
             "{family: hex_nut}]");
    }
    static const std::vector<std::pair<std::string, DistractorObject::Kind>> primitives = {
        {"box", DistractorObject::Kind::kBox},
        {"cylinder", DistractorObject::Kind::kCylinder},
        {"sphere", DistractorObject::Kind::kSphere}};
    for (size_t i = 0; i < list.size(); ++i) {
      const YAML::Node item = list[i];
      const std::string key = at + ".objects[" + std::to_string(i) + "]";
      DistractorObject object;
      object.where = r.Where(item);
      if (item.IsScalar() || item["primitive"]) {
        const YAML::Node name_node = item.IsScalar() ? item : item["primitive"];
        if (!item.IsScalar()) {
          r.ExpectKeys(item, key, SchemaAt("randomize.distractors.objects[]"));
          if (item.size() > 1)
            r.Fail(item, key, "a primitive is all a distractor object then says: no other keys");
        }
        const std::string name = r.Scalar(name_node, key);
        const auto it = std::find_if(primitives.begin(), primitives.end(),
                                     [&](const auto& p) { return p.first == name; });
        if (it == primitives.end()) {
          r.Fail(name_node, key,
                 "unknown primitive '" + name +
                     "' (known: box, cylinder, sphere; files and families go in a map such as "
                     "{file: part.stl})");
        }
        object.kind = it->second;
        objects.push_back(std::move(object));
        continue;
      }
      r.ExpectKeys(item, key, SchemaAt("randomize.distractors.objects[]"));
      if ((item["file"] ? 1 : 0) + (item["folder"] ? 1 : 0) + (item["family"] ? 1 : 0) != 1)
        r.Fail(item, key, "give one of 'primitive', 'file', 'folder' or 'family'");
      object.kind = DistractorObject::Kind::kSource;  // (no `up`: distractors fall at random)
      if (item["family"]) {
        if (item["unit"]) r.Fail(item["unit"], key + ".unit", "goes with 'file' or 'folder'");
        ReadFamily(r, item, key, &object.source);
        objects.push_back(std::move(object));
        continue;
      }
      for (const char* k : {"params", "grid", "random"}) {
        if (item[k]) r.Fail(item[k], key + "." + k, "goes with 'family'");
      }
      if (item["file"]) {
        ReadFileSource(r, item, key, &object.source);
        objects.push_back(std::move(object));
        continue;
      }
      // A folder: every CAD and mesh file in it, sorted by name (the picks do not depend on the
      // file system's order).
      std::filesystem::path folder = r.Scalar(item["folder"], key + ".folder");
      if (folder.is_relative()) folder = r.base_dir() / folder;
      folder = folder.lexically_normal();
      std::error_code ec;
      if (!std::filesystem::is_directory(folder, ec))
        r.Fail(item["folder"], key + ".folder", folder.string() + ": no such folder");
      static const std::set<std::string> extensions = {".step", ".stp",  ".p21", ".iges", ".igs",
                                                       ".brep", ".rle",  ".stl", ".obj",  ".ply",
                                                       ".dae",  ".gltf", ".glb", ".3mf",  ".off"};
      std::vector<std::filesystem::path> files;
      for (const auto& entry : std::filesystem::directory_iterator(folder, ec)) {
        std::string ext = entry.path().extension().string();
        std::transform(ext.begin(), ext.end(), ext.begin(),
                       [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
        if (entry.is_regular_file() && extensions.count(ext) != 0) files.push_back(entry.path());
      }
      if (files.empty()) {
        r.Fail(item["folder"], key + ".folder",
               folder.string() +
                   ": no CAD or mesh files in the folder (STEP, IGES, BREP, STL, "
                   "OBJ, PLY, DAE, glTF, 3MF, OFF)");
      }
      std::sort(files.begin(), files.end());
      PartSource base = object.source;
      if (item["unit"]) {
        base.unit = r.Scalar(item["unit"], key + ".unit");
        if (!LengthUnitMm(base.unit)) {
          r.Fail(item["unit"], key + ".unit",
                 "unknown length unit '" + base.unit + "' (use um, mm, cm, m, in or ft)");
        }
      }
      for (const std::filesystem::path& file : files) {
        DistractorObject one = object;
        one.source = base;
        one.source.kind = PartSource::Kind::kFile;
        one.source.path = file;
        one.source.where = r.Where(item["folder"]);
        objects.push_back(std::move(one));
      }
    }
  } else {
    for (const auto kind : {DistractorObject::Kind::kBox, DistractorObject::Kind::kCylinder,
                            DistractorObject::Kind::kSphere}) {
      DistractorObject object;
      object.kind = kind;
      object.where = r.Where(n);
      objects.push_back(std::move(object));
    }
  }
  std::string why;
  if (!d.Check(&why)) r.Fail(n, at, why);
  spec->draws.distractors = std::move(d);
  spec->distractor_objects = std::move(objects);
}

// `randomize:` (or a scene's, which replaces the groups it gives of `base`).
RandomizeSpec ReadRandomize(const Reader& r, const YAML::Node& node, const std::string& key,
                            const RandomizeSpec& base) {
  r.ExpectKeys(node, key, SchemaAt("randomize"));
  RandomizeSpec spec = base;
  Randomization& d = spec.draws;
  // (A negative seed wraps.)
  if (node["seed"]) d.seed = static_cast<uint64_t>(r.Integer(node["seed"], key + ".seed"));
  if (const YAML::Node parts = node["parts"]) {
    if (!parts.IsSequence())
      r.Fail(parts, key + ".parts", "expected a list of {name|family|file: pattern, ...}");
    d.parts.clear();
    spec.part_rules.clear();
    for (size_t i = 0; i < parts.size(); ++i) {
      const std::string at = key + ".parts[" + std::to_string(i) + "]";
      const YAML::Node item = parts[i];
      PartRandomization p;
      p.where = r.Where(item);
      p.material = ReadMaterialRandomization(r, item, at, SchemaAt("randomize.parts[]"),
                                             FieldOf<PartRandomization>("per"), &p.per);
      if (item["each"])
        ReadField(r, item["each"], at + ".each", FieldOf<PartRandomization>("each"),
                  &p.per_instance);
      RandomizeRule rule;
      rule.where = p.where;
      ReadPartPatterns(r, item, at, &rule);
      d.parts.push_back(std::move(p));
      spec.part_rules.push_back(std::move(rule));
    }
  }
  if (node["floor"]) {
    d.floor =
        ReadMaterialRandomization(r, node["floor"], key + ".floor", SchemaAt("randomize.floor"),
                                  FieldOf<Randomization>("floor_per"), &d.floor_per);
  }
  if (node["fixtures"]) {
    d.fixtures = ReadMaterialRandomization(r, node["fixtures"], key + ".fixtures",
                                           SchemaAt("randomize.fixtures"),
                                           FieldOf<Randomization>("fixtures_per"), &d.fixtures_per);
  }
  if (const YAML::Node n = node["lights"]) {
    const std::string at = key + ".lights";
    r.ExpectKeys(n, at, SchemaAt("randomize.lights"));
    LightRandomization l;
    ReadDescribed(r, n, at, &l);
    if (n["type"]) {  // the kinds to pick from, by name
      const Field type = FieldOf<LightRandomization>("type");
      l.kinds.clear();
      for (const auto& choice : ReadNameChoice(r, n["type"], at + ".type"))
        l.kinds.push_back(
            ReadKnown<LightSource::Kind>(r, choice.first, at + ".type", type, "light"));
    }
    if (n["per"])
      ReadField(r, n["per"], at + ".per", FieldOf<Randomization>("lights_per"), &d.lights_per);
    std::string why;
    if (!l.Check(&why)) r.Fail(n, at, why);
    d.lights = l;
  }
  if (const YAML::Node n = node["environment"]) {
    const std::string at = key + ".environment";
    r.ExpectKeys(n, at, SchemaAt("randomize.environment"));
    EnvironmentRandomization e;
    if (const YAML::Node images = n["images"]) {
      r.ExpectKeys(images, at + ".images", SchemaAt("randomize.environment.images"));
      if (!images["folder"])
        r.Fail(images, at + ".images", "give the 'folder' of equirectangular images to pick from");
      e.images = ReadImageFolder(r, images["folder"], at + ".images.folder");
    }
    ReadDescribed(r, n, at, &e);
    if (n["per"]) {
      ReadField(r, n["per"], at + ".per", FieldOf<Randomization>("environment_per"),
                &d.environment_per);
    }
    std::string why;
    if (!e.Check(&why)) r.Fail(n, at, why);
    d.environment = e;
  }
  if (const YAML::Node n = node["camera"]) {
    const std::string at = key + ".camera";
    r.ExpectKeys(n, at, SchemaAt("randomize.camera"));
    CameraRandomization c;
    ReadDescribed(r, n, at, &c);
    std::string why;
    if (!c.Check(&why)) r.Fail(n, at, why);
    d.camera = c;
  }
  if (node["distractors"]) ReadDistractors(r, node["distractors"], key + ".distractors", &spec);
  if (const YAML::Node n = node["background"]) {
    const std::string at = key + ".background";
    r.ExpectKeys(n, at, SchemaAt("randomize.background"));
    if (!n["folder"]) r.Fail(n, at, "give the 'folder' of photos to pick from");
    BackgroundRandomization b;
    b.images = ReadImageFolder(r, n["folder"], at + ".folder");
    if (n["per"]) {
      ReadField(r, n["per"], at + ".per", FieldOf<Randomization>("background_per"),
                &d.background_per);
    }
    d.background = std::move(b);
  }
  return spec;
}

// What a recipe's (or scene's) randomisation needs of the rest of the recipe.
void CheckRandomize(const Reader& r, const YAML::Node& node, const std::string& key,
                    const RandomizeSpec& spec, const RunSpec& run) {
  const Randomization& d = spec.draws;
  // Where a group's key is (a scene's randomize may inherit the group from the recipe's: then
  // the scene's randomize itself).
  const auto at = [&node](const char* group, const char* k) {
    const YAML::Node g = node[group];
    if (!g) return node;
    const YAML::Node n = g[k];
    return n ? n : g;
  };
  if (d.changes_look() && run.render.mode != RenderOptions::Mode::kPbr) {
    r.Fail(node, key,
           "materials, lights, the environment, exposure, white balance and background photos "
           "are randomised in render.mode: pbr (the fast mode takes the camera's pose jitter "
           "and distractors)");
  }
  if (const auto& e = d.environment) {
    const Environment::Kind kind = run.look.environment.kind;
    if (e->temperature_k && (kind != Environment::Kind::kUniform || e->images)) {
      r.Fail(at("environment", "temperature"), key + ".environment.temperature",
             e->images ? "tints a uniform environment's colour (images are drawn)"
                       : "tints a uniform environment's colour (lighting.environment is not "
                         "uniform)");
    }
    if (e->rotation_deg && kind != Environment::Kind::kImage && !e->images) {
      r.Fail(at("environment", "rotation"), key + ".environment.rotation",
             "turns an image environment (lighting.environment is not an image)");
    }
  }
  if (d.background && run.look.floor) {
    r.Fail(at("background", "folder"), key + ".background",
           "pastes photos where nothing is hit, but the floor fills every downward view: set "
           "render.floor: false");
  }
  if (!d.camera) return;
  for (const RigSensor& sensor : RunSensors(run)) {
    const std::string who = run.rig.empty() ? "camera" : "cameras '" + sensor.name + "'";
    if (const auto& gain = d.camera->noise_gain) {
      const YAML::Node where = at("camera", "noise_gain");
      if (!(sensor.sensor.imager.full_well > 0)) {
        r.Fail(where, key + ".camera.noise_gain",
               "scales the image noise: " + who + " has none (give it imager.full_well)");
      }
      // The noisiest and the quietest sensor it can draw must be sensors.
      const bool normal = gain->kind == Distribution::Kind::kNormal;
      for (const double g : {normal ? CameraRandomization::kMinNoiseGain : gain->Lowest(),
                             normal ? CameraRandomization::kMaxNoiseGain : gain->Highest()}) {
        ImageSensor s = sensor.sensor.imager;
        s.full_well /= g * g;
        s.read_noise /= g;
        std::string why;
        if (!s.Check(&why))
          r.Fail(where, key + ".camera.noise_gain", "a gain of " + std::to_string(g) + ": " + why);
      }
    }
    if ((d.camera->focus_distance_mm || d.camera->f_number) && !sensor.sensor.lens.active()) {
      r.Fail(at("camera", "f_number"), key + ".camera",
             "focus_distance and f_number draw the lens's: " + who +
                 " has no lens (give it lens.focal_length)");
    }
  }
}

void ReadOutput(const Reader& r, const YAML::Node& node, RunSpec* spec) {
  ReadFields(r, node, "output", &spec->bop, SchemaAt("output"));
  // Keys that depend on others.
  if (node["visibility_delta"]) {
    if (spec->bop.visibility != BopOptions::Visibility::kBop19) {
      r.Fail(node["visibility_delta"], "output.visibility_delta", "needs visibility: bop19");
    }
    spec->bop.visib_delta_mm = r.Length(node["visibility_delta"], "output.visibility_delta");
    if (!(spec->bop.visib_delta_mm >= 0))
      r.Fail(node["visibility_delta"], "output.visibility_delta", "must not be negative");
  }
  if (node["rgb"]) {
    const std::string kind = r.Scalar(node["rgb"], "output.rgb");
    if (kind != "png" && kind != "jpg" && kind != "jpeg") {
      r.Fail(node["rgb"], "output.rgb", "expected png or jpg, got '" + kind + "'");
    }
    spec->bop.jpeg_quality = kind == "png" ? 0 : 95;
  }
  if (node["jpeg_quality"]) {
    if (spec->bop.jpeg_quality == 0)
      r.Fail(node["jpeg_quality"], "output.jpeg_quality", "needs rgb: jpg");
    spec->bop.jpeg_quality = r.Integer(node["jpeg_quality"], "output.jpeg_quality");
    if (spec->bop.jpeg_quality < 1 || spec->bop.jpeg_quality > 100) {
      r.Fail(node["jpeg_quality"], "output.jpeg_quality", "expected 1 to 100");
    }
  }
  if (const YAML::Node formats = node["formats"]) {
    if (!formats.IsSequence())
      r.Fail(formats, "output.formats", "expected a list, e.g. [bop, coco, paper]");
    // Each format of dataset/output_formats.cpp is off unless listed.
    for (const OutputFormat& format : OutputFormats()) {
      if (format.enabled != nullptr) spec->bop.*format.enabled = false;
    }
    bool bop = false;
    for (const YAML::Node& f : formats) {
      const std::string name = r.Scalar(f, "output.formats");
      const OutputFormat* format = FindOutputFormat(name);
      if (format == nullptr) {
        r.Fail(f, "output.formats",
               "unknown format '" + name + "' (known: " + JoinNames(OutputFormatNames()) + ")");
      }
      if (format->enabled == nullptr) {
        bop = true;
      } else {
        spec->bop.*format->enabled = true;
      }
    }
    if (!bop)
      r.Fail(formats, "output.formats",
             "bop is always written (the other formats derive from it): list it");
  }
  if (node["test_every"] && node["test_fraction"]) {
    r.Fail(node["test_fraction"], "output.test_fraction",
           "give test_every or test_fraction, not both");
  }
  if (node["test_every"]) spec->bop.test_every = r.Integer(node["test_every"], "output.test_every");
  if (node["test_fraction"]) {
    spec->bop.test_every = 0;
    spec->bop.test_fraction = r.Number(node["test_fraction"], "output.test_fraction");
  }
  if (node["dir"]) {
    std::filesystem::path dir = r.Scalar(node["dir"], "output.dir");
    spec->output = (dir.is_relative() ? r.base_dir() / dir : dir).lexically_normal();
  }
  r.Check(spec->bop, node, "output");
}

}  // namespace

std::vector<SceneSpec> DemoScenes() {
  const auto family = [](const std::string& name, ParamValues values = {}) {
    PartSource source;
    source.kind = PartSource::Kind::kFamily;
    source.family = name;
    source.variants = {CompleteParams(*FindFamily(name), values)};
    return source;
  };
  SceneSpec planetary{"planetary_gearbox", {family("planetary")}, {.layout = Layout::kAssembled}};
  SceneSpec crank{"slider_crank", {family("slider_crank")}, {.layout = Layout::kAssembled}};
  SceneSpec benchmark{
      "assembly_benchmark",
      {family("round_peg"), family("square_peg"), family("faceplate"), family("stepped_shaft"),
       family("hex_bolt", {{"size", std::string("M10")}, {"length", 40.0}})},
      {.layout = Layout::kGrid, .gap_mm = 30.0}};
  return {planetary, crank, benchmark};
}

RunSpec Reseed(const RunSpec& spec, uint64_t stream) {
  RunSpec out = spec;
  if (stream == 0) return out;
  out.reseed = stream;
  // Each seed to a hash of itself and the stream (SplitMix64's finaliser), so that streams do
  // not collide with each other's seeds or with the recipe's.
  const auto move = [stream](uint64_t seed) {
    uint64_t z = seed ^ (stream * 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  };
  // Every described seed marked as a run's (Field::per_run_seed).
  const auto seeds = [&](auto& options) {
    std::decay_t<decltype(options)>::Fields(options, [&](auto& value, const Field& field) {
      using T = std::decay_t<decltype(value)>;
      if constexpr (std::is_same_v<T, int>) {  // a recipe's int (render.seed): kept non-negative
        if (field.per_run_seed) value = static_cast<int>(move(static_cast<uint64_t>(value)) >> 33);
      } else if constexpr (std::is_same_v<T, uint64_t>) {
        if (field.per_run_seed) value = move(value);
      }
    });
  };
  for (SceneSpec& scene : out.scenes) {
    seeds(scene.arrangement);
    if (scene.randomize) seeds(scene.randomize->draws);
  }
  seeds(out.randomize.draws);
  seeds(out.sampler);
  seeds(out.render);
  seeds(out.bop);
  seeds(out.tessellation);
  seeds(out.limits);
  const auto sensor_seeds = [&](SensorOptions& sensor) {
    seeds(sensor.imager);
    seeds(sensor.depth);
    seeds(sensor.lens);
  };
  sensor_seeds(out.sensor);
  for (RigSensor& sensor : out.rig) sensor_seeds(sensor.sensor);
  seeds(out.grasps.gripper);
  seeds(out.grasps.sampling);
  seeds(out.grasps.scene);
  seeds(out.grasps.labels);
  seeds(out.grasps.cup);
  seeds(out.grasps.suction_sampling);
  return out;
}

RunSpec DefaultRunSpec() {
  RunSpec spec;
  spec.scenes = DemoScenes();
  for (int yaw = 0; yaw < 360; yaw += 30) spec.sweep.yaw_rad.push_back(yaw * kDeg);
  for (int pitch = 15; pitch <= 75; pitch += 20) spec.sweep.pitch_rad.push_back(pitch * kDeg);
  spec.sweep.radius_mm = {650.0, 1050.0, 1450.0};
  return spec;
}

// yaml-cpp keeps every pair of a mapping but looks a key up by its first pair: a key (or a whole
// section) written twice would silently lose one of its values.
void RejectDuplicateKeys(const std::string& name, const YAML::Node& node) {
  const auto where = [&](const YAML::Mark& mark) {
    return name + ":" + std::to_string(mark.line + 1) + ":" + std::to_string(mark.column + 1);
  };
  if (node.IsMap()) {
    std::map<std::string, YAML::Mark> seen;
    for (auto it = node.begin(); it != node.end(); ++it) {
      if (it->first.IsScalar()) {
        const auto [first, fresh] = seen.emplace(it->first.Scalar(), it->first.Mark());
        if (!fresh) {
          throw Error(where(it->first.Mark()) + ": '" + it->first.Scalar() +
                      "' is given twice (first at line " + std::to_string(first->second.line + 1) +
                      ")");
        }
      }
      RejectDuplicateKeys(name, it->second);
    }
  } else if (node.IsSequence()) {
    for (const YAML::Node& child : node) RejectDuplicateKeys(name, child);
  }
}

namespace {

// `grasps:` (see GraspSpec).
GraspSpec ReadGrasps(const Reader& r, const YAML::Node& g) {
  r.ExpectKeys(g, "grasps", SchemaAt("grasps"));
  GraspSpec grasps;
  grasps.enabled = true;
  std::string why;
  if (const YAML::Node node = g["gripper"]) {
    const auto preset = [&](const YAML::Node& n, const std::string& key) {
      const std::string name = r.Scalar(n, key);
      if (name == "franka") return ParallelJawGripper::Franka();
      if (name == "robotiq_2f85") return ParallelJawGripper::Robotiq2F85();
      r.Fail(n, key, "unknown gripper '" + name + "' (known: franka, robotiq_2f85)");
    };
    if (node.IsMap()) {
      r.ExpectKeys(node, "grasps.gripper", SchemaAt("grasps.gripper"));
      if (node["preset"]) grasps.gripper = preset(node["preset"], "grasps.gripper.preset");
      ReadDescribed(r, node, "grasps.gripper", &grasps.gripper);
      if (!grasps.gripper.Check(&why)) r.Fail(node, "grasps.gripper", why);
    } else {
      grasps.gripper = preset(node, "grasps.gripper");
    }
  }
  AntipodalOptions& s = grasps.sampling;
  ReadDescribed(r, g, "grasps", &s);
  if (const YAML::Node depths = g["depths"]) {  // on the fingers of the gripper given
    if (!depths.IsSequence() || depths.size() == 0)
      r.Fail(depths, "grasps.depths", "expected a list of lengths");
    for (const YAML::Node& item : depths) {
      const double depth = r.Length(item, "grasps.depths");
      if (!(depth >= 0 && depth <= grasps.gripper.finger_length_mm)) {
        std::ostringstream what;
        what << "must lie on the fingers (0 to " << grasps.gripper.finger_length_mm << " mm)";
        r.Fail(item, "grasps.depths", what.str());
      }
      s.depths_mm.push_back(depth);
    }
  }
  if (!s.Check(&why)) r.Fail(g, "grasps", why);
  if (const YAML::Node node = g["suction"]) {
    if (node.IsScalar()) {
      grasps.suction = r.Bool(node, "grasps.suction");  // true: the default cup
    } else {
      grasps.suction = true;
      r.ExpectKeys(node, "grasps.suction", SchemaAt("grasps.suction"));
      ReadDescribed(r, node, "grasps.suction", &grasps.cup);
      if (!grasps.cup.Check(&why)) r.Fail(node, "grasps.suction", why);
      ReadDescribed(r, node, "grasps.suction", &grasps.suction_sampling);
      if (!grasps.suction_sampling.Check(&why)) r.Fail(node, "grasps.suction", why);
    }
  }
  grasps.suction_sampling.seed = s.seed;
  grasps.suction_sampling.max_grasps = s.max_grasps;
  ReadDescribed(r, g, "grasps", &grasps.scene);
  if (!grasps.scene.Check(&why)) r.Fail(g["approach_distance"], "grasps.approach_distance", why);
  GraspLabelOptions& labels = grasps.labels;
  ReadDescribed(r, g, "grasps", &labels);
  if (!labels.Check(&why)) {
    // At the key at fault: the count alone (with the default tolerance) passes or not.
    GraspLabelOptions count;
    count.max_per_instance = labels.max_per_instance;
    std::string count_why;
    const char* bad = count.Check(&count_why) ? "visibility_tolerance" : "per_instance";
    r.Fail(g[bad], std::string("grasps.") + bad, why);
  }
  labels.graspnet = true;
  labels.suctionnet = grasps.suction;
  if (const YAML::Node formats = g["formats"]) {
    if (!formats.IsSequence() || formats.size() == 0)
      r.Fail(formats, "grasps.formats", "expected a list of acronym, graspnet, suctionnet");
    grasps.acronym = labels.graspnet = labels.suctionnet = false;
    for (const YAML::Node& item : formats) {
      const std::string name = r.Scalar(item, "grasps.formats");
      if (name == "acronym") {
        grasps.acronym = true;
      } else if (name == "graspnet") {
        labels.graspnet = true;
      } else if (name == "suctionnet") {
        if (!grasps.suction)
          r.Fail(item, "grasps.formats", "suctionnet needs a cup (grasps.suction)");
        labels.suctionnet = true;
      } else {
        r.Fail(item, "grasps.formats",
               "unknown format '" + name + "' (known: acronym, graspnet, suctionnet)");
      }
    }
  }
  return grasps;
}

}  // namespace

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
  RejectDuplicateKeys(name, root);

  const Reader r(name, base_dir);
  RunSpec spec = DefaultRunSpec();
  try {
    r.ExpectKeys(root, "", RecipeSchema());
    if (root["scenes"] && (root["parts"] || root["scene"])) {
      r.Fail(root["scenes"], "scenes", "give either 'scenes' or 'parts' (with 'scene'), not both");
    }
    if (root["parts"]) {
      SceneSpec scene;
      scene.name = "scene";
      scene.sources = ReadParts(r, root["parts"], "parts");
      if (root["scene"]) {
        ReadLayout(r, root["scene"], "scene", &scene, SchemaAt("scene"));
      }
      spec.scenes = {scene};
    } else if (root["scene"]) {
      r.Fail(root["scene"], "scene",
             "'scene' goes with 'parts' (without parts the default scenes are used)");
    }
    if (root["scenes"]) {
      const YAML::Node scenes = root["scenes"];
      if (scenes.IsScalar() && scenes.Scalar() == "default") {
        spec.scenes = DemoScenes();
      } else {
        if (!scenes.IsSequence() || scenes.size() == 0)
          r.Fail(scenes, "scenes", "expected a list of scenes, or 'default'");
        spec.scenes.clear();
        for (size_t i = 0; i < scenes.size(); ++i) {
          spec.scenes.push_back(ReadSceneEntry(r, scenes[i], "scenes[" + std::to_string(i) + "]"));
        }
      }
    }
    if (root["classes"]) ReadClasses(r, root["classes"], &spec);
    if (root["tessellation"]) ReadTessellation(r, root["tessellation"], &spec);
    if (root["camera"] && root["cameras"]) {
      r.Fail(root["cameras"], "cameras",
             "give 'camera' (one camera) or 'cameras' (a rig of named cameras), not both");
    }
    if (root["camera"])
      ReadCamera(r, root["camera"], "camera", &spec.intrinsics, &spec.sensor, SchemaAt("camera"));
    if (root["cameras"]) ReadCameras(r, root["cameras"], &spec);
    if (root["sweep"]) ReadSweep(r, root["sweep"], &spec);
    if (root["render"]) ReadRender(r, root["render"], &spec);
    // The default floor material follows the floor colour unless the recipe gives one.
    spec.look.floor_material = Scene::DefaultFloorMaterial(spec.look.floor_color);
    if (root["materials"]) ReadMaterials(r, root["materials"], &spec);
    if (root["lighting"]) ReadLighting(r, root["lighting"], &spec);
    if (root["output"]) ReadOutput(r, root["output"], &spec);
    // The camera's image (a rig: the first camera's) decides the paper and pvn3d formats, which
    // are written for that camera only; every camera's image decides whether JPEG is possible.
    const YAML::Node first =
        root["cameras"] ? YAML::Node(root["cameras"][0]) : YAML::Node(root["camera"]);
    const std::string first_key = root["cameras"] ? "cameras[0]" : "camera";
    const auto image_node = [&](const YAML::Node& camera) {
      return camera && camera["image"] ? YAML::Node(camera["image"]) : camera;
    };
    if (spec.sensor.image != SensorOptions::Image::kRgb) {
      std::vector<std::string> rgb_only;
      for (const OutputFormat& format : OutputFormats()) {
        if (format.needs_rgb && format.enabled != nullptr) rgb_only.push_back(format.name);
      }
      for (const OutputFormat& format : OutputFormats()) {
        if (format.needs_rgb && format.enabled != nullptr && spec.bop.*format.enabled) {
          r.Fail(
              image_node(first), first_key + ".image",
              "the " + JoinNames(rgb_only, " and ") + " formats need colour images (image: rgb)");
        }
      }
    }
    spec.bop.gray_bits = GrayBits(spec.sensor.image);
    // Depth of field and motion blur come from the path tracer's samples; distorted IR images
    // cannot be matched by the stereo matcher, which wants them rectified.
    for (size_t i = 0; i < std::max<size_t>(1, spec.rig.size()); ++i) {
      const bool rig = !spec.rig.empty();
      const YAML::Node camera = rig ? YAML::Node(root["cameras"][i]) : YAML::Node(root["camera"]);
      const std::string at = rig ? "cameras[" + std::to_string(i) + "]" : std::string("camera");
      const SensorOptions& sensor = rig ? spec.rig[i].sensor : spec.sensor;
      const Intrinsics& k = rig ? spec.rig[i].intrinsics : spec.intrinsics;
      for (const char* effect : {"lens", "motion"}) {
        if (camera && camera[effect] && spec.render.mode != RenderOptions::Mode::kPbr) {
          r.Fail(camera[effect], at + "." + effect,
                 "depth of field and motion blur need render.mode: pbr (the path tracer's "
                 "samples)");
        }
      }
      if (k.distortion.active() && sensor.depth.kind == DepthModel::Kind::kActiveStereo) {
        r.Fail(camera["distortion"], at + ".distortion",
               "active_stereo matches rectified IR images: give the distortion to another camera "
               "of the rig");
      }
    }
    for (size_t i = 0; i < std::max<size_t>(1, spec.rig.size()); ++i) {
      const SensorOptions::Image image =
          spec.rig.empty() ? spec.sensor.image : spec.rig[i].sensor.image;
      if (image == SensorOptions::Image::kGray16 && spec.bop.jpeg_quality > 0) {
        const bool rig = !spec.rig.empty();
        r.Fail(image_node(rig ? YAML::Node(root["cameras"][i]) : YAML::Node(root["camera"])),
               (rig ? "cameras[" + std::to_string(i) + "]" : std::string("camera")) + ".image",
               "16-bit grey images cannot be JPEG (rgb: png)");
      }
    }
    if (root["randomize"]) {
      spec.randomize = ReadRandomize(r, root["randomize"], "randomize", RandomizeSpec{});
      CheckRandomize(r, root["randomize"], "randomize", spec.randomize, spec);
    }
    if (const YAML::Node scenes = root["scenes"]; scenes && scenes.IsSequence()) {
      for (size_t i = 0; i < scenes.size(); ++i) {
        const YAML::Node own = scenes[i]["randomize"];
        if (!own) continue;
        const std::string at = "scenes[" + std::to_string(i) + "].randomize";
        spec.scenes[i].randomize = ReadRandomize(r, own, at, spec.randomize);
        CheckRandomize(r, own, at, *spec.scenes[i].randomize, spec);
      }
    }
    if (const YAML::Node g = root["grasps"]) spec.grasps = ReadGrasps(r, g);
    if (root["limits"]) {
      ReadFields(r, root["limits"], "limits", &spec.limits, SchemaAt("limits"));
      r.Check(spec.limits, root["limits"], "limits");
    }
    CheckLimits(spec, name);
  } catch (const YAML::Exception& e) {
    throw Error(name + ":" + std::to_string(e.mark.line + 1) + ":" +
                std::to_string(e.mark.column + 1) + ": " + e.msg);
  }
  return spec;
}

int GrayBits(SensorOptions::Image image) {
  switch (image) {
    case SensorOptions::Image::kRgb:
      return 0;
    case SensorOptions::Image::kGray:
      return 8;
    case SensorOptions::Image::kGray16:
      return 16;
  }
  return 0;
}

std::vector<RigSensor> RunSensors(const RunSpec& spec) {
  if (!spec.rig.empty()) return spec.rig;
  RigSensor one;
  one.intrinsics = spec.intrinsics;
  one.sensor = spec.sensor;
  return {one};
}

bool RunLimits::Check(std::string* why) const {
  if (max_variants < 1 || max_count < 1) {
    *why = "max_variants and max_count must be at least 1";
  } else if (!(min_deflection_mm > 0) || !std::isfinite(min_deflection_mm)) {
    *why = "min_deflection must be a positive length";
  } else if (!(read_timeout_s > 0) || !std::isfinite(read_timeout_s)) {
    *why = "read_timeout must be a positive number of seconds";
  } else {
    return true;
  }
  return false;
}

void CheckLimits(const RunSpec& spec, const std::string& recipe) {
  const RunLimits& limits = spec.limits;
  size_t variants = 0;
  // The scenes' parts and the distractor sources the scenes use (an inherited one once).
  std::vector<const PartSource*> sources;
  std::set<std::string> counted;
  const auto distractors = [&](const RandomizeSpec& randomize) {
    if (!randomize.draws.distractors) return;
    for (const DistractorObject& object : randomize.distractor_objects) {
      if (object.kind != DistractorObject::Kind::kSource) continue;
      const std::string key = object.where + "|" + object.source.path.string() + "|" +
                              object.source.family + "|" +
                              std::to_string(object.source.variants.size());
      if (object.where.empty() || counted.insert(key).second) sources.push_back(&object.source);
    }
  };
  for (const SceneSpec& scene : spec.scenes) {
    for (const PartSource& source : scene.sources) sources.push_back(&source);
    distractors(scene.randomize ? *scene.randomize : spec.randomize);
  }
  {
    for (const PartSource* each : sources) {
      const PartSource& source = *each;
      const std::string where = source.where.empty() ? "" : source.where + ": ";
      variants += source.kind == PartSource::Kind::kFile ? 1 : source.variants.size();
      if (variants > static_cast<size_t>(limits.max_variants)) {
        throw Error(where + "the recipe asks for more than " + std::to_string(limits.max_variants) +
                    " parts and variants; if you mean it, raise limits.max_variants");
      }
      const FamilyInfo* family =
          source.kind == PartSource::Kind::kFamily ? FindFamily(source.family) : nullptr;
      if (family == nullptr) continue;
      for (const ParamValues& values : source.variants) {
        for (const FamilyParam& param : family->params) {
          if (param.kind != FamilyParam::Kind::kCount) continue;
          const auto it = values.find(param.name);
          if (it == values.end() || !std::holds_alternative<double>(it->second)) continue;
          const double count = std::get<double>(it->second);
          if (count > limits.max_count) {
            std::ostringstream out;
            out << where << source.family << ": " << param.name << " = " << count
                << " is more than " << limits.max_count
                << " (building it would take minutes); if you mean it, raise limits.max_count";
            throw Error(out.str());
          }
        }
      }
    }
  }
  if (spec.tessellation.linear_deflection_mm < limits.min_deflection_mm) {
    std::ostringstream out;
    out << (recipe.empty() ? "" : recipe + ": ") << "tessellation.linear_deflection "
        << spec.tessellation.linear_deflection_mm << " mm is finer than "
        << limits.min_deflection_mm
        << " mm (millions of triangles per part); if you mean it, lower limits.min_deflection";
    throw Error(out.str());
  }
}

RunSpec LoadRecipe(const std::filesystem::path& path) {
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (!std::filesystem::exists(status)) throw Error(path.string() + ": no such recipe file");
  if (std::filesystem::is_directory(status))
    throw Error(path.string() + ": is a folder, not a recipe");
  // A device or a pipe is read once and without end (/dev/zero): only regular files, bounded.
  if (!std::filesystem::is_regular_file(status))
    throw Error(path.string() + ": not a regular file (a recipe is a YAML file)");
  constexpr uintmax_t kMaxRecipeBytes = 16u << 20;
  const uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) throw Error(path.string() + ": cannot read the recipe: " + ec.message());
  if (size > kMaxRecipeBytes)
    throw Error(path.string() + ": " + std::to_string(size >> 20) +
                " MB is too large for a recipe (at most 16 MB)");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path.string() + ": cannot open the recipe");
  std::string text(static_cast<size_t>(size), '\0');
  in.read(text.data(), static_cast<std::streamsize>(size));
  text.resize(static_cast<size_t>(in.gcount()));
  const std::filesystem::path base = std::filesystem::absolute(path, ec).parent_path();
  RunSpec spec = ParseRecipe(text, path.string(), base);
  spec.recipe = path;
  spec.recipe_text = std::move(text);
  return spec;
}

}  // namespace cadsynth
