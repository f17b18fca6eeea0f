// Facts about a triangle mesh: is it closed, what does it weigh.
#pragma once

#include <cstddef>

#include "cad/mesh.h"
#include "cad/part.h"

namespace cadsynth {

// Edge statistics after welding vertices that share the same position exactly (B-rep
// tessellations repeat edge nodes per face; the positions agree to the bit).
struct MeshTopology {
  size_t edges = 0;
  size_t boundary_edges = 0;      // used by one triangle: a hole
  size_t non_manifold_edges = 0;  // used by three or more triangles
  size_t misoriented_edges = 0;   // used twice in the same direction: flipped neighbours
  bool watertight() const {
    return edges > 0 && boundary_edges == 0 && non_manifold_edges == 0 && misoriented_edges == 0;
  }
};
MeshTopology AnalyzeTopology(const Mesh& mesh);

// Per-vertex normals with sharp edges kept: a triangle corner's normal is the normalised sum of
// the unit normals of the triangles that share its position (exactly equal coordinates) and
// whose normal is within `crease_angle_rad` of its own triangle's. A vertex shared by triangles
// whose corners need different normals is split (the first normal keeps the vertex, copies are
// appended), so every triangle keeps its winding and positions. Degenerate triangles get the
// normal of their neighbours, or +z. Time O(n log n) plus the squared number of triangles at
// each position.
void ComputeCreaseNormals(Mesh* mesh, double crease_angle_rad);

// Volume, centre of mass and inertia (about the centre of mass, density 1) of the solid a closed,
// outward-wound mesh bounds. For an open mesh the numbers are those of the surface closed by
// straight lines to the origin: meaningless, so check AnalyzeTopology first.
MassProperties ComputeMeshMassProperties(const Mesh& mesh);

}  // namespace cadsynth
