#include "cad/error.h"

#include <atomic>
#include <cstdio>
#include <mutex>

namespace cadsynth {
namespace {

void StderrSink(const std::string& message) {
  static std::mutex mutex;
  std::lock_guard<std::mutex> lock(mutex);
  std::fprintf(stderr, "warning: %s\n", message.c_str());
}

std::atomic<WarningSink> g_sink{&StderrSink};

}  // namespace

void Warn(const std::string& message) { g_sink.load()(message); }

WarningSink SetWarningSink(WarningSink sink) {
  return g_sink.exchange(sink != nullptr ? sink : &StderrSink);
}

}  // namespace cadsynth
