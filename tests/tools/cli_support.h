// Running the cadsynth executable from a test (tools_tests only: CADSYNTH_EXE is its path).
#pragma once

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "tests/test_support.h"

namespace cadsynth::testing {

struct CliRun {
  int code = -1;
  std::string out, err;
};

// Runs `cadsynth ARGS` in `dir` (a shell command line), capturing exit code, stdout and stderr
// (through files named with `tag`: runs at the same time need different tags).
inline CliRun Cadsynth(const std::string& args, const ScratchDir& dir,
                       const std::string& tag = "") {
  const std::string out_name = "stdout" + tag + ".txt", err_name = "stderr" + tag + ".txt";
  const std::string command = "cd '" + dir.path().string() + "' && '" CADSYNTH_EXE "' " + args +
                              " > " + out_name + " 2> " + err_name;
  const int status = std::system(command.c_str());
  CliRun run;
  run.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  for (auto [name, text] : {std::pair{out_name, &run.out}, std::pair{err_name, &run.err}}) {
    std::ifstream in(dir / name);
    std::stringstream s;
    s << in.rdbuf();
    *text = s.str();
    std::filesystem::remove(dir / name);
  }
  return run;
}

}  // namespace cadsynth::testing
