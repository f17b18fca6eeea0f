// STEP tessellated geometry (AP242 TESSELLATED_SOLID / TESSELLATED_SHELL with TRIANGULATED_FACE
// and COMPLEX_TRIANGULATED_FACE), which OpenCASCADE 7.6 does not read. Internal to cad/.
#pragma once

#include <filesystem>
#include <string>

#include "cad/part.h"

namespace cadsynth::internal {

// Every tessellated solid or shell in the file (but supplemental geometry, i.e. items of a
// CONSTRUCTIVE_GEOMETRY_REPRESENTATION) becomes one part (triangles passed through, in the
// file's root frame, times `unit_mm`); its colour is the colour styling most of its triangles.
// Triangles are wound to agree with the normals the file gives. Returns an assembly without parts
// when the file holds no tessellated geometry. Throws Error naming the file on malformed data.
Assembly ReadStepTessellated(const std::filesystem::path& path, double unit_mm);

}  // namespace cadsynth::internal
