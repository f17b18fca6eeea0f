#include "dataset/file_io.h"

#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "cad/core/error.h"
#include "tests/test_support.h"

namespace cadsynth {
namespace {

TEST(WriteFileAtomic, WritesAndReplacesWithoutLeavingTemporaries) {
  testing::ScratchDir dir;
  WriteFileAtomic(dir / "a.txt", "first");
  WriteFileAtomic(dir / "a.txt", "second");
  std::ifstream in(dir / "a.txt");
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), "second");
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), {}), 1);
}

TEST(WriteFileAtomic, FailureNamesTheFile) {
  testing::ScratchDir dir;
  try {
    WriteFileAtomic(dir / "missing" / "a.txt", "x");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find((dir / "missing" / "a.txt").string()), std::string::npos);
  }
}

}  // namespace
}  // namespace cadsynth
