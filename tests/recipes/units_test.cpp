#include "recipes/units.h"

#include <cmath>

#include <gtest/gtest.h>

namespace cadsynth {
namespace {

TEST(Units, LengthsComeOutInMillimetres) {
  std::string why;
  EXPECT_DOUBLE_EQ(*ParseLengthMm("650", &why), 650.0);
  EXPECT_DOUBLE_EQ(*ParseLengthMm("650 mm", &why), 650.0);
  EXPECT_DOUBLE_EQ(*ParseLengthMm("0.65 m", &why), 650.0);
  EXPECT_DOUBLE_EQ(*ParseLengthMm("0.65m", &why), 650.0);
  EXPECT_DOUBLE_EQ(*ParseLengthMm("1 in", &why), 25.4);
  EXPECT_DOUBLE_EQ(*ParseLengthMm("2 cm", &why), 20.0);
  EXPECT_DOUBLE_EQ(*ParseLengthMm("-3e2 um", &why), -0.3);
  EXPECT_FALSE(ParseLengthMm("0.65 parsecs", &why));
  EXPECT_NE(why.find("unknown length unit 'parsecs'"), std::string::npos);
  EXPECT_FALSE(ParseLengthMm("m", &why));
  EXPECT_FALSE(ParseLengthMm("", &why));
}

TEST(Units, AnglesComeOutInRadians) {
  std::string why;
  EXPECT_DOUBLE_EQ(*ParseAngleRad("90", &why), M_PI / 2);
  EXPECT_DOUBLE_EQ(*ParseAngleRad("90 deg", &why), M_PI / 2);
  EXPECT_DOUBLE_EQ(*ParseAngleRad("0.5 rad", &why), 0.5);
  EXPECT_FALSE(ParseAngleRad("90 grad", &why));
}

}  // namespace
}  // namespace cadsynth
