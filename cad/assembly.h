// Operations on whole assemblies: finding repeated parts, fusing an assembly into one object.
#pragma once

#include <cstddef>
#include <optional>

#include <Eigen/Geometry>

#include "cad/part.h"

namespace cadsynth {

// Largest distance (mm) from the vertices of `points`, moved by `transform`, to the surface of
// `surface`. Zero for a symmetry of a mesh (up to tessellation differences).
double MaxSurfaceDistance(const Mesh& surface, const Mesh& points,
                          const Eigen::Isometry3d& transform);

// The rigid motion that carries mesh `b` onto mesh `a` (x_a = a_from_b * x_b, model frames), if
// the two are the same shape: every vertex of each lies within `tolerance_mm` of the other's
// surface. Tessellations may differ (a seam elsewhere, other triangles): two meshes of one exact
// surface lie within twice the deflection of each other, so pass at least that. Candidate
// rotations come from the principal axes of the surfaces; for axes with equal moments (cylinders,
// gears) the angle about the distinct axis is searched, for three equal moments the 24 rotations
// of the coordinate axes are tried.
std::optional<Eigen::Isometry3d> FindCongruence(const Mesh& a, const Mesh& b, double tolerance_mm);
// The same, read from (or stored in) `cache` when given.
class PartCache;
std::optional<Eigen::Isometry3d> FindCongruence(const Mesh& a, const Mesh& b, double tolerance_mm,
                                                const PartCache* cache);

// Parts that are the same shape (FindCongruence, and equal exact volumes when both have a B-rep)
// become one part, and their instances refer to
// it with poses corrected by the congruence: a part used N times is one model with N instances,
// even when the file stores N copies, rotated or not. The first part's name is kept. Returns the
// number of parts merged away. Congruence checks are read from (and stored in) `cache` if given.
size_t MergeIdenticalParts(Assembly* assembly, double tolerance_mm,
                           const PartCache* cache = nullptr);

// The whole assembly as one rigid part: every instance's mesh in the assembly frame, joined and
// moved to its own model frame; mass properties combined (parallel-axis theorem); watertight when
// every piece is. One instance places it where the assembly was. Throws Error when empty.
Assembly FuseAssembly(const Assembly& assembly);

}  // namespace cadsynth
