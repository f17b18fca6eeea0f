#include "variants/gear_from_file.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <BRepAlgoAPI_Cut.hxx>
#include <BRepAlgoAPI_Fuse.hxx>
#include <BRepBuilderAPI_Transform.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <ShapeUpgrade_UnifySameDomain.hxx>
#include <gp_Ax2.hxx>

#include "cad/core/error.h"
#include "cad/occt_shape.h"
#include "variants/gear.h"
#include "variants/occt_boolean.h"

namespace cadsynth {

namespace {

// A cylinder of radius r about the gear frame's z axis from z0 to z1, in the CAD frame.
TopoDS_Shape Cylinder(const Eigen::Isometry3d& cad_from_gear, double r, double z0, double z1) {
  const Eigen::Vector3d o = cad_from_gear * Eigen::Vector3d(0, 0, z0);
  const Eigen::Vector3d z = cad_from_gear.linear().col(2), x = cad_from_gear.linear().col(0);
  return BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(o.x(), o.y(), o.z()), gp_Dir(z.x(), z.y(), z.z()),
                                         gp_Dir(x.x(), x.y(), x.z())),
                                  r, z1 - z0)
      .Shape();
}

std::string Mm(double v) {
  std::ostringstream out;
  out.precision(4);
  out << v << " mm";
  return out.str();
}

}  // namespace

Shape RebuildGear(const Part& part, const RecognizedGear& gear, const GearRebuild& change) {
  if (part.brep.IsNull()) {
    throw Error("'" + part.name + "' is a mesh: rebuilding its gear needs the B-rep (STEP, IGES " +
                "or BREP)");
  }
  if (gear.internal) throw Error("'" + part.name + "' is an internal gear: not rebuilt (yet)");
  if (gear.herringbone) {
    throw Error("'" + part.name + "' is a herringbone gear: recognised, not rebuilt (its two " +
                "opposite helices are not a spur_gear)");
  }
  if (change.teeth < 0 || change.module_mm < 0 || change.face_width_mm < 0)
    throw Error("teeth, module and face width must not be negative (0: as the file has it)");
  GearOptions o;
  o.teeth = change.teeth > 0 ? change.teeth : gear.teeth;
  // Measured to about 1e-4 of a module: kept to the micron.
  o.module_mm = change.module_mm > 0 ? change.module_mm : std::round(gear.module_mm * 1e3) / 1e3;
  o.face_width_mm = change.face_width_mm > 0 ? change.face_width_mm : gear.face_width_mm;
  const double deg = M_PI / 180;
  o.pressure_angle_rad = gear.pressure_angle_rad;
  for (const double standard : {14.5, 15.0, 17.5, 20.0, 22.5, 25.0, 30.0}) {
    if (std::abs(gear.pressure_angle_rad / (standard * deg) - 1) < 0.005)
      o.pressure_angle_rad = standard * deg;
  }
  o.profile_shift = std::abs(gear.profile_shift) < 0.01 ? 0.0 : gear.profile_shift;
  o.helix_angle_rad = gear.helix_angle_rad;
  std::string why;
  if (!o.Check(&why)) throw Error("the rebuilt gear: " + why);

  // The kept body: inside the smaller root circle, a quarter module in.
  const double r_cut =
      std::min(gear.root_radius_mm, o.RootRadius()) - 0.25 * std::min(gear.module_mm, o.module_mm);
  const double wall = 0.5 * o.module_mm;
  if (gear.bore_diameter_mm > 0 && r_cut < 0.5 * gear.bore_diameter_mm + wall) {
    throw Error("the rebuilt gear's root circle (" + Mm(o.RootRadius()) + ") leaves less than " +
                Mm(wall) + " of wall around the " + Mm(gear.bore_diameter_mm) + " bore");
  }
  if (!(r_cut > wall)) throw Error("the rebuilt gear is too small to keep the file's body");

  // The gear frame (model frame of the part, then CAD): z along the axis, x through tooth 0,
  // z = 0 where the new toothed band starts (centred on the file's).
  Eigen::Isometry3d model_from_gear = Eigen::Isometry3d::Identity();
  const Eigen::Vector3d z = gear.axis.normalized();
  const Eigen::Vector3d x = (gear.reference - gear.reference.dot(z) * z).normalized();
  model_from_gear.linear().col(0) = x;
  model_from_gear.linear().col(1) = z.cross(x);
  model_from_gear.linear().col(2) = z;
  model_from_gear.translation() = gear.centre + 0.5 * (gear.face_width_mm - o.face_width_mm) * z;
  const Eigen::Isometry3d cad_from_gear = part.cad_from_model * model_from_gear;
  // The part's extent along the axis (in the gear frame) and from it, with a margin.
  double lo = 0, hi = o.face_width_mm, reach = 0;
  for (const Eigen::Vector3f& p : part.mesh.positions) {
    const Eigen::Vector3d d = p.cast<double>() - model_from_gear.translation();
    const double h = d.dot(z);
    lo = std::min(lo, h), hi = std::max(hi, h);
    reach = std::max(reach, (d - h * z).norm());
  }
  lo -= 1, hi += 1;
  // The file's toothed band in the gear frame; where nothing of the part lies beyond an end
  // (outside r_cut), the cut reaches 1 mm past it, so that no sliver of an old tooth stays on
  // a plane the booleans would have to meet exactly. Next to a flange it stops at the band.
  double band_lo = 0.5 * (o.face_width_mm - gear.face_width_mm);
  double band_hi = band_lo + gear.face_width_mm;
  bool below = false, above = false;
  for (const Eigen::Vector3f& p : part.mesh.positions) {
    const Eigen::Vector3d d = p.cast<double>() - model_from_gear.translation();
    const double h = d.dot(z);
    if ((d - h * z).norm() <= r_cut) continue;
    below = below || h < band_lo - 1e-3;
    above = above || h > band_hi + 1e-3;
  }
  if (!below) band_lo -= 1;
  if (!above) band_hi += 1;

  try {
    const TopoDS_Shape& original = OcctShape(part.brep);
    // The old teeth: the ring outside r_cut along the old band. Everything else (the hub, the
    // web, a flange or a second gear beside the band) is kept.
    const TopoDS_Shape old_ring =
        RunBoolean(BRepAlgoAPI_Cut(Cylinder(cad_from_gear, reach + 1, band_lo, band_hi),
                                   Cylinder(cad_from_gear, r_cut, band_lo - 1, band_hi + 1)),
                   "outline the old teeth");
    const TopoDS_Shape kept =
        RunBoolean(BRepAlgoAPI_Cut(original, old_ring), "cut the old teeth off");
    const TopoDS_Shape inner = Cylinder(cad_from_gear, r_cut, lo, hi);
    const TopoDS_Shape teeth =
        BRepBuilderAPI_Transform(OcctShape(MakeGear(o)), ToTrsf(cad_from_gear), /*copy=*/true)
            .Shape();
    const TopoDS_Shape ring = RunBoolean(BRepAlgoAPI_Cut(teeth, inner), "cut the new teeth's ring");
    TopoDS_Shape fused = RunBoolean(BRepAlgoAPI_Fuse(kept, ring), "join the teeth to the body");
    ShapeUpgrade_UnifySameDomain unify(fused, /*UnifyEdges=*/true, /*UnifyFaces=*/true,
                                       /*ConcatBSplines=*/false);
    unify.Build();
    return WrapShape(unify.Shape());
  } catch (const Standard_Failure& e) {
    throw Error(std::string("OpenCASCADE failed rebuilding the gear: ") + e.GetMessageString());
  }
}

}  // namespace cadsynth
