// Prepare as the list of its stages (tools/pipeline/prepare_stages.h): the part stages
// (prepare_parts.cpp), then the scene stages (prepare_scenes.cpp).
#include "tools/pipeline/prepare.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "cad/core/error.h"
#include "tools/pipeline/prepare_stages.h"

namespace cadsynth {
using prepare_stages::Mm;

std::vector<std::string> PlacementWarnings(const std::vector<Part>& parts,
                                           const std::vector<Instance>& instances,
                                           const Intrinsics& k, const SweepOptions& sweep) {
  std::vector<std::string> warnings;
  if (instances.empty() || sweep.radius_mm.empty()) return warnings;
  const double nearest = *std::min_element(sweep.radius_mm.begin(), sweep.radius_mm.end());
  const double farthest = *std::max_element(sweep.radius_mm.begin(), sweep.radius_mm.end());
  // The camera always looks at the target: the scene must fit in the cone of the narrower half
  // field of view at the nearest radius.
  const double half_fov = std::min(std::atan2(std::min(k.cx, k.width - k.cx), k.fx),
                                   std::atan2(std::min(k.cy, k.height - k.cy), k.fy));
  double reach = 0;
  for (const Instance& i : instances) {
    for (const Eigen::Vector3f& p : parts[i.part].mesh.positions) {
      reach = std::max(reach, (i.world_from_model * p.cast<double>() - sweep.target).norm());
    }
  }
  std::ostringstream out;
  out.precision(4);
  if (reach >= nearest) {
    out << "the scene reaches " << Mm(reach)
        << " mm from the target, beyond the nearest camera radius " << Mm(nearest)
        << " mm: " << kCameraInsideScene;
    warnings.push_back(out.str());
  } else if (std::asin(reach / nearest) > half_fov) {
    out << "the scene reaches " << Mm(reach) << " mm from the target; at the nearest radius "
        << Mm(nearest) << " mm the camera sees only " << Mm(nearest * std::sin(half_fov))
        << " mm around it: objects will be cut off";
    warnings.push_back(out.str());
  }
  // The smallest object at the farthest radius.
  double smallest = 1e300;
  std::string name;
  for (const Instance& i : instances) {
    const double d = parts[i.part].mesh.Bounds().sizes().maxCoeff();
    if (d < smallest) smallest = d, name = parts[i.part].name;
  }
  const double pixels = k.fx * smallest / farthest;
  if (pixels < 10.0) {
    std::ostringstream small;
    small.precision(3);
    small << "'" << name << "' (" << smallest << " mm) spans only " << pixels
          << " px at the farthest radius " << Mm(farthest) << " mm";
    warnings.push_back(small.str());
  }
  return warnings;
}

PreparedRun Prepare(const RunSpec& spec, const std::function<void(const std::string&)>& info_sink,
                    const PartCache* cache, const ReaderProcess* reader,
                    const PrepareControls& controls) {
  using namespace prepare_stages;
  if (spec.scenes.empty()) throw Error("no scenes to render");
  const auto info = [&](const std::string& line) {
    if (info_sink) info_sink(line);
  };
  const Context context{
      spec, info, cache, reader, controls.strict, controls.progress, controls.progress_interval_s};
  // The parts: read and built, gathered into one list, measured, merged, named and classed.
  PrepareState state;
  state.jobs = BuildParts(context);
  state.container_mesh = BuildContainers(context);
  state.distractor_candidates = BuildDistractorObjects(context);
  const std::vector<SymmetryCheck> symmetry_checks = GatherParts(context, &state);
  FindSymmetries(context, symmetry_checks, &state.all.parts);
  ReportFamilies(context);
  MergeRepeatedShapes(context, &state);
  RenameRepeatedNames(&state.all.parts);
  ComputeHulls(context, &state.all.parts);
  state.classes = AssignPartClasses(context, state);
  // The scenes: checked, arranged in parallel, then recorded in scene order.
  CheckScenesCanBeMade(context, state);
  state.pile_shapes = MakePileShapes(context, state);
  std::vector<Placement> placements = ArrangeScenes(context, state);
  CheckCamerasOutsideParts(context, state, placements);
  PreparedRun prepared = RecordScenes(context, state, &placements);
  prepared.variants_json = VariantsRecord(spec, state);
  prepared.parts = std::move(state.all.parts);
  prepared.classes = std::move(state.classes);
  return prepared;
}

}  // namespace cadsynth
