#include "variants/gear.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <BRepAlgoAPI_Cut.hxx>
#include <BRepAlgoAPI_Fuse.hxx>
#include <BRepBuilderAPI_MakeEdge.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakeWire.hxx>
#include <BRepBuilderAPI_Transform.hxx>
#include <BRepOffsetAPI_ThruSections.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakePrism.hxx>
#include <GC_MakeArcOfCircle.hxx>
#include <GC_MakeSegment.hxx>
#include <GeomAPI_Interpolate.hxx>
#include <Geom_BSplineCurve.hxx>
#include <Standard_Failure.hxx>
#include <TColgp_HArray1OfPnt.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Wire.hxx>
#include <gp_Ax1.hxx>
#include <gp_Ax2.hxx>
#include <gp_Circ.hxx>
#include <gp_Trsf.hxx>
#include <gp_Vec.hxx>

#include "cad/core/error.h"
#include "cad/occt_shape.h"
#include "variants/occt_boolean.h"

namespace cadsynth {
namespace {

// The transverse tooth of an external gear (or of an internal gear's cutter), tooth 0 centred on
// +x. Angles are polar angles of the upper (y > 0) side; the lower side is its mirror image.
struct Tooth {
  int z = 0;
  double r = 0, rb = 0, ra = 0, rf = 0;
  double psi = 0;       // half the tooth angle at the pitch circle
  double theta_p = 0;   // inv(transverse pressure angle)
  double rho = 0;       // fillet radius (0: corner)
  double start = 0;     // radius where the involute starts: max(rb, rf)
  double line_end = 0;  // radius where the fillet meets the radial line below the base circle
  double gamma_c = 0;   // polar angle where the fillet meets the root circle

  double Angle(double radius) const {  // upper flank at radius >= rb
    return psi + theta_p - Involute(std::acos(std::min(1.0, rb / radius)));
  }
  double RadialAngle() const { return psi + theta_p; }  // the flank below the base circle
  bool HasRadialPart() const { return rb > rf; }
  // A straight piece of flank between the fillet (or the root) and the base circle.
  bool HasRadialSegment() const { return HasRadialPart() && rb - line_end > 1e-7 * r; }
  double HalfPitch() const { return M_PI / z; }
};

// Tooth of the external gear, or of the cutter of an internal gear (its teeth are the ring's
// spaces: addendum and dedendum swapped, thickness the ring's space width).
Tooth MakeTooth(const GearOptions& o) {
  Tooth t;
  t.z = o.teeth;
  const double mt = o.TransverseModule(), at = o.TransversePressureAngle(), m = o.module_mm;
  t.r = 0.5 * mt * o.teeth;
  t.rb = t.r * std::cos(at);
  double thickness;
  if (!o.internal) {
    t.ra = t.r + m * (1.0 + o.profile_shift);
    t.rf = t.r - m * (1.25 - o.profile_shift);
    thickness = mt * (M_PI / 2 + 2 * o.profile_shift * std::tan(at)) - o.backlash_mm;
  } else {
    t.ra = t.r + m * (1.25 + o.profile_shift);  // the ring's root
    t.rf = t.r - m * (1.0 - o.profile_shift);   // the ring's tip
    thickness = mt * (M_PI / 2 + 2 * o.profile_shift * std::tan(at)) + o.backlash_mm;
  }
  t.psi = thickness / (2 * t.r);
  t.theta_p = Involute(at);
  t.start = std::max(t.rb, t.rf);
  t.line_end = t.rf;  // without a fillet the radial flank runs down to the root circle
  t.gamma_c = t.HasRadialPart() ? t.RadialAngle() : t.Angle(t.rf);
  if (!o.internal && t.HasRadialPart() && o.root_fillet > 0) {
    // Circle of radius rho tangent to the root circle and to the radial line at RadialAngle():
    // centre at radius rf + rho, angle RadialAngle() + asin(rho / (rf + rho)). It must meet the
    // line above the root and below the base circle, and stay within half the tooth space.
    const auto fits = [&](double rho) {
      const double rc = t.rf + rho, delta = std::asin(rho / rc);
      return rc * std::cos(delta) <= t.rb && t.RadialAngle() + delta <= t.HalfPitch();
    };
    double rho = o.root_fillet * m;
    if (!fits(rho)) {
      double lo = 0, hi = rho;
      for (int i = 0; i < 60; ++i) (fits(0.5 * (lo + hi)) ? lo : hi) = 0.5 * (lo + hi);
      rho = lo;
    }
    if (rho > 1e-6 * m) {
      const double rc = t.rf + rho, delta = std::asin(rho / rc);
      t.rho = rho;
      t.line_end = rc * std::cos(delta);
      t.gamma_c = t.RadialAngle() + delta;
    }
  }
  return t;
}

Eigen::Vector2d Polar(double radius, double angle) {
  return {radius * std::cos(angle), radius * std::sin(angle)};
}

// Points of the upper involute flank from the start radius to the tip, uniform in roll angle.
std::vector<Eigen::Vector2d> FlankPoints(const Tooth& t, int count) {
  const double t0 = std::sqrt(std::max(0.0, (t.start / t.rb) * (t.start / t.rb) - 1));
  const double ta = std::sqrt((t.ra / t.rb) * (t.ra / t.rb) - 1);
  std::vector<Eigen::Vector2d> points;
  for (int i = 0; i < count; ++i) {
    const double roll = t0 + (ta - t0) * i / (count - 1);
    const double radius = t.rb * std::sqrt(1 + roll * roll);
    points.push_back(Polar(radius, t.Angle(radius)));
  }
  return points;
}

// The fillet's centre and its two ends (on the root circle and on the radial line).
struct Fillet {
  Eigen::Vector2d centre, on_root, on_line;
};
Fillet UpperFillet(const Tooth& t) {
  const double rc = t.rf + t.rho;
  return {Polar(rc, t.gamma_c), Polar(t.rf, t.gamma_c), Polar(t.line_end, t.RadialAngle())};
}

Eigen::Vector2d Mirror(const Eigen::Vector2d& p) { return {p.x(), -p.y()}; }

std::vector<Eigen::Vector2d> ArcPoints(const Eigen::Vector2d& centre, double radius, double from,
                                       double to, int count) {
  std::vector<Eigen::Vector2d> points;
  for (int i = 0; i < count; ++i)
    points.push_back(centre + Polar(radius, from + (to - from) * i / (count - 1)));
  return points;
}

// Outline of tooth 0 and the space after it, counter-clockwise, from the lower root point to the
// next tooth's lower root point (exclusive).
std::vector<Eigen::Vector2d> ToothOutline(const Tooth& t, int n) {
  std::vector<Eigen::Vector2d> out;
  const auto append = [&](const std::vector<Eigen::Vector2d>& points, bool reverse) {
    if (reverse) {
      out.insert(out.end(), points.rbegin(), points.rend() - 1);
    } else {
      out.insert(out.end(), points.begin(), points.end() - 1);
    }
  };
  std::vector<Eigen::Vector2d> flank = FlankPoints(t, n);
  std::vector<Eigen::Vector2d> lower_flank;
  for (const auto& p : flank) lower_flank.push_back(Mirror(p));
  std::vector<Eigen::Vector2d> fillet_upper;
  if (t.rho > 0) {
    const Fillet f = UpperFillet(t);
    const double a1 = std::atan2(f.on_line.y() - f.centre.y(), f.on_line.x() - f.centre.x());
    double a0 = std::atan2(f.on_root.y() - f.centre.y(), f.on_root.x() - f.centre.x());
    while (a0 < a1)
      a0 += 2 * M_PI;  // from the line (a1) round to the root point (a0), the short way
    if (a0 - a1 > M_PI) a0 -= 2 * M_PI;
    fillet_upper = ArcPoints(f.centre, t.rho, a1, a0, n);  // line -> root
  }
  // Lower side, root to tip: fillet (root -> line), radial line, involute.
  if (t.rho > 0) {
    std::vector<Eigen::Vector2d> lower;
    for (auto it = fillet_upper.rbegin(); it != fillet_upper.rend(); ++it)
      lower.push_back(Mirror(*it));
    append(lower, false);
  }
  if (t.HasRadialSegment()) out.push_back(Mirror(Polar(t.line_end, t.RadialAngle())));
  append(lower_flank, false);
  // Tip.
  const double gamma_a = t.Angle(t.ra);
  append(ArcPoints({0, 0}, t.ra, -gamma_a, gamma_a, n), false);
  // Upper side, tip to root.
  append(flank, true);
  if (t.HasRadialSegment()) out.push_back(Polar(t.line_end, t.RadialAngle()));
  if (t.rho > 0) append(fillet_upper, false);
  // Root arc to the next tooth.
  append(ArcPoints({0, 0}, t.rf, t.gamma_c, 2 * M_PI / t.z - t.gamma_c, n), false);
  return out;
}

gp_Pnt P3(const Eigen::Vector2d& p, double z = 0) { return gp_Pnt(p.x(), p.y(), z); }

TopoDS_Edge Segment(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return BRepBuilderAPI_MakeEdge(GC_MakeSegment(P3(a), P3(b)).Value());
}

TopoDS_Edge Arc(const Eigen::Vector2d& a, const Eigen::Vector2d& mid, const Eigen::Vector2d& b) {
  return BRepBuilderAPI_MakeEdge(GC_MakeArcOfCircle(P3(a), P3(mid), P3(b)).Value());
}

Handle(Geom_BSplineCurve) FlankCurve(const Tooth& t, bool lower) {
  const std::vector<Eigen::Vector2d> points = FlankPoints(t, 25);
  Handle(TColgp_HArray1OfPnt) array = new TColgp_HArray1OfPnt(1, static_cast<int>(points.size()));
  for (size_t i = 0; i < points.size(); ++i) {
    array->SetValue(static_cast<int>(i) + 1, P3(lower ? Mirror(points[i]) : points[i]));
  }
  GeomAPI_Interpolate interpolate(array, /*periodic=*/false, 1e-9);
  interpolate.Perform();
  if (!interpolate.IsDone()) throw Error("gear: could not fit the involute flank");
  return interpolate.Curve();
}

// Edges of tooth 0 and the space after it, in the same order as ToothOutline.
std::vector<TopoDS_Edge> ToothEdges(const Tooth& t) {
  std::vector<TopoDS_Edge> edges;
  const double gamma_a = t.Angle(t.ra);
  Fillet f;
  if (t.rho > 0) f = UpperFillet(t);
  const auto fillet_mid = [&](const Fillet& fl) {
    const Eigen::Vector2d d =
        (fl.on_root - fl.centre).normalized() + (fl.on_line - fl.centre).normalized();
    return Eigen::Vector2d(fl.centre + t.rho * d.normalized());
  };
  const Eigen::Vector2d base_upper = Polar(t.start, t.Angle(t.start));
  if (t.rho > 0) {
    const Fillet lower{Mirror(f.centre), Mirror(f.on_root), Mirror(f.on_line)};
    edges.push_back(Arc(lower.on_root, fillet_mid(lower), lower.on_line));
  }
  if (t.HasRadialSegment())
    edges.push_back(Segment(Mirror(Polar(t.line_end, t.RadialAngle())), Mirror(base_upper)));
  edges.push_back(BRepBuilderAPI_MakeEdge(FlankCurve(t, true)));
  edges.push_back(Arc(Polar(t.ra, -gamma_a), Polar(t.ra, 0), Polar(t.ra, gamma_a)));
  Handle(Geom_BSplineCurve) upper = FlankCurve(t, false);
  upper->Reverse();
  edges.push_back(BRepBuilderAPI_MakeEdge(upper));
  if (t.HasRadialSegment())
    edges.push_back(Segment(base_upper, Polar(t.line_end, t.RadialAngle())));
  if (t.rho > 0) edges.push_back(Arc(f.on_line, fillet_mid(f), f.on_root));
  const double end = 2 * M_PI / t.z - t.gamma_c;
  if (end - t.gamma_c > 1e-9) {
    edges.push_back(Arc(Polar(t.rf, t.gamma_c), Polar(t.rf, M_PI / t.z), Polar(t.rf, end)));
  }
  return edges;
}

// The closed transverse outline, turned by `angle` about z and lifted to height z.
TopoDS_Wire OutlineWire(const Tooth& t, double angle, double z) {
  const std::vector<TopoDS_Edge> tooth = ToothEdges(t);
  BRepBuilderAPI_MakeWire wire;
  for (int k = 0; k < t.z; ++k) {
    gp_Trsf turn;
    turn.SetRotation(gp_Ax1(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), angle + 2 * M_PI * k / t.z);
    gp_Trsf lift;
    lift.SetTranslation(gp_Vec(0, 0, z));
    for (const TopoDS_Edge& edge : tooth) {
      wire.Add(TopoDS::Edge(BRepBuilderAPI_Transform(edge, lift * turn, /*copy=*/true).Shape()));
      if (!wire.IsDone())
        throw Error("gear: the tooth outline does not close (edge " + std::to_string(k) + ")");
    }
  }
  if (!wire.Wire().Closed()) throw Error("gear: the tooth outline does not close");
  return wire.Wire();
}

// The toothed body between z0 and z1 (a prism, or for helical gears a loft through twisted
// sections; the twist at height z is z tan(helix) / r, right hand positive).
TopoDS_Shape ToothedBody(const Tooth& t, double helix, double turn, double z0, double z1) {
  if (helix == 0.0) {
    const TopoDS_Face face = BRepBuilderAPI_MakeFace(OutlineWire(t, turn, z0), /*onlyPlane=*/true);
    return BRepPrimAPI_MakePrism(face, gp_Vec(0, 0, z1 - z0)).Shape();
  }
  const double twist_per_mm = std::tan(helix) / t.r;
  const double total = std::abs((z1 - z0) * twist_per_mm);
  const int sections = std::max(3, static_cast<int>(std::ceil(total / (4.0 * M_PI / 180.0))) + 1);
  BRepOffsetAPI_ThruSections loft(/*isSolid=*/true, /*ruled=*/false, 1e-6);
  loft.CheckCompatibility(false);
  for (int i = 0; i < sections; ++i) {
    const double z = z0 + (z1 - z0) * i / (sections - 1);
    loft.AddWire(OutlineWire(t, turn + z * twist_per_mm, z));
  }
  loft.Build();
  if (!loft.IsDone()) throw Error("gear: OpenCASCADE could not loft the helical teeth");
  return loft.Shape();
}

TopoDS_Wire CircleWire(double radius) {
  const gp_Circ circle(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), radius);
  return BRepBuilderAPI_MakeWire(BRepBuilderAPI_MakeEdge(circle)).Wire();
}

// A planar face bounded by `outer` with `inner` as a hole, extruded from z = 0 to `height`.
TopoDS_Shape PrismWithHole(const TopoDS_Wire& outer, TopoDS_Wire inner, double height) {
  BRepBuilderAPI_MakeFace face(outer, /*onlyPlane=*/true);
  inner.Reverse();  // holes run clockwise
  face.Add(inner);
  if (!face.IsDone()) throw Error("gear: OpenCASCADE could not make the face with a hole");
  return BRepPrimAPI_MakePrism(face.Face(), gp_Vec(0, 0, height)).Shape();
}

TopoDS_Shape Cylinder(double radius, double z0, double z1) {
  return BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, z0), gp_Dir(0, 0, 1)), radius, z1 - z0)
      .Shape();
}

}  // namespace

double GearOptions::TransverseModule() const { return module_mm / std::cos(helix_angle_rad); }
double GearOptions::TransversePressureAngle() const {
  return std::atan(std::tan(pressure_angle_rad) / std::cos(helix_angle_rad));
}
double GearOptions::PitchRadius() const { return 0.5 * TransverseModule() * teeth; }
double GearOptions::BaseRadius() const {
  return PitchRadius() * std::cos(TransversePressureAngle());
}
double GearOptions::TipRadius() const {
  return internal ? PitchRadius() - module_mm * (1.0 - profile_shift)
                  : PitchRadius() + module_mm * (1.0 + profile_shift);
}
double GearOptions::RootRadius() const {
  return internal ? PitchRadius() + module_mm * (1.25 + profile_shift)
                  : PitchRadius() - module_mm * (1.25 - profile_shift);
}
double GearOptions::FilletRadius() const { return MakeTooth(*this).rho; }

bool GearOptions::Check(std::string* why) const {
  std::ostringstream out;
  const double deg = 180.0 / M_PI;
  if (teeth < 5) {
    out << "a gear needs at least 5 teeth (got " << teeth << ")";
  } else if (!(module_mm > 0) || !std::isfinite(module_mm)) {
    out << "module must be positive (got " << module_mm << " mm)";
  } else if (!(face_width_mm > 0)) {
    out << "face width must be positive (got " << face_width_mm << " mm)";
  } else if (!(pressure_angle_rad >= 10.0 / deg && pressure_angle_rad <= 35.0 / deg)) {
    out << "pressure angle must lie between 10 and 35 degrees (got " << pressure_angle_rad * deg
        << ")";
  } else if (!(std::abs(helix_angle_rad) < 45.0 / deg)) {
    out << "helix angle must lie between -45 and 45 degrees (got " << helix_angle_rad * deg << ")";
  } else if (!(std::abs(profile_shift) <= 1.0)) {
    out << "profile shift must lie between -1 and 1 modules (got " << profile_shift << ")";
  } else if (!(backlash_mm >= 0) || !(root_fillet >= 0)) {
    out << "backlash and root fillet must not be negative";
  } else if (RootRadius() <= 0) {
    out << "the root circle vanishes (" << teeth << " teeth with profile shift " << profile_shift
        << ")";
  } else {
    const Tooth t = MakeTooth(*this);
    const double tip_half = t.Angle(t.ra);
    if (!(t.psi > 0)) {
      out << "backlash " << backlash_mm << " mm is more than the tooth is thick";
    } else if (!(tip_half > 0.02 * M_PI / teeth)) {
      out << "the teeth would be pointed: tip circle " << 2 * t.ra << " mm is too large for "
          << teeth << " teeth (reduce the profile shift)";
    } else if (t.gamma_c >= M_PI / teeth) {
      out << "the tooth spaces close at the root: too few teeth or too much profile shift";
    } else if (!internal && bore_diameter_mm > 0 && 0.5 * bore_diameter_mm >= RootRadius()) {
      out << "bore diameter " << bore_diameter_mm << " mm must be smaller than the root diameter "
          << 2 * RootRadius() << " mm";
    } else if (!internal && (hub_length_mm > 0) != (hub_diameter_mm > 0)) {
      out << "a hub needs both a diameter and a length";
    } else if (!internal && hub_diameter_mm > 0 && hub_diameter_mm <= bore_diameter_mm) {
      out << "hub diameter " << hub_diameter_mm << " mm must be larger than the bore "
          << bore_diameter_mm << " mm";
    } else if (internal && (bore_diameter_mm > 0 || hub_diameter_mm > 0)) {
      out << "an internal gear has no bore or hub (it is a ring)";
    } else if (!(rim_width_mm >= 0)) {
      out << "rim width must not be negative";
    } else {
      return true;
    }
  }
  *why = out.str();
  return false;
}

std::vector<Eigen::Vector2d> GearOutline(const GearOptions& options, int per_segment) {
  std::string why;
  if (!options.Check(&why)) throw Error("gear: " + why);
  const Tooth t = MakeTooth(options);
  const std::vector<Eigen::Vector2d> tooth = ToothOutline(t, std::max(3, per_segment));
  std::vector<Eigen::Vector2d> outline;
  for (int k = 0; k < t.z; ++k) {
    const Eigen::Rotation2Dd turn(2 * M_PI * k / t.z);
    for (const auto& p : tooth) outline.push_back(turn * p);
  }
  return outline;
}

double InvoluteFitError(const GearOptions& options) {
  std::string why;
  if (!options.Check(&why)) throw Error("gear: " + why);
  const Tooth t = MakeTooth(options);
  const Handle(Geom_BSplineCurve) curve = FlankCurve(t, false);
  double worst = 0.0;
  for (int i = 0; i <= 2000; ++i) {
    const double u =
        curve->FirstParameter() + (curve->LastParameter() - curve->FirstParameter()) * i / 2000.0;
    const gp_Pnt p = curve->Value(u);
    const double radius = std::hypot(p.X(), p.Y());
    const double error = radius * std::abs(std::atan2(p.Y(), p.X()) - t.Angle(radius));
    worst = std::max(worst, error);
  }
  return worst;
}

Symmetries GearSymmetries(const GearOptions& o) {
  // Without a hub the gear is the same seen from either face: half-turns about radial axes
  // through mid-face. A helical gear has them too (a half-turn keeps a helix's hand): its tooth
  // 0 is turned by (b / 2) tan(helix) / r at mid-face, and so are the axes.
  const bool flat = o.hub_length_mm == 0.0;
  const double mid = 0.5 * o.face_width_mm;
  return Symmetries::Cyclic(o.teeth, flat, mid,
                            mid * std::tan(o.helix_angle_rad) / o.PitchRadius());
}

Shape MakeGear(const GearOptions& o) {
  std::string why;
  if (!o.Check(&why)) throw Error("gear: " + why);
  try {
    const Tooth t = MakeTooth(o);
    const bool spur = o.helix_angle_rad == 0.0;
    if (!o.internal) {
      TopoDS_Shape gear;
      bool bored = false;
      if (spur && o.bore_diameter_mm > 0 && o.hub_diameter_mm == 0) {  // no Boolean needed
        gear = PrismWithHole(OutlineWire(t, 0.0, 0.0), CircleWire(0.5 * o.bore_diameter_mm),
                             o.face_width_mm);
        bored = true;
      } else {
        gear = ToothedBody(t, o.helix_angle_rad, 0.0, 0.0, o.face_width_mm);
      }
      if (o.hub_diameter_mm > 0) {
        gear = RunBoolean(
            BRepAlgoAPI_Fuse(gear, Cylinder(0.5 * o.hub_diameter_mm, -o.hub_length_mm, 0.0)),
            "add the gear's hub");
      }
      if (o.bore_diameter_mm > 0 && !bored) {
        gear = RunBoolean(
            BRepAlgoAPI_Cut(gear, Cylinder(0.5 * o.bore_diameter_mm, -o.hub_length_mm - 1.0,
                                           o.face_width_mm + 1.0)),
            "cut the gear's bore");
      }
      return WrapShape(gear);
    }
    // Ring: a rim minus the cutter whose teeth are the ring's spaces, turned half a pitch so that
    // the ring's tooth 0 points along +x.
    const double rim = o.rim_width_mm > 0 ? o.rim_width_mm : 2.5 * o.module_mm;
    if (spur) {
      return WrapShape(PrismWithHole(CircleWire(o.RootRadius() + rim),
                                     OutlineWire(t, M_PI / o.teeth, 0.0), o.face_width_mm));
    }
    const TopoDS_Shape blank = Cylinder(o.RootRadius() + rim, 0.0, o.face_width_mm);
    const TopoDS_Shape cutter =
        ToothedBody(t, o.helix_angle_rad, M_PI / o.teeth, -1.0, o.face_width_mm + 1.0);
    return WrapShape(RunBoolean(BRepAlgoAPI_Cut(blank, cutter), "cut the ring gear's teeth"));
  } catch (const Standard_Failure& failure) {
    throw Error(std::string("gear: OpenCASCADE failed: ") + failure.GetMessageString());
  }
}

}  // namespace cadsynth
