// Reading CAD and mesh files in a child process. OpenCASCADE and assimp can crash (SIGSEGV, an
// assert's abort) or loop for ever on a hostile file, and no check from outside catches every
// case; a child process that dies or hangs ends with a clear error instead of taking the run
// with it. The child is a cadsynth executable running the hidden `__read-part` command: it imports
// the file as ImportCad does and writes the assembly, B-reps and warnings included, in the part
// cache's encoding (cad/part_cache.h) to its standard output.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "cad/import.h"
#include "cad/part.h"

namespace cadsynth {

struct ReaderProcess {
  std::filesystem::path executable;  // a cadsynth executable (the running one: /proc/self/exe)
  double timeout_s = 600.0;          // a reader still running after this is stopped
};

// Whether a file's format is read in a child process: every format but STL, PLY and OFF, which
// our own checked readers read (cad/mesh_formats.h; fuzzed, and STL files are the bulk of large
// meshes, where a process start and a copy through a pipe would cost).
bool NeedsGuardedReader(const std::filesystem::path& path);

// Imports `path` like ImportCad. With `reader`, and a format that needs it, in a child process:
// a crash becomes "FILE: cannot read: the reader crashed (Segmentation fault)", a hang past the
// timeout "FILE: the reader did not finish in N s". The import's warnings are returned in
// `warnings`, not emitted. Throws Error.
Assembly ImportGuarded(const std::filesystem::path& path, const ImportOptions& options,
                       const ReaderProcess* reader, std::vector<std::string>* warnings);

// The child's side, behind `cadsynth __read-part ARGS...`: ARGS as ReadPartArguments makes them.
// Writes the encoded assembly to standard output and returns 0, or writes the error to standard
// error and returns 3.
int ReadPartMain(const std::vector<std::string>& args);
std::vector<std::string> ReadPartArguments(const std::filesystem::path& path,
                                           const ImportOptions& options);

}  // namespace cadsynth
