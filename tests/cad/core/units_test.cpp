#include "cad/core/units.h"

#include <gtest/gtest.h>

namespace cadsynth {
namespace {

TEST(LengthUnitMm, KnowsTheNamesCadFilesUse) {
  EXPECT_EQ(*LengthUnitMm("inch"), 25.4);
  EXPECT_EQ(*LengthUnitMm("INCH"), 25.4);
  EXPECT_EQ(*LengthUnitMm("millimetre"), 1.0);
  EXPECT_EQ(*LengthUnitMm("metre"), 1000.0);
  EXPECT_EQ(*LengthUnitMm("um"), 1e-3);
  EXPECT_EQ(*LengthUnitMm("ft"), 304.8);
  EXPECT_FALSE(LengthUnitMm("furlong"));
  EXPECT_FALSE(LengthUnitMm(""));
}

}  // namespace
}  // namespace cadsynth
