// The B-rep's share of symmetry detection: the exact axes of its faces of revolution.
#include <algorithm>
#include <cmath>

#include <BRepAdaptor_Surface.hxx>
#include <BRepGProp.hxx>
#include <GProp_GProps.hxx>
#include <Standard_Failure.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <gp_Ax1.hxx>

#include "cad/occt_shape.h"
#include "cad/symmetry.h"

namespace cadsynth {

std::vector<SymmetryOptions::Line> RevolutionAxes(const Shape& shape, int max_axes) {
  std::vector<std::pair<double, SymmetryOptions::Line>> lines;  // area, line
  if (shape.IsNull()) return {};
  const auto add = [&](const TopoDS_Face& face) {
    const BRepAdaptor_Surface surface(face, /*useTrsf=*/true);
    gp_Ax1 axis;
    switch (surface.GetType()) {
      case GeomAbs_Cylinder:
        axis = surface.Cylinder().Axis();
        break;
      case GeomAbs_Cone:
        axis = surface.Cone().Axis();
        break;
      case GeomAbs_Torus:
        axis = surface.Torus().Axis();
        break;
      case GeomAbs_SurfaceOfRevolution:
        axis = surface.AxeOfRevolution();
        break;
      default:
        return;
    }
    GProp_GProps props;
    BRepGProp::SurfaceProperties(face, props);
    SymmetryOptions::Line line;
    line.point = {axis.Location().X(), axis.Location().Y(), axis.Location().Z()};
    line.direction = {axis.Direction().X(), axis.Direction().Y(), axis.Direction().Z()};
    // One line however its faces place their origins and orient their axes.
    for (auto& [area, known] : lines) {
      const Eigen::Vector3d off = line.point - known.point;
      if (std::abs(line.direction.dot(known.direction)) > 1 - 1e-9 &&
          (off - off.dot(known.direction) * known.direction).norm() < 1e-6) {
        area += props.Mass();
        return;
      }
    }
    lines.emplace_back(props.Mass(), line);
  };
  for (TopExp_Explorer e(OcctShape(shape), TopAbs_FACE); e.More(); e.Next()) {
    // A damaged face (imported B-reps have them) gives no axis rather than an OpenCASCADE
    // exception: the axes are only candidates, the mesh decides.
    try {
      add(TopoDS::Face(e.Current()));
    } catch (const Standard_Failure&) {
    }
  }
  std::stable_sort(lines.begin(), lines.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<SymmetryOptions::Line> out;
  for (size_t i = 0; i < lines.size() && static_cast<int>(i) < max_axes; ++i)
    out.push_back(lines[i].second);
  return out;
}

SymmetryOptions PartSymmetryOptions(const Part& part, double tolerance_mm) {
  SymmetryOptions options;
  options.tolerance_mm = tolerance_mm;
  options.deviation_mm = std::max(0.0, part.max_deviation_mm);
  const Eigen::Isometry3d model_from_cad = part.cad_from_model.inverse();
  for (SymmetryOptions::Line line : RevolutionAxes(part.brep)) {
    line.point = model_from_cad * line.point;
    line.direction = model_from_cad.linear() * line.direction;
    options.axis_hints.push_back(line);
  }
  return options;
}

}  // namespace cadsynth
