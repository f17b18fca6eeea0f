// The small job most pipeline tests run: the default job (the reference paper's three demo sets)
// at 160 x 120 (Kinect v1's K scaled by 1/4), with the given yaws at pitch 0.6 rad and radius
// 700 mm: a few seconds for the whole pipeline, every module exercised.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "recipes/recipe.h"
#include "tools/pipeline/generate.h"
#include "variants/families.h"

namespace cadsynth::testing {

// A family entry with the given variants (parameters completed with the family's defaults).
inline PartSource Family(const std::string& name, const std::vector<ParamValues>& variants,
                         bool one_class = false) {
  PartSource source;
  source.kind = PartSource::Kind::kFamily;
  source.family = name;
  for (const ParamValues& v : variants)
    source.variants.push_back(CompleteParams(*FindFamily(name), v));
  source.one_class = one_class;
  return source;
}

inline RunSpec SmallJob(std::vector<double> yaws_rad = {0.0, 2.0}) {
  RunSpec spec = DefaultRunSpec();
  spec.intrinsics = Intrinsics{160, 120, 131.25, 131.25, 79.5, 59.5};
  spec.sweep.yaw_rad = std::move(yaws_rad);
  spec.sweep.pitch_rad = {0.6};
  spec.sweep.radius_mm = {700.0};
  return spec;
}

// The farm tests' job: SmallJob with four views (12 units, three scenes) and every output format
// derived from the frames (paper layout, PVN3D meta, grasp points), 200-point model clouds.
inline RunSpec SmallFarmJob() {
  RunSpec spec = SmallJob({0.0, 1.5, 3.0, 4.5});
  spec.bop.paper_layout = spec.bop.pvn3d_meta = spec.bop.grasp_points = true;
  spec.bop.model_points = 200;
  return spec;
}

// SmallFarmJob seen by a rig of two sensors: "a", the camera with a Kinect v1 depth model, and
// "b", a 120 x 90 grey camera 50 mm to its right.
inline RunSpec SmallRigFarmJob() {
  RunSpec spec = SmallFarmJob();
  RigSensor a{"a", spec.intrinsics, {}};
  a.sensor.depth = DepthModel::Defaults(DepthModel::Kind::kKinectV1);
  RigSensor b{"b", Intrinsics{120, 90, 100.0, 100.0, 59.5, 44.5}, {}};
  b.sensor.image = SensorOptions::Image::kGray;
  b.rig_from_cam.translation() = Eigen::Vector3d(50, 0, 0);
  spec.rig = {a, b};
  spec.sensor = a.sensor;
  return spec;
}

// Runs `spec` into `out` (as shard `shard` of a farm run when given), as `cadsynth generate` does.
inline GenerateSummary RunJob(const RunSpec& spec, const std::filesystem::path& out,
                              std::optional<ShardSpec> shard = {}) {
  GenerateOptions options;
  options.output = out;
  options.shard = shard;
  return Generate(spec, options);
}

}  // namespace cadsynth::testing
