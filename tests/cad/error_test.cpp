#include "cad/error.h"

#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace cadsynth {
namespace {

std::vector<std::string>* g_seen = nullptr;
void Collect(const std::string& message) { g_seen->push_back(message); }

TEST(Error, CarriesItsMessage) {
  try {
    throw Error("part.stp: no such file");
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "part.stp: no such file");
  }
}

TEST(Warn, GoesToTheInstalledSinkAndBack) {
  std::vector<std::string> seen;
  g_seen = &seen;
  const WarningSink previous = SetWarningSink(&Collect);
  Warn("first");
  Warn("second");
  EXPECT_EQ(SetWarningSink(previous), &Collect);
  Warn("not collected");  // back to stderr
  EXPECT_EQ(seen, (std::vector<std::string>{"first", "second"}));
}

}  // namespace
}  // namespace cadsynth
