#include "tools/pipeline/prepare.h"

#include <set>

#include <gtest/gtest.h>

namespace cadsynth {
namespace {

// The default job's three demo sets: objects shared by the scenes, one obj_id per instance,
// every instance resting on the floor (z >= 0, touching it).
TEST(Prepare, DefaultJobScenesObjectsAndClasses) {
  const RunSpec spec = DefaultRunSpec();
  const PreparedRun run = Prepare(spec);
  EXPECT_EQ(run.parts.size(), 13u);
  EXPECT_EQ(run.classes.size(), run.parts.size());
  ASSERT_EQ(run.scenes.size(), 3u);
  ASSERT_EQ(run.obj_ids.size(), 3u);
  size_t instances = 0;
  for (size_t s = 0; s < 3; ++s) {
    SCOPED_TRACE(s);
    ASSERT_EQ(run.obj_ids[s].size(), run.scenes[s].instances.size());
    double lowest = 1e300;
    for (size_t i = 0; i < run.scenes[s].instances.size(); ++i) {
      const Instance& instance = run.scenes[s].instances[i];
      EXPECT_EQ(run.obj_ids[s][i], instance.part + 1);
      for (const Eigen::Vector3f& p : run.parts[instance.part].mesh.positions) {
        lowest = std::min(lowest, (instance.world_from_model * p.cast<double>()).z());
      }
    }
    EXPECT_NEAR(lowest, 0.0, 1e-3);  // resting on the floor
    instances += run.scenes[s].instances.size();
  }
  EXPECT_EQ(instances, 15u);
  EXPECT_NE(run.variants_json.find("\"variants\""), std::string::npos);
}

TEST(Prepare, PlacementWarningsSayWhenTheSceneIsTooLargeOrTooSmall) {
  const RunSpec spec = DefaultRunSpec();
  const PreparedRun run = Prepare(spec);
  SweepOptions near = spec.sweep;
  near.radius_mm = {30.0};  // inside the scene (it reaches 48 mm from the target)
  const auto warnings =
      PlacementWarnings(run.parts, run.scenes[0].instances, spec.intrinsics, near);
  ASSERT_FALSE(warnings.empty());
  EXPECT_NE(warnings[0].find("beyond the nearest camera radius"), std::string::npos) << warnings[0];
  EXPECT_TRUE(
      PlacementWarnings(run.parts, run.scenes[0].instances, spec.intrinsics, spec.sweep).empty());
}

}  // namespace
}  // namespace cadsynth
