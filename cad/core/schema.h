// One description per option, and one description of the whole recipe.
//
// An Options struct lists its fields once, in a static
//
//   template <class Self, class Visitor> static void Fields(Self& self, Visitor&& visit);
//
// that calls visit(self.field, Field{...}) for every field (Self is the struct, const or not).
// Everything that must know every option is a visitor, so a new field cannot be forgotten in one
// of them: the recipe reader (recipes/), the run key and the shard file (tools/), the recipe
// reference (`cadsynth generate --help-recipe`, docs/recipes.md), and a test that changing any
// field changes the run key.
//
// The recipe as a whole is a tree of `Key`s (recipes/recipe_schema.h): sections, lists of sections
// and values. A described struct enters the tree through KeysOf<Options>() (its fields, their
// kinds, docs, choices and defaults); keys whose syntax is the recipe's own (part sources, class
// groups, camera presets and rigs, image folders) are declared in the tree with their kind. The
// reader takes every section's allowed keys from the tree, and the reference, the docs page and
// the JSON Schema (`cadsynth generate --recipe-schema`) are written from it.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include <Eigen/Core>

namespace cadsynth {

// The values a number may take; the recipe reader refuses others: kUnit "must lie in [0, 1], got
// X" (X as the recipe writes it), kNonNegative "must not be negative", kPositive "must be
// positive".
enum class Range { kAny, kUnit, kNonNegative, kPositive };

struct Field {
  // The key in the struct's recipe section ("depth_scale"); empty for a field set by the program
  // or by another key (still part of the run key and the shard file).
  std::string_view key;
  // How the recipe writes the value: "length" (a length with a unit, mm inside), "angle"
  // (degrees or with a unit, radians inside), "number", "integer", "bool", "text", "choice"
  // (one of `choices`; an enum's values in order, a bool's false then true), "color" (sRGB
  // [r, g, b]), "linear_color" ([r, g, b] or "#RRGGBB"), "vector3" ([x, y, z]), "length3" ([x, y,
  // z] with units, mm inside), "degrees3" ([x, y, z] in degrees, radians inside), "milliseconds"
  // (a number of ms, seconds inside), "series_angle" and "series_length" (a value, a list or
  // {from, to, step}; read by hand), "path" (a file, relative to the recipe), "distribution" or
  // "distribution_length" (a value or {uniform | normal | log_uniform | choice: [...]} of numbers
  // or of lengths, mm inside: a Distribution, render/randomize.h) or "names" (a name, a list or
  // {choice: [...]}; read by hand).
  std::string_view kind;
  std::string_view doc;  // one line: what it does, its range
  std::vector<std::string_view> choices = {};
  // A field read or checked by hand in the recipe reader (it depends on other keys).
  bool by_hand = false;
  // The name the run key and the shard file use: the recipe key, else `internal_name`.
  std::string_view internal_name = {};
  // A seed of one run's draws (poses, noise, samples) that Reseed (recipes/recipe.h) moves to
  // each stream of reseeded runs; the seeds of what a dataset holds once (model clouds, grasps,
  // the split) are not marked. Made by RunSeed().
  bool per_run_seed = false;
  Range range = Range::kAny;  // a number's (the recipe reader checks it)
  // A key that goes only with these values of its section's tag (Key::tag: a light's `type`).
  std::vector<std::string_view> only_with = {};
  std::string_view Name() const { return key.empty() ? internal_name : key; }
};

// An integer `key` that is a per-run seed (Field::per_run_seed).
inline Field RunSeed(std::string_view key, std::string_view doc) {
  Field field{key, "integer", doc};
  field.per_run_seed = true;
  return field;
}

// A number `key` in [0, 1] (Range::kUnit: a weight, a roughness).
inline Field UnitNumber(std::string_view key, std::string_view doc) {
  return Field{.key = key, .kind = "number", .doc = doc, .range = Range::kUnit};
}

// The value of a field as text, for the run key and the reference: numbers exactly (the shortest
// text that reads back the same), bools as true/false, enums and choice bools by their choice name,
// an unset optional as none, and a type of its own (a Distribution) by its member Text().
template <typename T>
struct IsVector : std::false_type {};
template <typename T>
struct IsVector<std::vector<T>> : std::true_type {};
// A fixed-size Eigen column vector (Eigen::Vector3f, Eigen::Vector3d): written [x, y, z].
template <typename T>
struct IsFixedVector : std::false_type {};
template <typename S, int N, int O, int MaxRows, int MaxCols>
struct IsFixedVector<Eigen::Matrix<S, N, 1, O, MaxRows, MaxCols>> : std::bool_constant<(N > 0)> {};
template <typename T>
struct IsOptional : std::false_type {};
template <typename T>
struct IsOptional<std::optional<T>> : std::true_type {};
// A value that writes itself as the recipe writes it: std::string Text() const.
template <typename T>
concept HasText = requires(const T& value) {
  value.Text();
};

template <typename T>
std::string FieldText(const T& value, const Field& field) {
  if constexpr (IsOptional<T>::value) {
    return value ? FieldText(*value, field) : "none";
  } else if constexpr (HasText<T>) {
    return value.Text();
  } else if constexpr (IsVector<T>::value) {  // a list: [a, b, c]
    std::string text = "[";
    for (size_t i = 0; i < value.size(); ++i) text += (i ? ", " : "") + FieldText(value[i], field);
    return text + "]";
  } else if constexpr (IsFixedVector<T>::value) {  // [x, y, z]
    std::string text = "[";
    for (int i = 0; i < value.size(); ++i) text += (i ? ", " : "") + FieldText(value[i], field);
    return text + "]";
  } else if constexpr (std::is_same_v<T, std::filesystem::path>) {
    return value.string();
  } else if constexpr (std::is_enum_v<T>) {
    const auto i = static_cast<size_t>(value);
    return i < field.choices.size() ? std::string(field.choices[i]) : std::to_string(i);
  } else if constexpr (std::is_same_v<T, bool>) {
    if (field.choices.size() == 2) return std::string(field.choices[value ? 1 : 0]);
    return value ? "true" : "false";
  } else if constexpr (std::is_same_v<T, std::string>) {
    return value;
  } else if constexpr (std::is_same_v<T, float>) {
    // The shortest of 6 to 9 digits that reads back as the same float.
    char text[40];
    for (int digits = 6; digits <= 9; ++digits) {
      std::snprintf(text, sizeof(text), "%.*g", digits, static_cast<double>(value));
      if (std::strtof(text, nullptr) == value) break;
    }
    return text;
  } else if constexpr (std::is_floating_point_v<T>) {
    // The shortest of 15, 16 or 17 digits that reads back as the same double.
    char text[40];
    for (int digits = 15; digits <= 17; ++digits) {
      std::snprintf(text, sizeof(text), "%.*g", digits, static_cast<double>(value));
      if (std::strtod(text, nullptr) == static_cast<double>(value)) break;
    }
    return text;
  } else {
    return std::to_string(value);
  }
}

// One recipe key: a value, a section of keys, or a list of sections.
struct Key {
  std::string name;
  // A value's kind (Field::kind's, or one of the recipe's own: "color" sRGB [r, g, b],
  // "linear_color" [r, g, b] or "#RRGGBB", "vector3" [x, y, z], "length3" [x, y, z] with units,
  // "degrees3" [x, y, z] in degrees, "milliseconds" a number of ms,
  // "lengths" a list of lengths, "series_angle" and "series_length" (a value, a list or
  // {from, to, step}), "distribution" and "distribution_length" (a value or {uniform | normal |
  // log_uniform | choice: [...]}), "names" (a name, a list, or {choice: [...]}), "choices" (a list
  // of `choices`), "path" (a file), "folder", "numbers" (a list of numbers), "length_or_pair"
  // (a length or [x, y]), "any" (the doc says)); "section" (a mapping of `keys`) or "list" (a
  // list of sections, each with `keys`).
  std::string kind;
  std::string doc;
  std::vector<std::string> choices = {};
  std::vector<Key> keys = {};     // section, list: the keys of the section (of each item)
  std::string default_text = {};  // the default as a recipe writes it ("" where none applies)
  // A section or a list item that may also be written as one value of this kind (`depth:
  // kinect_v1`, `suction: true`, `objects: [box, {file: a.stl}]`); "" where it may not.
  std::string scalar_kind = {};
  std::vector<std::string> scalar_choices = {};
  // A section whose keys depend on one of them (`type` of a light): `tag` names it, `tag_default`
  // is its value when absent, and a key with `only_with` is allowed only with those values.
  std::string tag = {};
  std::string tag_default = {};
  std::vector<std::string> only_with = {};
  bool required = false;  // a section's key that must be given

  // The child named `name`, or nullptr.
  const Key* Find(std::string_view child) const {
    for (const Key& k : keys)
      if (k.name == child) return &k;
    return nullptr;
  }
};

// The recipe text of a described field's default value: lengths in mm, angles in degrees (a
// length3's numbers bare, as [0, 0, 2000]: mm too, and a distribution's); none for an unset
// optional (the key then leaves its value as it is).
template <typename T>
std::string DefaultText(const T& value, const Field& field) {
  if constexpr (IsOptional<T>::value) {
    return value ? DefaultText(*value, field) : "";
  } else if constexpr (IsVector<T>::value) {
    std::string text = "[";
    for (size_t i = 0; i < value.size(); ++i)
      text += (i ? ", " : "") + DefaultText(value[i], field);
    return text + "]";
  } else if constexpr (IsFixedVector<T>::value) {
    std::string text = "[";
    for (int i = 0; i < value.size(); ++i) text += (i ? ", " : "") + DefaultText(value[i], field);
    return text + "]";
  } else if constexpr (std::is_floating_point_v<T>) {
    if (field.kind == "milliseconds") return FieldText(static_cast<double>(value) * 1000.0, field);
    if (field.kind == "angle" || field.kind == "series_angle" || field.kind == "degrees3") {
      return FieldText(std::round(static_cast<double>(value) * 180.0 / M_PI * 1e6) / 1e6, field);
    }
    return FieldText(value, field) +
           (field.kind == "length" || field.kind == "lengths" || field.kind == "series_length"
                ? " mm"
                : "");
  } else {
    return FieldText(value, field);
  }
}

// The keys of a described struct, from its Fields (those the recipe writes), with `defaults`'
// values as their defaults.
template <typename Options>
std::vector<Key> KeysOf(const Options& defaults = Options{}) {
  std::vector<Key> keys;
  Options::Fields(defaults, [&keys](const auto& value, const Field& field) {
    if (field.key.empty()) return;
    Key key{std::string(field.key), std::string(field.kind), std::string(field.doc)};
    for (std::string_view c : field.choices) key.choices.emplace_back(c);
    for (std::string_view t : field.only_with) key.only_with.emplace_back(t);
    key.default_text = DefaultText(value, field);
    keys.push_back(std::move(key));
  });
  return keys;
}

}  // namespace cadsynth
