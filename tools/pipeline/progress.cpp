#include "tools/pipeline/progress.h"

#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>

#include <nlohmann/json.hpp>

namespace cadsynth {
namespace {

std::string Duration(double seconds) {
  const long s = std::lround(std::max(0.0, seconds));
  char buffer[32];
  if (s >= 3600) {
    std::snprintf(buffer, sizeof(buffer), "%ld:%02ld:%02ld", s / 3600, s / 60 % 60, s % 60);
  } else {
    std::snprintf(buffer, sizeof(buffer), "%ld:%02ld", s / 60, s % 60);
  }
  return buffer;
}

}  // namespace

std::string FormatRate(size_t frames, double seconds) {
  char text[64];
  if (seconds <= 0 || frames == 0) {
    std::snprintf(text, sizeof(text), "0 frames/s");
  } else if (frames >= seconds) {
    std::snprintf(text, sizeof(text), "%.1f frames/s", frames / seconds);
  } else {  // below one frame a second: how long one takes
    std::snprintf(text, sizeof(text), "%.1f s/frame", seconds / frames);
  }
  return text;
}

std::string FormatProgressBar(size_t done, size_t total, double seconds, int width) {
  const double fraction = total > 0 ? std::min(1.0, static_cast<double>(done) / total) : 1.0;
  const int filled = static_cast<int>(fraction * width);
  std::string bar;
  if (width > 0) {
    bar.push_back('[');
    bar.append(static_cast<size_t>(filled), '#');
    bar.append(static_cast<size_t>(width - filled), '-');
    bar.append("] ");
  }
  char text[160];
  std::snprintf(text, sizeof(text), "%3d%%  %zu/%zu frames", static_cast<int>(100 * fraction), done,
                total);
  bar += text;
  if (seconds > 0 && done > 0) {
    const double rate = done / seconds;
    std::snprintf(text, sizeof(text), "  %s  %s %s", FormatRate(done, seconds).c_str(),
                  done < total ? "ETA" : "in",
                  Duration(done < total ? (total - done) / rate : seconds).c_str());
    bar += text;
  }
  return bar;
}

std::string FormatProgressJson(size_t done, size_t total, double seconds,
                               const std::string& shard) {
  const double rate = seconds > 0 ? done / seconds : 0.0;
  nlohmann::ordered_json j = nlohmann::ordered_json::object();
  if (!shard.empty()) j["shard"] = shard;
  j["done"] = done;
  j["total"] = total;
  j["seconds"] = std::round(seconds * 100) / 100;
  // To three decimals: a physically based bin renders at 0.04 frames/s.
  j["frames_per_s"] = std::round(rate * 1000) / 1000;
  j["s_per_frame"] = done > 0 ? nlohmann::ordered_json(std::round(seconds / done * 100) / 100)
                              : nlohmann::ordered_json(nullptr);
  j["eta_s"] =
      rate > 0
          ? nlohmann::ordered_json(std::round((total - std::min(done, total)) / rate * 10) / 10)
          : nlohmann::ordered_json(nullptr);
  return j.dump();
}

ProgressReporter::ProgressReporter(Mode mode, std::FILE* out, double interval_s,
                                   std::function<double()> clock)
    : mode_(mode), out_(out), interval_s_(interval_s), clock_(std::move(clock)) {
  if (!clock_) {
    clock_ = [start = std::optional<std::chrono::steady_clock::time_point>()]() mutable {
      const auto now = std::chrono::steady_clock::now();
      if (!start) start = now;
      return std::chrono::duration<double>(now - *start).count();
    };
  }
}

void ProgressReporter::Stage(const StageReport& report) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (mode_ == Mode::kJson) {
    nlohmann::ordered_json j = nlohmann::ordered_json::object();
    if (!shard_.empty()) j["shard"] = shard_;
    j["stage"] = report.stage;
    if (!report.scene.empty()) j["scene"] = report.scene;
    j["done"] = std::round(report.done * 100) / 100;
    j["total"] = report.total;
    j["detail"] = report.detail;
    std::fprintf(out_, "%s\n", j.dump().c_str());
  } else if (report.stage == "pile") {
    std::fprintf(out_, "%s: simulating the pile, %.1f of %g s simulated, %s\n",
                 report.scene.c_str(), report.done, report.total, report.detail.c_str());
  } else {
    std::fprintf(out_, "%s: %g of %g parts, %s\n",
                 report.stage == "collision_shapes" ? "collision shapes" : report.stage.c_str(),
                 report.done, report.total, report.detail.c_str());
  }
  std::fflush(out_);
}

void ProgressReporter::Update(size_t done, size_t total) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (done < last_done_) return;  // an older count arriving late
  last_done_ = done;
  const double now = clock_();
  const bool last = done >= total;
  switch (mode_) {
    case Mode::kBar: {
      if (!last && now - last_report_ < 0.1) return;  // redraw at most 10 times a second
      // One line that fits the terminal: a line that wraps is no longer redrawn by '\r', it
      // scrolls. The bar shrinks (or goes) to fit, and a line shorter than the one before blanks
      // its leftover characters ("in 0:18" over "ETA 0:05" showed "in 0:180").
      int columns = columns_;
      if (columns <= 0) {
        winsize size{};
        columns = ::ioctl(::fileno(out_), TIOCGWINSZ, &size) == 0 && size.ws_col > 0
                      ? static_cast<int>(size.ws_col)
                      : 80;
      }
      std::string line = FormatProgressBar(done, total, now, 0);
      const int room = columns - 1 - static_cast<int>(line.size()) - 3;
      if (room >= 10) line = FormatProgressBar(done, total, now, std::min(30, room));
      if (static_cast<int>(line.size()) >= columns) {  // narrow: the numbers only
        const double fraction = total > 0 ? std::min(1.0, static_cast<double>(done) / total) : 1.0;
        char text[160];
        std::snprintf(text, sizeof(text), "%3d%% %zu/%zu", static_cast<int>(100 * fraction), done,
                      total);
        line = text;
        if (now > 0 && done > 0) {
          const double rate = done / now;
          std::string short_rate = FormatRate(done, now);
          short_rate.replace(short_rate.find(' '), std::string::npos, done >= now ? "/s" : " s/f");
          std::snprintf(text, sizeof(text), " %s %s %s", short_rate.c_str(), last ? "in" : "ETA",
                        Duration(last ? now : (total - done) / rate).c_str());
          line += text;
        }
      }
      if (static_cast<int>(line.size()) >= columns) line.resize(static_cast<size_t>(columns - 1));
      const size_t width = line.size();
      if (line.size() < last_width_) line.append(last_width_ - line.size(), ' ');
      last_width_ = width;
      std::fprintf(out_, "\r%s%s", line.c_str(), last ? "\n" : "");
      break;
    }
    case Mode::kLines:
      if (!last && done % std::max<size_t>(1, total / 10) != 0) return;
      std::fprintf(out_, "%s\n", FormatProgressBar(done, total, now, 0).c_str());
      break;
    case Mode::kJson:
      if (!last && now - last_report_ < interval_s_) return;
      std::fprintf(out_, "%s\n", FormatProgressJson(done, total, now, shard_).c_str());
      break;
  }
  last_report_ = now;
  std::fflush(out_);
}

}  // namespace cadsynth
