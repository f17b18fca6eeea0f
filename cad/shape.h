// Exact B-rep solids, kept opaque: OpenCASCADE types never leave cad/ and variants/.
#pragma once

#include <memory>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "cad/brep.h"
#include "cad/core/schema.h"
#include "cad/mesh.h"
#include "cad/part.h"

namespace cadsynth {

// Controls how B-rep surfaces become triangles.
struct TessellationOptions {
  // Largest distance (mm) allowed between a triangle and the exact surface.
  double linear_deflection_mm = 0.1;
  // Largest angle (radians) between the normals of neighbouring triangles on a curved face.
  double angular_deflection_rad = 0.35;  // 20 degrees
  // MakePart never uses a linear deflection finer than this fraction of the part's bounding-box
  // diagonal: a 100 m part (real files have them, by unit mistakes) at 0.1 mm would need billions
  // of triangles. At 1e-5 it changes nothing for parts under 10 m.
  double min_relative_deflection = 1e-5;
  // MakePart measures Part::max_deviation_mm (see Tessellate); costs about as much as meshing.
  bool measure_deviation = false;

  // False, with a reason, when a value is out of range.
  bool Check(std::string* why) const;

  // Every field, once (cad/core/schema.h): the recipe's `tessellation:` section, the run key.
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.linear_deflection_mm,
          Field{"linear_deflection", "length", "largest triangle-to-surface distance"});
    visit(o.angular_deflection_rad,
          Field{"angular_deflection", "angle",
                "largest angle between neighbouring triangles on a curved face"});
    visit(o.min_relative_deflection, Field{"",
                                           "number",
                                           "finest deflection as a fraction of the part's size",
                                           {},
                                           true,
                                           "min_relative_deflection"});
    visit(
        o.measure_deviation,
        Field{"", "bool", "measure the mesh-to-surface deviation", {}, true, "measure_deviation"});
  }
};

// Primitives, all in mm.
// A box with one corner at the origin and the opposite corner at (dx, dy, dz).
Shape MakeBox(double dx, double dy, double dz);
// A cylinder around +z with its base centred at the origin.
Shape MakeCylinder(double radius, double height);
// A sphere centred at the origin.
Shape MakeSphere(double radius);
// `shape` moved by `transform`.
Shape Transformed(const Shape& shape, const Eigen::Isometry3d& transform);
// `shape` scaled about the origin by (sx, sy, sz) (exact; a general affine map when unequal).
Shape Scaled(const Shape& shape, const Eigen::Vector3d& factors);

// Triangles for every face, with per-vertex normals from the exact surface. Throws Error when the
// options are invalid or the shape yields no triangles. With `max_deviation_mm`, also measures
// the largest distance between the triangles and the exact surface: each triangle's centroid and
// edge midpoints are projected onto its face's surface (Gauss-Newton from the mid-UV).
Mesh Tessellate(const Shape& shape, const TessellationOptions& options,
                double* max_deviation_mm = nullptr);

// Checks the B-rep (BRepCheck) and, when it is invalid, repairs it with OpenCASCADE's shape
// healing (ShapeFix: orientation, gaps, missing seams, small edges). Returns the shape unchanged
// when it is valid; sets *healed when it repaired something.
Shape Heal(const Shape& shape, bool* healed);

// Volume (mm^3) of the intersection of two shapes placed by `a_pose` and `b_pose`: zero for parts
// that touch but do not overlap.
double CommonVolume(const Shape& a, const Eigen::Isometry3d& a_pose, const Shape& b,
                    const Eigen::Isometry3d& b_pose);

// Exact volume, centre of mass and inertia of the solids in `shape`.
MassProperties ComputeMassProperties(const Shape& shape);

// Tessellates `shape` (see min_relative_deflection, with a warning when it applies) and moves it
// into its model frame (see Part).
Part MakePart(const std::string& name, const Shape& shape, const TessellationOptions& options);

}  // namespace cadsynth
