#include "dataset/bop.h"

#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include <opencv2/imgproc.hpp>
#include "tests/image_support.h"

#include <gtest/gtest.h>

#include "cad/core/error.h"
#include "cad/shape.h"
#include "dataset/coco.h"
#include "render/renderer.h"
#include "tests/test_support.h"

namespace cadsynth {
namespace {

using nlohmann::json;

json ReadJson(const std::filesystem::path& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in) << path;
  return json::parse(in);
}

TEST(EncodeDepth, RoundsToTheScaleAndDropsWhatDoesNotFit) {
  EXPECT_EQ(EncodeDepth(0.0f, 0.1), 0);
  EXPECT_EQ(EncodeDepth(523.46f, 0.1), 5235);
  EXPECT_EQ(EncodeDepth(6553.5f, 0.1), 65535);
  EXPECT_EQ(EncodeDepth(6553.6f, 0.1), 0);  // beyond the uint16 range: no value, not a clamp
  EXPECT_EQ(EncodeDepth(6553.6f, 1.0), 6554);
}

// A 4x3 frame worked by hand: instance 0 is fully visible in two pixels; instance 1 has a full
// silhouette of four pixels, of which one is hidden by instance 0 and one has no valid depth.
Frame HandFrame() {
  Frame f;
  f.camera.intrinsics = Intrinsics{4, 3, 10, 10, 2, 1.5};
  f.rgb.assign(4 * 3 * 3, 0);
  f.depth.assign(12, 0.0f);
  f.instance.assign(12, 0);
  f.instances.resize(2);
  for (auto& t : f.instances) t.amodal_mask.assign(12, 0);
  // Instance 0 at (1,0) and (2,0).
  for (int p : {1, 2}) {
    f.instance[p] = 1;
    f.instances[0].amodal_mask[p] = 1;
    f.depth[p] = 100.0f;
  }
  // Instance 1 silhouette at (2,0), (2,1), (3,1), (3,2); (2,0) hidden by instance 0.
  for (int p : {2, 6, 7, 11}) f.instances[1].amodal_mask[p] = 1;
  for (int p : {6, 7}) {
    f.instance[p] = 2;
    f.depth[p] = 200.0f;
  }
  f.instance[11] = 2;
  f.depth[11] = 9000.0f;  // visible but too far for uint16 at 0.1 mm
  return f;
}

TEST(GtInfo, HandWorkedFrame) {
  const Frame f = HandFrame();
  const GtInfo a = ComputeGtInfo(f, 0, BopOptions{});
  EXPECT_EQ(a.px_count_all, 2);
  EXPECT_EQ(a.px_count_visib, 2);
  EXPECT_EQ(a.px_count_valid, 2);
  EXPECT_DOUBLE_EQ(a.visib_fract, 1.0);
  EXPECT_EQ(std::vector<int>(a.bbox_obj, a.bbox_obj + 4),
            (std::vector<int>{1, 0, 1, 0}));  // bop_toolkit: width = max - min
  const GtInfo b = ComputeGtInfo(f, 1, BopOptions{});
  EXPECT_EQ(b.px_count_all, 4);
  EXPECT_EQ(b.px_count_visib, 3);
  EXPECT_EQ(b.px_count_valid, 3);  // (2,0) via instance 0's depth, (2,1), (3,1); not (3,2)
  EXPECT_DOUBLE_EQ(b.visib_fract, 0.75);
  EXPECT_EQ(std::vector<int>(b.bbox_obj, b.bbox_obj + 4), (std::vector<int>{2, 0, 1, 2}));
  EXPECT_EQ(std::vector<int>(b.bbox_visib, b.bbox_visib + 4), (std::vector<int>{2, 1, 1, 1}));
  Frame hidden = HandFrame();
  std::fill(hidden.instances[0].amodal_mask.begin(), hidden.instances[0].amodal_mask.end(), 0);
  std::replace(hidden.instance.begin(), hidden.instance.end(), uint16_t{1}, uint16_t{0});
  const GtInfo none = ComputeGtInfo(hidden, 0, BopOptions{});
  EXPECT_EQ(std::vector<int>(none.bbox_obj, none.bbox_obj + 4), (std::vector<int>{-1, -1, -1, -1}));
  EXPECT_EQ(none.visib_fract, 0.0);
}

// bop_toolkit's "bop19" rule on the hand-worked frame: instance 1, rendered alone, lies 10 mm
// behind instance 0 at pixel (2, 0) and has no written depth at (3, 2). Distances are depths times
// |((u - cx) / fx, (v - cy) / fy, 1)|, which at (2, 0) is |(0, -0.15, 1)| = 1.01119.
TEST(GtInfo, Bop19RuleWorkedByHand) {
  Frame f = HandFrame();
  for (auto& t : f.instances) t.roi[2] = 4, t.roi[3] = 3;  // the whole 4 x 3 image
  f.instances[0].amodal_depth.assign(12, 0.0f);
  f.instances[0].amodal_depth[1] = f.instances[0].amodal_depth[2] = 100.0f;
  f.instances[1].amodal_depth.assign(12, 0.0f);
  f.instances[1].amodal_depth[2] = 110.0f;  // behind instance 0 (100 mm)
  f.instances[1].amodal_depth[6] = f.instances[1].amodal_depth[7] = 200.0f;
  f.instances[1].amodal_depth[11] = 9000.0f;  // its written depth is 0: visible in bop19

  BopOptions bop19;
  bop19.visibility = BopOptions::Visibility::kBop19;
  bop19.visib_delta_mm = 15.0;  // 10 mm * 1.01119 = 10.11 <= 15: (2, 0) is visible
  const GtInfo b = ComputeGtInfo(f, 1, bop19);
  EXPECT_EQ(b.px_count_visib, 4);
  EXPECT_DOUBLE_EQ(b.visib_fract, 1.0);
  EXPECT_EQ(std::vector<int>(b.bbox_visib, b.bbox_visib + 4), (std::vector<int>{2, 0, 1, 2}));
  EXPECT_EQ(ComputeGtInfo(f, 0, bop19).px_count_visib, 2);  // both are visible at (2, 0)

  bop19.visib_delta_mm = 10.1;  // 10.11 > 10.1: hidden, as in the exact rule
  EXPECT_EQ(ComputeGtInfo(f, 1, bop19).px_count_visib, 3);
  bop19.visib_delta_mm = 10.12;
  EXPECT_EQ(ComputeGtInfo(f, 1, bop19).px_count_visib, 4);
  EXPECT_EQ(ComputeGtInfo(f, 1, BopOptions{}).px_count_visib, 3);  // exact: (2, 0) shows instance 0

  Frame no_depth = HandFrame();  // bop19 without the renderer's amodal depth is refused
  EXPECT_THROW(ComputeGtInfos(no_depth, bop19), Error);
}

// Two touching boxes seen straight down: a 60 x 60 x T mm block resting on a 200 x 200 x 20 mm
// slab, the camera 500 mm above the block. Under the block the slab is T mm farther than the
// block's top, T times at most 1.07 as a distance (the block spans 32 px from the principal
// point at f = 525). With T = 10 mm and delta 15 mm bop_toolkit calls the whole slab visible; with
// T = 20 mm the part under the block is hidden, as in the exact rule.
TEST(GtInfo, Bop19TwoTouchingBoxes) {
  for (const double t : {10.0, 20.0}) {
    SCOPED_TRACE(t);
    const std::vector<Part> parts = {MakePart("slab", MakeBox(200, 200, 20), TessellationOptions{}),
                                     MakePart("block", MakeBox(60, 60, t), TessellationOptions{})};
    Scene scene;
    scene.instances = {
        Instance{0, "slab", Eigen::Isometry3d(Eigen::Translation3d(0, 0, 10))},
        Instance{1, "block", Eigen::Isometry3d(Eigen::Translation3d(0, 0, 20 + t / 2))}};
    Camera camera;
    camera.intrinsics = Intrinsics{640, 480, 525.0, 525.0, 320.0, 240.0};
    camera.world_from_cam.linear() << 1, 0, 0, 0, -1, 0, 0, 0, -1;  // looking down
    camera.world_from_cam.translation() = Eigen::Vector3d(0, 0, 20 + t + 500);
    RenderOptions render;
    render.amodal_depth = true;
    const Frame frame = Renderer(parts, scene, render).Render(camera);
    const std::vector<GtInfo> exact = ComputeGtInfos(frame, BopOptions{});
    BopOptions options;
    options.visibility = BopOptions::Visibility::kBop19;
    const std::vector<GtInfo> bop19 = ComputeGtInfos(frame, options);
    // The block's top face: 60 mm at 500 mm is 63 px on a side.
    EXPECT_NEAR(exact[1].px_count_all, 63 * 63, 2 * 64);
    EXPECT_EQ(exact[1].px_count_visib, exact[1].px_count_all);
    EXPECT_EQ(exact[0].px_count_visib, exact[0].px_count_all - exact[1].px_count_all);
    EXPECT_EQ(bop19[1].px_count_visib, exact[1].px_count_all);
    if (t == 10.0) {
      EXPECT_EQ(bop19[0].px_count_visib, exact[0].px_count_all);
      EXPECT_DOUBLE_EQ(bop19[0].visib_fract, 1.0);
    } else {
      EXPECT_EQ(bop19[0].px_count_visib, exact[0].px_count_visib);
    }
  }
}

// bop_toolkit's definition, recomputed independently: render each instance alone with a camera
// whose image is three times as large (principal point moved by the image size) and count.
TEST(GtInfo, TruncatedAndOccludedMatchTheThreeTimesCanvas) {
  const std::vector<Part> parts = {MakePart("big", MakeBox(100, 100, 40), TessellationOptions{}),
                                   MakePart("small", MakeBox(40, 40, 20), TessellationOptions{})};
  Scene scene;
  scene.floor = false;
  // The big box's 100 mm top face, 525 mm from an f = 525 camera, spans u in [-50, 50): half of
  // it lies left of the image. The small box above it (u in [-26, 20)) hides part of the rest and
  // is cut by the image border too.
  scene.instances = {Instance{0, "big", Eigen::Isometry3d(Eigen::Translation3d(-320, 0, 20))},
                     Instance{1, "small", Eigen::Isometry3d(Eigen::Translation3d(-280, 0, 100))}};
  Camera camera;
  camera.intrinsics = Intrinsics{640, 480, 525.0, 525.0, 320.0, 240.0};
  camera.world_from_cam = Eigen::Isometry3d::Identity();
  camera.world_from_cam.linear() << 1, 0, 0, 0, -1, 0, 0, 0, -1;  // looking down
  camera.world_from_cam.translation() = Eigen::Vector3d(0, 0, 40 + 525);
  const Frame frame = Renderer(parts, scene).Render(camera);
  const std::vector<GtInfo> infos = ComputeGtInfos(frame, BopOptions{});

  // Hand-worked for the big box: the top face covers u in [-50, 50), v in [190, 290); the side
  // wall facing the optical axis (x = -270, 525...565 mm deep) adds u up to 320 - 525 * 270 / 565
  // = 69.1, so 119 columns (bop_toolkit writes width 118 = max - min). Not clipped at u = 0.
  EXPECT_GT(infos[0].px_count_all, 100 * 100);
  EXPECT_EQ(std::vector<int>(infos[0].bbox_obj, infos[0].bbox_obj + 4),
            (std::vector<int>{-50, 190, 118, 99}));
  EXPECT_LT(infos[0].px_count_visib, frame.instances[0].px_count_all);  // occluded inside the image

  Camera canvas = camera;
  canvas.intrinsics = Intrinsics{3 * 640, 3 * 480, 525.0, 525.0, 320.0 + 640, 240.0 + 480};
  for (size_t i = 0; i < 2; ++i) {
    SCOPED_TRACE(i);
    Scene alone = scene;
    alone.instances = {scene.instances[i]};
    const Frame solo = Renderer(parts, alone).Render(canvas);
    int count = 0, u0 = 1 << 30, v0 = 1 << 30, u1 = -(1 << 30), v1 = -(1 << 30);
    for (int v = 0; v < canvas.intrinsics.height; ++v) {
      for (int u = 0; u < canvas.intrinsics.width; ++u) {
        if (solo.instance[static_cast<size_t>(v) * canvas.intrinsics.width + u] == 0) continue;
        ++count;
        u0 = std::min(u0, u - 640), u1 = std::max(u1, u - 640);
        v0 = std::min(v0, v - 480), v1 = std::max(v1, v - 480);
      }
    }
    EXPECT_EQ(infos[i].px_count_all, count);
    EXPECT_EQ(std::vector<int>(infos[i].bbox_obj, infos[i].bbox_obj + 4),
              (std::vector<int>{u0, v0, u1 - u0, v1 - v0}));
    // Visible pixels straight from the id image, and the fraction of the whole.
    int visible = 0;
    for (uint16_t id : frame.instance) visible += id == i + 1;
    EXPECT_EQ(infos[i].px_count_visib, visible);
    EXPECT_DOUBLE_EQ(infos[i].visib_fract, static_cast<double>(visible) / count);
    EXPECT_LT(infos[i].visib_fract, 0.6);  // both are truncated
  }
  EXPECT_LT(infos[1].bbox_obj[0], 0);  // the small box's box starts left of the image too
}

TEST(AssignClasses, GroupsByNamePatternThenOneClassPerRemainingPart) {
  std::vector<std::string> empty;
  const std::vector<ObjectClass> classes = AssignClasses(
      {"M6 bolt", "plate", "NUT_M6", "M8 Bolt", "washer"}, {},
      {{"bolt", {"*bolt*"}}, {"nut", {"nut*", "*-nut"}}, {"screw", {"*screw*"}}}, &empty);
  ASSERT_EQ(classes.size(), 5u);
  EXPECT_EQ(classes[0].id, 1);
  EXPECT_EQ(classes[0].name, "bolt");
  EXPECT_EQ(classes[3].id, 1);  // case-insensitive
  EXPECT_EQ(classes[2].id, 2);
  EXPECT_EQ(classes[2].name, "nut");
  EXPECT_EQ(classes[1].id, 4);  // after the three groups, in part order
  EXPECT_EQ(classes[1].name, "plate");
  EXPECT_EQ(classes[4].id, 5);
  EXPECT_EQ(empty, std::vector<std::string>{"screw"});
  EXPECT_EQ(AssignClasses({"a", "b"}, {}, {}, &empty)[1].id, 2);
  // Labels (a family that is one class) come before name groups take a part, after the groups.
  const auto labelled =
      AssignClasses({"gear_z12", "M6 bolt", "gear_z13", "plate"},
                    {"spur_gear", "", "spur_gear", ""}, {{"bolt", {"*bolt*"}}}, &empty);
  EXPECT_EQ(labelled[0].id, 2);
  EXPECT_EQ(labelled[0].name, "spur_gear");
  EXPECT_EQ(labelled[2].id, 2);
  EXPECT_EQ(labelled[1].id, 1);
  EXPECT_EQ(labelled[3].id, 3);
}

TEST(Bop, EveryFourthImageIsATestImageWithItsTargets) {
  testing::ScratchDir dir;
  const std::vector<Part> parts = {MakePart("box", MakeBox(60, 40, 20), TessellationOptions{})};
  Scene scene;
  scene.instances = {
      Instance{0, "a", Eigen::Isometry3d(Eigen::Translation3d(0, 0, 10))},
      Instance{0, "b", Eigen::Isometry3d(Eigen::Translation3d(0, 0, -500))}};  // under the floor
  const Renderer renderer(parts, scene);
  BopOptions options;  // every 4th
  BopSceneWriter writer(dir.path(), 0, options, {1, 1});
  for (int i = 0; i < 8; ++i) {
    Camera camera;
    camera.world_from_cam = WorldFromCamOnSphere({0, 0, 0}, i * 0.5, 0.8, 600.0);
    writer.WriteFrame(i, renderer.Render(camera));
  }
  const SceneSplit split = writer.Finish();
  EXPECT_EQ(split.train, (std::vector<int>{0, 1, 2, 4, 5, 6}));
  EXPECT_EQ(split.test, (std::vector<int>{3, 7}));
  ASSERT_EQ(split.targets.size(),
            2u);  // one visible box per test image; the buried one is not a target
  EXPECT_EQ(split.targets[0].im_id, 3);
  EXPECT_EQ(split.targets[0].obj_id, 1);
  EXPECT_EQ(split.targets[0].inst_count, 1);
  WriteSplits(dir.path(), {split});
  std::ifstream test(dir / "splits" / "test.txt");
  std::stringstream text;
  text << test.rdbuf();
  EXPECT_EQ(text.str(), "000000 000003\n000000 000007\n");
  const json targets = ReadJson(dir / "test_targets_bop19.json");
  ASSERT_EQ(targets.size(), 2u);
  EXPECT_EQ(targets[1]["im_id"], 7);
  EXPECT_EQ(targets[1]["scene_id"], 0);
  // A seeded fraction: reproducible, about the fraction asked.
  BopOptions fraction;
  fraction.test_every = 0;
  fraction.test_fraction = 0.3;
  int tests = 0;
  for (int i = 0; i < 1000; ++i) tests += fraction.IsTest(i, 1000);
  EXPECT_NEAR(tests, 300, 45);
  EXPECT_EQ(fraction.IsTest(17, 1000), fraction.IsTest(17, 1000));
}

TEST(Bop, JpegColourWhenAsked) {
  testing::ScratchDir dir;
  const std::vector<Part> parts = {MakePart("box", MakeBox(60, 40, 20), TessellationOptions{})};
  Scene scene;
  scene.instances = {Instance{0, "a", Eigen::Isometry3d(Eigen::Translation3d(0, 0, 10))}};
  Camera camera;
  camera.world_from_cam = WorldFromCamOnSphere({0, 0, 0}, 0.4, 0.8, 400.0);
  const Frame frame = Renderer(parts, scene).Render(camera);
  BopOptions options;
  options.jpeg_quality = 90;
  BopSceneWriter writer(dir.path(), 0, options, {1});
  writer.WriteFrame(0, frame);
  writer.Finish();
  const auto scene_dir = dir / "train" / "000000";
  EXPECT_FALSE(std::filesystem::exists(scene_dir / "rgb" / "000000.png"));
  const cv::Mat bgr =
      testing::Imread((scene_dir / "rgb" / "000000.jpg").string(), cv::IMREAD_COLOR);
  ASSERT_EQ(bgr.type(), CV_8UC3);
  double error = 0;  // mean absolute error per channel: small at quality 90
  for (int v = 0; v < bgr.rows; ++v) {
    for (int u = 0; u < bgr.cols; ++u) {
      for (int c = 0; c < 3; ++c)
        error += std::abs(bgr.at<cv::Vec3b>(v, u)[2 - c] - frame.rgb[3 * (v * bgr.cols + u) + c]);
    }
  }
  EXPECT_LT(error / (bgr.total() * 3), 2.0);
  EXPECT_EQ(ReadJson(scene_dir / "scene_gt_coco.json")["images"][0]["file_name"], "rgb/000000.jpg");
}

TEST(Bop, NormalsAreWrittenWhenRendered) {
  testing::ScratchDir dir;
  Scene scene;  // the floor, seen straight down: normal (0, 0, -1) in the camera frame
  RenderOptions options;
  options.normals = true;
  Camera camera;
  camera.world_from_cam.linear() << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  camera.world_from_cam.translation() = Eigen::Vector3d(0, 0, 500);
  const Frame frame = Renderer({}, scene, options).Render(camera);
  BopSceneWriter writer(dir.path(), 0, BopOptions{}, {});
  writer.WriteFrame(0, frame);
  const cv::Mat normals = testing::Imread(
      (dir / "train" / "000000" / "normal" / "000000.png").string(), cv::IMREAD_COLOR);
  ASSERT_EQ(normals.type(), CV_8UC3);
  const cv::Vec3b n = normals.at<cv::Vec3b>(240, 320);  // BGR of (0, 0, -1) -> (128, 128, 0)
  EXPECT_EQ(n[2], 128);
  EXPECT_EQ(n[1], 128);
  EXPECT_EQ(n[0], 0);
}

TEST(Bop, WritesEveryFileWithTheKeysBopToolkitReads) {
  testing::ScratchDir dir;
  const std::vector<Part> parts = {MakePart("box", MakeBox(60, 40, 20), TessellationOptions{}),
                                   MakePart("pin", MakeCylinder(8, 50), TessellationOptions{})};
  Scene scene;
  scene.instances = {
      Instance{0, "a", Eigen::Isometry3d(Eigen::Translation3d(0, 0, 10))},
      Instance{1, "b", Eigen::Translation3d(50, 0, 25) * Eigen::Isometry3d::Identity()}};
  const Renderer renderer(parts, scene);
  BopOptions options;
  WriteBopModels(dir.path(), parts);
  WriteBopCamera(dir.path(), Intrinsics::KinectV1(), options);
  BopSceneWriter writer(dir.path(), 3, options, {1, 2});
  std::vector<Frame> frames;
  for (int i = 0; i < 2; ++i) {
    Camera camera;
    camera.world_from_cam = WorldFromCamOnSphere({0, 0, 0}, i * 1.0, 0.7, 600.0);
    frames.push_back(renderer.Render(camera));
  }
  writer.WriteFrame(1, frames[1]);  // out of order on purpose
  writer.WriteFrame(0, frames[0]);
  const SceneSplit split = writer.Finish();

  const json camera = ReadJson(dir / "camera.json");
  for (const char* key : {"cx", "cy", "depth_scale", "fx", "fy", "height", "width"}) {
    EXPECT_TRUE(camera.contains(key)) << key;
  }
  EXPECT_EQ(camera["width"], 640);
  const json info = ReadJson(dir / "models" / "models_info.json");
  ASSERT_EQ(info.size(), 2u);
  EXPECT_NEAR(info["1"]["diameter"].get<double>(), std::sqrt(60.0 * 60 + 40 * 40 + 20 * 20), 1e-4);
  EXPECT_NEAR(info["1"]["min_x"].get<double>(), -30.0, 1e-5);
  EXPECT_NEAR(info["1"]["size_y"].get<double>(), 40.0, 1e-5);
  EXPECT_TRUE(std::filesystem::exists(dir / "models" / "obj_000001.ply"));
  EXPECT_TRUE(std::filesystem::exists(dir / "models" / "obj_000002.ply"));
  EXPECT_EQ(ReadJson(dir / "models" / "models_cad.json")["2"]["name"], "pin");

  const auto scene_dir = dir / "train" / "000003";
  const json cams = ReadJson(scene_dir / "scene_camera.json");
  const json gt = ReadJson(scene_dir / "scene_gt.json");
  const json gt_info = ReadJson(scene_dir / "scene_gt_info.json");
  ASSERT_EQ(cams.size(), 2u);
  EXPECT_EQ(cams.begin().key(), "0");  // ordered by image id
  for (int im = 0; im < 2; ++im) {
    const std::string key = std::to_string(im);
    EXPECT_EQ(cams[key]["cam_K"].size(), 9u);
    EXPECT_EQ(cams[key]["cam_R_w2c"].size(), 9u);
    EXPECT_EQ(cams[key]["cam_t_w2c"].size(), 3u);
    EXPECT_EQ(cams[key]["depth_scale"], 0.1);
    ASSERT_EQ(gt[key].size(), 2u);
    ASSERT_EQ(gt_info[key].size(), 2u);
    // cam_t_w2c is the translation of cam_from_world: the world origin seen from the camera.
    const Eigen::Isometry3d cam_from_world = frames[im].camera.world_from_cam.inverse();
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(cams[key]["cam_t_w2c"][c].get<double>(), cam_from_world.translation()[c], 1e-9);
    }
    for (int i = 0; i < 2; ++i) {
      const json& g = gt[key][i];
      EXPECT_EQ(g["obj_id"], i + 1);
      EXPECT_EQ(g["cam_R_m2c"].size(), 9u);
      const Eigen::Isometry3d& m2c = frames[im].instances[i].cam_from_model;
      EXPECT_NEAR(g["cam_R_m2c"][1].get<double>(), m2c.linear()(0, 1), 1e-12);  // row-major
      EXPECT_NEAR(g["cam_t_m2c"][2].get<double>(), m2c.translation().z(), 1e-9);
      const json& gi = gt_info[key][i];
      for (const char* k : {"bbox_obj", "bbox_visib", "px_count_all", "px_count_valid",
                            "px_count_visib", "visib_fract"}) {
        EXPECT_TRUE(gi.contains(k)) << k;
      }
      EXPECT_EQ(gi["px_count_visib"], frames[im].instances[i].px_count_visib);
      char name[32];
      std::snprintf(name, sizeof(name), "%06d_%06d.png", im, i);
      const cv::Mat mask =
          testing::Imread((scene_dir / "mask_visib" / name).string(), cv::IMREAD_UNCHANGED);
      ASSERT_FALSE(mask.empty()) << name;
      EXPECT_EQ(cv::countNonZero(mask), frames[im].instances[i].px_count_visib);
      const cv::Mat full =
          testing::Imread((scene_dir / "mask" / name).string(), cv::IMREAD_UNCHANGED);
      EXPECT_EQ(cv::countNonZero(full), frames[im].instances[i].px_count_all);
    }
    char image[16];
    std::snprintf(image, sizeof(image), "%06d.png", im);
    const cv::Mat depth =
        testing::Imread((scene_dir / "depth" / image).string(), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(depth.type(), CV_16UC1);
    EXPECT_EQ(depth.at<uint16_t>(240, 320), EncodeDepth(frames[im].depth[240 * 640 + 320], 0.1));
    const cv::Mat rgb = testing::Imread((scene_dir / "rgb" / image).string(), cv::IMREAD_COLOR);
    ASSERT_EQ(rgb.type(), CV_8UC3);
    EXPECT_EQ(rgb.at<cv::Vec3b>(240, 320)[0], frames[im].rgb[3 * (240 * 640 + 320) + 2]);  // BGR
  }

  // COCO: every visible mask, decoded from its compressed RLE, is the mask_visib PNG.
  const json coco = ReadJson(scene_dir / "scene_gt_coco.json");
  for (const char* k : {"annotations", "categories", "images", "info", "licenses"})
    EXPECT_TRUE(coco.contains(k)) << k;
  ASSERT_EQ(coco["images"].size(), 2u);
  EXPECT_EQ(coco["images"][0]["file_name"], "rgb/000000.png");
  EXPECT_EQ(coco["categories"].size(), 2u);
  int annotations = 0;
  for (const json& a : coco["annotations"]) {
    const int im = a["image_id"], inst = a["inst_id"];
    SCOPED_TRACE(std::to_string(im) + "/" + std::to_string(inst));
    EXPECT_EQ(a["category_id"], gt[std::to_string(im)][inst]["obj_id"]);
    EXPECT_EQ(a["segmentation"]["size"], json::array({480, 640}));
    const RleMask rle{480, 640,
                      DecompressRleCounts(a["segmentation"]["counts"].get<std::string>())};
    const std::vector<uint8_t> decoded = DecodeRle(rle);
    char name[32];
    std::snprintf(name, sizeof(name), "%06d_%06d.png", im, inst);
    const cv::Mat mask =
        testing::Imread((scene_dir / "mask_visib" / name).string(), cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(mask.empty());
    int differ = 0;
    for (int v = 0; v < 480; ++v) {
      for (int u = 0; u < 640; ++u)
        differ += (mask.at<uint8_t>(v, u) != 0) != (decoded[v * 640 + u] != 0);
    }
    EXPECT_EQ(differ, 0);
    EXPECT_EQ(a["area"], cv::countNonZero(mask));
    // bop_toolkit's calc_gt_coco.py: the amodal box, bbox_from_binary_mask of the full mask
    // (width max - min + 1), and "ignore" below 10% visibility.
    const cv::Mat full =
        testing::Imread((scene_dir / "mask" / name).string(), cv::IMREAD_UNCHANGED);
    const cv::Rect box = cv::boundingRect(full);
    EXPECT_EQ(a["bbox"], json::array({box.x, box.y, box.width, box.height}));
    EXPECT_EQ(a["ignore"], gt_info[std::to_string(im)][inst]["visib_fract"].get<double>() < 0.1);
    ++annotations;
  }
  EXPECT_EQ(annotations, 4);  // both instances show in both views

  // Merged by split: with 2 images and every 4th a test image, both are training images.
  std::vector<SceneSplit> scenes(4);
  scenes[3] = split;
  WriteMergedCoco(dir.path(), options, scenes, {{7, "block"}, {8, "pin"}});
  const json train = ReadJson(dir / "coco" / "train.json");
  ASSERT_EQ(train["images"].size(), 2u);
  EXPECT_EQ(train["images"][1]["file_name"], "train/000003/rgb/000001.png");
  EXPECT_EQ(train["images"][1]["id"], 2);
  EXPECT_EQ(train["categories"], json::parse(R"([{"id":7,"name":"block","supercategory":"cadsynth"},
                                                  {"id":8,"name":"pin","supercategory":"cadsynth"}])"));
  ASSERT_EQ(train["annotations"].size(), 4u);
  EXPECT_EQ(train["annotations"][3]["category_id"], 8);  // the pin's class
  EXPECT_EQ(train["annotations"][3]["obj_id"], 2);
  EXPECT_EQ(train["annotations"][3]["image_id"], 2);
  EXPECT_EQ(ReadJson(dir / "coco" / "test.json")["images"].size(), 0u);
}

}  // namespace
}  // namespace cadsynth
