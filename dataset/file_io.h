// Writing files so that no reader ever sees half of one.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

namespace cadsynth {

// Writes `bytes` to `path` through a temporary name in the same folder, then renames it into
// place. Throws Error naming the file (with the system's reason, e.g. a full disk) on failure.
void WriteFileAtomic(const std::filesystem::path& path, std::string_view bytes);

}  // namespace cadsynth
