// The one exception type of cadsynth. Every module boundary translates bad input (and third-party
// error channels) into an Error whose message already names where the problem came from: a file,
// a recipe line:column, a CAD entity or part name. The command line prints "error: <what()>".
#pragma once

#include <stdexcept>
#include <string>

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

}  // namespace cadsynth
