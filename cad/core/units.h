// Length units by name, as CAD files and recipes spell them.
#pragma once

#include <optional>
#include <string>

namespace cadsynth {

// Millimetres per unit for a length unit name, case-insensitive: "mm", "millimetre", "m", "metre",
// "meter", "cm", "um", "micrometre", "in", "inch", "ft", "foot". nullopt when unknown.
std::optional<double> LengthUnitMm(const std::string& unit);

}  // namespace cadsynth
