// Reading the JSON files a test's dataset holds (nlohmann-json).
#pragma once

#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

namespace cadsynth::testing {

inline nlohmann::json ReadJson(const std::filesystem::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

}  // namespace cadsynth::testing
