// Parallel-jaw grasps from CAD (issue 19): antipodal contact pairs sampled on a part's exact
// mesh, the gripper's geometry checked free of the part with FCL (Debian's libfcl-dev, the
// collision library MoveIt uses).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "cad/core/schema.h"
#include "cad/grasp.h"
#include "cad/part.h"

namespace cadsynth {

struct AntipodalOptions {
  double friction = 0.5;  // Coulomb's mu at the contacts
  int samples = 2000;     // surface points tried
  int approaches = 8;     // approach directions tried about each contact pair's axis
  // The fingers open to the grasp's width plus this on each side (within the gripper's maximum),
  // as a controller opens them before closing.
  double clearance_mm = 5.0;
  // Grasp depths: how far the fingertips reach past the contacts (GraspNet samples 10 to 40 mm).
  // Each contact pair and approach is tried at each; empty: the gripper's pad_mm only.
  std::vector<double> depths_mm;
  // Stop once this many grasps are kept (0: no limit): the first in sampling order, a uniform
  // subset of what all the samples would give.
  int max_grasps = 0;
  uint64_t seed = 0;

  bool Check(std::string* why) const;

  // Every field, once (cad/core/schema.h): keys of the recipe's `grasps` section, the run key.
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.friction, Field{"friction", "number", "Coulomb's mu at the contacts"});
    visit(o.samples, Field{"samples", "integer", "surface points tried per object"});
    visit(o.max_grasps, Field{"per_part", "integer",
                              "keep at most this many grasps per object and cup (0: all)"});
    visit(o.approaches,
          Field{"approaches", "integer", "approach directions about each contact pair's axis"});
    visit(o.clearance_mm,
          Field{"clearance", "length", "fingers open to the grasp's width plus this on each side"});
    visit(o.depths_mm, Field{"depths",
                             "lengths",
                             "fingertips' reach past the contacts (default: the gripper's pad)",
                             {},
                             true});
    visit(o.seed, Field{"seed", "integer", "the sampling's seed"});
  }
};

// Samples antipodal grasps of `part` (a closed, outward-wound mesh): a surface point drawn by
// area, the closing axis along its inward normal, the part's far side where the axis leaves it
// (the second contact), kept when the second contact's normal lies inside the friction cone about
// the axis, the width plus twice the clearance is within the opening, and the gripper, opened to
// that, is free of the part at that approach (FCL: the part's triangles against the palm's and
// fingers' boxes). Same options, same grasps, in the order sampled. Throws Error for impossible
// options or a part without triangles.
std::vector<ParallelJawGrasp> SampleAntipodalGrasps(const Part& part,
                                                    const ParallelJawGripper& gripper,
                                                    const AntipodalOptions& options);

}  // namespace cadsynth
