// Object models as BOP stores them: PLY meshes in mm and their bounding facts.
#pragma once

#include <string>

#include "cad/mesh.h"
#include "cad/part.h"

namespace cadsynth {

// The largest distance (mm) between any two vertices: BOP's object diameter. Exact: the pair is
// searched among the corners of the convex hull (every vertex for a flat mesh).
double MeshDiameter(const Mesh& mesh);
// The same for a part, from its cached hull when it has one.
double PartDiameter(const Part& part);

// Binary little-endian PLY with vertex positions (x, y, z, float, mm), normals (nx, ny, nz) and
// triangles (uchar count, int indices), as bop_toolkit's loader reads it.
std::string EncodePly(const Mesh& mesh);

}  // namespace cadsynth
