// Writing files so that no reader ever sees half of one.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

namespace cadsynth {

// Writes `bytes` to `path` through a temporary name in the same folder, then renames it into
// place. Throws Error naming the file (with the system's reason, e.g. a full disk) on failure.
void WriteFileAtomic(const std::filesystem::path& path, std::string_view bytes);

// Creates `dir` and its parents; throws Error naming it on failure.
void CreateFolder(const std::filesystem::path& dir);

// Makes `to` a hard link to `from` (no extra disk space), or a copy where links are not possible
// (another file system); replaces an existing `to`. Throws Error naming the files on failure.
void LinkOrCopy(const std::filesystem::path& from, const std::filesystem::path& to);

// The whole file; throws Error naming it when it cannot be read.
std::string ReadFileText(const std::filesystem::path& path);

// A BOP id: six digits, zero-padded ("000042").
std::string Id6(int id);

}  // namespace cadsynth
