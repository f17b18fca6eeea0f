#include "cad/core/util.h"

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

}  // namespace
}  // namespace cadsynth
