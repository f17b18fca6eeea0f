// The one exception type of cadsynth. Every module boundary translates bad input (and third-party
// error channels) into an Error whose message already names where the problem came from: a file,
// a recipe line:column, a CAD entity or part name. The command line prints "error: <what()>".
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace cadsynth {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what) : std::runtime_error(what) {}
};

// Warnings are not fatal: they go to one sink that the command line owns (stderr by default).
// Safe to call from any thread.
void Warn(const std::string& message);

// Replaces the sink; pass nullptr to restore the default (stderr). Returns the previous sink.
using WarningSink = void (*)(const std::string& message);
WarningSink SetWarningSink(WarningSink sink);

// Holds back the warnings this thread emits while it lives, so that work done in parallel can
// report them in a fixed order and a cached result can replay them. Captures nest (the innermost
// one on the thread collects); the destructor passes what it still holds on, in order, to the
// enclosing capture or the sink. Create and destroy on the same thread, in stack order.
class WarningCapture {
 public:
  WarningCapture();
  ~WarningCapture();
  WarningCapture(const WarningCapture&) = delete;
  WarningCapture& operator=(const WarningCapture&) = delete;
  // The warnings collected so far, which the capture then no longer holds.
  std::vector<std::string> Take();

 private:
  friend void Warn(const std::string& message);
  std::vector<std::string> warnings_;
  WarningCapture* outer_;
};

}  // namespace cadsynth
