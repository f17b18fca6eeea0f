#include "render/scene.h"

#include <gtest/gtest.h>

namespace cadsynth {
namespace {

TEST(Palette, ColoursAreDistinctAndNotGrey) {
  for (int i = 0; i < 24; ++i) {
    const Eigen::Vector3f c = PaletteColor(i);
    EXPECT_GT(c.maxCoeff() - c.minCoeff(), 0.3f) << i;  // saturated: never the grey floor
    for (int j = 0; j < i; ++j) EXPECT_GT((c - PaletteColor(j)).norm(), 0.02f) << i << " " << j;
  }
}

}  // namespace
}  // namespace cadsynth
