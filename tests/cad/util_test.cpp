#include "cad/util.h"

#include <gtest/gtest.h>

namespace cadsynth {
namespace {

TEST(EditDistance, CountsInsertionsDeletionsAndSubstitutions) {
  EXPECT_EQ(EditDistance("kitten", "sitting"), 3u);
  EXPECT_EQ(EditDistance("", "abc"), 3u);
  EXPECT_EQ(EditDistance("pitch", "pitch"), 0u);
  EXPECT_EQ(NearestName("pich", {"yaw", "pitch", "radius"}), "pitch");
  EXPECT_EQ(NearestName("exposure", {"yaw", "pitch", "radius"}), "");
}

TEST(UniformDraw, KnownValuesDoNotChange) {
  // The draws are part of the recipe format: the same seed must give the same scene forever.
  EXPECT_EQ(UniformDraw(0, 0, 0), 0.34408081154591164);
  EXPECT_EQ(UniformDraw(2026, 3, 7), 0.972067743885073);
  EXPECT_EQ(UniformDraw(1, 2, 3), 0.9653869021704965);
}

}  // namespace
}  // namespace cadsynth
