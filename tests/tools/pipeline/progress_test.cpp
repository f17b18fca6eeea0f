#include "tools/pipeline/progress.h"

#include <cstdio>

#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

namespace cadsynth {
namespace {

TEST(Progress, BarShowsShareRateAndEta) {
  EXPECT_EQ(FormatProgressBar(1665, 3330, 19.0, 10),
            "[#####-----]  50%  1665/3330 frames  87.6 frames/s  ETA 0:19");
  EXPECT_EQ(FormatProgressBar(3330, 3330, 3725.0, 4),
            "[####] 100%  3330/3330 frames  1.1 s/frame  in 1:02:05");
  // Below one frame a second the rate is the time of a frame (27.3 s a frame: "0.0 frames/s"
  // said nothing).
  EXPECT_EQ(FormatProgressBar(3, 10, 81.9, 0), " 30%  3/10 frames  27.3 s/frame  ETA 3:11");
  EXPECT_EQ(FormatRate(10, 4.0), "2.5 frames/s");
  EXPECT_EQ(FormatRate(10, 10.0), "1.0 frames/s");
  EXPECT_EQ(FormatRate(2, 95.0), "47.5 s/frame");
  EXPECT_EQ(FormatRate(0, 3.0), "0 frames/s");
  EXPECT_EQ(FormatProgressBar(0, 10, 0.0, 0),
            "  0%  0/10 frames");  // no rate before the first frame
}

TEST(Progress, JsonLineHasTheNumbersAClusterLogNeeds) {
  const auto j = nlohmann::json::parse(FormatProgressJson(250, 1000, 10.0));
  EXPECT_EQ(j["done"], 250);
  EXPECT_EQ(j["total"], 1000);
  EXPECT_DOUBLE_EQ(j["frames_per_s"].get<double>(), 25.0);
  EXPECT_DOUBLE_EQ(j["eta_s"].get<double>(), 30.0);
  EXPECT_DOUBLE_EQ(j["s_per_frame"].get<double>(), 0.04);
  EXPECT_TRUE(nlohmann::json::parse(FormatProgressJson(0, 1000, 0.0))["eta_s"].is_null());
  EXPECT_TRUE(nlohmann::json::parse(FormatProgressJson(0, 1000, 0.0))["s_per_frame"].is_null());
  // A physically based bin: 2 frames in 60 s is 0.033 frames/s (not 0.0), 30 s a frame.
  const auto slow = nlohmann::json::parse(FormatProgressJson(2, 10, 60.0));
  EXPECT_DOUBLE_EQ(slow["frames_per_s"].get<double>(), 0.033);
  EXPECT_DOUBLE_EQ(slow["s_per_frame"].get<double>(), 30.0);
  EXPECT_EQ(
      FormatProgressJson(250, 1000, 10.0, "3/100").rfind("{\"shard\":\"3/100\",\"done\":250,", 0),
      0u);
}

// JSON mode prints at most one line per interval, always the last one, and ignores late counts.
TEST(Progress, JsonLinesAreThrottledAndTheLastAlwaysComes) {
  char* buffer = nullptr;
  size_t size = 0;
  std::FILE* out = open_memstream(&buffer, &size);
  double now = 0;
  {
    ProgressReporter reporter(ProgressReporter::Mode::kJson, out, 5.0, [&] { return now; });
    for (size_t done = 1; done <= 100; ++done) {
      now = done * 0.2;  // 20 s in all: lines at 0.2 s, then every 5 s
      reporter.Update(done, 100);
    }
    reporter.Update(99, 100);  // late: ignored
  }
  std::fclose(out);
  const std::string text(buffer, size);
  std::free(buffer);
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 5)
      << text;  // 0.2, 5.2, 10.2, 15.2 s and the end
  EXPECT_NE(text.find("{\"done\":100,\"total\":100"), std::string::npos) << text;
}

// The bar redraws one line: a shorter line blanks what the longer one before left ("in 0:18"
// drawn over "ETA 0:05" showed "in 0:180"), and every line fits the terminal's width (a wrapped
// line scrolls instead of being redrawn).
TEST(Progress, BarLinesBlankLeftoversAndFitTheTerminal) {
  for (const int columns : {80, 60, 40}) {
    SCOPED_TRACE(columns);
    char* buffer = nullptr;
    size_t size = 0;
    std::FILE* out = open_memstream(&buffer, &size);
    double now = 0;
    {
      ProgressReporter reporter(ProgressReporter::Mode::kBar, out, 5.0, [&] { return now; });
      reporter.SetColumns(columns);
      now = 1.0;
      reporter.Update(10, 1000);  // 10.0 frames/s, ETA 1:39
      now = 18.0;
      reporter.Update(1000, 1000);  // 55.6 frames/s, in 0:18: shorter
    }
    std::fclose(out);
    const std::string text(buffer, size);
    std::free(buffer);
    ASSERT_EQ(text.back(), '\n');
    const size_t last = text.rfind('\r');
    ASSERT_NE(last, std::string::npos);
    const std::string first_line = text.substr(1, last - 1);
    const std::string final_line = text.substr(last + 1, text.size() - last - 2);
    EXPECT_LT(static_cast<int>(first_line.size()), columns) << first_line;
    EXPECT_GE(final_line.size(), first_line.size()) << "leftovers would show";
    const std::string shown = final_line.substr(0, final_line.find_last_not_of(' ') + 1);
    EXPECT_LT(static_cast<int>(shown.size()), columns) << shown;
    EXPECT_EQ(shown.substr(shown.size() - 7), "in 0:18") << shown;
  }
}

}  // namespace
}  // namespace cadsynth
