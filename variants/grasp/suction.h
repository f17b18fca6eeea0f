// Suction grasps from CAD (issue 19): Dex-Net 3.0's seal model (the cup's rim projected onto the
// exact mesh) and the wrench the vacuum must resist against gravity.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "cad/core/schema.h"
#include "cad/grasp.h"
#include "cad/part.h"

namespace cadsynth {

struct SuctionOptions {
  int samples = 2000;           // surface points tried
  double density_kg_m3 = 7850;  // the part's mass = density x its volume (steel by default)
  double gravity_m_s2 = 9.80665;
  int max_grasps = 0;  // stop once this many are kept (0: no limit)
  uint64_t seed = 0;

  bool Check(std::string* why) const;

  // Every field, once (cad/core/schema.h): keys of `grasps.suction`, the run key. The limit and
  // the seed are the parallel-jaw sampling's (grasps.per_part, grasps.seed).
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.samples, Field{"samples", "integer", "surface points tried per object"});
    visit(o.density_kg_m3,
          Field{"density", "number", "kg/m3, for the weight the cup must hold (steel: 7850)"});
    visit(o.gravity_m_s2, Field{"", "number", "gravity (m/s2)", {}, true, "gravity"});
    visit(o.max_grasps, Field{"", "integer", "grasps.per_part", {}, true, "max_grasps"});
    visit(o.seed, Field{"", "integer", "grasps.seed", {}, true, "seed"});
  }
};

// Samples suction grasps of `part` (a closed, outward-wound mesh), in the order drawn: a surface
// point c drawn by area, the approach a along its inward normal. Rays along a from outside the
// part find, first, c itself (else the point is hidden from the approach), then the rim: the
// cup's ring_points on the circle of radius r about c, perpendicular to a. The grasp seals when
// every rim ray hits the part, the hits lie within compliance_mm of their least-squares plane and
// no perimeter spring (between neighbouring hits, rest length 2 r sin(pi / n)) stretches or
// shrinks by more than `stretch`; its seal score is 1 - max(plane distance / compliance,
// stretch / cup.stretch), and the cup's body (from 0.5 mm above the rim's highest hit) and shaft
// must be free of the part (FCL). Wrench: the part hanging under the cup with a vertical, weight
// F = m g, moment M = F |com - c projected off a|; the rim stays pressed while
// F + 2 M / r < V = vacuum x pi r^2, and the score is 1 - (F + 2 M / r) / V. Kept when both
// scores are above 0. A part whose volume is unknown (an open mesh, MassProperties volume 0) has
// no weight here: every wrench score is 1 (the pipeline warns). Throws Error for impossible
// options or a part without triangles.
std::vector<SuctionGrasp> SampleSuctionGrasps(const Part& part, const SuctionCup& cup,
                                              const SuctionOptions& options);

// The seal of the cup at c approaching along a (unit) on `part`, as SampleSuctionGrasps judges
// it: the seal score (> 0: sealed), or a value <= 0 when it does not seal (-1: the rim falls off
// the part or c is hidden). For tests and previews.
double SuctionSeal(const Part& part, const SuctionCup& cup, const Eigen::Vector3d& c,
                   const Eigen::Vector3d& a);

}  // namespace cadsynth
