// The libraries are layered: nothing includes upward. Each folder's sources include only their
// own folder and the floors beneath it:
//
//   cad/core  <  cad  <  variants  <  recipes  <  tools
//                cad  <  render  <  dataset  <  recipes
//
// (render and dataset know nothing of variants; variants nothing of render.) The test reads every
// source file of the tree, so a new include that runs upward fails here, naming file and line.
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>

#include <gtest/gtest.h>

namespace cadsynth {
namespace {

namespace fs = std::filesystem;

// The library a project header or source belongs to: its first folder, cad/core apart.
std::string Floor(const std::string& relative) {
  if (relative.rfind("cad/core/", 0) == 0) return "cad/core";
  return relative.substr(0, relative.find('/'));
}

TEST(Layering, NoIncludeRunsUpward) {
  const std::map<std::string, std::set<std::string>> allowed = {
      {"cad/core", {"cad/core"}},
      {"cad", {"cad/core", "cad"}},
      {"variants", {"cad/core", "cad", "variants"}},
      {"render", {"cad/core", "cad", "render"}},
      {"dataset", {"cad/core", "cad", "render", "dataset"}},
      {"recipes", {"cad/core", "cad", "variants", "render", "dataset", "recipes"}},
      {"tools", {"cad/core", "cad", "variants", "render", "dataset", "recipes", "tools"}},
  };
  const fs::path root = CADSYNTH_SOURCE_DIR;
  int files = 0, includes = 0;
  for (const char* top : {"cad", "variants", "render", "dataset", "recipes", "tools"}) {
    for (const fs::directory_entry& entry : fs::recursive_directory_iterator(root / top)) {
      const std::string ext = entry.path().extension().string();
      if (!entry.is_regular_file() || (ext != ".h" && ext != ".cpp")) continue;
      const std::string relative = fs::relative(entry.path(), root).generic_string();
      const std::string floor = Floor(relative);
      ASSERT_TRUE(allowed.count(floor)) << relative;
      ++files;
      std::ifstream in(entry.path());
      std::string line;
      for (int number = 1; std::getline(in, line); ++number) {
        if (line.rfind("#include \"", 0) != 0) continue;
        const std::string target = line.substr(10, line.find('"', 10) - 10);
        if (target.find('/') == std::string::npos) continue;  // a header beside it
        const std::string to = Floor(target);
        if (!allowed.count(to)) continue;  // not one of ours (e.g. "gtest/...")
        ++includes;
        EXPECT_TRUE(allowed.at(floor).count(to)) << relative << ":" << number << ": " << floor
                                                 << " includes " << target << ", a floor above it";
      }
    }
  }
  // The walk saw the tree (a moved source folder would otherwise pass by checking nothing).
  EXPECT_GT(files, 150);
  EXPECT_GT(includes, 300);
}

}  // namespace
}  // namespace cadsynth
