// The cluster examples in tools/ agree with the command line: the Kubernetes Indexed Job's shard
// count, the folder its shards write and the folder the merge job reads; the Slurm scripts pass
// what generate and merge accept. (The Slurm scripts also run for real in tests/slurm.)
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

namespace {

const std::string kSource = CADSYNTH_SOURCE_DIR;

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(Deploy, KubernetesIndexedJobShardsAndMergeAgree) {
  const YAML::Node shards = YAML::LoadFile(kSource + "/tools/kubernetes/shards-job.yaml");
  const YAML::Node merge = YAML::LoadFile(kSource + "/tools/kubernetes/merge-job.yaml");
  ASSERT_EQ(shards["kind"].as<std::string>(), "Job");
  ASSERT_EQ(shards["spec"]["completionMode"].as<std::string>(), "Indexed");
  const int completions = shards["spec"]["completions"].as<int>();
  const YAML::Node command = shards["spec"]["template"]["spec"]["containers"][0]["command"];
  std::string line;
  for (const YAML::Node& word : command) line += word.as<std::string>() + " ";
  std::smatch m;
  ASSERT_TRUE(std::regex_search(line, m, std::regex(R"(--shard \"\$JOB_COMPLETION_INDEX/(\d+)\")")))
      << line;
  EXPECT_EQ(std::stoi(m[1]), completions) << "the /N in the command must equal completions";
  ASSERT_TRUE(std::regex_search(line, m, std::regex(R"(-o (\S+))"))) << line;
  const std::string dir = m[1];
  const YAML::Node merge_command = merge["spec"]["template"]["spec"]["containers"][0]["command"];
  ASSERT_EQ(merge_command.size(), 3u);
  EXPECT_EQ(merge_command[1].as<std::string>(), "merge");
  EXPECT_EQ(merge_command[2].as<std::string>(), dir);
  EXPECT_EQ(shards["spec"]["template"]["spec"]["restartPolicy"].as<std::string>(), "OnFailure");
}

TEST(Deploy, SlurmScriptsCallGenerateWithAShardAndMerge) {
  const std::string generate = ReadText(kSource + "/tools/slurm/generate.sbatch");
  const std::string merge = ReadText(kSource + "/tools/slurm/merge.sbatch");
  EXPECT_NE(generate.find("generate \"$recipe\" --shard \"$index/$count\" -o \"$out\""),
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
