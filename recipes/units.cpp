#include "recipes/units.h"

#include <cctype>
#include <cmath>
#include <cstdlib>

#include "cad/core/units.h"

namespace cadsynth {
namespace {

// Splits "12.5 mm" into 12.5 and "mm". False when there is no leading number.
bool SplitNumber(const std::string& text, double* value, std::string* unit) {
  const char* begin = text.c_str();
  char* end = nullptr;
  *value = std::strtod(begin, &end);
  if (end == begin || !std::isfinite(*value)) return false;
  std::string rest(end);
  size_t a = 0, b = rest.size();
  while (a < b && std::isspace(static_cast<unsigned char>(rest[a]))) ++a;
  while (b > a && std::isspace(static_cast<unsigned char>(rest[b - 1]))) --b;
  *unit = rest.substr(a, b - a);
  return true;
}

}  // namespace

std::optional<double> ParseLengthMm(const std::string& text, std::string* why) {
  double value = 0.0;
  std::string unit;
  if (!SplitNumber(text, &value, &unit)) {
    *why = "expected a length such as '650 mm' or '0.65 m', got '" + text + "'";
    return std::nullopt;
  }
  if (unit.empty()) return value;
  const std::optional<double> scale = LengthUnitMm(unit);
  if (!scale) {
    *why = "unknown length unit '" + unit + "' (use um, mm, cm, m, in or ft)";
    return std::nullopt;
  }
  return value * *scale;
}

std::optional<double> ParseAngleRad(const std::string& text, std::string* why) {
  double value = 0.0;
  std::string unit;
  if (!SplitNumber(text, &value, &unit)) {
    *why = "expected an angle such as '30' (degrees) or '0.5 rad', got '" + text + "'";
    return std::nullopt;
  }
  if (unit.empty() || unit == "deg" || unit == "\xC2\xB0") return value * M_PI / 180.0;
  if (unit == "rad") return value;
  *why = "unknown angle unit '" + unit + "' (use deg or rad)";
  return std::nullopt;
}

}  // namespace cadsynth
