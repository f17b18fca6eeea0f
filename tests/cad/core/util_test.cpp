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

TEST(Count, OneIsSingularEverythingElsePlural) {
  EXPECT_EQ(Count(1, "part"), "1 part");
  EXPECT_EQ(Count(0, "part"), "0 parts");
  EXPECT_EQ(Count(30, "part"), "30 parts");
  EXPECT_EQ(Count(1, "was", "were"), "1 was");
  EXPECT_EQ(Count(2, "was", "were"), "2 were");
}

}  // namespace
}  // namespace cadsynth
