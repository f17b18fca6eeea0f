// One description per option. An Options struct lists its fields once, in a static
//
//   template <class Self, class Visitor> static void Fields(Self& self, Visitor&& visit);
//
// that calls visit(self.field, Field{...}) for every field (Self is the struct, const or not).
// Everything that must know every option is a visitor, so a new field cannot be forgotten in one
// of them: the recipe reader (recipes/), the run key and the shard file (tools/), the recipe
// reference (`cadsynth generate --help-recipe`, README), and a test that changing any field
// changes the run key.
#pragma once

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
  std::string_view Name() const { return key.empty() ? internal_name : key; }
};

// The value of a field as text, for the run key and the reference: numbers exactly (the shortest
// text that reads back the same), bools as true/false, enums and choice bools by their choice name.
template <typename T>
std::string FieldText(const T& value, const Field& field) {
  if constexpr (std::is_enum_v<T>) {
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

}  // namespace cadsynth
