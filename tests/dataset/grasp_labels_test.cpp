// Per-frame grasp rows checked by hand: a grasp of a known pose seen by a known camera.
#include "dataset/grasp_labels.h"

#include <cmath>
#include <cstring>

#include <gtest/gtest.h>

#include "dataset/grasp.h"

namespace cadsynth {
namespace {

// A 100 x 80 camera (f = 100 px, centre (50, 40)) looking at one instance 500 mm away along z.
// Its instance image and depth show a plane z = 500 over the whole image.
Frame TestFrame() {
  Frame f;
  f.camera.intrinsics = Intrinsics{100, 80, 100.0, 100.0, 50.0, 40.0};
  f.instance.assign(100 * 80, 1);
  f.depth.assign(100 * 80, 500.0f);
  Frame::InstanceTruth t;
  t.cam_from_model =
      Eigen::Translation3d(0, 0, 500) * Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ());
  t.px_count_visib = 8000;
  f.instances = {t};
  return f;
}

// A grasp of the Franka hand across a 40 mm cube's x faces (model frame), approaching along -z
// from above: the contacts' midpoint (the origin) lies tip - depth = 112.2 - 8.8 = 103.4 mm from
// the hand's base along the approach.
ParallelJawGrasp CubeGrasp(double quality) {
  ParallelJawGrasp g;
  g.model_from_gripper.linear() << 1, 0, 0,  //
      0, -1, 0,                              //
      0, 0, -1;                              // x closing, z approach (down), y = z cross x
  g.model_from_gripper.translation() = Eigen::Vector3d(0, 0, 103.4);
  g.width_mm = 40;
  g.opening_mm = 50;
  g.depth_mm = 8.8;
  g.contacts[0] = Eigen::Vector3d(-20, 0, 0);
  g.contacts[1] = Eigen::Vector3d(20, 0, 0);
  g.quality = quality;
  return g;
}

TEST(GraspLabels, GraspNetRowsAreTheGraspInTheCameraFrame) {
  const Frame frame = TestFrame();
  const std::vector<std::vector<ParallelJawGrasp>> jaw = {
      {CubeGrasp(0.5), CubeGrasp(0.9), CubeGrasp(0.7)}};
  SceneGrasps scene;
  scene.part_of_instance = {0};
  scene.obj_id_of_instance = {7};
  scene.jaw = &jaw;
  scene.jaw_placed = {{0, 0, false}, {0, 1, true}, {0, 2, false}};
  GraspLabelOptions options;
  options.max_per_instance = 2;  // the best two: grasps 1 (0.9) then 2 (0.7)
  std::vector<float> labels;
  const std::vector<float> rows = GraspNetRows(frame, scene, options, &labels);
  ASSERT_EQ(rows.size(), 2u * 17);
  ASSERT_EQ(labels.size(), 2u * 6);
  EXPECT_FLOAT_EQ(rows[0], 0.9f);
  EXPECT_FLOAT_EQ(rows[17], 0.7f);
  EXPECT_FLOAT_EQ(rows[1], 0.050f);   // width: the opening checked, m
  EXPECT_FLOAT_EQ(rows[2], 0.020f);   // height: the Franka finger's width
  EXPECT_FLOAT_EQ(rows[3], 0.0088f);  // depth
  // The camera sees the model turned 90 degrees about z: model x -> camera y, model y -> -x.
  // Approach (model -z) stays -z; closing (model x) becomes camera +y; height = approach x
  // closing = (0, 0, -1) x (0, 1, 0) = (1, 0, 0).
  const float expected[9] = {0,  0, 1,   // row 0: x of approach, closing, height
                             0,  1, 0,   // row 1
                             -1, 0, 0};  // row 2
  for (int k = 0; k < 9; ++k) EXPECT_NEAR(rows[4 + k], expected[k], 1e-6) << k;
  // The contacts' midpoint: the model origin, 0.5 m in front of the camera; the hand's base lies
  // 103.4 mm back along the approach from it.
  const Eigen::Isometry3d cam_from_gripper =
      frame.instances[0].cam_from_model * jaw[0][1].model_from_gripper;
  EXPECT_NEAR((cam_from_gripper.translation() + 103.4 * cam_from_gripper.linear().col(2) -
               Eigen::Vector3d(0, 0, 500))
                  .norm(),
              0.0, 1e-9);
  // GraspNet's translation lies `depth` back along the approach (camera -z) from the midpoint:
  // graspnetAPI's evaluator closes the jaws at translation + depth * approach = the contacts.
  EXPECT_NEAR(rows[13], 0.0, 1e-7);
  EXPECT_NEAR(rows[14], 0.0, 1e-7);
  EXPECT_NEAR(rows[15], 0.5088, 1e-7);
  for (int i = 0; i < 3; ++i)
    EXPECT_NEAR(rows[13 + i] + rows[3] * rows[4 + 3 * i], i == 2 ? 0.5 : 0.0, 1e-7);
  EXPECT_FLOAT_EQ(rows[16], 7.0f);
  // Labels: instance 0, obj 7, blocked, contacts (camera (0, -20, 500) and (0, 20, 500)) seen on
  // the plane z = 500, grasp index 1.
  const float first[6] = {0, 7, 1, 1, 1, 1};
  for (int k = 0; k < 6; ++k) EXPECT_FLOAT_EQ(labels[k], first[k]) << k;
  EXPECT_FLOAT_EQ(labels[6 + 2], 0.0f);  // grasp 2 is not blocked
  EXPECT_FLOAT_EQ(labels[6 + 5], 2.0f);
  // An invisible instance has no rows.
  Frame hidden = frame;
  hidden.instances[0].px_count_visib = 0;
  EXPECT_TRUE(GraspNetRows(hidden, scene, options, &labels).empty());
  // 0: all of them, ties in list order.
  options.max_per_instance = 0;
  EXPECT_EQ(GraspNetRows(frame, scene, options, &labels).size(), 3u * 17);
}

TEST(GraspLabels, AContactIsSeenWhereItsInstanceShowsAtItsDepth) {
  Frame frame = TestFrame();
  // (10, 0, 500) projects to u = 50 + 100 x 10 / 500 = 52, v = 40: pixel (52, 40).
  EXPECT_TRUE(PointSeen(frame, 0, {10, 0, 500}, 3.0));
  EXPECT_TRUE(PointSeen(frame, 0, {10, 0, 502.5}, 3.0));
  EXPECT_FALSE(PointSeen(frame, 0, {10, 0, 510}, 3.0));    // behind the surface seen
  EXPECT_FALSE(PointSeen(frame, 1, {10, 0, 500}, 3.0));    // another instance's pixels
  EXPECT_FALSE(PointSeen(frame, 0, {1000, 0, 500}, 3.0));  // outside the image
  // Another instance in front over the 3 x 3 pixels around (52, 40): hidden.
  for (int v = 39; v <= 41; ++v) {
    for (int u = 51; u <= 53; ++u) {
      frame.instance[static_cast<size_t>(v * 100 + u)] = 2;
      frame.depth[static_cast<size_t>(v * 100 + u)] = 450;
    }
  }
  EXPECT_FALSE(PointSeen(frame, 0, {10, 0, 500}, 3.0));
  frame.instance[40 * 100 + 53] = 1;  // one neighbour shows it again
  frame.depth[40 * 100 + 53] = 500;
  EXPECT_TRUE(PointSeen(frame, 0, {10, 0, 500}, 3.0));
}

TEST(GraspLabels, SuctionRowsAndNpyFiles) {
  const Frame frame = TestFrame();
  SuctionGrasp top;
  top.point = Eigen::Vector3d(0, 0, -20);  // the cube's face towards the camera (model -z)
  top.approach = Eigen::Vector3d(0, 0, 1);
  top.seal = 0.8;
  top.wrench = 0.5;
  const std::vector<std::vector<SuctionGrasp>> suction = {{top}};
  SceneGrasps scene;
  scene.part_of_instance = {0};
  scene.obj_id_of_instance = {3};
  scene.suction = &suction;
  scene.suction_placed = {{0, 0, false}};
  std::vector<float> labels;
  const std::vector<float> rows = SuctionNetRows(frame, scene, GraspLabelOptions{}, &labels);
  ASSERT_EQ(rows.size(), 8u);  // suctionnetAPI's SUCTION_ARRAY_LEN
  // Score, outward normal, point (m), obj_id.
  const float expected[8] = {0.4f, 0, 0, -1, 0, 0, 0.48f, 3};
  for (int k = 0; k < 8; ++k) EXPECT_NEAR(rows[k], expected[k], 1e-6) << k;
  // Seen? The depth image says 500 mm there, the point lies at 480: not within 3 mm.
  const float first[6] = {0, 3, 0, 0, 0.8f, 0.5f};
  for (int k = 0; k < 6; ++k) EXPECT_FLOAT_EQ(labels[k], first[k]) << k;
  // The .npy encoding: header, then the rows as little-endian float32.
  const std::string npy = EncodeNpy(rows.data(), 1, 8);
  EXPECT_EQ(npy.substr(0, 8), std::string("\x93NUMPY\x01\x00", 8));
  EXPECT_NE(npy.find("'shape': (1, 8)"), std::string::npos);
  EXPECT_EQ(npy.size() % 64, 32u);  // a 64-byte aligned header, then 32 bytes of data
  float back[8];
  std::memcpy(back, npy.data() + npy.size() - 32, 32);
  for (int k = 0; k < 8; ++k) EXPECT_EQ(back[k], rows[k]);
}

}  // namespace
}  // namespace cadsynth
