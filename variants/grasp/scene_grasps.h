// Grasps in a scene (issue 19): each part's grasps placed on every instance of it, those whose
// tool hits the floor, a fixture (tote, distractor) or another instance removed, and those whose
// way in is blocked marked so. FCL's dynamic AABB tree over the scene, its BVH meshes and shapes.
#pragma once

#include <vector>

#include <Eigen/Geometry>

#include "cad/core/schema.h"
#include "cad/grasp.h"
#include "cad/mesh.h"

namespace cadsynth {

// What a tool may hit, in the world frame (mm). The pointers must outlive the call.
struct GraspObstacles {
  bool floor = true;                  // the half-space z <= 0
  std::vector<const Mesh*> fixtures;  // world-frame meshes: totes, distractors
  struct Body {
    const Mesh* mesh = nullptr;  // in its model frame
    Eigen::Isometry3d world_from_model = Eigen::Isometry3d::Identity();
    int part = 0;  // index into the per-part grasp lists
  };
  std::vector<Body> instances;  // Scene::instances order
};

struct SceneGraspOptions {
  // How far back along -approach the tool must come in from: the swept tool hitting anything
  // (its own instance included) marks the grasp's approach blocked.
  double approach_mm = 100.0;
  bool Check(std::string* why) const;

  // Every field, once (cad/core/schema.h): keys of the recipe's `grasps` section, the run key.
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.approach_mm, Field{"approach_distance", "length",
                               "the tool swept back this far must be free, else approach blocked"});
  }
};

// Every instance's parallel-jaw grasps (part_grasps[part]) that leave the open gripper free of
// the floor, the fixtures and the other instances, in instance then grasp order. The same inputs
// give the same list on any number of threads.
std::vector<PlacedGrasp> PlaceParallelJawGrasps(
    const GraspObstacles& scene, const std::vector<std::vector<ParallelJawGrasp>>& part_grasps,
    const ParallelJawGripper& gripper, const SceneGraspOptions& options);

// The same for suction grasps: the cup and shaft free of the floor, fixtures and other instances.
std::vector<PlacedGrasp> PlaceSuctionGrasps(
    const GraspObstacles& scene, const std::vector<std::vector<SuctionGrasp>>& part_grasps,
    const SuctionCup& cup, const SceneGraspOptions& options);

// The pose of a suction grasp's tool frame in the model frame: origin at the contact, +z the
// approach (SuctionShapes' frame).
Eigen::Isometry3d ModelFromSuctionTool(const SuctionGrasp& grasp);

}  // namespace cadsynth
