// Grasps in a scene, checked by a test that does not use the sampler's collision code: CGAL's
// exact triangle-box predicate on the gripper's boxes, rebuilt here from the gripper's sizes.
#include "variants/grasp/scene_grasps.h"

#include <cmath>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "cad/core/error.h"
#include "cad/shape.h"
#include "variants/grasp/parallel_jaw.h"
#include "variants/grasp/suction.h"

namespace cadsynth {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;

// An axis-aligned box in a local frame: local = frame_from_world * world.
struct LocalBox {
  Eigen::Isometry3d frame_from_world;
  Eigen::Vector3d lo, hi;
};

// The parallel-jaw gripper's boxes at world_from_gripper, opened to `opening`, stretched `back`
// along -z and grown by `grow` mm on every side (negative: shrunk).
std::vector<LocalBox> JawBoxes(const ParallelJawGripper& g, double opening, double back,
                               const Eigen::Isometry3d& world_from_gripper, double grow) {
  const Eigen::Isometry3d inverse = world_from_gripper.inverse();
  const double half = 0.5 * opening, w = 0.5 * g.finger_width_mm;
  const double z0 = g.palm_height_mm - back, z1 = g.tip_mm();
  std::vector<LocalBox> boxes = {
      {inverse, {half, -w, z0}, {half + g.finger_thickness_mm, w, z1}},
      {inverse, {-half - g.finger_thickness_mm, -w, z0}, {-half, w, z1}},
      {inverse,
       {-0.5 * g.palm_width_mm, -0.5 * g.palm_depth_mm, -back},
       {0.5 * g.palm_width_mm, 0.5 * g.palm_depth_mm, g.palm_height_mm}}};
  for (LocalBox& b : boxes) {
    b.lo.array() -= grow;
    b.hi.array() += grow;
  }
  return boxes;
}

bool BoxHitsMesh(const LocalBox& box, const Mesh& mesh, const Eigen::Isometry3d& world_from_mesh) {
  const K::Iso_cuboid_3 cuboid(K::Point_3(box.lo.x(), box.lo.y(), box.lo.z()),
                               K::Point_3(box.hi.x(), box.hi.y(), box.hi.z()));
  const Eigen::Isometry3d local = box.frame_from_world * world_from_mesh;
  const auto point = [&](uint32_t i) {
    const Eigen::Vector3d p = local * mesh.positions[i].cast<double>();
    return K::Point_3(p.x(), p.y(), p.z());
  };
  for (const auto& t : mesh.triangles) {
    if (CGAL::do_intersect(K::Triangle_3(point(t[0]), point(t[1]), point(t[2])), cuboid))
      return true;
  }
  return false;
}

bool BoxBelowFloor(const LocalBox& box) {
  const Eigen::Isometry3d world_from_box = box.frame_from_world.inverse();
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d local(corner & 1 ? box.hi.x() : box.lo.x(),
                                corner & 2 ? box.hi.y() : box.lo.y(),
                                corner & 4 ? box.hi.z() : box.lo.z());
    if ((world_from_box * local).z() < 0) return true;
  }
  return false;
}

// The test scene: a 40 mm cube on the floor, a rod (30 mm across, 120 long) lying beside it 10 mm
// away, a second cube 20 mm away on the other side, a wall (a fixture) 100 mm behind them, and a
// plate (another fixture) 130 mm over the second cube.
struct TestScene {
  std::vector<Part> parts;
  Mesh wall, plate;
  GraspObstacles obstacles;

  TestScene() {
    parts.push_back(MakePart("cube", MakeBox(40, 40, 40), TessellationOptions{}));
    parts.push_back(MakePart("rod", MakeCylinder(15, 120), TessellationOptions{}));
    wall = MakePart("wall", MakeBox(10, 200, 100), TessellationOptions{}).mesh;
    wall.Transform(Eigen::Isometry3d(Eigen::Translation3d(-125, 0, 50)));
    plate = MakePart("plate", MakeBox(60, 60, 10), TessellationOptions{}).mesh;
    plate.Transform(Eigen::Isometry3d(Eigen::Translation3d(0, -60, 175)));
    obstacles.floor = true;
    obstacles.fixtures = {&wall, &plate};
    Eigen::Isometry3d rod = Eigen::Isometry3d::Identity();
    rod.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
    rod.translation() = Eigen::Vector3d(10, 45, 15);
    obstacles.instances = {
        {&parts[0].mesh, Eigen::Isometry3d(Eigen::Translation3d(0, 0, 20)), 0},
        {&parts[1].mesh, rod, 1},
        {&parts[0].mesh, Eigen::Isometry3d(Eigen::Translation3d(0, -60, 20)), 0}};
  }
};

TEST(SceneGrasps, KeptExactlyWhenTheGripperIsFreeOfTheScene) {
  const TestScene scene;
  const ParallelJawGripper franka = ParallelJawGripper::Franka();
  AntipodalOptions o;
  o.samples = 60;
  o.approaches = 8;
  o.depths_mm = {3, 8.8, 20};
  std::vector<std::vector<ParallelJawGrasp>> grasps;
  for (const Part& part : scene.parts) grasps.push_back(SampleAntipodalGrasps(part, franka, o));
  SceneGraspOptions options;
  options.approach_mm = 50;
  const std::vector<PlacedGrasp> placed =
      PlaceParallelJawGrasps(scene.obstacles, grasps, franka, options);
  size_t next = 0, kept = 0, removed = 0, blocked = 0;
  for (size_t i = 0; i < scene.obstacles.instances.size(); ++i) {
    const GraspObstacles::Body& body = scene.obstacles.instances[i];
    const auto& list = grasps[static_cast<size_t>(body.part)];
    for (size_t g = 0; g < list.size(); ++g) {
      const bool is_kept = next < placed.size() && placed[next].instance == static_cast<int>(i) &&
                           placed[next].grasp == static_cast<int>(g);
      const Eigen::Isometry3d pose = body.world_from_model * list[g].model_from_gripper;
      // Whether the boxes (grown by `grow`, stretched by `back`) hit the floor, the wall or
      // another instance (or, with `own`, this one).
      const auto hits = [&](double back, double grow, bool own) {
        for (const LocalBox& box : JawBoxes(franka, list[g].opening_mm, back, pose, grow)) {
          if (BoxBelowFloor(box) || BoxHitsMesh(box, scene.wall, Eigen::Isometry3d::Identity()) ||
              BoxHitsMesh(box, scene.plate, Eigen::Isometry3d::Identity()))
            return true;
          for (size_t j = 0; j < scene.obstacles.instances.size(); ++j) {
            if (j == i && !own) continue;
            const GraspObstacles::Body& other = scene.obstacles.instances[j];
            if (BoxHitsMesh(box, *other.mesh, other.world_from_model)) return true;
          }
        }
        return false;
      };
      if (is_kept) {
        ++kept;
        EXPECT_FALSE(hits(0, -0.01, false)) << "kept grasp " << g << " of instance " << i;
        if (placed[next].approach_blocked) {
          ++blocked;
          EXPECT_TRUE(hits(options.approach_mm, 0.01, true)) << i << " " << g;
        } else {
          EXPECT_FALSE(hits(options.approach_mm, -0.01, true)) << i << " " << g;
        }
        ++next;
      } else {
        ++removed;
        EXPECT_TRUE(hits(0, 0.01, false)) << "removed grasp " << g << " of instance " << i;
      }
    }
  }
  EXPECT_EQ(next, placed.size());
  // Not vacuous: the floor, the wall and the neighbours remove some, some are kept, some blocked.
  EXPECT_GT(kept, 50u);
  EXPECT_GT(removed, 50u);
  EXPECT_GT(blocked, 0u);
  EXPECT_LT(blocked, kept);
  // The same list on one thread.
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  const std::vector<PlacedGrasp> again =
      PlaceParallelJawGrasps(scene.obstacles, grasps, franka, options);
  ASSERT_EQ(again.size(), placed.size());
  for (size_t k = 0; k < placed.size(); ++k) {
    EXPECT_EQ(again[k].instance, placed[k].instance);
    EXPECT_EQ(again[k].grasp, placed[k].grasp);
    EXPECT_EQ(again[k].approach_blocked, placed[k].approach_blocked);
  }
}

TEST(SceneGrasps, SuctionCupsAreKeptWhereTheToolIsFree) {
  // The first cube's top face: the cup comes straight down and is free; its side facing the rod
  // (10 mm away) leaves no room for the cup, that facing the second cube (20 mm) none for the
  // cup and shaft; its bottom lies on the floor. The second cube's top is free (the shaft ends
  // 10 mm under the plate), but its way in is blocked by the plate.
  const TestScene scene;
  const SuctionCup cup;
  SuctionOptions o;
  o.samples = 400;
  std::vector<std::vector<SuctionGrasp>> grasps = {SampleSuctionGrasps(scene.parts[0], cup, o), {}};
  SceneGraspOptions options;
  const std::vector<PlacedGrasp> placed = PlaceSuctionGrasps(scene.obstacles, grasps, cup, options);
  int top = 0;
  for (const PlacedGrasp& p : placed) {
    if (p.instance == 1) ADD_FAILURE() << "the rod has no grasps";
    const SuctionGrasp& g = grasps[0][static_cast<size_t>(p.grasp)];
    const Eigen::Vector3d a =
        scene.obstacles.instances[static_cast<size_t>(p.instance)].world_from_model.linear() *
        g.approach;
    EXPECT_LT(a.z(), 0.999) << "from below the floor";
    if (p.instance == 0) {
      EXPECT_TRUE(a.z() < -0.999 || std::abs(a.x()) > 0.999) << a.transpose();
    }
    if (a.z() < -0.999) {
      ++top;
      EXPECT_EQ(p.approach_blocked, p.instance == 2) << p.instance;
    }
  }
  EXPECT_GT(top, 20);
}

TEST(SceneGrasps, BadInputIsRefused) {
  const TestScene scene;
  SceneGraspOptions options;
  options.approach_mm = -1;
  EXPECT_THROW(
      PlaceParallelJawGrasps(scene.obstacles, {{}, {}}, ParallelJawGripper::Franka(), options),
      Error);
  // An instance naming a part without a grasp list.
  EXPECT_THROW(PlaceParallelJawGrasps(scene.obstacles, {{}}, ParallelJawGripper::Franka(),
                                      SceneGraspOptions{}),
               Error);
}

}  // namespace
}  // namespace cadsynth
