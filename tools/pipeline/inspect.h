// The `inspect` command: what cadsynth reads from a CAD or mesh file, as text or JSON.
#pragma once

#include <filesystem>
#include <string>

#include "cad/import.h"
#include "tools/pipeline/guarded_import.h"

namespace cadsynth {

// Reads `path` (in a child process with `reader`: guarded_import.h) and describes it: format,
// declared unit, parts (instances, bounding box in mm, triangles, colour, volume, watertight) and
// instances (name, part, pose). Warnings go to the warning sink. Throws Error.
std::string InspectText(const std::filesystem::path& path, const ImportOptions& options,
                        const ReaderProcess* reader = nullptr);
std::string InspectJson(const std::filesystem::path& path, const ImportOptions& options,
                        const ReaderProcess* reader = nullptr);

}  // namespace cadsynth
