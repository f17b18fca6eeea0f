// The committed fuzz corpus (tests/fuzz_corpus/TARGET/: seeds written by hand or by our own code,
// and an input of each crash a fuzzer found) replayed through the fuzz targets of
// tools/fuzz/targets.h in this build; a crash, a sanitizer report or an exception other than
// cadsynth::Error fails the test. Inputs of third-party readers go through `cadsynth inspect`.
#include <sys/wait.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "tests/test_support.h"
#include "tools/fuzz/targets.h"

namespace cadsynth {
namespace {

namespace fs = std::filesystem;

std::vector<fs::path> CorpusOf(const std::string& target) {
  const fs::path dir = fs::path(CADSYNTH_SOURCE_DIR) / "tests" / "fuzz_corpus" / target;
  std::vector<fs::path> files;
  if (fs::is_directory(dir)) {
    for (const auto& entry : fs::directory_iterator(dir)) files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

TEST(FuzzCorpus, EveryInputOfOurReadersEndsInAResultOrAnError) {
  for (const fuzz::NamedTarget& t : fuzz::Targets()) {
    if (!t.in_process_safe) continue;
    const std::vector<fs::path> files = CorpusOf(t.name);
    EXPECT_GE(files.size(), 3u) << t.name << ": a corpus of at least a few seeds";
    for (const fs::path& file : files) {
      SCOPED_TRACE(file.string());
      const std::string bytes = testing::ReadFile(file);
      EXPECT_EQ(t.target(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()), 0);
    }
  }
}

TEST(FuzzCorpus, EveryInputOfThirdPartyReadersIsReadOrRefusedByInspect) {
  testing::ScratchDir dir;
  for (const fuzz::NamedTarget& t : fuzz::Targets()) {
    if (t.in_process_safe) continue;
    const std::vector<fs::path> files = CorpusOf(t.name);
    EXPECT_GE(files.size(), 3u) << t.name;
    for (const fs::path& file : files) {
      const std::string bytes = testing::ReadFile(file);
      if (bytes.empty()) continue;
      const std::string name =
          "input" + t.extensions[static_cast<uint8_t>(bytes[0]) % t.extensions.size()];
      std::ofstream(dir / name, std::ios::binary) << bytes.substr(1);
      const std::string command = "cd '" + dir.path().string() + "' && timeout -s KILL 300 '" +
                                  CADSYNTH_EXE + "' inspect " + name + " > /dev/null 2> stderr.txt";
      const int status = std::system(command.c_str());
      const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
      const std::string err = testing::ReadFile(dir / "stderr.txt");
      EXPECT_TRUE(code == 0 || code == 1) << file << ": exit " << code << ": " << err;
      if (code == 1) {
        EXPECT_EQ(err.rfind("error: " + name, 0) == 0 ||
                      err.find("\nerror: " + name) != std::string::npos,
                  true)
            << file << ": " << err;
      }
    }
  }
}

}  // namespace
}  // namespace cadsynth
