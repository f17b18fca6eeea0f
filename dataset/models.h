// Object models as BOP stores them: PLY meshes in mm and their bounding facts.
#pragma once

#include <string>

#include "cad/mesh.h"

namespace cadsynth {

// The largest distance (mm) between any two vertices: BOP's object diameter. Exact: the pair is
// searched among the extreme points of the convex hull.
double MeshDiameter(const Mesh& mesh);

// Binary little-endian PLY with vertex positions (x, y, z, float, mm), normals (nx, ny, nz) and
// triangles (uchar count, int indices), as bop_toolkit's loader reads it.
std::string EncodePly(const Mesh& mesh);

}  // namespace cadsynth
