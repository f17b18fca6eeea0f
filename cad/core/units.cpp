#include "cad/core/units.h"

#include <algorithm>
#include <cctype>
#include <map>

namespace cadsynth {

std::optional<double> LengthUnitMm(const std::string& unit) {
  static const std::map<std::string, double> kUnits = {
      {"um", 1e-3},         {"micron", 1e-3},     {"micrometre", 1e-3}, {"micrometer", 1e-3},
      {"mm", 1.0},          {"millimetre", 1.0},  {"millimeter", 1.0},  {"cm", 10.0},
      {"centimetre", 10.0}, {"centimeter", 10.0}, {"m", 1000.0},        {"metre", 1000.0},
      {"meter", 1000.0},    {"in", 25.4},         {"inch", 25.4},       {"ft", 304.8},
      {"foot", 304.8},      {"feet", 304.8}};
  std::string key = unit;
  std::transform(key.begin(), key.end(), key.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  const auto it = kUnits.find(key);
  if (it == kUnits.end()) return std::nullopt;
  return it->second;
}

}  // namespace cadsynth
