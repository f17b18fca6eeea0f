#include "variants/builtin.h"

#include <cmath>
#include <sstream>

#include <BRepAlgoAPI_Cut.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakePolygon.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakePrism.hxx>
#include <Standard_Failure.hxx>
#include <gp_Vec.hxx>

#include "cad/error.h"
#include "cad/occt_shape.h"

namespace cadsynth {

bool GearBlankOptions::Check(std::string* why) const {
  std::ostringstream out;
  if (teeth < 5) {
    out << "a gear needs at least 5 teeth (got " << teeth << ")";
  } else if (!(module_mm > 0.0)) {
    out << "module must be positive (got " << module_mm << " mm)";
  } else if (!(face_width_mm > 0.0)) {
    out << "face width must be positive (got " << face_width_mm << " mm)";
  } else if (!(bore_diameter_mm >= 0.0) || 0.5 * bore_diameter_mm >= RootRadius()) {
    out << "bore diameter " << bore_diameter_mm << " mm must be smaller than the root diameter "
        << 2.0 * RootRadius() << " mm";
  } else {
    return true;
  }
  *why = out.str();
  return false;
}

Shape MakeGearBlank(const GearBlankOptions& options) {
  std::string why;
  if (!options.Check(&why)) throw Error("gear blank: " + why);
  const double pitch = 2.0 * M_PI / options.teeth;
  const double r_tip = options.TipRadius();
  const double r_root = options.RootRadius();
  try {
    BRepBuilderAPI_MakePolygon outline;
    for (int k = 0; k < options.teeth; ++k) {
      const double centre = k * pitch;
      // Root half-width 0.3 of the pitch, tip half-width 0.15: a trapezoid per tooth.
      const double angles[4] = {centre - 0.3 * pitch, centre - 0.15 * pitch,
                                centre + 0.15 * pitch, centre + 0.3 * pitch};
      const double radii[4] = {r_root, r_tip, r_tip, r_root};
      for (int i = 0; i < 4; ++i) {
        outline.Add(gp_Pnt(radii[i] * std::cos(angles[i]), radii[i] * std::sin(angles[i]), 0.0));
      }
    }
    outline.Close();
    BRepBuilderAPI_MakeFace face(outline.Wire(), /*onlyPlane=*/true);
    TopoDS_Shape gear =
        BRepPrimAPI_MakePrism(face.Face(), gp_Vec(0.0, 0.0, options.face_width_mm)).Shape();
    if (options.bore_diameter_mm > 0.0) {
      const TopoDS_Shape bore =
          BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, -1), gp_Dir(0, 0, 1)),
                                   0.5 * options.bore_diameter_mm, options.face_width_mm + 2.0)
              .Shape();
      BRepAlgoAPI_Cut cut(gear, bore);
      if (!cut.IsDone()) throw Error("gear blank: OpenCASCADE could not cut the bore");
      gear = cut.Shape();
    }
    return WrapShape(gear);
  } catch (const Standard_Failure& failure) {
    throw Error(std::string("gear blank: OpenCASCADE failed: ") + failure.GetMessageString());
  }
}

Assembly MakeDefaultParts(const TessellationOptions& tessellation) {
  Assembly assembly;
  assembly.name = "default_parts";
  assembly.format = "built-in";
  assembly.length_unit = "mm";
  const auto add = [&](const std::string& name, const Shape& shape) {
    assembly.parts.push_back(MakePart(name, shape, tessellation));
    Instance instance;
    instance.part = static_cast<int>(assembly.parts.size()) - 1;
    instance.name = name;
    instance.world_from_model = assembly.parts.back().cad_from_model;
    assembly.instances.push_back(instance);
  };
  add("box", MakeBox(80.0, 60.0, 40.0));
  add("round_peg", MakeCylinder(15.0, 80.0));
  add("gear_blank", MakeGearBlank(GearBlankOptions{}));
  return assembly;
}

}  // namespace cadsynth
