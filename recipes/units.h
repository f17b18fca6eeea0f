// Quantities with units, as recipes write them: "0.65 m", "650 mm", "1 in", "20 deg".
#pragma once

#include <optional>
#include <string>

namespace cadsynth {

// A length in millimetres. Units: um, mm, cm, m, in (inch), ft; a bare number is millimetres.
// Returns nullopt (with `why`) for text that is not a number with a known length unit.
std::optional<double> ParseLengthMm(const std::string& text, std::string* why);

// An angle in radians. Units: deg (or °), rad; a bare number is degrees.
std::optional<double> ParseAngleRad(const std::string& text, std::string* why);

}  // namespace cadsynth
