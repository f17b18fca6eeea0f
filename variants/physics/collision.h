// Collision shapes of parts for the physics of piles (issue 16): a part is one convex hull when
// it is nearly convex, else a set of convex pieces from an approximate convex decomposition (HACD,
// Mamou and Ghorbel 2009, from Debian's Bullet extras) of its mesh.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "cad/part.h"

namespace cadsynth {

struct CollisionOptions {
  // A part whose volume is at least this fraction of its convex hull's is simulated as its hull.
  double convex_fraction = 0.92;
  // HACD: the largest concavity a piece may keep, as a fraction of the part's diameter, and the
  // most pieces (beyond it the smallest merge with their nearest neighbours).
  double concavity = 0.03;
  int max_pieces = 64;
  // Meshes are simplified to about this many triangles before the decomposition (vertex
  // clustering on a grid), which bounds its time; the pieces' hulls are taken of the original
  // vertices each piece covers, so they keep the exact surface. HACD's time grows steeply and
  // erratically with it: spur gears of 18-23 teeth took 0.4-3.9 s at 1,000 triangles, 56 s at
  // 2,000 and over 80 s at 3,000.
  int max_triangles = 1000;
  // Each piece keeps at most max_corners of its hull's corners, chosen so that the corners left
  // out lie within tolerance_mm of it where the cap allows. Bullet's contact search scans every
  // corner of a piece for each support point (a third of a pile's time): 60 M16 bolts settled
  // in 0.65 s of wall time per simulated second at 32 corners, 0.95 s at 64 (the shaft's
  // 16-gon lies 0.15 mm inside its cylinder, within Bullet's 0.5 mm collision margin).
  int max_corners = 32;
  double tolerance_mm = 0.1;

  bool Check(std::string* why) const;
};

// Convex pieces in the part's model frame (mm): each the corners of a convex hull.
struct CollisionShape {
  std::vector<std::vector<Eigen::Vector3d>> pieces;
  bool decomposed = false;  // false: one piece, the part's hull
  // The pieces' hulls' volume over the part's volume (1 for a convex part; more where the pieces
  // bridge concavities; 0 when the part's volume is unknown).
  double volume_ratio = 0;
};

// The collision shape of `part`. Throws Error naming the part when its mesh has no volume or the
// decomposition finds no pieces.
CollisionShape MakeCollisionShape(const Part& part, const CollisionOptions& options = {});

// The bytes of a shape for the part cache, and back (Error on damaged bytes).
std::string EncodeCollisionShape(const CollisionShape& shape);
CollisionShape DecodeCollisionShape(const std::string& bytes);

}  // namespace cadsynth
