// Reading what engineers have: STEP, IGES, OpenCASCADE BREP and triangle meshes, in millimetres.
#pragma once

#include <filesystem>
#include <string>

#include "cad/part.h"
#include "cad/shape.h"

namespace cadsynth {

// The largest part cadsynth takes, in mm (1 km): a larger one is an error (most likely a unit
// mistake), as ray tracing loses its precision far beyond the scale of a work cell.
inline constexpr double kMaxPartSizeMm = 1e6;

struct ImportOptions {
  TessellationOptions tessellation;
  // The length unit the file's numbers are really in ("mm", "inch", "m", ...). For STEP and IGES
  // it overrides the unit the file declares (for files that declare one unit and hold another);
  // for BREP and meshes, which carry no unit, it states it. Empty: trust the file; BREP and
  // meshes are then taken as millimetres.
  std::string unit;
  // STEP only: the code page of names written as raw bytes (cp1251, sjis, ...); see StepEncodings.
  std::string encoding;
  // Meshes: normals of neighbouring triangles meeting at more than this angle stay apart (a
  // sharp edge); below it they are averaged (smooth shading). B-rep parts keep the exact normals
  // of their surfaces, sharp between faces. 0 gives faceted normals for every format.
  double crease_angle_rad = 30.0 * 3.14159265358979323846 / 180.0;

  bool Check(std::string* why) const;
};

enum class CadFormat { kStep, kIges, kBrep, kMesh };

// The format of a file from its extension (.step .stp .p21, .iges .igs, .brep .rle, and the
// mesh formats .stl .obj .ply .dae .gltf .glb .3mf .off), or from its first bytes when the
// extension says nothing. Throws Error for anything else.
CadFormat DetectFormat(const std::filesystem::path& path);

// Reads any supported file into parts (in their model frames) and instances (placed in the
// file's root frame). A mesh file is one part. Throws Error naming the file.
Assembly ImportCad(const std::filesystem::path& path, const ImportOptions& options);

// Format-specific readers behind ImportCad (lengths as the file gives them, converted to mm by
// the translator for STEP and IGES; BREP and meshes unscaled).
Assembly ReadIges(const std::filesystem::path& path, const TessellationOptions& options);
Assembly ReadBrep(const std::filesystem::path& path, const TessellationOptions& options);
Assembly ReadMesh(const std::filesystem::path& path, double crease_angle_rad);

// Multiplies every length of the assembly by `factor` (meshes, placements, mass properties).
void ScaleAssembly(Assembly* assembly, double factor);

namespace internal {
// What assimp's error string `why` says about `file`, in plain words (ReadMesh's errors; here
// for tests).
std::string PlainAssimpError(std::string why, const std::string& file);
}  // namespace internal

}  // namespace cadsynth
