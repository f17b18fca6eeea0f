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
// groups, sweep ranges, distributions) are declared in the tree with their kind. The reader takes
// every section's allowed keys from the tree, and the reference, the docs page and the JSON Schema
// (`cadsynth generate --recipe-schema`) are written from it.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <initializer_list>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace cadsynth {

struct Field {
  // The key in the struct's recipe section ("depth_scale"); empty for a field set by the program
  // or by another key (still part of the run key and the shard file).
  std::string_view key;
  // How the recipe writes the value: "length" (a length with a unit, mm inside), "angle"
  // (degrees or with a unit, radians inside), "number", "integer", "bool", "text", or "choice"
  // (one of `choices`; an enum's values in order, a bool's false then true).
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
  std::string_view Name() const { return key.empty() ? internal_name : key; }
};

// An integer `key` that is a per-run seed (Field::per_run_seed).
inline Field RunSeed(std::string_view key, std::string_view doc) {
  Field field{key, "integer", doc};
  field.per_run_seed = true;
  return field;
}

// The value of a field as text, for the run key and the reference: numbers exactly (the shortest
// text that reads back the same), bools as true/false, enums and choice bools by their choice name.
template <typename T>
struct IsVector : std::false_type {};
template <typename T>
struct IsVector<std::vector<T>> : std::true_type {};

template <typename T>
std::string FieldText(const T& value, const Field& field) {
  if constexpr (IsVector<T>::value) {  // a list: [a, b, c]
    std::string text = "[";
    for (size_t i = 0; i < value.size(); ++i) text += (i ? ", " : "") + FieldText(value[i], field);
    return text + "]";
  } else if constexpr (std::is_enum_v<T>) {
    const auto i = static_cast<size_t>(value);
    return i < field.choices.size() ? std::string(field.choices[i]) : std::to_string(i);
  } else if constexpr (std::is_same_v<T, bool>) {
    if (field.choices.size() == 2) return std::string(field.choices[value ? 1 : 0]);
    return value ? "true" : "false";
  } else if constexpr (std::is_same_v<T, std::string>) {
    return value;
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

// The recipe text of a described field's default value: lengths in mm, angles in degrees.
template <typename T>
std::string DefaultText(const T& value, const Field& field) {
  if constexpr (IsVector<T>::value) {
    std::string text = "[";
    for (size_t i = 0; i < value.size(); ++i)
      text += (i ? ", " : "") + DefaultText(value[i], field);
    return text + "]";
  } else if constexpr (std::is_floating_point_v<T>) {
    if (field.kind == "angle") {
      return FieldText(std::round(static_cast<double>(value) * 180.0 / M_PI * 1e6) / 1e6, field);
    }
    return FieldText(value, field) +
           (field.kind == "length" || field.kind == "lengths" ? " mm" : "");
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
    key.default_text = DefaultText(value, field);
    keys.push_back(std::move(key));
  });
  return keys;
}

}  // namespace cadsynth
