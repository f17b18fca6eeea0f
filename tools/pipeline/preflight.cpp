// Prepare's checks before any simulation or rendering (prepare_stages.h): scenes that cannot be
// made, refused at once with the recipe line that asks for them, instead of minutes of simulation
// and a dataset of parts on the floor.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "cad/core/error.h"
#include "cad/core/util.h"
#include "cad/hull.h"
#include "render/camera.h"
#include "tools/pipeline/prepare_stages.h"

namespace cadsynth::prepare_stages {

std::string Mm(double x) {
  std::ostringstream out;
  if (std::abs(x) < 10.0) {  // 0.8 mm is not "1 mm"
    out.precision(2);
    out << std::round(x * 100.0) / 100.0 + 0.0;  // (+ 0.0: no "-0")
  } else if (std::abs(x) < 1e12) {
    out << std::llround(x);
  } else {  // (llround overflows past 9e18)
    out.precision(3);
    out << x;
  }
  return out.str();
}

namespace {

std::string At(const std::string& where) { return where.empty() ? "" : where + ": "; }

// The smallest width of a convex hull over its facets' normals: the thinnest slot the part passes
// through. (The true minimum can lie between two edges instead, a little below this on a few
// shapes: the rule refuses only parts wider than the tote by 2 % more than this.)
double FacetWidth(const ConvexHull& hull) {
  double best = 1e300;
  for (const std::array<int, 3>& t : hull.triangles) {
    const Eigen::Vector3d& a = hull.vertices[t[0]];
    const Eigen::Vector3d n = (hull.vertices[t[1]] - a).cross(hull.vertices[t[2]] - a);
    if (n.norm() < 1e-12) continue;
    const Eigen::Vector3d u = n.normalized();
    double lo = 1e300, hi = -1e300;
    for (const Eigen::Vector3d& v : hull.vertices) {
      const double d = v.dot(u);
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
    best = std::min(best, hi - lo);
  }
  return best;
}

// The volume a part fills: its solid's, or its hull's when its mesh is not closed.
double FilledVolume(const Part& part) {
  if (part.watertight && part.mass.volume_mm3 > 0) return part.mass.volume_mm3;
  double six = 0;
  for (const std::array<int, 3>& t : part.hull->triangles)
    six +=
        part.hull->vertices[t[0]].dot(part.hull->vertices[t[1]].cross(part.hull->vertices[t[2]]));
  return std::abs(six) / 6.0;
}

// ", read with unit: inch (r.yaml:3:5): without it, 100 mm" for a part whose file's unit the
// recipe overrides: the likely cause of a part too large.
std::string UnitHint(const PartSource& source, double size_mm) {
  if (source.kind != PartSource::Kind::kFile || source.unit.empty()) return "";
  return "; its file is read with unit: " + source.unit + " (" + source.where +
         "): is that the file's unit? (" + Mm(size_mm) + " mm as read)";
}

// A pile's parts against its tote: each must fit between the walls and inside, and all of them
// together must fit at the densest random packing.
void CheckTote(const Context& context, const PrepareState& state, size_t s) {
  const SceneSpec& scene = context.spec.scenes[s];
  const Container& tote = scene.arrangement.container;
  const double length = std::max(tote.inner_mm.x(), tote.inner_mm.y());
  const double width = std::min(tote.inner_mm.x(), tote.inner_mm.y());
  const double diagonal =
      std::sqrt(length * length + width * width + tote.height_mm * tote.height_mm);
  std::ostringstream inner;
  inner << "inner " << Mm(tote.inner_mm.x()) << " x " << Mm(tote.inner_mm.y()) << " x "
        << Mm(tote.height_mm) << " mm";
  double volume = 0, thickest = 0;
  size_t copies = 0;
  for (size_t i = 0; i < state.all.instances.size(); ++i) {
    const Job& job = state.jobs[state.job_of_instance[i]];
    if (job.scene != static_cast<int>(s)) continue;
    const Part& part = state.all.parts[state.all.instances[i].part];
    if (!part.hull || part.hull->empty()) continue;  // flat: Arrange refuses it
    const double thinnest = FacetWidth(*part.hull);
    const double reach = part.hull->diameter;
    const std::string where =
        At(scene.container_where.empty() ? scene.where : scene.container_where);
    if (thinnest > 1.02 * width) {
      throw Error(where + "scene '" + scene.name + "': part '" + part.name + "' is " +
                  Mm(thinnest) + " mm across at its thinnest, wider than the tote's inside (" +
                  inner.str() + "): it cannot lie between the walls in any orientation" +
                  UnitHint(*job.source, reach));
    }
    if (reach > 1.02 * diagonal) {
      throw Error(where + "scene '" + scene.name + "': part '" + part.name + "' is " + Mm(reach) +
                  " mm long, longer than the tote's inner diagonal (" + Mm(diagonal) + " mm, " +
                  inner.str() + "): it cannot lie inside in any orientation" +
                  UnitHint(*job.source, reach));
    }
    thickest = std::max(thickest, thinnest);
    volume += FilledVolume(part) * scene.arrangement.copies;
    copies += static_cast<size_t>(scene.arrangement.copies);
  }
  // Equal spheres fill at most 64 % of a box when poured in (random close packing); bolts, nuts
  // and brackets fill far less. More solid than that up to the rim spills over whatever the seed.
  // (Up to the rim, or two layers of the thickest part where that is higher: a shallow tray holds
  // parts lying flat that stand above its rim.)
  constexpr double kRandomClosePacking = 0.64;
  const double room =
      tote.inner_mm.x() * tote.inner_mm.y() * std::max(tote.height_mm, 2.0 * thickest);
  if (volume > kRandomClosePacking * room) {
    std::ostringstream m;
    m << At(scene.copies_where.empty() ? scene.where : scene.copies_where) << "scene '"
      << scene.name << "': " << Count(copies, "part") << " of " << Mm(volume / 1000.0)
      << " cm3 of solid cannot fit a tote of " << Mm(room / 1000.0) << " cm3 (" << inner.str()
      << "): poured parts fill at most 64 % of a container up to its rim (random close packing of "
         "spheres; "
         "real parts less), here "
      << Mm(kRandomClosePacking * room / 1000.0) << " cm3: use fewer copies or a larger tote";
    throw Error(m.str());
  }
}

// No camera of the sweep may sit inside the tote's walls (below its rim, within its outer
// size): it would see the pile from inside a wall.
void CheckCamerasOutsideTote(const Context& context, const std::vector<SweepView>& views,
                             const std::vector<RigSensor>& sensors, size_t s) {
  const SceneSpec& scene = context.spec.scenes[s];
  const Container& tote = scene.arrangement.container;
  const Eigen::Vector2d half = 0.5 * tote.inner_mm + Eigen::Vector2d::Constant(tote.wall_mm);
  const Eigen::AlignedBox3d box(Eigen::Vector3d(-half.x(), -half.y(), 0.0),
                                Eigen::Vector3d(half.x(), half.y(), tote.RimZ()));
  for (size_t v = 0; v < views.size(); ++v) {
    for (const RigSensor& sensor : sensors) {
      const Eigen::Vector3d eye = (views[v].world_from_cam * sensor.rig_from_cam).translation();
      if (!box.contains(eye)) continue;
      std::ostringstream m;
      m << "sweep: view " << v << " of scene '" << scene.name << "' puts the camera"
        << (sensors.size() > 1 ? " '" + sensor.name + "'" : "") << " at (" << Mm(eye.x()) << ", "
        << Mm(eye.y()) << ", " << Mm(eye.z()) << ") mm, inside the tote (its walls reach "
        << Mm(half.x()) << " x " << Mm(half.y()) << " mm from the centre, its rim "
        << Mm(tote.RimZ()) << " mm high), " << Mm(views[v].radius_mm)
        << " mm from the target: give a sweep.radius that keeps the camera above the tote";
      throw Error(m.str());
    }
  }
}

// The views and sensors of the run (its sweep as sampled, its rig), for the camera checks.
void RunViews(const RunSpec& spec, std::vector<SweepView>* views, std::vector<RigSensor>* sensors) {
  std::string why;
  if (!views->empty() || !spec.sampler.Check(&why) || !spec.sweep.Check(&why)) return;
  *views = SampleViews(spec.sampler, spec.sweep);
  *sensors = RunSensors(spec);
}

}  // namespace

void CheckCamerasOutsideParts(const Context& context, const PrepareState& state,
                              const std::vector<Placement>& placements) {
  const RunSpec& spec = context.spec;
  std::vector<SweepView> views;
  std::vector<RigSensor> sensors;
  RunViews(spec, &views, &sensors);
  for (size_t s = 0; s < placements.size(); ++s) {
    const Arrangement& arranged = placements[s].arranged;
    if (!placements[s].error.empty() || placements[s].exception) continue;  // reported first
    for (size_t i = 0; i < arranged.instances.size(); ++i) {
      const Instance& instance = arranged.instances[i];
      const Part& part = state.all.parts[instance.part];
      const Eigen::AlignedBox3d box = part.mesh.Bounds();
      const Eigen::Isometry3d model_from_world = instance.world_from_model.inverse();
      for (size_t v = 0; v < views.size(); ++v) {
        for (const RigSensor& sensor : sensors) {
          const Eigen::Vector3d eye = (views[v].world_from_cam * sensor.rig_from_cam).translation();
          if (!box.contains(model_from_world * eye)) continue;
          const PartSource* source =
              arranged.group.empty() ? nullptr : state.jobs[arranged.group[i]].source;
          std::ostringstream m;
          m << "sweep: view " << v << " of scene '" << spec.scenes[s].name << "' puts the camera"
            << (sensors.size() > 1 ? " '" + sensor.name + "'" : "") << " inside part '" << part.name
            << "' (" << Mm(box.sizes().maxCoeff()) << " mm long), " << Mm(views[v].radius_mm)
            << " mm from the target: give a sweep.radius beyond the scene"
            << (source ? UnitHint(*source, box.sizes().maxCoeff()) : "");
          throw Error(m.str());
        }
      }
    }
  }
}

void CheckScenesCanBeMade(const Context& context, const PrepareState& state) {
  const RunSpec& spec = context.spec;
  std::vector<SweepView> views;
  std::vector<RigSensor> sensors;
  for (size_t s = 0; s < spec.scenes.size(); ++s) {
    const ArrangementOptions& a = spec.scenes[s].arrangement;
    if (a.layout != Layout::kPile || a.container.kind != Container::Kind::kTote) continue;
    CheckTote(context, state, s);
    RunViews(spec, &views, &sensors);
    CheckCamerasOutsideTote(context, views, sensors, s);
  }
}

}  // namespace cadsynth::prepare_stages
