// Small utilities every module may use: seeded draws and name suggestions.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace cadsynth {

// A portable, seeded uniform number in [0, 1) from (seed, stream, index): SplitMix64, the same on
// every machine and compiler (std:: distributions are not).
double UniformDraw(uint64_t seed, uint64_t stream, uint64_t index);

// Levenshtein distance between two names.
size_t EditDistance(const std::string& a, const std::string& b);

// The candidate closest to `name` within 2 edits, or empty: for "did you mean ...?".
std::string NearestName(const std::string& name, const std::vector<std::string>& candidates);

}  // namespace cadsynth
