// The Slurm scripts pass what generate and merge accept (they also run for real in tests/slurm;
// the Kubernetes manifests are checked and run in tests/farm).
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

namespace {

const std::string kSource = CADSYNTH_SOURCE_DIR;

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(Deploy, SlurmScriptsCallGenerateWithAShardAndMerge) {
  const std::string generate = ReadText(kSource + "/tools/slurm/generate.sbatch");
  const std::string merge = ReadText(kSource + "/tools/slurm/merge.sbatch");
  EXPECT_NE(generate.find("generate \"$recipe\" --shard auto \"${shards[@]}\" -o \"$out\""),
            std::string::npos);
  EXPECT_NE(generate.find("--progress=json"), std::string::npos);
  EXPECT_NE(merge.find("merge \"$1\""), std::string::npos);
  // The README shows the two commands a user types.
  const std::string readme = ReadText(kSource + "/README.md");
  EXPECT_NE(readme.find("sbatch --parsable --array=0-99 tools/slurm/generate.sbatch"),
            std::string::npos);
  EXPECT_NE(readme.find("sbatch --dependency=afterok:$jobid tools/slurm/merge.sbatch"),
            std::string::npos);
}

}  // namespace
