#include "cad/shape.h"

#include <cmath>
#include <sstream>

#include <BRepAdaptor_Surface.hxx>
#include <BRepAlgoAPI_Common.hxx>
#include <BRepBndLib.hxx>
#include <BRepBuilderAPI_GTransform.hxx>
#include <BRepBuilderAPI_Transform.hxx>
#include <BRepCheck_Analyzer.hxx>
#include <BRepGProp.hxx>
#include <BRepLProp_SLProps.hxx>
#include <BRepMesh_IncrementalMesh.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <GProp_GProps.hxx>
#include <GeomAPI_ProjectPointOnSurf.hxx>
#include <Geom_Surface.hxx>
#include <Poly_Triangulation.hxx>
#include <ShapeFix_Shape.hxx>
#include <Standard_Failure.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <gp_GTrsf.hxx>
#include <gp_Trsf.hxx>

#include "cad/core/error.h"
#include "cad/mesh_analysis.h"
#include "cad/occt_shape.h"
#include "cad/xde.h"

namespace cadsynth {

bool TessellationOptions::Check(std::string* why) const {
  if (!(linear_deflection_mm > 0.0) || !std::isfinite(linear_deflection_mm)) {
    *why = "linear_deflection must be a positive length";
    return false;
  }
  if (!(min_relative_deflection >= 0.0) || min_relative_deflection > 0.1) {
    *why = "min_relative_deflection must be between 0 and 0.1";
    return false;
  }
  if (!(angular_deflection_rad > 0.0) || angular_deflection_rad >= M_PI) {
    *why = "angular_deflection must be between 0 and 180 degrees (exclusive)";
    return false;
  }
  return true;
}

Shape::Shape() : impl_(std::make_shared<const Impl>()) {}
Shape::Shape(std::shared_ptr<const Impl> impl) : impl_(std::move(impl)) {}

bool Shape::IsNull() const { return impl_->shape.IsNull(); }

bool Shape::HasFaces() const {
  return !IsNull() && TopExp_Explorer(impl_->shape, TopAbs_FACE).More();
}

Eigen::AlignedBox3d Shape::Bounds() const {
  Eigen::AlignedBox3d box;
  if (IsNull()) return box;
  Bnd_Box bnd;
  BRepBndLib::Add(impl_->shape, bnd);
  if (bnd.IsVoid()) return box;
  double x0, y0, z0, x1, y1, z1;
  bnd.Get(x0, y0, z0, x1, y1, z1);
  box.extend(Eigen::Vector3d(x0, y0, z0));
  box.extend(Eigen::Vector3d(x1, y1, z1));
  return box;
}

namespace {

template <typename Builder>
Shape Build(Builder&& builder, const char* what) {
  try {
    builder.Build();
    if (!builder.IsDone()) throw Error(std::string("OpenCASCADE could not build ") + what);
    return WrapShape(builder.Shape());
  } catch (const Standard_Failure& failure) {
    throw Error(std::string("OpenCASCADE could not build ") + what + ": " +
                internal::PlainFailure(failure));
  }
}

void RequirePositive(double value, const char* what) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    std::ostringstream out;
    out << what << " must be positive (got " << value << ")";
    throw Error(out.str());
  }
}

}  // namespace

Shape MakeBox(double dx, double dy, double dz) {
  RequirePositive(dx, "box size x");
  RequirePositive(dy, "box size y");
  RequirePositive(dz, "box size z");
  return Build(BRepPrimAPI_MakeBox(dx, dy, dz), "a box");
}

Shape MakeCylinder(double radius, double height) {
  RequirePositive(radius, "cylinder radius");
  RequirePositive(height, "cylinder height");
  return Build(BRepPrimAPI_MakeCylinder(radius, height), "a cylinder");
}

Shape MakeSphere(double radius) {
  RequirePositive(radius, "sphere radius");
  return Build(BRepPrimAPI_MakeSphere(radius), "a sphere");
}

Shape Transformed(const Shape& shape, const Eigen::Isometry3d& transform) {
  return Build(BRepBuilderAPI_Transform(OcctShape(shape), ToTrsf(transform), /*copy=*/true),
               "a moved shape");
}

namespace {

// Distance from `p` to the face's surface: Gauss-Newton on |S(u, v) - p|^2 from (u, v), which
// converges in a few steps for a point near its own triangle; where it does not (degenerate
// parametrisations such as sphere poles), OpenCASCADE's global projection decides.
double DistanceToSurface(const BRepAdaptor_Surface& surface, const Handle(Geom_Surface) & geometry,
                         const gp_Pnt& p, double u, double v) {
  gp_Pnt s;
  gp_Vec du, dv;
  for (int iteration = 0; iteration < 8; ++iteration) {
    surface.D1(u, v, s, du, dv);
    const gp_Vec r(p, s);
    const double a = du.Dot(du), b = du.Dot(dv), c = dv.Dot(dv);
    const double det = a * c - b * b;
    if (!(det > 1e-12 * a * c) || !(a * c > 0)) break;
    const double gu = du.Dot(r), gv = dv.Dot(r);
    const double step_u = (c * gu - b * gv) / det, step_v = (a * gv - b * gu) / det;
    u -= step_u;
    v -= step_v;
    if ((step_u * du + step_v * dv).Magnitude() < 1e-9) {
      surface.D0(u, v, s);
      return s.Distance(p);
    }
  }
  GeomAPI_ProjectPointOnSurf projection(p, geometry);
  return projection.NbPoints() > 0 ? projection.LowerDistance() : -1.0;
}

}  // namespace

Shape Scaled(const Shape& shape, const Eigen::Vector3d& f) {
  if (!(f.minCoeff() > 0) || !f.allFinite()) throw Error("scale factors must be positive");
  if (f.x() == f.y() && f.y() == f.z()) {
    gp_Trsf scale;
    scale.SetScale(gp_Pnt(0, 0, 0), f.x());
    return Build(BRepBuilderAPI_Transform(OcctShape(shape), scale, /*copy=*/true),
                 "a scaled shape");
  }
  gp_GTrsf scale;
  scale.SetValue(1, 1, f.x());
  scale.SetValue(2, 2, f.y());
  scale.SetValue(3, 3, f.z());
  return Build(BRepBuilderAPI_GTransform(OcctShape(shape), scale, /*copy=*/true), "a scaled shape");
}

Mesh Tessellate(const Shape& shape, const TessellationOptions& options, double* max_deviation_mm) {
  std::string why;
  if (!options.Check(&why)) throw Error("tessellation: " + why);
  const TopoDS_Shape& s = OcctShape(shape);
  if (s.IsNull()) throw Error("tessellation: empty shape");

  try {
    BRepMesh_IncrementalMesh mesher(s, options.linear_deflection_mm, /*isRelative=*/false,
                                    options.angular_deflection_rad, /*isInParallel=*/true);
  } catch (const Standard_Failure& failure) {
    throw Error(std::string("tessellation failed: ") + internal::PlainFailure(failure));
  }

  Mesh mesh;
  if (max_deviation_mm != nullptr) *max_deviation_mm = 0.0;
  uint32_t face_index = 0;
  for (TopExp_Explorer it(s, TopAbs_FACE); it.More(); it.Next(), ++face_index) {
    const TopoDS_Face& face = TopoDS::Face(it.Current());
    TopLoc_Location location;
    const Handle(Poly_Triangulation) tri = BRep_Tool::Triangulation(face, location);
    if (tri.IsNull() || tri->NbTriangles() == 0) continue;

    const gp_Trsf trsf = location.Transformation();
    const bool reversed = face.Orientation() == TopAbs_REVERSED;
    const auto base = static_cast<uint32_t>(mesh.positions.size());
    const int num_nodes = tri->NbNodes();

    std::vector<Eigen::Vector3f> facet_normals(num_nodes, Eigen::Vector3f::Zero());
    for (int i = 1; i <= num_nodes; ++i) {
      const gp_Pnt p = tri->Node(i).Transformed(trsf);
      mesh.positions.emplace_back(float(p.X()), float(p.Y()), float(p.Z()));
    }
    for (int t = 1; t <= tri->NbTriangles(); ++t) {
      int a, b, c;
      tri->Triangle(t).Get(a, b, c);
      if (reversed) std::swap(b, c);
      Eigen::Matrix<uint32_t, 3, 1> idx(base + a - 1, base + b - 1, base + c - 1);
      const Eigen::Vector3f& pa = mesh.positions[idx[0]];
      const Eigen::Vector3f n = (mesh.positions[idx[1]] - pa).cross(mesh.positions[idx[2]] - pa);
      facet_normals[a - 1] += n;
      facet_normals[b - 1] += n;
      facet_normals[c - 1] += n;
      mesh.triangles.push_back(idx);
      mesh.face_ids.push_back(face_index);
    }

    // Normals from the exact surface where it has one at the node; the area-weighted facet
    // normal otherwise (and to orient the surface normal consistently with the winding).
    BRepAdaptor_Surface surface(face, /*useTrsf=*/true);
    BRepLProp_SLProps props(surface, 1, 1e-9);
    for (int i = 1; i <= num_nodes; ++i) {
      Eigen::Vector3f facet = facet_normals[i - 1];
      const float facet_norm = facet.norm();
      if (facet_norm > 0.0f) facet /= facet_norm;
      Eigen::Vector3f normal = facet;
      if (tri->HasUVNodes()) {
        const gp_Pnt2d uv = tri->UVNode(i);
        props.SetParameters(uv.X(), uv.Y());
        if (props.IsNormalDefined()) {
          const gp_Dir d = props.Normal();
          Eigen::Vector3f exact(float(d.X()), float(d.Y()), float(d.Z()));
          if (reversed) exact = -exact;
          // A surface normal pointing against the facets means a degenerate parametrisation
          // (poles, seams): trust the facets there.
          if (facet_norm == 0.0f || exact.dot(facet) > 0.0f) normal = exact;
        }
      }
      mesh.normals.push_back(normal);
    }

    if (max_deviation_mm != nullptr && tri->HasUVNodes()) {
      const Handle(Geom_Surface) geometry = BRep_Tool::Surface(face);  // with the face's location
      const size_t first = mesh.triangles.size() - static_cast<size_t>(tri->NbTriangles());
      for (size_t t = first; t < mesh.triangles.size(); ++t) {
        const auto& idx = mesh.triangles[t];
        gp_Pnt2d uv[3];
        for (int k = 0; k < 3; ++k) uv[k] = tri->UVNode(static_cast<int>(idx[k] - base) + 1);
        const auto point = [&](int k) {
          const Eigen::Vector3f& q = mesh.positions[idx[k]];
          return gp_Pnt(q.x(), q.y(), q.z());
        };
        // Centroid and edge midpoints: where a chord strays furthest from the surface.
        const auto sample = [&](const gp_Pnt& p, double u, double v) {
          const double d = DistanceToSurface(surface, geometry, p, u, v);
          if (d >= 0.0) *max_deviation_mm = std::max(*max_deviation_mm, d);
        };
        const gp_Pnt a = point(0), b = point(1), c = point(2);
        sample(gp_Pnt((a.XYZ() + b.XYZ() + c.XYZ()) / 3.0),
               (uv[0].X() + uv[1].X() + uv[2].X()) / 3.0,
               (uv[0].Y() + uv[1].Y() + uv[2].Y()) / 3.0);
        for (int k = 0; k < 3; ++k) {
          const int l = (k + 1) % 3;
          sample(gp_Pnt((point(k).XYZ() + point(l).XYZ()) / 2.0), (uv[k].X() + uv[l].X()) / 2.0,
                 (uv[k].Y() + uv[l].Y()) / 2.0);
        }
      }
    }
  }
  if (mesh.empty()) throw Error("tessellation produced no triangles (the shape has no faces)");
  return mesh;
}

Shape Heal(const Shape& shape, bool* healed) {
  *healed = false;
  if (shape.IsNull()) return shape;
  try {
    if (BRepCheck_Analyzer(OcctShape(shape)).IsValid()) return shape;
    Handle(ShapeFix_Shape) fix = new ShapeFix_Shape(OcctShape(shape));
    fix->Perform();
    *healed = true;
    return WrapShape(fix->Shape());
  } catch (const Standard_Failure& failure) {
    throw Error(std::string("shape healing failed: ") + internal::PlainFailure(failure));
  }
}

double CommonVolume(const Shape& a, const Eigen::Isometry3d& a_pose, const Shape& b,
                    const Eigen::Isometry3d& b_pose) {
  try {
    BRepAlgoAPI_Common common(OcctShape(Transformed(a, a_pose)), OcctShape(Transformed(b, b_pose)));
    if (!common.IsDone()) throw Error("OpenCASCADE could not intersect the shapes");
    GProp_GProps props;
    BRepGProp::VolumeProperties(common.Shape(), props);
    return std::max(0.0, props.Mass());
  } catch (const Standard_Failure& failure) {
    throw Error(std::string("intersecting shapes failed: ") + internal::PlainFailure(failure));
  }
}

MassProperties ComputeMassProperties(const Shape& shape) {
  MassProperties result;
  GProp_GProps props;
  BRepGProp::VolumeProperties(OcctShape(shape), props);
  result.volume_mm3 = props.Mass();
  if (result.volume_mm3 > 0.0) {
    const gp_Pnt c = props.CentreOfMass();
    result.center_of_mass = Eigen::Vector3d(c.X(), c.Y(), c.Z());
    const gp_Mat m = props.MatrixOfInertia();
    for (int r = 0; r < 3; ++r) {
      for (int col = 0; col < 3; ++col) result.inertia(r, col) = m.Value(r + 1, col + 1);
    }
  }
  return result;
}

Part MakePart(const std::string& name, const Shape& shape, const TessellationOptions& options) {
  Part part;
  part.name = name;
  TessellationOptions effective = options;
  const Eigen::AlignedBox3d bounds = shape.Bounds();
  if (!bounds.isEmpty()) {
    const double diagonal = bounds.diagonal().norm();
    const double floor = options.min_relative_deflection * diagonal;
    if (floor > options.linear_deflection_mm) {
      effective.linear_deflection_mm = floor;
      std::ostringstream message;
      message.precision(3);
      message << "part '" << name << "' is " << diagonal / 1000.0 << " m across; tessellated with "
              << floor << " mm deflection instead of " << options.linear_deflection_mm << " mm";
      Warn(message.str());
    }
  }
  part.mesh =
      Tessellate(shape, effective, options.measure_deviation ? &part.max_deviation_mm : nullptr);
  const Eigen::Vector3d centre = part.mesh.Bounds().center();
  part.cad_from_model = Eigen::Translation3d(centre);
  part.mesh.Transform(part.cad_from_model.inverse());
  part.mass = ComputeMassProperties(shape);
  part.mass.center_of_mass -= centre;
  part.mass_from_brep = part.mass.volume_mm3 > 0.0;
  part.watertight = AnalyzeTopology(part.mesh).watertight();
  part.brep = shape;
  return part;
}

}  // namespace cadsynth
