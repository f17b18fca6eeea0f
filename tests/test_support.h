// Helpers shared by the tests: the shared data folder and scratch folders.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "render/image_codec.h"

namespace cadsynth::testing {

// ../shared/data by default; CADSYNTH_TEST_DATA in the environment overrides it.
inline std::filesystem::path DataDir() {
  const char* env = std::getenv("CADSYNTH_TEST_DATA");
  return std::filesystem::absolute(env != nullptr ? env : CADSYNTH_TEST_DATA).lexically_normal();
}

// The path of a shared data file, or empty when it is not there.
inline std::filesystem::path DataFile(const std::string& relative) {
  const std::filesystem::path path = DataDir() / relative;
  return std::filesystem::exists(path) ? path : std::filesystem::path();
}

#define CADSYNTH_REQUIRE_DATA(var, relative)                                                      \
  const std::filesystem::path var = ::cadsynth::testing::DataFile(relative);                      \
  if (var.empty()) {                                                                              \
    GTEST_SKIP() << "shared test data not found: " << (::cadsynth::testing::DataDir() / relative) \
                 << " (set CADSYNTH_TEST_DATA to the shared/data folder)";                        \
  }

// A fresh folder removed at the end of the test.
class ScratchDir {
 public:
  ScratchDir() {
    std::random_device rd;
    path_ = std::filesystem::temp_directory_path() /
            ("cadsynth_test_" + std::to_string(rd()) + "_" + std::to_string(rd()));
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

// The whole file (empty when it cannot be read).
inline std::string ReadFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

// Every file under `root`: path relative to root -> bytes.
inline std::map<std::string, std::string> ReadTree(const std::filesystem::path& root) {
  std::map<std::string, std::string> files;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(root)) {
    // run.json records how the run went (its time, threads and shards): the one file that
    // differs between runs of one recipe (dataset/manifest.h).
    if (!entry.is_regular_file() || entry.path() == root / "run.json") continue;
    files[std::filesystem::relative(entry.path(), root).string()] = ReadFile(entry.path());
  }
  return files;
}

// Both folders hold the same files with the same bytes (named when not).
inline void ExpectSameTree(const std::filesystem::path& expected_dir,
                           const std::filesystem::path& actual_dir) {
  const auto expected = ReadTree(expected_dir), actual = ReadTree(actual_dir);
  EXPECT_EQ(expected.size(), actual.size()) << expected_dir << " vs " << actual_dir;
  for (const auto& [name, bytes] : expected) {
    if (!actual.count(name)) {
      ADD_FAILURE() << name << " is missing from " << actual_dir;
      continue;
    }
    const std::string& other = actual.at(name);
    if (other == bytes) continue;
    // Where they part, for text files: the line of each.
    size_t at = 0;
    while (at < bytes.size() && at < other.size() && bytes[at] == other[at]) ++at;
    const auto line = [at](const std::string& text) {
      const size_t begin = text.rfind('\n', at == 0 ? 0 : at - 1);
      const size_t start = begin == std::string::npos ? 0 : begin + 1;
      return text.substr(start, std::min<size_t>(text.find('\n', at) - start, 200));
    };
    ADD_FAILURE() << name << " differs at byte " << at << ": " << line(bytes) << " vs "
                  << line(other);
  }
}

// A small 8-bit RGB PNG of one colour (texture and environment images for recipe tests).
inline void WriteSolidPng(const std::filesystem::path& path, int width, int height, uint8_t value) {
  const std::string pixels(3 * static_cast<size_t>(width) * height, static_cast<char>(value));
  ImageView view;
  view.pixels = pixels.data();
  view.width = width;
  view.height = height;
  view.channels = 3;
  const std::string bytes = EncodePng(view);
  std::ofstream(path, std::ios::binary)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

}  // namespace cadsynth::testing
