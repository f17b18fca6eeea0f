// Parallel-jaw grasps from CAD (issue 19): antipodal contact pairs sampled on a part's exact
// mesh, the gripper's geometry checked free of the part with FCL (Debian's libfcl-dev, the
// collision library MoveIt uses).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "cad/grasp.h"
#include "cad/part.h"

namespace cadsynth {

struct AntipodalOptions {
  double friction = 0.5;      // Coulomb's mu at the contacts
  int samples = 2000;         // surface points tried
  int approaches = 8;         // approach directions tried about each contact pair's axis
  double clearance_mm = 1.0;  // the open fingers' inner faces this far outside the part's reach
  uint64_t seed = 0;

  bool Check(std::string* why) const;
};

// Samples antipodal grasps of `part` (a closed, outward-wound mesh): a surface point drawn by
// area, the closing axis along its inward normal, the part's far side where the axis leaves it
// (the second contact), kept when the second contact's normal lies inside the friction cone about
// the axis, the width is within the opening, and the gripper, open to its full width, is free of
// the part at that approach (FCL: the part's triangles against the palm's and fingers' boxes).
// Same options, same grasps, in the order sampled. Throws Error for impossible options or a part
// without triangles.
std::vector<ParallelJawGrasp> SampleAntipodalGrasps(const Part& part,
                                                    const ParallelJawGripper& gripper,
                                                    const AntipodalOptions& options);

}  // namespace cadsynth
