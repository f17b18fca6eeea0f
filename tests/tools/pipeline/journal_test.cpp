#include "tools/pipeline/journal.h"

#include <fstream>

#include <gtest/gtest.h>

#include "cad/core/error.h"
#include "tests/test_support.h"
#include "tools/pipeline/prepare.h"

namespace cadsynth {
namespace {

using testing::ReadFile;
using testing::ScratchDir;

TEST(StagingRun, ResumesTheSameKeyStartsOverOnAnotherAndPublishes) {
  ScratchDir dir;
  const std::filesystem::path output = dir / "data";
  std::vector<std::string> said;
  const auto info = [&](const std::string& line) { said.push_back(line); };
  std::filesystem::path root;
  {
    StagingRun run(output, "key A", info);
    root = run.root();
    EXPECT_EQ(root, dir / ".data.partial");
    EXPECT_EQ(ReadFile(root / ".run_key"), "key A");
    std::ofstream(root / "frame") << "done";
    // One run at a time: a second one on the same output is refused while the first holds it.
    EXPECT_THROW(StagingRun(output, "key A", info), Error);
  }  // killed here: the staging folder stays
  {
    StagingRun again(output, "key A", info);
    EXPECT_TRUE(std::filesystem::exists(again.root() / "frame"));  // continues
    ASSERT_FALSE(said.empty());
    EXPECT_NE(said.back().find("resuming"), std::string::npos);
  }
  {
    StagingRun other(output, "key B", info);
    EXPECT_FALSE(std::filesystem::exists(other.root() / "frame"));  // another run: starts over
    EXPECT_NE(said.back().find("starting over"), std::string::npos);
    std::ofstream(other.root() / "result") << "B";
    other.Publish(output, false);
  }
  EXPECT_EQ(ReadFile(output / "result"), "B");
  EXPECT_FALSE(std::filesystem::exists(output / ".run_key"));
  EXPECT_FALSE(std::filesystem::exists(root));
  // An existing dataset is replaced only when asked, and only by a complete one.
  {
    StagingRun next(output, "key C", info);
    std::ofstream(next.root() / "result") << "C";
    EXPECT_THROW(next.Publish(output, false), Error);
  }
  EXPECT_EQ(ReadFile(output / "result"), "B");
  StagingRun last(output, "key C", info);
  last.Publish(output, true);
  EXPECT_EQ(ReadFile(output / "result"), "C");
}

}  // namespace
}  // namespace cadsynth

namespace cadsynth {
namespace {

// A RunSpec built in code changes what is rendered without changing any recipe text: the run key
// follows the prepared parts and poses, so such a run never resumes onto the old frames.
TEST(RunKey, FollowsThePreparedScenesNotOnlyTheOptions) {
  RunSpec spec = DefaultRunSpec();
  spec.scenes = {spec.scenes[2]};  // the assembly benchmark's five separate parts
  spec.scenes[0].arrangement.layout = Layout::kRow;
  const std::vector<SweepView> views = ExpandSweep(spec.sweep);
  const std::string key = RunKey(spec, Prepare(spec), views);
  EXPECT_TRUE(RunKey(spec, Prepare(spec), views) == key);  // (keys are long: no printing)
  RunSpec wider = spec;
  wider.scenes[0].arrangement.gap_mm += 5;  // the same parts, further apart
  EXPECT_FALSE(RunKey(wider, Prepare(wider), views) == key);
  PreparedRun moved = Prepare(spec);
  moved.parts[0].mesh.positions[0].x() += 0.001f;  // one vertex of one object
  EXPECT_FALSE(RunKey(spec, moved, views) == key);
}

}  // namespace
}  // namespace cadsynth
