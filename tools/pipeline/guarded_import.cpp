#include "tools/pipeline/guarded_import.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>

#include "cad/core/error.h"
#include "cad/mesh_formats.h"
#include "cad/part_cache.h"

extern char** environ;

namespace cadsynth {
namespace {

std::string Number(double x) {
  char text[40];
  std::snprintf(text, sizeof(text), "%.17g", x);
  return text;
}

double ParseNumber(const std::string& text) {
  char* end = nullptr;
  const double x = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0') throw Error("__read-part: bad number '" + text + "'");
  return x;
}

// Closes a file descriptor when it goes out of scope.
struct Fd {
  int fd = -1;
  ~Fd() {
    if (fd >= 0) ::close(fd);
  }
};

}  // namespace

bool NeedsGuardedReader(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return !HasCheckedMeshReader(ext);
}

std::vector<std::string> ReadPartArguments(const std::filesystem::path& path,
                                           const ImportOptions& options) {
  const TessellationOptions& t = options.tessellation;
  return {path.string(),
          options.unit,
          options.encoding,
          Number(t.linear_deflection_mm),
          Number(t.angular_deflection_rad),
          Number(t.min_relative_deflection),
          t.measure_deviation ? "1" : "0",
          Number(options.crease_angle_rad)};
}

namespace {
void DropWarning(const std::string&) {}
}  // namespace

int ReadPartMain(const std::vector<std::string>& args) {
  // Warnings travel with the answer; on an error they are dropped (the error says enough), so
  // that standard error holds the error alone.
  SetWarningSink(&DropWarning);
  try {
    if (args.size() != 8) throw Error("__read-part: expected 8 arguments");
    ImportOptions options;
    options.unit = args[1];
    options.encoding = args[2];
    options.tessellation.linear_deflection_mm = ParseNumber(args[3]);
    options.tessellation.angular_deflection_rad = ParseNumber(args[4]);
    options.tessellation.min_relative_deflection = ParseNumber(args[5]);
    options.tessellation.measure_deviation = args[6] == "1";
    options.crease_angle_rad = ParseNumber(args[7]);
    std::vector<std::string> warnings;
    Assembly assembly;
    {
      WarningCapture capture;
      assembly = ImportCad(args[0], options);
      warnings = capture.Take();
    }
    const std::string bytes = EncodeAssembly(assembly, warnings);
    std::cout.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    std::cout.flush();
    return std::cout ? 0 : 3;
  } catch (const Error& e) {
    std::cerr << e.what() << std::flush;
    return 3;
  }
}

Assembly ImportGuarded(const std::filesystem::path& path, const ImportOptions& options,
                       const ReaderProcess* reader, std::vector<std::string>* warnings) {
  if (reader == nullptr || !NeedsGuardedReader(path)) {
    WarningCapture capture;
    Assembly assembly = ImportCad(path, options);
    *warnings = capture.Take();
    return assembly;
  }
  const std::string file = path.string();
  int out_pipe[2], err_pipe[2];
  if (::pipe2(out_pipe, O_CLOEXEC) != 0) throw Error(file + ": cannot start a reader: no pipe");
  Fd out_read{out_pipe[0]}, out_write{out_pipe[1]};
  if (::pipe2(err_pipe, O_CLOEXEC) != 0) throw Error(file + ": cannot start a reader: no pipe");
  Fd err_read{err_pipe[0]}, err_write{err_pipe[1]};

  std::vector<std::string> args = {reader->executable.string(), "__read-part"};
  for (std::string& a : ReadPartArguments(path, options)) args.push_back(std::move(a));
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, out_write.fd, 1);
  posix_spawn_file_actions_adddup2(&actions, err_write.fd, 2);
  pid_t pid = 0;
  const int spawned = ::posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) {
    throw Error(file + ": cannot start a reader (" + reader->executable.string() +
                "): " + std::strerror(spawned));
  }
  ::close(out_write.fd), out_write.fd = -1;
  ::close(err_write.fd), err_write.fd = -1;

  // Both pipes read as they fill (a child blocked on a full pipe would never end), until both
  // close or the time is up.
  std::string out, err;
  const auto start = std::chrono::steady_clock::now();
  bool timed_out = false;
  pollfd fds[2] = {{out_read.fd, POLLIN, 0}, {err_read.fd, POLLIN, 0}};
  int open = 2;
  char buffer[1 << 16];
  while (open > 0) {
    const double left =
        reader->timeout_s -
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (left <= 0) {
      timed_out = true;
      break;
    }
    const int ready = ::poll(fds, 2, static_cast<int>(std::min(left * 1000.0, 1000.0)) + 1);
    if (ready < 0 && errno != EINTR) break;
    for (int k = 0; k < 2; ++k) {
      if (fds[k].fd < 0 || (fds[k].revents & (POLLIN | POLLHUP | POLLERR)) == 0) continue;
      const ssize_t n = ::read(fds[k].fd, buffer, sizeof(buffer));
      if (n > 0) {
        (k == 0 ? out : err).append(buffer, static_cast<size_t>(n));
      } else if (n == 0 || errno != EINTR) {
        fds[k].fd = -1;
        --open;
      }
    }
  }
  // A child that closed its pipes may still not end: wait for it within the same time limit.
  int status = 0;
  while (!timed_out) {
    const pid_t done = ::waitpid(pid, &status, WNOHANG);
    if (done == pid || (done < 0 && errno != EINTR)) break;
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() >=
        reader->timeout_s) {
      timed_out = true;
      break;
    }
    ::usleep(2000);
  }
  if (timed_out) {
    ::kill(pid, SIGKILL);
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
  }
  if (timed_out) {
    throw Error(file + ": the reader did not finish in " + Number(reader->timeout_s) +
                " s (a damaged file? limits.read_timeout sets the time)");
  }
  if (WIFSIGNALED(status)) {
    throw Error(file + ": cannot read: the reader crashed on this file (" +
                std::string(::strsignal(WTERMSIG(status))) + ")");
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    while (!err.empty() && (err.back() == '\n' || err.back() == '\r')) err.pop_back();
    if (err.size() > 2000) err = err.substr(0, 2000) + "...";
    throw Error(err.empty() ? file + ": the reader failed (exit " +
                                  std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) + ")"
                            : err);
  }
  try {
    return DecodeAssembly(out, warnings);
  } catch (const Error& e) {
    throw Error(file + ": the reader's answer is damaged: " + e.what());
  }
}

}  // namespace cadsynth
