// Collision shapes of parts for the physics of piles (issue 16): a part is one convex hull when
// it is nearly convex, else a set of convex pieces from an approximate convex decomposition (HACD,
// Mamou and Ghorbel 2009, from Debian's Bullet extras) of its mesh.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "cad/core/schema.h"
#include "cad/part.h"

namespace cadsynth {

struct CollisionOptions {
  // A part whose volume is at least this fraction of its convex hull's is simulated as its hull.
  double convex_fraction = 0.92;
  // HACD: the largest concavity a piece may keep, as a fraction of the part's diameter, and the
  // most pieces (beyond it the smallest merge with their nearest neighbours).
  double concavity = 0.03;
  int max_pieces = 64;
  // Then neighbouring pieces merge (the hull of both), the pair that fills the least empty space
  // first, while all merges together fill at most this fraction of the part's volume: fewer
  // pieces, fewer contacts, faster piles.
  double merge_volume = 0.1;
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
  // The decomposition stops after this many seconds of wall time (checked between two of HACD's
  // merge steps, about every 1 % of its progress) and the part is simulated as its hull, with a
  // warning; 0: no limit. A shape made once is cached, so a farm's shards agree on it.
  double time_limit_s = 60;

  bool Check(std::string* why) const;

  // Every field, once (cad/core/schema.h): the recipe's `collision:` section, the cache keys.
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.convex_fraction,
          Field{"convex_fraction", "number",
                "a part with at least this fraction of its hull's volume is its hull (0-1]"});
    visit(o.concavity, Field{"concavity", "number",
                             "a piece's largest concavity, as a fraction of the part's size"});
    visit(o.max_pieces, Field{"max_pieces", "integer", "most convex pieces per part (1-256)"});
    visit(o.merge_volume,
          Field{"merge_volume", "number",
                "neighbouring pieces merge while that fills at most this fraction of the part's "
                "volume in all (0: only beyond max_pieces)"});
    visit(o.max_triangles,
          Field{"max_triangles", "integer", "the mesh is simplified to this many triangles first"});
    visit(o.max_corners, Field{"max_corners", "integer", "most corners per piece (8-4096)"});
    visit(o.tolerance_mm,
          Field{"tolerance", "length", "corners left out lie within this of their piece"});
    visit(o.time_limit_s,
          Field{.key = "time_limit",
                .kind = "number",
                .doc = "seconds: a decomposition still running then stops (the part is its hull; "
                       "0: no limit)",
                .range = Range::kNonNegative});
  }
};

// Convex pieces in the part's model frame (mm): each the corners of a convex hull.
struct CollisionShape {
  std::vector<std::vector<Eigen::Vector3d>> pieces;
  bool decomposed = false;  // false: one piece, the part's hull
  // The shape's quality: the volume the pieces cover together (each point once; on a grid of 2^18
  // cells, a decomposition) over the part's volume. 1 for a convex part; more where the pieces
  // fill concavities, less where they leave some of the part out; 0 when the part's volume is
  // unknown (an open mesh, simulated as its hull).
  double volume_ratio = 0;
  // The decomposition reached CollisionOptions::time_limit_s: the part is its hull.
  bool timed_out = false;
  double seconds = 0;  // wall time to make the shape (not cached: 0 when read from the cache)
};

// The collision shape of `part`. Throws Error naming the part when its mesh has no volume or the
// decomposition finds no pieces. A decomposition past the time limit warns (Warn) naming the part.
CollisionShape MakeCollisionShape(const Part& part, const CollisionOptions& options = {});

// The bytes of a shape for the part cache, and back (Error on damaged bytes).
std::string EncodeCollisionShape(const CollisionShape& shape);
CollisionShape DecodeCollisionShape(const std::string& bytes);

}  // namespace cadsynth
