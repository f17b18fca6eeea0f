// Parametric part families: every size of a bolt, every tooth count of a gear, any file scaled.
// A family has named, typed parameters with defaults; a variant is one choice of values.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <variant>
#include <vector>

#include "cad/core/util.h"
#include "cad/import.h"
#include "cad/part.h"
#include "variants/mechanisms.h"

namespace cadsynth {

struct FamilyParam {
  enum class Kind { kLength, kAngle, kCount, kNumber, kText };
  std::string name;
  Kind kind = Kind::kNumber;
  double default_number = 0.0;  // lengths in mm, angles in radians
  std::string default_text;
  std::string help;
};

// One value: a number (mm, radians, count) or a text (an ISO size, a file path, shaft sections).
using ParamValue = std::variant<double, std::string>;
using ParamValues = std::map<std::string, ParamValue>;  // sorted by name: stable output

// A family is one row of Families() (variants/families.cpp): its name, help, typed parameters
// with defaults, and the builder of a variant's B-rep parts from complete values. A new family is
// that row plus its geometry (variants/standard_parts.h, gear.h, mechanisms.h); `cadsynth
// families` and docs/parts.md's table come from the rows.
struct FamilyInfo {
  using Builder = ShapeAssembly (*)(const std::string& family, const ParamValues& values);
  std::string name;
  std::string help;
  std::vector<FamilyParam> params;
  Builder build = nullptr;  // null: not parametric ('scaled' scales a file: BuildVariant)
  const FamilyParam* Find(const std::string& param) const;
};

// Every family cadsynth knows, in a fixed order.
const std::vector<FamilyInfo>& Families();
const FamilyInfo* FindFamily(const std::string& name);

// The family's defaults overlaid with `values`. Throws Error for an unknown parameter (with the
// nearest known one) or a value of the wrong kind.
ParamValues CompleteParams(const FamilyInfo& family, const ParamValues& values);

// Builds one variant as parts with instances, tessellated. `values` must be complete
// (CompleteParams). Throws Error with the reason for impossible values.
Assembly BuildVariant(const FamilyInfo& family, const ParamValues& values,
                      const ImportOptions& options);

// The B-rep parts and placements of a parametric variant (not 'scaled'), e.g. for STEP export.
ShapeAssembly BuildVariantShapes(const FamilyInfo& family, const ParamValues& values);

// "name=value, ..." for messages and listings; with the family, angles in degrees as recipes
// write them ("pressure_angle=20 deg"), else every number as stored (radians).
std::string DescribeParams(const ParamValues& values, const FamilyInfo* family = nullptr);

// Every family as a Markdown table: name, help, and each parameter with its default (lengths in
// mm, angles in degrees) and help. `cadsynth variants --families` prints it; docs/parts.md holds
// it (tools/docs.py, checked by the docs_generated test).
std::string FamilyTable();

// Every length of `assembly` scaled by (sx, sy, sz) in its root frame. Uniform scales keep
// instances; otherwise each instance becomes a part of its own (a turned part scales
// differently). B-rep parts are scaled exactly and tessellated anew; mesh parts are scaled as
// meshes.
Assembly ScaleVariant(const Assembly& assembly, const Eigen::Vector3d& scale,
                      const TessellationOptions& options);

}  // namespace cadsynth
