// Per-frame grasp labels (issue 19): a scene's collision-free grasps (variants/grasp/) in each
// frame's camera, as GraspNet-1Billion's and SuctionNet-1Billion's APIs read grasps, with which
// instance each belongs to, whether its way in is blocked and whether its contacts are seen.
#pragma once

#include <filesystem>
#include <vector>

#include <Eigen/Core>

#include "cad/core/schema.h"
#include "cad/grasp.h"
#include "dataset/frame_writer.h"
#include "render/frame.h"

namespace cadsynth {

struct GraspLabelOptions {
  bool graspnet = true;     // parallel-jaw rows: DIR/graspnet/SCENE/IMAGE.npy
  bool suctionnet = false;  // suction rows: DIR/suctionnet/SCENE/IMAGE.npy
  // Per frame and visible instance, the best grasps by quality (ties: in the part's order); 0:
  // all of them.
  int max_per_instance = 100;
  // A contact counts as seen when a pixel of the 3 x 3 around its projection shows its instance
  // with a depth within this of the contact's.
  double visibility_mm = 3.0;
  bool Check(std::string* why) const;

  // Every field, once (cad/core/schema.h): keys of the recipe's `grasps` section, the run key.
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.graspnet, Field{"", "bool", "grasps.formats: graspnet", {}, true, "graspnet"});
    visit(o.suctionnet, Field{"", "bool", "grasps.formats: suctionnet", {}, true, "suctionnet"});
    visit(o.max_per_instance,
          Field{"per_instance", "integer", "per frame and visible instance, the best this many"});
    visit(o.visibility_mm, Field{"visibility_tolerance", "length",
                                 "a contact is seen when its instance shows within this depth"});
  }
};

// One scene's grasps, as the writer reads them. The pointers must outlive the writer.
struct SceneGrasps {
  std::vector<int> part_of_instance;    // Scene::instances order
  std::vector<int> obj_id_of_instance;  // BOP obj_id
  ParallelJawGripper gripper;
  const std::vector<std::vector<ParallelJawGrasp>>* jaw = nullptr;  // per part, model frame
  std::vector<PlacedGrasp> jaw_placed;
  SuctionCup cup;
  const std::vector<std::vector<SuctionGrasp>>* suction = nullptr;
  std::vector<PlacedGrasp> suction_placed;
};

// Whether camera-frame point `p` (mm) on instance `instance` is seen in `frame` (see
// GraspLabelOptions::visibility_mm).
bool PointSeen(const Frame& frame, int instance, const Eigen::Vector3d& p, double tolerance_mm);

// The frame's parallel-jaw rows, graspnetAPI's GraspGroup layout, 17 float32 each: score (the
// force-closure margin), width (m, the fingers' opening the grasp was checked free with: the
// contacts' distance plus the clearance on each side), height (m, the finger's width), depth
// (m, the contacts to the fingertips, the grasp's depth), the rotation row-major (columns:
// approach, closing direction, their cross product, in the camera frame), the translation (m,
// camera frame: `depth` back along the approach from the contacts' midpoint, so that
// translation + depth * approach is where graspnetAPI's evaluator closes the jaws) and the BOP
// obj_id. `labels` gets 6 per row: instance index
// (BOP scene_gt order), obj_id, approach blocked (0/1), first and second contact seen (0/1), the
// grasp's index in its object's ACRONYM file. Visible instances only (in instance order).
std::vector<float> GraspNetRows(const Frame& frame, const SceneGrasps& grasps,
                                const GraspLabelOptions& options, std::vector<float>* labels);

// The frame's suction rows, SuctionNet's SuctionGroup layout, 8 float32 each: score (seal x
// wrench), the direction (unit, camera frame: the outward surface normal, along which the cup
// comes in backwards), the contact point (m, camera frame), the BOP obj_id. `labels` gets 6 per
// row: instance index, obj_id, approach blocked, contact seen, seal score, wrench score.
std::vector<float> SuctionNetRows(const Frame& frame, const SceneGrasps& grasps,
                                  const GraspLabelOptions& options, std::vector<float>* labels);

class GraspLabelWriter : public FrameWriter {
 public:
  GraspLabelWriter(const std::filesystem::path& root, int scene_id, GraspLabelOptions options,
                   SceneGrasps grasps);
  // DIR/graspnet/SCENE/IMAGE.npy (N, 17) and IMAGE_labels.npy (N, 6); the same under
  // DIR/suctionnet/ with (N, 8) and (N, 6).
  void WriteFrame(int image_id, const Frame& frame, const BopFrameFiles& bop,
                  FileLog* files) const override;

 private:
  std::filesystem::path graspnet_dir_, suctionnet_dir_;
  GraspLabelOptions options_;
  SceneGrasps grasps_;
};

}  // namespace cadsynth
