#include "variants/grasp/scene_grasps.h"

#include <cstdint>
#include <map>
#include <memory>

#include <fcl/broadphase/broadphase_dynamic_AABB_tree.h>
#include <fcl/geometry/shape/halfspace.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/collision_object.h>
#include <tbb/parallel_for.h>

#include "cad/core/error.h"
#include "variants/grasp/grasp_geometry.h"

namespace cadsynth {

namespace {

// The scene for FCL: the fixtures and instances in one dynamic AABB tree (an object's user data
// is its tag: instance index + 1, or 0 for a fixture), the floor's half-space beside it (its
// infinite bounding box would break the tree's construction).
class SceneCollider {
 public:
  explicit SceneCollider(const GraspObstacles& scene) {
    if (scene.floor) {
      floor_ = std::make_unique<fcl::CollisionObjectd>(
          std::make_shared<fcl::Halfspaced>(fcl::Vector3d::UnitZ(), 0.0),
          fcl::Transform3d::Identity());
    }
    for (const Mesh* fixture : scene.fixtures) {
      if (fixture != nullptr && !fixture->triangles.empty())
        Add(grasp_detail::FclMesh(*fixture), Eigen::Isometry3d::Identity(), 0);
    }
    std::map<const Mesh*, std::shared_ptr<fcl::BVHModel<fcl::OBBd>>> models;
    for (size_t i = 0; i < scene.instances.size(); ++i) {
      const GraspObstacles::Body& body = scene.instances[i];
      if (body.mesh == nullptr || body.mesh->triangles.empty()) continue;
      auto& model = models[body.mesh];
      if (!model) model = grasp_detail::FclMesh(*body.mesh);
      Add(model, body.world_from_model, static_cast<intptr_t>(i) + 1);
    }
    std::vector<fcl::CollisionObjectd*> pointers;
    for (const auto& object : objects_) pointers.push_back(object.get());
    if (!pointers.empty()) {
      manager_.registerObjects(pointers);
      manager_.setup();
    }
  }

  // Whether any of `tool`'s shapes at world_from_tool hits an obstacle other than instance
  // `skip` (-1: none skipped).
  bool Hits(const std::vector<grasp_detail::ToolShape>& tool,
            const Eigen::Isometry3d& world_from_tool, int skip) const {
    for (const grasp_detail::ToolShape& shape : tool) {
      fcl::CollisionObjectd object(shape.shape, world_from_tool * shape.pose);
      object.setUserData(nullptr);  // FCL leaves it uninitialised
      if (floor_) {
        fcl::CollisionRequestd request;
        fcl::CollisionResultd result;
        fcl::collide(floor_.get(), &object, request, result);
        if (result.isCollision()) return true;
      }
      Query query{static_cast<intptr_t>(skip) + 1, false};
      manager_.collide(&object, &query, &Callback);
      if (query.hit) return true;
    }
    return false;
  }

 private:
  struct Query {
    intptr_t skip;  // the tag not to test
    bool hit;
  };

  static bool Callback(fcl::CollisionObjectd* a, fcl::CollisionObjectd* b, void* data) {
    Query& query = *static_cast<Query*>(data);
    if (query.hit) return true;
    // One of the two is the tool (no user data); the other the obstacle.
    const intptr_t tag =
        reinterpret_cast<intptr_t>(a->getUserData()) + reinterpret_cast<intptr_t>(b->getUserData());
    if (query.skip > 0 && tag == query.skip) return false;
    fcl::CollisionRequestd request;
    fcl::CollisionResultd result;
    fcl::collide(a, b, request, result);
    query.hit = result.isCollision();
    return query.hit;
  }

  void Add(std::shared_ptr<fcl::CollisionGeometryd> geometry, const Eigen::Isometry3d& pose,
           intptr_t tag) {
    auto object = std::make_unique<fcl::CollisionObjectd>(std::move(geometry), pose);
    object->setUserData(reinterpret_cast<void*>(tag));
    objects_.push_back(std::move(object));
  }

  std::unique_ptr<fcl::CollisionObjectd> floor_;
  std::vector<std::unique_ptr<fcl::CollisionObjectd>> objects_;
  fcl::DynamicAABBTreeCollisionManagerd manager_;
};

// Places every instance's grasps: `pose(grasp)` is the tool frame in the model frame; `tool(grasp,
// back)` the tool's shapes at the grasp (back 0: tested against all but the instance itself) and
// swept back by `approach_mm` (tested against everything).
template <typename Grasp, typename Pose, typename Tool>
std::vector<PlacedGrasp> Place(const GraspObstacles& scene,
                               const std::vector<std::vector<Grasp>>& part_grasps,
                               double approach_mm, const Pose& pose, const Tool& tool) {
  for (const GraspObstacles::Body& body : scene.instances) {
    if (body.part < 0 || static_cast<size_t>(body.part) >= part_grasps.size())
      throw Error("grasps: an instance names part " + std::to_string(body.part) + " of " +
                  std::to_string(part_grasps.size()));
  }
  const SceneCollider collider(scene);
  std::vector<std::vector<PlacedGrasp>> per_instance(scene.instances.size());
  tbb::parallel_for(size_t{0}, scene.instances.size(), [&](size_t i) {
    const GraspObstacles::Body& body = scene.instances[i];
    const std::vector<Grasp>& grasps = part_grasps[static_cast<size_t>(body.part)];
    for (size_t g = 0; g < grasps.size(); ++g) {
      const Eigen::Isometry3d world_from_tool = body.world_from_model * pose(grasps[g]);
      if (collider.Hits(tool(grasps[g], 0.0), world_from_tool, static_cast<int>(i))) continue;
      PlacedGrasp placed;
      placed.instance = static_cast<int>(i);
      placed.grasp = static_cast<int>(g);
      placed.approach_blocked =
          approach_mm > 0 && collider.Hits(tool(grasps[g], approach_mm), world_from_tool, -1);
      per_instance[i].push_back(placed);
    }
  });
  std::vector<PlacedGrasp> placed;
  for (const auto& list : per_instance) placed.insert(placed.end(), list.begin(), list.end());
  return placed;
}

void CheckOptions(const SceneGraspOptions& options) {
  std::string why;
  if (!options.Check(&why)) throw Error("grasps: " + why);
}

}  // namespace

bool SceneGraspOptions::Check(std::string* why) const {
  if (!(approach_mm >= 0 && approach_mm <= 10000)) {
    *why = "approach distance must lie in [0, 10000] mm";
    return false;
  }
  return true;
}

std::vector<PlacedGrasp> PlaceParallelJawGrasps(
    const GraspObstacles& scene, const std::vector<std::vector<ParallelJawGrasp>>& part_grasps,
    const ParallelJawGripper& gripper, const SceneGraspOptions& options) {
  CheckOptions(options);
  std::string why;
  if (!gripper.Check(&why)) throw Error("gripper '" + gripper.name + "': " + why);
  // The fingers opened as the sampler checked them. The way in: the gripper swept back from the
  // grasp; its own part cannot be hit at the grasp (the sampler checked that), but can be on the
  // way in.
  return Place(
      scene, part_grasps, options.approach_mm,
      [](const ParallelJawGrasp& g) { return g.model_from_gripper; },
      [&](const ParallelJawGrasp& g, double back) {
        return grasp_detail::GripperShapes(gripper, g.opening_mm, back);
      });
}

Eigen::Isometry3d ModelFromSuctionTool(const SuctionGrasp& grasp) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = grasp_detail::FrameFromZ(grasp.approach.normalized());
  pose.translation() = grasp.point;
  return pose;
}

std::vector<PlacedGrasp> PlaceSuctionGrasps(
    const GraspObstacles& scene, const std::vector<std::vector<SuctionGrasp>>& part_grasps,
    const SuctionCup& cup, const SceneGraspOptions& options) {
  CheckOptions(options);
  std::string why;
  if (!cup.Check(&why)) throw Error("suction cup '" + cup.name + "': " + why);
  // At the grasp the cup's rim touches its own part: the others are tested from the rim up (the
  // sampler checked its own part). On the way in, the tool starts clear of the sealed rim (its
  // highest point + 0.5 mm) and is tested against its own part too.
  // Shapes are built per grasp: FCL writes a shape's bounding box when an object is made of it,
  // so threads must not share them.
  return Place(scene, part_grasps, options.approach_mm, ModelFromSuctionTool,
               [&](const SuctionGrasp& g, double back) {
                 return back > 0 ? grasp_detail::SuctionShapes(
                                       cup, g.rim_height_mm + grasp_detail::kRimClearanceMm, back)
                                 : grasp_detail::SuctionShapes(cup, 0.0);
               });
}

}  // namespace cadsynth
