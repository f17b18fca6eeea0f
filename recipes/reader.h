// The recipe reader's tools, for recipes/ only: a YAML reader whose every failure names
// file:line:column, and the generic reading of described fields (cad/core/schema.h) by their kind.
// The sections are read in recipes/read_*.cpp and recipe.cpp (recipes/sections.h).
#pragma once

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <initializer_list>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <type_traits>
#include <utility>
#include <vector>

#include <yaml-cpp/yaml.h>
#include <Eigen/Core>

#include "cad/core/error.h"
#include "cad/core/schema.h"
#include "cad/core/util.h"
#include "recipes/units.h"
#include "render/image.h"
#include "render/randomize.h"

namespace cadsynth::recipe_detail {

inline constexpr double kDeg = M_PI / 180.0;
inline constexpr size_t kMaxSeries = 1000000;

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

  // A length the context expects in metres' range (a camera's distance, a tote's size), where a
  // bare number below `below_mm` is far more likely metres than millimetres: an error at the
  // number, "0.8 read as 0.8 mm (a bare number is millimetres): did you mean '0.8 m'?". Looks at
  // every number of a value, a list or a range; numbers with a unit pass.
  void CheckMetresMeant(const YAML::Node& node, const std::string& key, double below_mm) const {
    if (node.IsSequence() || node.IsMap()) {
      for (auto it = node.begin(); it != node.end(); ++it)
        CheckMetresMeant(node.IsMap() ? it->second : *it, key, below_mm);
      return;
    }
    if (!node.IsScalar()) return;
    const std::string text = node.Scalar();
    char* end = nullptr;
    const double value = std::strtod(text.c_str(), &end);
    if (end == text.c_str() || *end != '\0' || !(value > 0.0) || value >= below_mm) return;
    Fail(node, key,
         text + " is read as " + text + " mm (a bare number is millimetres): did you mean '" +
             text + " m'? Give the unit");
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

  // Options::Check's verdict at the key it names: the first word of `why` (a key, or a dotted
  // path such as "sequence.picks") that is a key under `node` is where the message points
  // ("copies must be 1 to 10000" at `copies: -3`, not at the section); else at `node`.
  template <typename Options>
  void Check(const Options& options, const YAML::Node& node, const std::string& key) const {
    std::string why;
    if (!options.Check(&why)) FailAtNamedKey(node, key, why);
  }

  [[noreturn]] void FailAtNamedKey(const YAML::Node& node, const std::string& key,
                                   const std::string& why) const {
    if (node.IsMap()) {
      const auto word_char = [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.';
      };
      for (size_t i = 0; i < why.size();) {
        if (!word_char(why[i])) {
          ++i;
          continue;
        }
        size_t end = i;
        while (end < why.size() && word_char(why[end])) ++end;
        std::string word = why.substr(i, end - i);
        while (!word.empty() && word.back() == '.') word.pop_back();  // a sentence's full stop
        i = end;
        // Walk the dotted path down the mappings; the whole path must be there.
        // (Looked up through const nodes and moved with reset(): yaml-cpp's operator= on a node
        // would rewrite the recipe's tree, and a non-const operator[] may add keys to it.)
        YAML::Node at = node;
        bool found = !word.empty() && std::isalpha(static_cast<unsigned char>(word[0]));
        for (size_t a = 0; found && a < word.size();) {
          const size_t dot = std::min(word.find('.', a), word.size());
          const std::string part = word.substr(a, dot - a);
          found = at.IsMap() && !part.empty();
          if (found) {
            const YAML::Node child = std::as_const(at)[part];
            found = child.IsDefined();
            if (found) at.reset(child);
          }
          a = dot + 1;
        }
        if (found) Fail(at, key.empty() ? word : key + "." + word, why);
      }
    }
    Fail(node, key, why);
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

inline Eigen::Vector3d Triple(const Reader& r, const YAML::Node& node, const std::string& key,
                              bool length) {
  if (!node.IsSequence() || node.size() != 3) r.Fail(node, key, "expected [x, y, z]");
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) v[i] = length ? r.Length(node[i], key) : r.Number(node[i], key);
  return v;
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
inline void CheckRange(const Reader& r, const YAML::Node& node, const std::string& key, Range range,
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

}  // namespace cadsynth::recipe_detail
