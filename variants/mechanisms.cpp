#include "variants/mechanisms.h"

#include <cmath>
#include <sstream>

#include <tbb/parallel_for.h>
#include <BRepAlgoAPI_Fuse.hxx>
#include <BRepBuilderAPI_MakeEdge.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakeWire.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakePrism.hxx>
#include <GC_MakeArcOfCircle.hxx>
#include <GC_MakeSegment.hxx>
#include <Standard_Failure.hxx>
#include <gp_Ax2.hxx>
#include <gp_Circ.hxx>

#include "cad/core/error.h"
#include "cad/occt_shape.h"
#include "variants/occt_boolean.h"

namespace cadsynth {
namespace {

Eigen::Isometry3d Pose(double x, double y, double z, double turn) {
  return Eigen::Translation3d(x, y, z) * Eigen::AngleAxisd(turn, Eigen::Vector3d::UnitZ());
}

// Turn of a gear placed in direction `phi` from another gear (`other_teeth`, turned by
// `other_turn`) so that the two mesh externally. Along the line of centres each gear's tooth
// phase is u = z (local angle of the line) / 2 pi, whole for a tooth centred on the line. Turning
// one gear moves the two phases in opposite senses, so their sum stays fixed, and a tooth must
// face a space: u_other + u_this = 1/2 (mod 1).
double MeshTurn(double phi, int other_teeth, double other_turn, int teeth) {
  const double u_other = (phi - other_turn) * other_teeth / (2 * M_PI);
  return phi + M_PI - (2 * M_PI / teeth) * (0.5 - u_other);
}

TopoDS_Shape Cylinder(double radius, double x, double y, double z0, double z1) {
  return BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(x, y, z0), gp_Dir(0, 0, 1)), radius, z1 - z0)
      .Shape();
}

TopoDS_Wire Circle(double x, double y, double radius) {
  return BRepBuilderAPI_MakeWire(
             BRepBuilderAPI_MakeEdge(gp_Circ(gp_Ax2(gp_Pnt(x, y, 0), gp_Dir(0, 0, 1)), radius)))
      .Wire();
}

// A flat link: a bar of `width` with round ends centred at (0, 0) and (length, 0), a hole of
// `hole` diameter at each end, `thickness` thick from z = 0.
TopoDS_Shape Link(double length, double width, double thickness, double hole) {
  const double r = 0.5 * width;
  BRepBuilderAPI_MakeWire outline;
  outline.Add(
      BRepBuilderAPI_MakeEdge(GC_MakeSegment(gp_Pnt(0, -r, 0), gp_Pnt(length, -r, 0)).Value()));
  outline.Add(BRepBuilderAPI_MakeEdge(
      GC_MakeArcOfCircle(gp_Pnt(length, -r, 0), gp_Pnt(length + r, 0, 0), gp_Pnt(length, r, 0))
          .Value()));
  outline.Add(
      BRepBuilderAPI_MakeEdge(GC_MakeSegment(gp_Pnt(length, r, 0), gp_Pnt(0, r, 0)).Value()));
  outline.Add(BRepBuilderAPI_MakeEdge(
      GC_MakeArcOfCircle(gp_Pnt(0, r, 0), gp_Pnt(-r, 0, 0), gp_Pnt(0, -r, 0)).Value()));
  BRepBuilderAPI_MakeFace face(outline.Wire(), true);
  for (double x : {0.0, length}) {
    TopoDS_Wire h = Circle(x, 0, 0.5 * hole);
    h.Reverse();
    face.Add(h);
  }
  return BRepPrimAPI_MakePrism(face.Face(), gp_Vec(0, 0, thickness)).Shape();
}

template <typename Build>
ShapeAssembly Guarded(const char* what, Build&& build) {
  try {
    return build();
  } catch (const Standard_Failure& failure) {
    throw Error(std::string(what) + ": OpenCASCADE failed: " + failure.GetMessageString());
  }
}

}  // namespace

Assembly TessellateAssembly(const ShapeAssembly& shapes, const TessellationOptions& options) {
  Assembly assembly;
  assembly.name = shapes.name;
  assembly.format = "parametric";
  assembly.length_unit = "mm";
  assembly.parts.resize(shapes.components.size());
  tbb::parallel_for(size_t{0}, shapes.components.size(), [&](size_t i) {
    assembly.parts[i] = MakePart(shapes.components[i].name, shapes.components[i].shape, options);
    assembly.parts[i].symmetries =
        shapes.components[i].symmetries.InFrame(assembly.parts[i].cad_from_model);
  });
  for (const ShapeAssembly::Placement& p : shapes.placements) {
    assembly.instances.push_back({p.component, p.name,
                                  p.pose * assembly.parts[p.component].cad_from_model, std::nullopt,
                                  shapes.name + "/" + p.name});
  }
  return assembly;
}

bool GearPairOptions::Check(std::string* why) const {
  if (!first.Check(why)) return *why = "first gear: " + *why, false;
  if (!second.Check(why)) return *why = "second gear: " + *why, false;
  std::ostringstream out;
  if (first.internal || second.internal) {
    out << "a gear pair is two external gears (use the planetary set for a ring)";
  } else if (std::abs(first.module_mm - second.module_mm) > 1e-9) {
    out << "modules differ (" << first.module_mm << " and " << second.module_mm
        << " mm): the gears cannot mesh";
  } else if (std::abs(first.pressure_angle_rad - second.pressure_angle_rad) > 1e-9) {
    out << "pressure angles differ: the gears cannot mesh";
  } else if (std::abs(first.helix_angle_rad + second.helix_angle_rad) > 1e-9) {
    out << "external helical gears need opposite helix angles (got "
        << first.helix_angle_rad * 180 / M_PI << " and " << second.helix_angle_rad * 180 / M_PI
        << " degrees)";
  } else {
    return true;
  }
  *why = out.str();
  return false;
}

double GearPairOptions::CentreDistance() const {
  // Working pressure angle from the profile shifts: inv(a_w) = 2 tan(a) (x1 + x2) / (z1 + z2) +
  // inv(a).
  const double at = first.TransversePressureAngle();
  const double target = 2 * std::tan(first.pressure_angle_rad) *
                            (first.profile_shift + second.profile_shift) /
                            (first.teeth + second.teeth) +
                        Involute(at);
  double aw = at;
  for (int i = 0; i < 50; ++i) {
    const double f = Involute(aw) - target, df = std::tan(aw) * std::tan(aw);
    if (df == 0) break;
    aw -= f / df;
  }
  return (first.PitchRadius() + second.PitchRadius()) * std::cos(at) / std::cos(aw);
}

ShapeAssembly MakeGearPair(const GearPairOptions& o) {
  std::string why;
  if (!o.Check(&why)) throw Error("gear pair: " + why);
  return Guarded("gear pair", [&] {
    ShapeAssembly a;
    a.name = "gear_pair";
    a.components = {
        {"gear_z" + std::to_string(o.first.teeth), MakeGear(o.first), GearSymmetries(o.first)},
        {"gear_z" + std::to_string(o.second.teeth), MakeGear(o.second), GearSymmetries(o.second)}};
    a.placements = {
        {0, "gear_1", Pose(0, 0, 0, 0)},
        {1, "gear_2",
         Pose(o.CentreDistance(), 0, 0, MeshTurn(0.0, o.first.teeth, 0.0, o.second.teeth))}};
    return a;
  });
}

bool PlanetaryOptions::Check(std::string* why) const {
  std::ostringstream out;
  const double pitch_gap = 2 * CentreDistance() * std::sin(M_PI / std::max(planets, 1));
  const double planet_tip = module_mm * (planet_teeth + 2);
  if (planets < 1) {
    out << "a planetary set needs at least one planet";
  } else if ((sun_teeth + RingTeeth()) % planets != 0) {
    out << "planets cannot be spaced evenly: (z_sun + z_ring) / planets = (" << sun_teeth << " + "
        << RingTeeth() << ") / " << planets << " is not a whole number";
  } else if (planets > 1 && pitch_gap <= planet_tip + 0.5 * module_mm) {
    out << planets << " planets of " << planet_teeth << " teeth collide: their centres are "
        << pitch_gap << " mm apart, their tips " << planet_tip << " mm across";
  } else if (!(pin_diameter_mm > 0) || pin_diameter_mm + 0.2 >= module_mm * (planet_teeth - 2.5)) {
    out << "pin diameter " << pin_diameter_mm
        << " mm must be positive and fit inside the planets' root circle";
  } else if (!(carrier_thickness_mm > 0)) {
    out << "carrier thickness must be positive";
  } else {
    GearOptions g;
    g.module_mm = module_mm;
    g.face_width_mm = face_width_mm;
    g.backlash_mm = backlash_mm;
    for (int teeth : {sun_teeth, planet_teeth, RingTeeth()}) {
      g.teeth = teeth;
      g.internal = teeth == RingTeeth();
      g.bore_diameter_mm = teeth == sun_teeth && !g.internal ? sun_bore_mm : 0.0;
      if (!g.Check(why))
        return *why = "gear of " + std::to_string(teeth) + " teeth: " + *why, false;
    }
    return true;
  }
  *why = out.str();
  return false;
}

ShapeAssembly MakePlanetary(const PlanetaryOptions& o) {
  std::string why;
  if (!o.Check(&why)) throw Error("planetary gearbox: " + why);
  return Guarded("planetary gearbox", [&] {
    GearOptions sun, planet, ring;
    for (GearOptions* g : {&sun, &planet, &ring}) {
      g->module_mm = o.module_mm;
      g->face_width_mm = o.face_width_mm;
      g->backlash_mm = o.backlash_mm;
    }
    sun.teeth = o.sun_teeth;
    sun.bore_diameter_mm = o.sun_bore_mm;
    planet.teeth = o.planet_teeth;
    planet.bore_diameter_mm = o.pin_diameter_mm + 0.2;
    ring.teeth = o.RingTeeth();
    ring.internal = true;

    const double a = o.CentreDistance();
    const double gap = 0.5;  // between carrier and gears
    const double carrier_radius = a + 0.5 * o.pin_diameter_mm + 3.0;
    TopoDS_Shape carrier = Cylinder(carrier_radius, 0, 0, -gap - o.carrier_thickness_mm, -gap);
    std::vector<double> planet_turn(o.planets);
    for (int i = 0; i < o.planets; ++i) {
      const double phi = 2 * M_PI * i / o.planets;
      planet_turn[i] = MeshTurn(phi, o.sun_teeth, 0.0, o.planet_teeth);
      carrier =
          RunBoolean(BRepAlgoAPI_Fuse(carrier, Cylinder(0.5 * o.pin_diameter_mm, a * std::cos(phi),
                                                        a * std::sin(phi), -gap, o.face_width_mm)),
                     "add a carrier pin");
    }
    // Ring phased from planet 0 (along +x). In an internal mesh both gears turn the same way, so
    // the difference of the phases (the planet's pointing outward, the ring's) stays fixed, at
    // half a pitch. The assembly condition makes the other planets agree.
    const double u_planet = (0.0 - planet_turn[0]) * o.planet_teeth / (2 * M_PI);
    const double ring_turn = 0.0 - (2 * M_PI / o.RingTeeth()) * (u_planet + 0.5);

    ShapeAssembly s;
    s.name = "planetary_gearbox";
    s.components = {
        {"sun_z" + std::to_string(o.sun_teeth), MakeGear(sun), GearSymmetries(sun)},
        {"planet_z" + std::to_string(o.planet_teeth), MakeGear(planet), GearSymmetries(planet)},
        {"ring_z" + std::to_string(o.RingTeeth()), MakeGear(ring), GearSymmetries(ring)},
        {"carrier", WrapShape(carrier), Symmetries::Cyclic(o.planets, false)}};
    s.placements.push_back({0, "sun", Pose(0, 0, 0, 0)});
    for (int i = 0; i < o.planets; ++i) {
      const double phi = 2 * M_PI * i / o.planets;
      s.placements.push_back({1, "planet_" + std::to_string(i + 1),
                              Pose(a * std::cos(phi), a * std::sin(phi), 0, planet_turn[i])});
    }
    s.placements.push_back({2, "ring", Pose(0, 0, 0, ring_turn)});
    s.placements.push_back({3, "carrier", Pose(0, 0, 0, 0)});
    return s;
  });
}

bool SliderCrankOptions::Check(std::string* why) const {
  std::ostringstream out;
  if (!(crank_mm > 0) || !(rod_mm > 0)) {
    out << "crank and rod lengths must be positive";
  } else if (rod_mm <= crank_mm + 0.5 * link_width_mm) {
    out << "the connecting rod (" << rod_mm << " mm) must be longer than the crank (" << crank_mm
        << " mm) plus half a link width, or the slider cannot follow";
  } else if (!(link_width_mm > pin_diameter_mm + 2) || !(pin_diameter_mm > 0)) {
    out << "links must be wider than their pin holes plus 2 mm";
  } else if (rod_mm - crank_mm - 0.5 * slider_mm <= crank_mm + 0.5 * link_width_mm) {
    out << "the crank would hit the slider: rod (" << rod_mm
        << " mm) minus crank minus half the slider must "
        << "exceed the crank plus half a link width (" << crank_mm + 0.5 * link_width_mm << " mm)";
  } else if (!(link_thickness_mm > 0) || !(slider_mm > link_width_mm)) {
    out << "link thickness must be positive and the slider longer than a link is wide";
  } else if (!std::isfinite(crank_angle_rad)) {
    out << "crank angle must be finite";
  } else {
    return true;
  }
  *why = out.str();
  return false;
}

double SliderCrankOptions::SliderX() const {
  const double s = crank_mm * std::sin(crank_angle_rad);
  return crank_mm * std::cos(crank_angle_rad) + std::sqrt(rod_mm * rod_mm - s * s);
}

ShapeAssembly MakeSliderCrank(const SliderCrankOptions& o) {
  std::string why;
  if (!o.Check(&why)) throw Error("slider-crank: " + why);
  return Guarded("slider-crank", [&] {
    const double t = o.link_thickness_mm, w = o.link_width_mm;
    // Layers: crank and slider on the base (0..t), the rod above them (t..2t).
    const double base_t = 5.0, slider_w = w + 8.0, slider_h = t;
    const double x_min = -o.crank_mm - w, x_max = o.crank_mm + o.rod_mm + o.slider_mm;
    const double y_half = o.crank_mm + w;
    const TopoDS_Shape base =
        BRepPrimAPI_MakeBox(gp_Pnt(x_min, -y_half, -base_t), gp_Pnt(x_max, y_half, 0)).Shape();
    const TopoDS_Shape slider =
        BRepPrimAPI_MakeBox(gp_Pnt(-0.5 * o.slider_mm, -0.5 * slider_w, 0),
                            gp_Pnt(0.5 * o.slider_mm, 0.5 * slider_w, slider_h))
            .Shape();
    const double theta = o.crank_angle_rad;
    const Eigen::Vector2d pin(o.crank_mm * std::cos(theta), o.crank_mm * std::sin(theta));
    const double xs = o.SliderX();
    const double rod_turn = std::atan2(-pin.y(), xs - pin.x());
    ShapeAssembly s;
    s.name = "slider_crank";
    // A link is symmetric under the half-turn about its mid-line and under the half-turn about
    // z through its middle (and the two combined).
    const auto link_symmetries = [&](double length) {
      Symmetries sym;
      const Eigen::Isometry3d to_mid{Eigen::Translation3d(0.5 * length, 0, 0.5 * t)};
      for (const Eigen::Vector3d axis :
           {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ()}) {
        sym.discrete.push_back(to_mid * Eigen::AngleAxisd(M_PI, axis) * to_mid.inverse());
      }
      return sym;
    };
    s.components = {{"base", WrapShape(base), {}},
                    {"crank", WrapShape(Link(o.crank_mm, w, t, o.pin_diameter_mm)),
                     link_symmetries(o.crank_mm)},
                    {"connecting_rod", WrapShape(Link(o.rod_mm, w, t, o.pin_diameter_mm)),
                     link_symmetries(o.rod_mm)},
                    {"slider", WrapShape(slider), {}}};
    s.placements = {{0, "base", Pose(0, 0, 0, 0)},
                    {1, "crank", Pose(0, 0, 0.0, theta)},
                    {2, "connecting_rod", Pose(pin.x(), pin.y(), t, rod_turn)},
                    {3, "slider", Pose(xs, 0, 0.0, 0)}};
    return s;
  });
}

}  // namespace cadsynth
