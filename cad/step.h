// STEP files through OpenCASCADE's XDE: assembly tree, instance placements and names.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "cad/part.h"
#include "cad/shape.h"

namespace cadsynth {

// Reads a STEP file (AP203/AP214/AP242) into distinct parts and their instances. Lengths come
// out in millimetres whatever unit the file declares. Parts are tessellated in parallel.
// `encoding` is the code page of names written as raw bytes instead of STEP's escapes (see
// StepCodePage(); empty: UTF-8, with a warning when the file's bytes are not UTF-8).
// Throws Error naming the file for a missing, unreadable, corrupted or empty file.
Assembly ReadStep(const std::filesystem::path& path, const TessellationOptions& options,
                  const std::string& encoding = "");

// OpenCASCADE's name for a code page ReadStep accepts, in any case: UTF8 (utf-8), SJIS
// (shift_jis), EUC, GB (gb2312), CP850, CP1250-CP1258, iso8859-1 (latin1) to iso8859-9.
// Empty when unknown.
std::string StepCodePage(const std::string& encoding);

// One part written to STEP, placed once per entry of `placements`.
struct StepComponent {
  std::string name;
  Shape shape;
  std::vector<Eigen::Isometry3d> placements = {Eigen::Isometry3d::Identity()};
  std::optional<Eigen::Vector3f> color;  // sRGB in [0, 1], written as the part's surface colour
};

// Writes the components as one assembly named `assembly_name`, in millimetres (AP214).
// The file appears complete or not at all (written under a temporary name, then renamed).
void WriteStep(const std::filesystem::path& path, const std::string& assembly_name,
               const std::vector<StepComponent>& components);

}  // namespace cadsynth
