// Small utilities every module may use: name suggestions and lists. Seeded draws:
// cad/core/random.h.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace cadsynth {

// Levenshtein distance between two names.
size_t EditDistance(const std::string& a, const std::string& b);

// The candidate closest to `name` within 2 edits, or empty: for "did you mean ...?".
std::string NearestName(const std::string& name, const std::vector<std::string>& candidates);

// "a, b, c": names for a message ("known: ..."), `separator` between them.
std::string JoinNames(const std::vector<std::string>& names, const std::string& separator = ", ");

// "1 part", "3 parts": a count and its noun for a message (`plural` empty: `singular` + "s").
std::string Count(size_t n, const std::string& singular, const std::string& plural = "");

}  // namespace cadsynth
