// The B-rep's share of symmetry detection: the exact axes of its faces of revolution.
#include <algorithm>
#include <cmath>
#include <limits>

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

namespace {

// One surface of a B-rep (model frame): an analytic one (plane, cylinder, cone, sphere, torus)
// with all the faces that lie on it, so that a cylinder split into halves at its seam is one
// cylinder; any other face on its own, by its centroid.
struct BrepSurface {
  int kind = 0;  // GeomAbs_SurfaceType
  double area = 0;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();       // plane: a point; axial kinds: the apex or
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();  // centre on the axis; free: centroid
  double r1 = 0, r2 = 0;  // radius (cylinder, sphere), major and minor (torus), angle (cone)
};

// How far apart two surfaces of one kind are (mm), for a part `size` across: 0 for the same.
double Apart(const BrepSurface& a, const BrepSurface& b, double size) {
  const Eigen::Vector3d off = a.point - b.point;
  const double cross = a.direction.cross(b.direction).norm();  // sine of the axes' angle
  const double across = (off - off.dot(b.direction) * b.direction).norm();
  switch (a.kind) {
    case GeomAbs_Plane:
      return std::abs(off.dot(b.direction)) + size * cross;
    case GeomAbs_Cylinder:
      return across + size * cross + std::abs(a.r1 - b.r1);
    case GeomAbs_Cone:
      // (A cone about -d with angle -a is the one about d with a.)
      return off.norm() + size * cross + size * std::abs(std::abs(a.r1) - std::abs(b.r1));
    case GeomAbs_Sphere:
      return off.norm() + std::abs(a.r1 - b.r1);
    case GeomAbs_Torus:
      return off.norm() + size * cross + std::abs(a.r1 - b.r1) + std::abs(a.r2 - b.r2);
    default:
      return off.norm();
  }
}

}  // namespace

void CompareBrepFaces(const Part& part, DetectedSymmetries* found) {
  found->discrete_brep_mm.clear();
  found->continuous_brep_mm.clear();
  found->brep_faces_not_compared = 0;
  if (part.brep.IsNull() || found->symmetries.empty()) return;
  const Eigen::Isometry3d model_from_cad = part.cad_from_model.inverse();
  const double size = std::max(1e-9, part.mesh.Bounds().diagonal().norm());
  const auto vec = [&](const gp_XYZ& v) {
    return Eigen::Vector3d(model_from_cad.linear() * Eigen::Vector3d(v.X(), v.Y(), v.Z()));
  };
  const auto at = [&](const gp_Pnt& p) {
    return Eigen::Vector3d(model_from_cad * Eigen::Vector3d(p.X(), p.Y(), p.Z()));
  };
  std::vector<BrepSurface> surfaces;
  try {
    for (TopExp_Explorer e(OcctShape(part.brep), TopAbs_FACE); e.More(); e.Next()) {
      const TopoDS_Face& face = TopoDS::Face(e.Current());
      GProp_GProps props;
      BRepGProp::SurfaceProperties(face, props);
      if (!(props.Mass() > 0)) continue;
      const BRepAdaptor_Surface adaptor(face, /*useTrsf=*/true);
      BrepSurface f;
      f.kind = static_cast<int>(adaptor.GetType());
      f.area = props.Mass();
      switch (adaptor.GetType()) {
        case GeomAbs_Plane:
          f.point = at(adaptor.Plane().Location());
          f.direction = vec(adaptor.Plane().Axis().Direction().XYZ());
          break;
        case GeomAbs_Cylinder:
          f.point = at(adaptor.Cylinder().Location());
          f.direction = vec(adaptor.Cylinder().Axis().Direction().XYZ());
          f.r1 = adaptor.Cylinder().Radius();
          break;
        case GeomAbs_Cone:
          f.point = at(adaptor.Cone().Apex());
          f.direction = vec(adaptor.Cone().Axis().Direction().XYZ());
          f.r1 = adaptor.Cone().SemiAngle();
          break;
        case GeomAbs_Sphere:
          f.point = at(adaptor.Sphere().Location());
          f.r1 = adaptor.Sphere().Radius();
          break;
        case GeomAbs_Torus:
          f.point = at(adaptor.Torus().Location());
          f.direction = vec(adaptor.Torus().Axis().Direction().XYZ());
          f.r1 = adaptor.Torus().MajorRadius();
          f.r2 = adaptor.Torus().MinorRadius();
          break;
        default:
          f.point = at(props.CentreOfMass());
          break;
      }
      // Faces on one analytic surface are that surface.
      bool merged = false;
      if (f.kind <= GeomAbs_Torus) {
        for (BrepSurface& known : surfaces) {
          if (known.kind == f.kind && Apart(f, known, size) < 1e-7 * size) {
            known.area += f.area;
            merged = true;
            break;
          }
        }
      }
      if (!merged) surfaces.push_back(f);
    }
  } catch (const Standard_Failure&) {
    return;
  }
  if (surfaces.empty()) return;
  std::stable_sort(surfaces.begin(), surfaces.end(),
                   [](const BrepSurface& a, const BrepSurface& b) { return a.area < b.area; });
  const double inf = std::numeric_limits<double>::infinity();
  // The largest distance from a moved surface to the nearest one of its kind and area. A free-form
  // face without a partner is counted, not failed: files split such faces where they please (an
  // old writer's cylinder as two B-spline halves, which a turn maps onto no face).
  int skipped = 0;
  const auto mismatch = [&](const Eigen::Isometry3d& t) {
    double worst = 0;
    for (const BrepSurface& s : surfaces) {
      BrepSurface moved = s;
      moved.point = t * s.point;
      moved.direction = t.linear() * s.direction;
      double best = inf;
      auto it = std::lower_bound(surfaces.begin(), surfaces.end(), s.area * (1 - 1e-3),
                                 [](const BrepSurface& x, double a) { return x.area < a; });
      for (; it != surfaces.end() && it->area <= s.area * (1 + 1e-3); ++it) {
        if (it->kind == s.kind) best = std::min(best, Apart(moved, *it, size));
      }
      // A partner lies within 0.1% of the part's size (an exact symmetry: microns); farther, there
      // is none. A free-form face without one was split differently, an analytic surface
      // without one is a detail that breaks the symmetry.
      if (!(best < 1e-3 * size)) {
        if (s.kind > GeomAbs_Torus) {
          ++skipped;
          continue;
        }
        best = inf;
      }
      worst = std::max(worst, best);
      if (worst == inf) break;
    }
    return worst;
  };
  for (const Eigen::Isometry3d& t : found->symmetries.discrete)
    found->discrete_brep_mm.push_back(mismatch(t));
  // A continuous axis: the turns detection tests it with.
  for (const Symmetries::Axis& axis : found->symmetries.continuous) {
    double worst = 0;
    for (const double angle : {0.70710678, 2.23606798, 4.12310563}) {
      worst = std::max(worst, mismatch(Eigen::Translation3d(axis.offset) *
                                       Eigen::AngleAxisd(angle, axis.direction.normalized()) *
                                       Eigen::Translation3d(-axis.offset)));
    }
    found->continuous_brep_mm.push_back(worst);
  }
  found->brep_faces_not_compared = skipped;
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
