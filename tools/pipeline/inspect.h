// The `inspect` command: what cadsynth reads from a CAD or mesh file, as text or JSON.
#pragma once

#include <filesystem>
#include <string>

#include "cad/import.h"

namespace cadsynth {

// Reads `path` and describes it: format, declared unit, parts (instances, bounding box in mm,
// triangles, colour, volume, watertight) and instances (name, part, pose). Throws Error.
std::string InspectText(const std::filesystem::path& path, const ImportOptions& options);
std::string InspectJson(const std::filesystem::path& path, const ImportOptions& options);

}  // namespace cadsynth
