// Parallel-jaw grasps from CAD (issue 19): antipodal contact pairs sampled on a part's exact
// mesh, the gripper's geometry checked free of the part with FCL (Debian's libfcl-dev, the
// collision library MoveIt uses).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "cad/part.h"

namespace cadsynth {

// A parallel-jaw gripper in its own frame, as ACRONYM and 6-DOF GraspNet define it: the origin at
// the hand's base, +z the approach direction, the fingers closing along x, symmetric about the
// y-z plane. All lengths in mm.
//   palm:    a box centred on the z axis from z = 0 to palm_height_mm, palm_width_mm along x,
//            palm_depth_mm along y;
//   fingers: two boxes finger_thickness_mm (x) by finger_width_mm (y) by finger_length_mm (z),
//            from palm_height_mm to tip_mm = palm_height_mm + finger_length_mm, their inner faces
//            at x = +-opening / 2;
//   pad:     a grasp's contacts sit on the fingers' inner faces pad_mm below the tips.
struct ParallelJawGripper {
  std::string name = "franka";
  double max_opening_mm = 80.0;
  double finger_width_mm = 20.0;
  double finger_thickness_mm = 10.0;
  double finger_length_mm = 46.2;
  double palm_height_mm = 66.0;
  double palm_width_mm = 204.0;
  double palm_depth_mm = 63.2;
  double pad_mm = 8.8;

  bool Check(std::string* why) const;
  double tip_mm() const { return palm_height_mm + finger_length_mm; }

  // The Franka Emika hand of ACRONYM and 6-DOF GraspNet (NVlabs/acronym's gripper marker and
  // collision mesh: fingers at x = +-41 mm from z = 66 to 112.2 mm, the hand +-102 x +-31.6 mm;
  // Contact-GraspNet's control points put the pad centre at z = 103.4 mm), 80 mm opening.
  static ParallelJawGripper Franka();
};

struct AntipodalOptions {
  double friction = 0.5;      // Coulomb's mu at the contacts
  int samples = 2000;         // surface points tried
  int approaches = 8;         // approach directions tried about each contact pair's axis
  double clearance_mm = 1.0;  // the open fingers' inner faces this far outside the part's reach
  uint64_t seed = 0;

  bool Check(std::string* why) const;
};

// One grasp of a part, in its model frame.
struct ParallelJawGrasp {
  Eigen::Isometry3d model_from_gripper = Eigen::Isometry3d::Identity();
  double width_mm = 0;          // the distance between the contacts along x
  Eigen::Vector3d contacts[2];  // model frame, mm
  Eigen::Vector3d normals[2];   // outward surface normals at the contacts
  // The force-closure margin: 1 - (angle between the closing axis and the second contact's
  // inward normal) / atan(mu); the first contact's normal is the axis itself (angle 0). 1: the
  // two normals are exactly opposite; 0: on the edge of the friction cone.
  double quality = 0;
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
