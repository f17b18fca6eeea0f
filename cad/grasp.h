// Grasp vocabulary (issue 19): grippers as data and the grasps of a part, plain structs shared
// by the sampler (variants/grasp/), the writers (dataset/) and the recipe reader. Lengths in mm.
#pragma once

#include <string>
#include "cad/core/schema.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace cadsynth {

// A parallel-jaw gripper in its own frame, as ACRONYM and 6-DOF GraspNet define it: the origin at
// the hand's base, +z the approach direction, the fingers closing along x, symmetric about the
// y-z plane. A box model:
//   palm:    a box centred on the z axis from z = 0 to palm_height_mm, palm_width_mm along x,
//            palm_depth_mm along y;
//   fingers: two boxes finger_thickness_mm (x) by finger_width_mm (y) by finger_length_mm (z),
//            from palm_height_mm to tip_mm = palm_height_mm + finger_length_mm, their inner faces
//            at x = +-opening / 2;
//   pad:     a grasp's contacts sit on the fingers' inner faces pad_mm below the tips (the
//            default grasp depth; AntipodalOptions::depths_mm may give others).
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
  bool operator==(const ParallelJawGripper&) const = default;
  double tip_mm() const { return palm_height_mm + finger_length_mm; }

  // Every field, once (cad/core/schema.h): the recipe's `grasps.gripper` section, the run key.
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.name, Field{"name", "text", "its name in the grasp files"});
    visit(o.max_opening_mm, Field{"max_opening", "length", "the widest opening of the jaws"});
    visit(o.finger_width_mm,
          Field{"finger_width", "length", "finger size across the closing direction"});
    visit(o.finger_thickness_mm,
          Field{"finger_thickness", "length", "finger size along the closing direction"});
    visit(o.finger_length_mm, Field{"finger_length", "length", "finger length"});
    visit(o.palm_height_mm, Field{"palm_height", "length", "palm size along the approach"});
    visit(o.palm_width_mm, Field{"palm_width", "length", "palm size along the closing direction"});
    visit(o.palm_depth_mm, Field{"palm_depth", "length", "palm size across"});
    visit(o.pad_mm, Field{"pad", "length", "the pads' length at the fingertips"});
  }

  // The Franka Emika hand of ACRONYM and 6-DOF GraspNet (NVlabs/acronym's gripper marker and
  // collision mesh: fingers at x = +-41 mm from z = 66 to 112.2 mm, the hand +-102 x +-31.6 mm;
  // Contact-GraspNet's control points put the pad centre at z = 103.4 mm), 80 mm opening.
  static ParallelJawGripper Franka();
  // The Robotiq 2F-85 as boxes around its open linkage: 85 mm stroke, 22 mm wide pads, the tips
  // 163 mm from the coupling (Robotiq's open height) and the grasp point 155 mm (rai-robotModels'
  // gripper marker), the body and knuckles a 110 x 76 mm box up to 100 mm. Approximate: the real
  // fingers swing on four-bar linkages; this is their envelope when open.
  static ParallelJawGripper Robotiq2F85();
};

// A suction cup on a straight tool, as Dex-Net 3.0 models it: a ring of contact points (the
// cup's rim, ring_points of them on a circle of diameter_mm) projected along the approach onto
// the surface, joined by perimeter springs and carried by a compliant bellows. The tool: the cup
// (diameter_mm wide, cup_length_mm long) then a shaft (shaft_diameter_mm, shaft_length_mm)
// straight behind it along -approach.
struct SuctionCup {
  std::string name = "cup20";
  double diameter_mm = 20.0;   // SuctionNet-1Billion's cup: radius 10 mm
  int ring_points = 16;        // rim contacts (Dex-Net 3.0: 8; SuctionNet: 72-bin rings)
  double compliance_mm = 2.0;  // the bellows' give: the rim's largest distance off a plane
  double stretch = 0.1;        // perimeter springs: the largest relative stretch (Dex-Net: 10%)
  double vacuum_kpa = 80.0;    // the pressure difference the vacuum holds
  double cup_length_mm = 20.0;
  double shaft_diameter_mm = 12.0;
  double shaft_length_mm = 100.0;

  bool Check(std::string* why) const;
  double radius_mm() const { return 0.5 * diameter_mm; }

  // Every field, once (cad/core/schema.h): the recipe's `grasps.suction` section, the run key.
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.name, Field{"name", "text", "its name in the grasp files"});
    visit(o.diameter_mm, Field{"diameter", "length", "the cup's rim diameter"});
    visit(o.ring_points, Field{"ring_points", "integer", "contacts on the rim (3-360)"});
    visit(o.compliance_mm, Field{"compliance", "length",
                                 "the bellows' give: the rim's largest distance off a plane"});
    visit(o.stretch, Field{"stretch", "number", "the rim springs' largest relative stretch"});
    visit(o.vacuum_kpa, Field{"vacuum", "number", "the pressure difference held (kPa)"});
    visit(o.cup_length_mm, Field{"cup_length", "length", "the cup's length"});
    visit(o.shaft_diameter_mm, Field{"shaft_diameter", "length", "the shaft's diameter"});
    visit(o.shaft_length_mm, Field{"shaft_length", "length", "the shaft's length"});
  }
  // The vacuum's pull, V = dP pi a^2, in newtons.
  double vacuum_force_n() const;
};

// One parallel-jaw grasp of a part, in its model frame.
struct ParallelJawGrasp {
  Eigen::Isometry3d model_from_gripper = Eigen::Isometry3d::Identity();
  double width_mm = 0;    // the distance between the contacts along x
  double opening_mm = 0;  // the fingers' opening the grasp was checked with
  double depth_mm = 0;    // the fingertips' reach past the contacts along the approach
  // Whether the hand is also free of the part fully open (max_opening_mm), as ACRONYM's grasps
  // are tried: its files mark the others as failures.
  bool free_when_open = false;
  Eigen::Vector3d contacts[2] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};  // model, mm
  Eigen::Vector3d normals[2] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};   // outward
  // The force-closure margin: 1 - angle / atan(mu), the angle between the closing axis (from the
  // first contact to the second) and the second contact's outward normal; the first contact's
  // inward normal is the axis itself (angle 0). 1: the two normals are exactly opposite; 0: on
  // the edge of the friction cone.
  double quality = 0;
};

// One suction grasp of a part, in its model frame: the cup's centre touches `point` moving along
// `approach` (unit, into the surface: minus the outward normal for a head-on grasp).
struct SuctionGrasp {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d approach = -Eigen::Vector3d::UnitZ();
  // Seal: 1 - max(rim's distance off its best plane / compliance, largest perimeter stretch /
  // stretch); in (0, 1] for a seal.
  double seal = 0;
  // Wrench against gravity with the approach vertical (the part hanging under the cup):
  // 1 - (m g + 2 M / a) / V, M the moment of the weight about the contact, a the cup's radius;
  // above 0 the rim stays pressed all round (see docs/formats.md, "Grasp labels").
  double wrench = 0;
  // The rim's highest point above `point` towards the cup (mm; 0 on a flat face): the cup's body
  // clears the part from there up.
  double rim_height_mm = 0;
  double quality() const { return seal * wrench; }
};

// Where a part's grasp lands in a scene: instance `instance` (Scene::instances order), grasp
// `grasp` of that part's list; approach_blocked: the tool, moved back along -approach by the
// scene's approach distance, hits something on the way in.
struct PlacedGrasp {
  int instance = 0;
  int grasp = 0;
  bool approach_blocked = false;
};

}  // namespace cadsynth
