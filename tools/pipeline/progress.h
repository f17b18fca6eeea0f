// Progress of a long run on the terminal or in a cluster log.
#pragma once

#include <cstdio>
#include <functional>
#include <mutex>
#include <string>

#include "tools/pipeline/prepare.h"

namespace cadsynth {

// "87.4 frames/s", or below one frame a second "27.3 s/frame" (a physically based bin: "0.0
// frames/s" says nothing); "0 frames/s" before the first frame.
std::string FormatRate(size_t frames, double seconds);
// "[##########----------]  50%  1665/3330 frames  87.4 frames/s  ETA 0:19" (width = bar cells;
// 0: no bar; the rate as FormatRate). When done, "ETA" becomes "in" and the total time.
std::string FormatProgressBar(size_t done, size_t total, double seconds, int width = 30);
// One JSON object (no newline):
// {"done":..,"total":..,"seconds":..,"frames_per_s":..,"s_per_frame":.., "eta_s":..}, led by
// "shard":"I/N" when `shard` is not empty (cluster logs mix many shards).
std::string FormatProgressJson(size_t done, size_t total, double seconds,
                               const std::string& shard = "");

class ProgressReporter {
 public:
  enum class Mode {
    kBar,    // one line redrawn in place (a terminal)
    kLines,  // a line at every 10% (a log file)
    kJson,   // a JSON line at most every `interval_s` seconds, and at the end (cluster logs)
  };
  // `clock` returns seconds since some start (default: a steady clock started at the first
  // Update, so that rates count the rendering only, not reading the CAD).
  ProgressReporter(Mode mode, std::FILE* out, double interval_s = 5.0,
                   std::function<double()> clock = {});

  // Thread-safe; call with the running count of finished frames.
  void Update(size_t done, size_t total);
  // Thread-safe: a line on a preparation stage (StageReport), before the frames: "pile_1:
  // simulating the pile, 2.0 of 10 s simulated, 37 of 60 bodies moving" or "collision shapes: 2
  // of 3 parts, 'bracket': 12 convex pieces in 1.3 s"; in JSON mode {"stage":"pile",
  // "scene":"pile_1","done":2.0,"total":10.0,"detail":"..."} (led by the shard's name).
  void Stage(const StageReport& report);
  // Names the shard in JSON lines ("I/N"); call before the first Update.
  void SetShard(std::string shard) { shard_ = std::move(shard); }
  // The terminal's width for the bar (default: asked of the terminal, 80 when it does not say).
  void SetColumns(int columns) { columns_ = columns; }

 private:
  Mode mode_;
  std::FILE* out_;
  double interval_s_;
  std::function<double()> clock_;
  std::mutex mutex_;
  double last_report_ = -1e300;
  size_t last_done_ = 0;
  std::string shard_;
  int columns_ = 0;        // 0: ask the terminal
  size_t last_width_ = 0;  // of the bar line drawn last (a shorter one must blank the rest)
};

}  // namespace cadsynth
