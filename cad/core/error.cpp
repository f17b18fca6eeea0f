#include "cad/core/error.h"

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
thread_local WarningCapture* t_capture = nullptr;

}  // namespace

void Warn(const std::string& message) {
  if (t_capture != nullptr) {
    t_capture->warnings_.push_back(message);
  } else {
    g_sink.load()(message);
  }
}

WarningCapture::WarningCapture() : outer_(t_capture) { t_capture = this; }

WarningCapture::~WarningCapture() {
  t_capture = outer_;
  for (const std::string& warning : warnings_) Warn(warning);
}

std::vector<std::string> WarningCapture::Take() {
  std::vector<std::string> out;
  out.swap(warnings_);
  return out;
}

WarningSink SetWarningSink(WarningSink sink) {
  return g_sink.exchange(sink != nullptr ? sink : &StderrSink);
}

}  // namespace cadsynth
