#include "variants/families.h"

#include <cmath>
#include <sstream>

#include "cad/core/error.h"
#include "cad/core/util.h"
#include "cad/gear_recognition.h"
#include "cad/mesh_analysis.h"
#include "cad/symmetry.h"
#include "variants/gear.h"
#include "variants/gear_from_file.h"
#include "variants/standard_parts.h"

namespace cadsynth {
namespace {

using Kind = FamilyParam::Kind;
constexpr double kDeg = M_PI / 180.0;

FamilyParam Length(const char* name, double mm, const char* help) {
  return {name, Kind::kLength, mm, "", help};
}
FamilyParam Angle(const char* name, double deg, const char* help) {
  return {name, Kind::kAngle, deg * kDeg, "", help};
}
FamilyParam Count(const char* name, int n, const char* help) {
  return {name, Kind::kCount, double(n), "", help};
}
FamilyParam Number(const char* name, double x, const char* help) {
  return {name, Kind::kNumber, x, "", help};
}
FamilyParam Text(const char* name, const char* text, const char* help) {
  return {name, Kind::kText, 0.0, text, help};
}

std::vector<FamilyParam> GearParams(int teeth) {
  return {Count("teeth", teeth, "number of teeth"),
          Length("module", 2.0, "normal module"),
          Length("face_width", 10.0, "tooth width along the axis"),
          Angle("pressure_angle", 20.0, "normal pressure angle"),
          Number("profile_shift", 0.0, "profile shift in modules"),
          Length("backlash", 0.0, "tooth thinning at the pitch circle"),
          Number("root_fillet", 0.38, "root fillet radius in modules"),
          Angle("helix_angle", 0.0, "0 for spur; positive right hand")};
}

double Num(const ParamValues& v, const char* name) { return std::get<double>(v.at(name)); }
int Int(const ParamValues& v, const char* name) {
  return static_cast<int>(std::lround(Num(v, name)));
}
const std::string& Str(const ParamValues& v, const char* name) {
  return std::get<std::string>(v.at(name));
}

GearOptions GearFrom(const ParamValues& v, const std::string& suffix = "") {
  GearOptions g;
  g.teeth = Int(v, ("teeth" + suffix).c_str());
  g.module_mm = Num(v, "module");
  g.face_width_mm = Num(v, "face_width");
  g.pressure_angle_rad = Num(v, "pressure_angle");
  g.profile_shift = Num(v, ("profile_shift" + suffix).c_str());
  g.backlash_mm = Num(v, "backlash");
  g.helix_angle_rad = Num(v, "helix_angle");
  return g;
}

ShapeAssembly Single(const std::string& name, ShapeAssembly::Component component) {
  ShapeAssembly a;
  a.name = name;
  a.placements = {{0, component.name, Eigen::Isometry3d::Identity()}};
  a.components = {std::move(component)};
  return a;
}

std::vector<std::pair<double, double>> ParseSections(const std::string& text) {
  // "20x10, 30x40, 20x10": diameter x length in mm.
  std::vector<std::pair<double, double>> sections;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    double d = 0, l = 0;
    char x = 0;
    std::stringstream one(item);
    if (!(one >> d >> x >> l) || (x != 'x' && x != 'X')) {
      throw Error("sections: expected diameter x length pairs such as '20x10, 30x40', got '" +
                  item + "'");
    }
    sections.emplace_back(d, l);
  }
  return sections;
}

// from_file: the file's gear (the named part, or the first part recognised as one), rebuilt.
ShapeAssembly GearFromFile(const ParamValues& v) {
  const std::string& file = Str(v, "file");
  if (file.empty()) throw Error("give the file whose gear to rebuild");
  ImportOptions import;
  import.unit = Str(v, "unit");
  const Assembly a = ImportCad(file, import);
  const std::string& wanted = Str(v, "part");
  for (const Part& part : a.parts) {
    if (!wanted.empty() && part.name != wanted) continue;
    if (part.mesh.triangles.empty()) {
      if (!wanted.empty()) throw Error("part '" + wanted + "' of " + file + " has no triangles");
      continue;
    }
    // The B-rep's axes of revolution (a bore, the tip cylinders) first; the symmetry's main axis
    // only where they do not carry the gear (detection costs far more).
    std::optional<RecognizedGear> gear = RecognizePartGear(part, DetectedSymmetries{});
    if (!gear)
      gear = RecognizePartGear(part, DetectSymmetries(part.mesh, PartSymmetryOptions(part)));
    if (!gear) {
      if (!wanted.empty()) throw Error("no gear recognised in part '" + wanted + "' of " + file);
      continue;
    }
    const GearRebuild change{Int(v, "teeth"), Num(v, "module"), Num(v, "face_width")};
    // Named for what it now is: "Spur gear (25 teeth) as z16 m1.5".
    std::ostringstream name;
    name.precision(4);
    name << part.name << " as z" << (change.teeth > 0 ? change.teeth : gear->teeth) << " m"
         << (change.module_mm > 0 ? change.module_mm : std::round(gear->module_mm * 1e3) / 1e3);
    if (change.face_width_mm > 0) name << " b" << change.face_width_mm;
    ShapeAssembly::Component c{name.str(), RebuildGear(part, *gear, change), {}};
    return Single(name.str(), std::move(c));
  }
  if (!wanted.empty()) {
    std::vector<std::string> names;
    for (const Part& part : a.parts) names.push_back(part.name);
    const std::string best = NearestName(wanted, names);
    throw Error(file + " has no part '" + wanted + "'" +
                (best.empty() ? "" : " (did you mean '" + best + "'?)"));
  }
  throw Error("no gear recognised in " + file);
}

// The builders of the parametric families (Families() names each with its parameters).
ShapeAssembly BuildGear(const std::string& f, const ParamValues& v) {
  GearOptions g = GearFrom(v);
  g.internal = f == "ring_gear";
  if (g.internal) {
    g.rim_width_mm = Num(v, "rim_width");
  } else {
    g.bore_diameter_mm = Num(v, "bore");
    g.hub_diameter_mm = Num(v, "hub_diameter");
    g.hub_length_mm = Num(v, "hub_length");
  }
  return Single(f, {f + "_z" + std::to_string(g.teeth), MakeGear(g), GearSymmetries(g)});
}

ShapeAssembly BuildGearPair(const std::string&, const ParamValues& v) {
  GearPairOptions o;
  o.first = GearFrom(v, "_1");
  o.second = GearFrom(v, "_2");
  o.second.helix_angle_rad = -o.first.helix_angle_rad;
  o.first.bore_diameter_mm = o.second.bore_diameter_mm = Num(v, "bore");
  return MakeGearPair(o);
}

ShapeAssembly BuildPlanetary(const std::string&, const ParamValues& v) {
  PlanetaryOptions o;
  o.sun_teeth = Int(v, "sun_teeth");
  o.planet_teeth = Int(v, "planet_teeth");
  o.planets = Int(v, "planets");
  o.module_mm = Num(v, "module");
  o.face_width_mm = Num(v, "face_width");
  o.backlash_mm = Num(v, "backlash");
  o.pin_diameter_mm = Num(v, "pin_diameter");
  o.carrier_thickness_mm = Num(v, "carrier_thickness");
  o.sun_bore_mm = Num(v, "sun_bore");
  return MakePlanetary(o);
}

ShapeAssembly BuildSliderCrank(const std::string&, const ParamValues& v) {
  SliderCrankOptions o;
  o.crank_mm = Num(v, "crank");
  o.rod_mm = Num(v, "rod");
  o.crank_angle_rad = Num(v, "crank_angle");
  o.link_width_mm = Num(v, "link_width");
  o.link_thickness_mm = Num(v, "link_thickness");
  o.pin_diameter_mm = Num(v, "pin_diameter");
  o.slider_mm = Num(v, "slider");
  return MakeSliderCrank(o);
}

}  // namespace

const FamilyParam* FamilyInfo::Find(const std::string& param) const {
  for (const FamilyParam& p : params) {
    if (p.name == param) return &p;
  }
  return nullptr;
}

const std::vector<FamilyInfo>& Families() {
  static const std::vector<FamilyInfo> families = [] {
    std::vector<FamilyInfo> f;
    std::vector<FamilyParam> spur = GearParams(20);
    spur.push_back(Length("bore", 0.0, "centre hole diameter (0: none)"));
    spur.push_back(Length("hub_diameter", 0.0, "hub below the gear (0: none)"));
    spur.push_back(Length("hub_length", 0.0, "hub length"));
    f.push_back({"spur_gear", "an involute spur or helical gear", spur, BuildGear});
    std::vector<FamilyParam> ring = GearParams(60);
    ring.push_back(Length("rim_width", 0.0, "ring wall beyond the root circle (0: 2.5 modules)"));
    f.push_back({"ring_gear", "an internal (ring) gear", ring, BuildGear});
    f.push_back({"gear_pair",
                 "two external gears in mesh at the working centre distance",
                 {Count("teeth_1", 14, "teeth of the first gear"),
                  Count("teeth_2", 28, "teeth of the second gear"),
                  Length("module", 2.0, "normal module"), Length("face_width", 10.0, "tooth width"),
                  Angle("pressure_angle", 20.0, "normal pressure angle"),
                  Number("profile_shift_1", 0.0, "profile shift of the first gear"),
                  Number("profile_shift_2", 0.0, "profile shift of the second gear"),
                  Length("backlash", 0.05, "tooth thinning per gear"),
                  Angle("helix_angle", 0.0, "first gear's helix (the second is opposite)"),
                  Length("bore", 6.0, "bore of both gears")},
                 BuildGearPair});
    f.push_back(
        {"planetary",
         "sun, planets, ring (z_ring = z_sun + 2 z_planet) and carrier",
         {Count("sun_teeth", 18, "sun teeth"), Count("planet_teeth", 18, "planet teeth"),
          Count("planets", 3, "number of planets"), Length("module", 1.5, "module"),
          Length("face_width", 10.0, "tooth width"),
          Length("backlash", 0.05, "tooth thinning per gear"),
          Length("pin_diameter", 6.0, "carrier pins"),
          Length("carrier_thickness", 4.0, "carrier plate"), Length("sun_bore", 6.0, "sun bore")},
         BuildPlanetary});
    f.push_back(
        {"slider_crank",
         "base, crank, connecting rod and slider at a crank angle",
         {Length("crank", 40.0, "crank radius"), Length("rod", 120.0, "connecting rod length"),
          Angle("crank_angle", 35.0, "crank angle"), Length("link_width", 16.0, "link width"),
          Length("link_thickness", 6.0, "link thickness"), Length("pin_diameter", 6.0, "pin holes"),
          Length("slider", 30.0, "slider block length")},
         BuildSliderCrank});
    f.push_back({"round_peg",
                 "a cylinder",
                 {Length("diameter", 20.0, "diameter"), Length("length", 50.0, "length")},
                 [](const std::string& f, const ParamValues& v) {
                   return Single(f, MakeRoundPeg(Num(v, "diameter"), Num(v, "length")));
                 }});
    f.push_back({"square_peg",
                 "a square prism",
                 {Length("side", 20.0, "side"), Length("length", 50.0, "length")},
                 [](const std::string& f, const ParamValues& v) {
                   return Single(f, MakeSquarePeg(Num(v, "side"), Num(v, "length")));
                 }});
    f.push_back({"casing",
                 "an open-top box housing with half-round bearing seats in its end walls",
                 {Length("length", 38.0, "outer length (x)"), Length("width", 15.0, "outer width"),
                  Length("height", 14.5, "outer height"), Length("wall", 2.0, "wall and floor"),
                  Length("seat_diameter", 8.0, "bearing seat in each end wall (0: none)")},
                 [](const std::string& f, const ParamValues& v) {
                   return Single(f, MakeCasing(Num(v, "length"), Num(v, "width"), Num(v, "height"),
                                               Num(v, "wall"), Num(v, "seat_diameter")));
                 }});
    f.push_back(
        {"faceplate",
         "a plate with a grid of holes",
         {Length("width", 120.0, "x size"), Length("height", 80.0, "y size"),
          Length("thickness", 8.0, "z size"), Count("rows", 2, "hole rows"),
          Count("columns", 3, "hole columns"), Length("hole_diameter", 10.0, "hole diameter"),
          Length("margin", 15.0, "edge to outer hole centres")},
         [](const std::string& f, const ParamValues& v) {
           return Single(f, MakeFaceplate(Num(v, "width"), Num(v, "height"), Num(v, "thickness"),
                                          Int(v, "rows"), Int(v, "columns"),
                                          Num(v, "hole_diameter"), Num(v, "margin")));
         }});
    f.push_back({"stepped_shaft",
                 "cylinders one after another",
                 {Text("sections", "16x20, 24x50, 16x20", "diameter x length pairs, mm")},
                 [](const std::string& f, const ParamValues& v) {
                   return Single(f, MakeSteppedShaft(ParseSections(Str(v, "sections"))));
                 }});
    f.push_back({"shoulder_bolt",
                 "ISO 7379 shoulder bolt",
                 {Length("shoulder_diameter", 10.0, "6, 8, 10, 12, 16 or 20 mm"),
                  Length("shoulder_length", 30.0, "shoulder length")},
                 [](const std::string& f, const ParamValues& v) {
                   return Single(
                       f, MakeShoulderBolt(Num(v, "shoulder_diameter"), Num(v, "shoulder_length")));
                 }});
    f.push_back({"hex_bolt",
                 "ISO 4017 hex bolt (thread as a plain shank)",
                 {Text("size", "M8", "M3 to M24"), Length("length", 30.0, "length under the head")},
                 [](const std::string& f, const ParamValues& v) {
                   return Single(f, MakeHexBolt(Str(v, "size"), Num(v, "length")));
                 }});
    f.push_back({"hex_nut",
                 "ISO 4032 hex nut",
                 {Text("size", "M8", "M3 to M24")},
                 [](const std::string& f, const ParamValues& v) {
                   return Single(f, MakeHexNut(Str(v, "size")));
                 }});
    f.push_back({"washer",
                 "ISO 7089 plain washer",
                 {Text("size", "M8", "M3 to M24")},
                 [](const std::string& f, const ParamValues& v) {
                   return Single(f, MakeWasher(Str(v, "size")));
                 }});
    f.push_back({"ball_bearing",
                 "deep-groove ball bearing",
                 {Length("bore", 20.0, "bore"), Length("outer_diameter", 47.0, "outer diameter"),
                  Length("width", 14.0, "width")},
                 [](const std::string& f, const ParamValues& v) {
                   return Single(f, MakeBallBearing(Num(v, "bore"), Num(v, "outer_diameter"),
                                                    Num(v, "width")));
                 }});
    f.push_back(
        {"scaled",
         "any CAD or mesh file, scaled",
         {Text("file", "", "the file (relative to the recipe)"),
          Number("scale", 1.0, "uniform scale"), Number("scale_x", 1.0, "extra scale along x"),
          Number("scale_y", 1.0, "extra scale along y"),
          Number("scale_z", 1.0, "extra scale along z"),
          Text("unit", "", "the file's unit (see parts.unit)")}});
    f.push_back(
        {"from_file",
         "the gear recognised in a CAD file, rebuilt with other teeth, module or face width",
         {Text("file", "", "the STEP, IGES or BREP file (relative to the recipe)"),
          Text("unit", "", "the file's unit (see parts.unit)"),
          Text("part", "", "which part (by name; empty: the first recognised as a gear)"),
          Count("teeth", 0, "number of teeth (0: as the file has it)"),
          Length("module", 0.0, "normal module (0: as the file has it)"),
          Length("face_width", 0.0, "tooth width, centred on the file's (0: as the file has it)")},
         [](const std::string&, const ParamValues& v) { return GearFromFile(v); }});
    return f;
  }();
  return families;
}

const FamilyInfo* FindFamily(const std::string& name) {
  for (const FamilyInfo& f : Families()) {
    if (f.name == name) return &f;
  }
  return nullptr;
}

ParamValues CompleteParams(const FamilyInfo& family, const ParamValues& values) {
  ParamValues out;
  for (const FamilyParam& p : family.params) {
    out[p.name] = p.kind == Kind::kText ? ParamValue(p.default_text) : ParamValue(p.default_number);
  }
  for (const auto& [name, value] : values) {
    const FamilyParam* p = family.Find(name);
    if (p == nullptr) {
      std::vector<std::string> names;
      for (const FamilyParam& q : family.params) names.push_back(q.name);
      const std::string best = NearestName(name, names);
      throw Error("family '" + family.name + "' has no parameter '" + name + "'" +
                  (best.empty() ? "" : " (did you mean '" + best + "'?)"));
    }
    const bool text = std::holds_alternative<std::string>(value);
    if (text != (p->kind == Kind::kText)) {
      throw Error(family.name + "." + name + ": expected " + (text ? "a number" : "a text"));
    }
    if (p->kind == Kind::kCount && std::get<double>(value) != std::floor(std::get<double>(value))) {
      throw Error(family.name + "." + name + ": expected a whole number");
    }
    out[name] = value;
  }
  return out;
}

ShapeAssembly BuildVariantShapes(const FamilyInfo& family, const ParamValues& v) {
  if (family.build == nullptr) {
    throw Error("family '" + family.name + "' is not parametric (it scales a file)");
  }
  try {
    return family.build(family.name, v);
  } catch (const Error& e) {
    throw Error(family.name + ": " + e.what());
  }
}

Assembly BuildVariant(const FamilyInfo& family, const ParamValues& v,
                      const ImportOptions& options) {
  if (family.name != "scaled") {
    Assembly a = TessellateAssembly(BuildVariantShapes(family, v), options.tessellation);
    return a;
  }
  if (Str(v, "file").empty()) throw Error("scaled: give the file to scale");
  ImportOptions import = options;
  import.unit = Str(v, "unit");
  const Assembly source = ImportCad(Str(v, "file"), import);
  const double s = Num(v, "scale");
  const Eigen::Vector3d factors(s * Num(v, "scale_x"), s * Num(v, "scale_y"),
                                s * Num(v, "scale_z"));
  if (!(factors.minCoeff() > 0)) throw Error("scaled: scale factors must be positive");
  return ScaleVariant(source, factors, options.tessellation);
}

std::string DescribeParams(const ParamValues& values, const FamilyInfo* family) {
  std::ostringstream out;
  out.precision(6);
  bool first = true;
  for (const auto& [name, value] : values) {
    out << (first ? "" : ", ") << name << "=";
    if (const double* x = std::get_if<double>(&value)) {
      // As a recipe writes it: angles in degrees (radians inside).
      const FamilyParam* param = family != nullptr ? family->Find(name) : nullptr;
      if (param != nullptr && param->kind == FamilyParam::Kind::kAngle) {
        out << *x * 180.0 / M_PI << " deg";
      } else {
        out << *x;
      }
    } else {
      out << std::get<std::string>(value);
    }
    first = false;
  }
  return out.str();
}

std::string FamilyTable() {
  std::ostringstream out;
  out.precision(6);
  out << "| family | what | parameters (default) |\n|---|---|---|\n";
  for (const FamilyInfo& family : Families()) {
    out << "| `" << family.name << "` | " << family.help << " | ";
    bool first = true;
    for (const FamilyParam& p : family.params) {
      out << (first ? "" : "; ") << "`" << p.name << "` (";
      switch (p.kind) {
        case Kind::kLength:
          out << p.default_number << " mm";
          break;
        case Kind::kAngle:
          out << p.default_number / kDeg << " deg";
          break;
        case Kind::kCount:
        case Kind::kNumber:
          out << p.default_number;
          break;
        case Kind::kText:
          out << '"' << p.default_text << '"';
          break;
      }
      out << "): " << p.help;
      first = false;
    }
    out << " |\n";
  }
  return out.str();
}

Assembly ScaleVariant(const Assembly& assembly, const Eigen::Vector3d& f,
                      const TessellationOptions& options) {
  const bool uniform = f.x() == f.y() && f.y() == f.z();
  Assembly out;
  out.name = assembly.name;
  out.format = assembly.format;
  out.length_unit = assembly.length_unit;
  const auto scaled_part = [&](const Part& part, const Eigen::Isometry3d& root_from_cad,
                               const std::string& name) {
    // The part's geometry in the root frame, scaled there.
    if (!part.brep.IsNull()) {
      Part p = MakePart(name, Scaled(Transformed(part.brep, root_from_cad), f), options);
      p.color = part.color;
      return p;
    }
    Part p;
    p.name = name;
    p.color = part.color;
    p.mesh = part.mesh;
    p.mesh.Transform(root_from_cad * part.cad_from_model);
    const Eigen::Vector3f ff = f.cast<float>();
    for (Eigen::Vector3f& v : p.mesh.positions) v = v.cwiseProduct(ff);
    for (Eigen::Vector3f& n : p.mesh.normals)
      n = n.cwiseQuotient(ff).normalized();  // inverse transpose
    const Eigen::Vector3d centre = p.mesh.Bounds().center();
    p.cad_from_model = Eigen::Translation3d(centre);
    p.mesh.Transform(p.cad_from_model.inverse());
    p.watertight = AnalyzeTopology(p.mesh).watertight();
    if (p.watertight) p.mass = ComputeMeshMassProperties(p.mesh);
    return p;
  };
  if (uniform) {
    for (const Part& part : assembly.parts) {
      Part p = scaled_part(part, Eigen::Isometry3d::Identity(), part.name);
      const double s = f.x();
      // Symmetries survive a uniform scale (about the scaled model origin).
      p.symmetries = part.symmetries;
      for (Eigen::Isometry3d& t : p.symmetries.discrete) t.translation() *= s;
      for (Symmetries::Axis& a : p.symmetries.continuous) a.offset *= s;
      out.parts.push_back(std::move(p));
    }
    for (const Instance& i : assembly.instances) {
      Instance j = i;
      // world_from_model = [R, t]: R stays, t scales; the new model frame is the scaled CAD frame
      // moved to its own box centre.
      const Part& old_part = assembly.parts[i.part];
      const Eigen::Isometry3d root_from_cad =
          i.world_from_model * old_part.cad_from_model.inverse();
      Eigen::Isometry3d scaled_root_from_cad = root_from_cad;
      scaled_root_from_cad.translation() *= f.x();
      j.world_from_model = scaled_root_from_cad * out.parts[i.part].cad_from_model;
      out.instances.push_back(std::move(j));
    }
    return out;
  }
  for (const Instance& i : assembly.instances) {
    const Part& part = assembly.parts[i.part];
    const Eigen::Isometry3d root_from_cad = i.world_from_model * part.cad_from_model.inverse();
    out.parts.push_back(scaled_part(part, root_from_cad, part.name));
    Instance j = i;
    j.part = static_cast<int>(out.parts.size()) - 1;
    j.world_from_model = out.parts.back().cad_from_model;  // the geometry is in the root frame
    out.instances.push_back(std::move(j));
  }
  return out;
}

}  // namespace cadsynth
