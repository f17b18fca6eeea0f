// Part sources (files, families and their variants) and class groups: the recipe's own syntax.
#include "recipes/sections.h"

#include <algorithm>
#include <map>
#include <set>

#include "cad/core/random.h"
#include "cad/core/units.h"
#include "cad/step.h"

namespace cadsynth::recipe_detail {

// "spur_gear, ring_gear, ...": for unknown-family messages.
std::string KnownFamilies() {
  std::vector<std::string> names;
  for (const FamilyInfo& f : Families()) names.push_back(f.name);
  return JoinNames(names);
}

namespace {

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
    values.emplace_back(std::in_place_type<double>,
                        p.kind == FamilyParam::Kind::kCount ? std::round(v) : v);
  return values;
}

}  // namespace

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

}  // namespace cadsynth::recipe_detail
