#include "cad/core/error.h"

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

// Captures nest; what a capture still holds goes on, in order, to the enclosing one or the sink.
TEST(WarningCapture, HoldsBackWarningsAndPassesOnTheRest) {
  std::vector<std::string> seen;
  g_seen = &seen;
  const WarningSink previous = SetWarningSink(&Collect);
  {
    WarningCapture outer;
    Warn("a");
    {
      WarningCapture inner;
      Warn("b");
      EXPECT_EQ(inner.Take(), std::vector<std::string>{"b"});  // taken: not passed on
      Warn("c");
    }  // passes "c" to outer
    EXPECT_TRUE(seen.empty());
    const std::vector<std::string> held = outer.Take();
    EXPECT_EQ(held, (std::vector<std::string>{"a", "c"}));
    Warn("d");
  }  // passes "d" to the sink
  Warn("e");
  SetWarningSink(previous);
  EXPECT_EQ(seen, (std::vector<std::string>{"d", "e"}));
}

}  // namespace
}  // namespace cadsynth
