#include "recipes/recipe.h"

#include <sys/stat.h>

#include <cmath>
#include <fstream>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "cad/core/error.h"
#include "tests/test_support.h"

namespace cadsynth {
namespace {

std::string ErrorOf(const std::string& text, const std::filesystem::path& base = ".") {
  try {
    ParseRecipe(text, "r.yaml", base);
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(Recipe, PaperSweepExpandsExactly) {
  const RunSpec spec = ParseRecipe(R"(
sweep:
  yaw: {from: 0, to: 360, step: 10}
  pitch: {from: 0, to: 90, step: 10}
  radius: {from: 0.65 m, to: 1.45 m, step: 0.1 m}
)",
                                   "r.yaml", ".");
  EXPECT_EQ(spec.sweep.yaw_rad.size(), 37u);
  EXPECT_EQ(spec.sweep.pitch_rad.size(), 10u);
  ASSERT_EQ(spec.sweep.radius_mm.size(), 9u);
  EXPECT_NEAR(spec.sweep.radius_mm.back(), 1450.0, 1e-9);
  EXPECT_NEAR(spec.sweep.yaw_rad.back(), 2 * M_PI, 1e-12);
  EXPECT_EQ(spec.sweep.NumViews(), 3330u);
  ASSERT_EQ(spec.scenes.size(), 3u);  // no parts: the three demo sets
  EXPECT_EQ(spec.scenes[0].name, "planetary_gearbox");
  EXPECT_EQ(spec.scenes[2].arrangement.layout, Layout::kGrid);
}

TEST(Recipe, CameraListsAndOptions) {
  const RunSpec spec = ParseRecipe(R"(
camera: {preset: kinect_v1, width: 320, height: 240, fx: 262.5, fy: 262.5, cx: 159.5, cy: 119.5}
sweep: {yaw: [0, 90 deg, 3.14159 rad], pitch: 45, radius: 1 m, target: [0, 0, 2 cm]}
tessellation: {linear_deflection: 20 um, angular_deflection: 10}
parts: [{family: round_peg}]
scene: {layout: row, gap: 1 in}
render: {floor: false, background: [1, 1, 1]}
output: {dir: out/x, depth_scale: 1.0, split: val, formats: [bop, pvn3d, grasp], model_points: 500, point_sampling: even,
         point_seed: 4, test_fraction: 0.1, split_seed: 2, rgb: jpg, jpeg_quality: 90}
)",
                                   "r.yaml", "/base");
  EXPECT_EQ(spec.intrinsics.width, 320);
  EXPECT_DOUBLE_EQ(spec.intrinsics.fx, 262.5);
  EXPECT_EQ(spec.sweep.yaw_rad.size(), 3u);
  EXPECT_DOUBLE_EQ(spec.sweep.yaw_rad[1], M_PI / 2);
  EXPECT_DOUBLE_EQ(spec.sweep.radius_mm[0], 1000.0);
  EXPECT_DOUBLE_EQ(spec.sweep.target.z(), 20.0);
  EXPECT_DOUBLE_EQ(spec.tessellation.linear_deflection_mm, 0.02);
  EXPECT_DOUBLE_EQ(spec.scenes.at(0).arrangement.gap_mm, 25.4);
  EXPECT_FALSE(spec.look.floor);
  EXPECT_EQ(spec.output, std::filesystem::path("/base/out/x"));
  EXPECT_EQ(spec.bop.split, "val");
  EXPECT_FALSE(spec.bop.coco);
  EXPECT_EQ(spec.bop.jpeg_quality, 90);
  EXPECT_EQ(spec.bop.RgbExtension(), ".jpg");
  EXPECT_THROW(ParseRecipe("output: {jpeg_quality: 80}\n", "r.yaml", "."),
               Error);  // PNG has no quality
  EXPECT_THROW(ParseRecipe("output: {rgb: jpg, jpeg_quality: 101}\n", "r.yaml", "."), Error);
  EXPECT_FALSE(spec.bop.paper_layout);
  EXPECT_TRUE(spec.bop.pvn3d_meta);
  EXPECT_TRUE(spec.bop.grasp_points);
  for (const char* bad : {"output: {formats: [bop, yolo]}\n", "output: {formats: [coco]}\n",
                          "output: {formats: bop}\n"}) {
    EXPECT_THROW(ParseRecipe(bad, "r.yaml", "."), Error) << bad;
  }
  EXPECT_EQ(spec.bop.model_points, 500);
  EXPECT_TRUE(spec.bop.even_points);
  EXPECT_EQ(spec.bop.point_seed, 4u);
  EXPECT_EQ(spec.bop.test_every, 0);
  EXPECT_DOUBLE_EQ(spec.bop.test_fraction, 0.1);
  EXPECT_EQ(spec.bop.split_seed, 2u);
  try {
    ParseRecipe("output: {point_sampling: poisson}\n", "r.yaml", ".");
    FAIL() << "an unknown sampling must be refused";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("r.yaml:1"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("'area' or 'even'"), std::string::npos) << e.what();
  }
}

TEST(Recipe, CamerasSamplersAndFilter) {
  const RunSpec spec = ParseRecipe(R"(
camera: {preset: realsense_d435}
sweep:
  sampler: random
  count: 500
  seed: 9
  pitch: {from: 20, to: 80, step: 60}
  radius: [0.5 m, 1 m]
  roll_jitter: 5
  target_jitter: 2 cm
  min_visible_pixels: 200
)",
                                   "r.yaml", ".");
  EXPECT_EQ(spec.intrinsics.width, 1280);
  EXPECT_EQ(spec.sampler.kind, ViewSampler::Kind::kRandom);
  EXPECT_EQ(spec.sampler.count, 500);
  EXPECT_EQ(spec.sampler.seed, 9u);
  EXPECT_NEAR(spec.sampler.min_pitch_rad, 20 * M_PI / 180, 1e-12);
  EXPECT_NEAR(spec.sampler.max_pitch_rad, 80 * M_PI / 180, 1e-12);
  EXPECT_EQ(spec.sampler.max_radius_mm, 1000);
  EXPECT_EQ(spec.sampler.target_jitter_mm, 20);
  EXPECT_EQ(spec.min_visible_pixels, 200);
  EXPECT_NEAR(ParseRecipe("camera: {width: 800, height: 600, hfov: 90}\n", "r", ".").intrinsics.fx,
              400.0, 1e-9);
  EXPECT_EQ(ErrorOf("sweep: {sampler: spiral}\n"),
            "r.yaml:1:18: sweep.sampler: expected 'grid', 'fibonacci' or 'random', got 'spiral'");
  EXPECT_EQ(
      ErrorOf("camera: {preset: kinect_v2}\n"),
      "r.yaml:1:18: camera.preset: unknown preset 'kinect_v2' (known: kinect_v1, "
      "realsense_d435, realsense_d435_640, realsense_d435_depth, realsense_l515, "
      "azure_kinect_nfov, azure_kinect_wfov, xyz_ibd, photoneo_phoxi_m, photoneo_phoxi_l, itodd, "
      "zivid2_m70)");
  // Industrial presets are grey cameras unless the recipe says otherwise; sizes as BOP's.
  const RunSpec phoxi = ParseRecipe("camera: {preset: photoneo_phoxi_m}\n", "r", ".");
  EXPECT_EQ(phoxi.intrinsics.width, 2064);
  EXPECT_EQ(phoxi.intrinsics.height, 1544);
  EXPECT_EQ(phoxi.sensor.image, SensorOptions::Image::kGray);
  EXPECT_EQ(ParseRecipe("camera: {preset: xyz_ibd, image: rgb}\n", "r", ".").sensor.image,
            SensorOptions::Image::kRgb);
  // The D435's depth camera: 87 degrees across 848 px, f = 424 / tan(43.5 deg).
  const RunSpec d435 = ParseRecipe("camera: {preset: realsense_d435_depth}\n", "r", ".");
  EXPECT_NEAR(d435.intrinsics.fx, 424.0 / std::tan(43.5 * M_PI / 180), 1e-9);
  EXPECT_EQ(d435.sensor.image, SensorOptions::Image::kRgb);
  EXPECT_EQ(ErrorOf("camera: {hfov: 200}\n"),
            "r.yaml:1:16: camera.hfov: must lie between 0 and 180 degrees");
  EXPECT_EQ(ParseRecipe("render: {isa: avx2}\n", "r", ".").render.isa, "avx2");
  EXPECT_NE(
      ErrorOf("render: {isa: neon}\n").find("isa must be auto, sse2, sse4.2, avx, avx2 or avx512"),
      std::string::npos);
}

TEST(Recipe, CameraSensor) {
  const RunSpec spec = ParseRecipe(R"(
camera:
  preset: kinect_v1
  image: gray16
  depth: {model: structured_light, baseline: 12 cm, noise: 0.05 mm, max_incidence: 70}
)",
                                   "r.yaml", ".");
  EXPECT_EQ(spec.sensor.image, SensorOptions::Image::kGray16);
  EXPECT_EQ(spec.bop.gray_bits, 16);
  const DepthModel& d = spec.sensor.depth;
  EXPECT_EQ(d.kind, DepthModel::Kind::kStructuredLight);
  EXPECT_EQ(d.baseline_mm, 120);
  EXPECT_EQ(d.noise_mm, 0.05);
  EXPECT_NEAR(d.max_incidence_rad, 70 * M_PI / 180, 1e-12);
  // Keys not given keep the model's defaults.
  EXPECT_EQ(d.min_signal, DepthModel::Defaults(DepthModel::Kind::kStructuredLight).min_signal);
  // A bare name is the model with its defaults.
  const RunSpec kinect = ParseRecipe("camera: {depth: kinect_v1}\n", "r", ".");
  EXPECT_EQ(kinect.sensor.depth.baseline_mm, 75);
  EXPECT_EQ(kinect.sensor.depth.disparity_step_px, 0.125);
  EXPECT_EQ(kinect.bop.gray_bits, 0);
  EXPECT_EQ(ErrorOf("camera: {depth: kinect_v2}\n"),
            "r.yaml:1:17: camera.depth: expected 'ideal', 'kinect_v1', 'azure_kinect', "
            "'structured_light' or 'active_stereo', got 'kinect_v2'");
  const RunSpec imager = ParseRecipe(
      "camera: {imager: {full_well: 6000, read_noise: 4, vignetting: 0.3, seed: 2}}\n", "r", ".");
  EXPECT_EQ(imager.sensor.imager.full_well, 6000);
  EXPECT_EQ(imager.sensor.imager.read_noise, 4);
  EXPECT_EQ(imager.sensor.imager.vignetting, 0.3);
  EXPECT_EQ(imager.sensor.imager.seed, 2u);
  EXPECT_EQ(ErrorOf("camera:\n  imager: {vignetting: 2}\n"),
            "r.yaml:2:24: camera.imager.vignetting: vignetting must lie between 0 and 1");
  const RunSpec stereo =
      ParseRecipe("camera: {depth: {model: active_stereo, baseline: 95 mm, block: 7}}\n", "r", ".");
  EXPECT_EQ(stereo.sensor.depth.kind, DepthModel::Kind::kActiveStereo);
  EXPECT_EQ(stereo.sensor.depth.baseline_mm, 95);
  EXPECT_EQ(stereo.sensor.depth.block, 7);
  EXPECT_EQ(stereo.sensor.depth.dot_spacing_px, 3.0);  // the model's default
  EXPECT_EQ(ErrorOf("camera:\n  depth: {model: active_stereo, block: 4}\n"),
            "r.yaml:2:40: camera.depth.block: block must be odd, between 3 and 11");
  EXPECT_EQ(
      ErrorOf("camera:\n  depth: {model: kinect_v1, baseline: 0}\n"),
      "r.yaml:2:39: camera.depth.baseline: baseline must not be 0 for kinect_v1 (its disparity "
      "is f B / z)");
  EXPECT_EQ(ErrorOf("camera:\n  depth: {baseline: 5 cm}\n"),
            "r.yaml:2:10: camera.depth: give the sensor's 'model'");
  EXPECT_EQ(ErrorOf("camera:\n  depth: {model: azure_kinect, basline: 5 cm}\n"),
            "r.yaml:2:32: unknown key 'camera.depth.basline' (did you mean 'baseline'?)");
  EXPECT_EQ(ErrorOf("camera: {image: color}\n"),
            "r.yaml:1:17: camera.image: expected 'rgb', 'gray' or 'gray16', got 'color'");
  EXPECT_EQ(ErrorOf("camera: {image: gray16}\noutput: {rgb: jpg}\n"),
            "r.yaml:1:17: camera.image: 16-bit grey images cannot be JPEG (rgb: png)");
  EXPECT_EQ(ErrorOf("camera: {image: gray}\noutput: {formats: [bop, paper]}\n"),
            "r.yaml:1:17: camera.image: the paper and pvn3d formats need colour images (image: "
            "rgb)");
}

TEST(Recipe, CameraRig) {
  const RunSpec spec = ParseRecipe(R"(
cameras:
  - name: xyz
    preset: xyz_ibd
    depth: structured_light
  - name: realsense
    preset: realsense_d435_640
    position: [100 mm, 0, 0]
    look_at: [0, 0, 600 mm]
    depth: active_stereo
  - name: cam1
    image: gray16
    position: [0, -5 cm, 0]
    rotation: [0, -1, 0,  1, 0, 0,  0, 0, 1]
)",
                                   "r.yaml", ".");
  ASSERT_EQ(spec.rig.size(), 3u);
  EXPECT_EQ(spec.rig[0].name, "xyz");
  EXPECT_EQ(spec.rig[0].sensor.image, SensorOptions::Image::kGray);  // the preset's
  EXPECT_TRUE(spec.rig[0].rig_from_cam.matrix().isIdentity());
  // The first camera is the run's camera as well.
  EXPECT_EQ(spec.intrinsics.width, 1440);
  EXPECT_EQ(spec.sensor.depth.kind, DepthModel::Kind::kStructuredLight);
  EXPECT_EQ(spec.bop.gray_bits, 8);
  // look_at: the optical axis from (100, 0, 0) through (0, 0, 600): (-1, 0, 6) / sqrt(37); x in
  // the rig's x-z plane, y the rig's y.
  const RigSensor& rs = spec.rig[1];
  EXPECT_EQ(rs.intrinsics.width, 640);
  EXPECT_EQ(rs.sensor.depth.kind, DepthModel::Kind::kActiveStereo);
  EXPECT_TRUE(rs.rig_from_cam.translation().isApprox(Eigen::Vector3d(100, 0, 0)));
  const Eigen::Matrix3d r = rs.rig_from_cam.linear();
  EXPECT_TRUE(r.col(2).isApprox(Eigen::Vector3d(-1, 0, 6) / std::sqrt(37.0), 1e-12));
  EXPECT_TRUE(r.col(0).isApprox(Eigen::Vector3d(6, 0, 1) / std::sqrt(37.0), 1e-12));
  EXPECT_TRUE(r.col(1).isApprox(Eigen::Vector3d(0, 1, 0), 1e-12));
  const RigSensor& cam1 = spec.rig[2];
  EXPECT_EQ(cam1.sensor.image, SensorOptions::Image::kGray16);
  EXPECT_TRUE(cam1.rig_from_cam.translation().isApprox(Eigen::Vector3d(0, -50, 0)));
  EXPECT_TRUE(cam1.rig_from_cam.linear().col(0).isApprox(Eigen::Vector3d(0, 1, 0), 1e-12));

  EXPECT_EQ(ErrorOf("camera: {preset: xyz_ibd}\ncameras: [{name: a}]\n"),
            "r.yaml:2:10: cameras: give 'camera' (one camera) or 'cameras' (a rig of named "
            "cameras), not both");
  EXPECT_EQ(ErrorOf("cameras: {name: a}\n"),
            "r.yaml:1:10: cameras: expected a list of cameras (a rig), each with a 'name'");
  EXPECT_EQ(ErrorOf("cameras:\n  - {preset: xyz_ibd}\n"),
            "r.yaml:2:5: cameras[0]: a rig's camera needs a 'name' (e.g. xyz, realsense)");
  EXPECT_EQ(ErrorOf("cameras:\n  - {name: Cam_1}\n"),
            "r.yaml:2:12: cameras[0].name: 'Cam_1': use 1-32 lower-case letters and digits (BOP "
            "writes rgb_NAME/)");
  EXPECT_EQ(ErrorOf("cameras:\n  - {name: info2}\n"),
            "r.yaml:2:12: cameras[0].name: 'info2': names starting with info, coco or world would "
            "make scene_gt_NAME.json look like BOP's scene_gt_info.json and its kin");
  EXPECT_EQ(ErrorOf("cameras:\n  - {name: a}\n  - {name: a, position: [1, 0, 0]}\n"),
            "r.yaml:3:12: cameras[1].name: 'a' names two cameras");
  EXPECT_EQ(ErrorOf("cameras:\n  - {name: a, position: [1, 0, 0]}\n"),
            "r.yaml:2:25: cameras[0].position: the first camera is the rig's frame (the sweep "
            "places it): give the others' poses relative to it");
  EXPECT_EQ(ErrorOf("cameras:\n  - {name: a}\n  - {name: b, look_at: [0, 500, 0]}\n"),
            "r.yaml:3:24: cameras[1].look_at: must lie away from the camera and not straight above "
            "or below it (the rig's y)");
  EXPECT_EQ(ErrorOf("cameras:\n  - {name: a}\n  - {name: b, rotation: [1, 0, 0, 0, 1, 0, 0, 0, "
                    "-1]}\n"),
            "r.yaml:3:25: cameras[1].rotation: is not a rotation (orthonormal, determinant 1, to "
            "1e-4)");
  EXPECT_EQ(ErrorOf("cameras:\n  - {name: a}\n  - {name: b, positon: [0, 0, 0]}\n"),
            "r.yaml:3:15: unknown key 'cameras[1].positon' (did you mean 'position'?)");
  EXPECT_EQ(ErrorOf("cameras:\n  - {name: a}\n  - {name: b, image: gray16}\noutput: {rgb: jpg}\n"),
            "r.yaml:3:22: cameras[1].image: 16-bit grey images cannot be JPEG (rgb: png)");
  EXPECT_EQ(ErrorOf("cameras:\n  - {name: a, image: gray}\n  - {name: b}\noutput: {formats: [bop, "
                    "paper]}\n"),
            "r.yaml:2:22: cameras[0].image: the paper and pvn3d formats need colour images "
            "(image: rgb)");
  EXPECT_EQ(ErrorOf("cameras:\n  - {name: a, depth: {model: kinect_v1, baseline: 0}}\n"),
            "r.yaml:2:51: cameras[0].depth.baseline: baseline must not be 0 for kinect_v1 (its "
            "disparity is f B / z)");
}

TEST(Recipe, LensEffects) {
  const RunSpec spec = ParseRecipe(R"(
render: {mode: pbr}
cameras:
  - name: left
    preset: kinect_v1
    distortion: {k1: -0.12, k2: 0.03, p1: 0.001, p2: -0.002, k3: 0.0}
    lens: {focal_length: 8 mm, f_number: 1.4, focus_distance: 60 cm}
    motion: {velocity_mm_s: [200, 0, 0], angular_velocity_deg_s: [0, 0, 90], exposure_ms: 8}
  - name: right
    position: [50 mm, 0, 0]
)",
                                   "r.yaml", ".");
  ASSERT_EQ(spec.rig.size(), 2u);
  const Distortion& d = spec.rig[0].intrinsics.distortion;
  EXPECT_EQ(d.k1, -0.12);
  EXPECT_EQ(d.p2, -0.002);
  EXPECT_FALSE(spec.rig[1].intrinsics.distortion.active());
  EXPECT_DOUBLE_EQ(spec.rig[0].sensor.lens.aperture_mm(), 8.0 / 1.4);
  EXPECT_EQ(spec.rig[0].sensor.lens.focus_distance_mm, 600.0);
  EXPECT_FALSE(spec.rig[1].sensor.lens.active());
  const CameraMotion& m = spec.rig[0].sensor.motion;
  EXPECT_EQ(m.exposure_s, 0.008);
  EXPECT_NEAR(m.angular_velocity_rad_s.z(), M_PI / 2, 1e-15);
  // The right camera, 50 mm along x of a rig turning at pi/2 rad/s about z, moves at
  // v + w x t = (200, 0, 0) + (0, 0, pi/2) x (50, 0, 0) = (200, 25 pi, 0) mm/s.
  const CameraMotion& r = spec.rig[1].sensor.motion;
  EXPECT_TRUE(r.velocity_mm_s.isApprox(Eigen::Vector3d(200, 25 * M_PI, 0), 1e-12));
  EXPECT_EQ(r.exposure_s, 0.008);

  EXPECT_EQ(ErrorOf("camera: {hfov: 90, width: 640, height: 640, distortion: {k1: -0.3}}\n"),
            "r.yaml:1:57: camera.distortion: pixel (0, 0) has no ray: the distortion polynomial "
            "folds back inside the image (fold radius 1.05409 on the normalised plane); check the "
            "coefficients");
  EXPECT_EQ(ErrorOf("camera: {distortion: {k4: 0.1}}\n"),
            "r.yaml:1:23: unknown key 'camera.distortion.k4' (did you mean 'k1'?)");
  EXPECT_EQ(ErrorOf("camera: {lens: {focal_length: 8 mm}}\n"),
            "r.yaml:1:16: camera.lens: depth of field and motion blur need render.mode: pbr (the "
            "path tracer's samples)");
  EXPECT_EQ(ErrorOf("render: {mode: pbr}\ncamera: {lens: {f_number: 2}}\n"),
            "r.yaml:2:16: camera.lens: give the lens's 'focal_length' (with f_number: the "
            "aperture)");
  EXPECT_EQ(ErrorOf("render: {mode: pbr}\ncamera: {lens: {focal_length: 8, f_number: 0.1}}\n"),
            "r.yaml:2:44: camera.lens.f_number: f_number must lie between 0.5 and 128");
  EXPECT_EQ(ErrorOf("render: {mode: pbr}\ncamera: {motion: {velocity_mm_s: [1, 0, 0]}}\n"),
            "r.yaml:2:18: camera.motion: give 'exposure_ms', how long the shutter is open");
  EXPECT_EQ(ErrorOf("render: {mode: pbr}\ncameras:\n  - {name: a}\n  - {name: b, motion: "
                    "{exposure_ms: 5}}\n"),
            "r.yaml:4:23: cameras[1].motion: the rig moves as one: give its motion on the first "
            "camera (the rig's frame)");
  EXPECT_EQ(ErrorOf("camera: {depth: active_stereo, distortion: {k1: -0.1}}\n"),
            "r.yaml:1:44: camera.distortion: active_stereo matches rectified IR images: give the "
            "distortion to another camera of the rig");
}

TEST(Recipe, Classes) {
  const RunSpec spec = ParseRecipe(R"(
classes:
  by: assembly
  groups:
    fastener: ["*bolt*", "*nut*"]
    plate: plate
)",
                                   "r.yaml", ".");
  EXPECT_EQ(spec.class_by, RunSpec::ClassBy::kAssembly);
  ASSERT_EQ(spec.class_groups.size(), 2u);
  EXPECT_EQ(spec.class_groups[0].first, "fastener");
  EXPECT_EQ(spec.class_groups[0].second, (std::vector<std::string>{"*bolt*", "*nut*"}));
  EXPECT_EQ(spec.class_groups[1].second, std::vector<std::string>{"plate"});
  EXPECT_EQ(ErrorOf("classes: {by: shape}\n"),
            "r.yaml:1:15: classes.by: expected 'part' or 'assembly', got 'shape'");
  EXPECT_EQ(ErrorOf("classes: {group: {}}\n"),
            "r.yaml:1:11: unknown key 'classes.group' (did you mean 'groups'?)");
}

double Num(const ParamValues& v, const char* name) { return std::get<double>(v.at(name)); }

TEST(Recipe, FamilyGridExpandsInTheFamilysParameterOrder) {
  const RunSpec spec = ParseRecipe(R"(
parts:
  - family: spur_gear
    params: {face_width: 1 cm, bore: 5}
    grid: {module: [1, 2], teeth: {from: 12, to: 13, step: 1}}
    class: family
)",
                                   "r.yaml", ".");
  const PartSource& s = spec.scenes.at(0).sources.at(0);
  EXPECT_EQ(s.family, "spur_gear");
  EXPECT_TRUE(s.one_class);
  ASSERT_EQ(s.variants.size(),
            4u);  // teeth comes before module in the family: teeth varies slowest
  EXPECT_EQ(Num(s.variants[0], "teeth"), 12);
  EXPECT_EQ(Num(s.variants[0], "module"), 1);
  EXPECT_EQ(Num(s.variants[1], "module"), 2);
  EXPECT_EQ(Num(s.variants[2], "teeth"), 13);
  EXPECT_EQ(Num(s.variants[3], "face_width"), 10);
  EXPECT_EQ(Num(s.variants[3], "bore"), 5);
  EXPECT_EQ(Num(s.variants[3], "pressure_angle"), 20 * M_PI / 180);  // default filled in
  const RunSpec full = ParseRecipe(
      "parts: [{family: spur_gear, grid: {teeth: {from: 12, to: 40, step: 1}}}]\n", "r", ".");
  EXPECT_EQ(full.scenes[0].sources[0].variants.size(), 29u);
}

TEST(Recipe, SeededRandomFamilyIsTheSameEveryTime) {
  const auto parse = [](int seed) {
    return ParseRecipe("parts:\n  - family: spur_gear\n    random: {count: 6, seed: " +
                           std::to_string(seed) +
                           ", params: {teeth: {from: 12, to: 40}, module: [1.5, 2], helix_angle: "
                           "{from: 0, to: 30}}}\n",
                       "r.yaml", ".")
        .scenes[0]
        .sources[0]
        .variants;
  };
  const auto a = parse(3), b = parse(3), c = parse(4);
  ASSERT_EQ(a.size(), 6u);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  for (const ParamValues& v : a) {
    const double teeth = Num(v, "teeth");
    EXPECT_EQ(teeth, std::floor(teeth));
    EXPECT_GE(teeth, 12);
    EXPECT_LE(teeth, 40);
    EXPECT_TRUE(Num(v, "module") == 1.5 || Num(v, "module") == 2.0);
    EXPECT_LE(Num(v, "helix_angle"), 30 * M_PI / 180);
  }
}

TEST(Recipe, FamilyErrorsPointAtTheKey) {
  EXPECT_EQ(ErrorOf("parts: [{family: spur_gear, params: {teth: 12}}]\n"),
            "r.yaml:1:38: parts[0].params: family 'spur_gear' has no parameter 'teth' (did you "
            "mean 'teeth'?)");
  EXPECT_EQ(ErrorOf("parts: [{family: spur_gear, grid: {module: 2 parsec}}]\n"),
            "r.yaml:1:44: parts[0].grid.module: unknown length unit 'parsec' (use um, mm, cm, m, "
            "in or ft)");
  EXPECT_EQ(ErrorOf("parts: [{family: spur_gear, params: {teeth: 12.5}}]\n"),
            "r.yaml:1:45: parts[0].params.teeth: expected a whole number, got '12.5'");
  EXPECT_NE(ErrorOf("parts: [{family: sprocket}]\n")
                .find("r.yaml:1:18: parts[0].family: unknown family 'sprocket' (known: spur_gear,"),
            std::string::npos);
  EXPECT_EQ(ErrorOf("parts: [{family: washer, grid: {size: [M6]}, random: {count: 2, params: "
                    "{size: [M8]}}}]\n"),
            "r.yaml:1:9: parts[0]: give 'grid' or 'random', not both");
  EXPECT_EQ(ErrorOf("parts: [{family: washer, class: each}]\n"),
            "r.yaml:1:33: parts[0].class: expected 'variant' or 'family', got 'each'");
  EXPECT_EQ(ErrorOf("scenes: [{name: a}]\n"), "r.yaml:1:10: scenes[0]: a scene needs 'parts'");
}

TEST(Recipe, VisibilityRuleAndCocoBoxes) {
  const RunSpec defaults = ParseRecipe("output: {}\n", "r.yaml", ".");
  EXPECT_EQ(defaults.bop.visibility, BopOptions::Visibility::kExact);
  EXPECT_TRUE(defaults.bop.coco_amodal_bbox);
  const RunSpec spec = ParseRecipe(
      "output: {visibility: bop19, visibility_delta: 5 mm, coco_bbox: modal}\n", "r.yaml", ".");
  EXPECT_EQ(spec.bop.visibility, BopOptions::Visibility::kBop19);
  EXPECT_DOUBLE_EQ(spec.bop.visib_delta_mm, 5.0);
  EXPECT_FALSE(spec.bop.coco_amodal_bbox);
  EXPECT_DOUBLE_EQ(ParseRecipe("output: {visibility: bop19}\n", "r.yaml", ".").bop.visib_delta_mm,
                   15.0);
  EXPECT_EQ(ErrorOf("output: {visibility: bop18}\n"),
            "r.yaml:1:22: output.visibility: expected 'exact' or 'bop19', got 'bop18'");
  EXPECT_EQ(ErrorOf("output: {visibility_delta: 5}\n"),
            "r.yaml:1:28: output.visibility_delta: needs visibility: bop19");
  EXPECT_EQ(ErrorOf("output: {visibility: bop19, visibility_delta: -1 mm}\n"),
            "r.yaml:1:47: output.visibility_delta: must not be negative");
  EXPECT_EQ(ErrorOf("output: {coco_bbox: visible}\n"),
            "r.yaml:1:21: output.coco_bbox: expected 'modal' or 'amodal', got 'visible'");
}

TEST(Recipe, ErrorsPointAtLineAndColumn) {
  EXPECT_EQ(ErrorOf("camera:\n  preset: kinect_v1\n  fxx: 500\n"),
            "r.yaml:3:3: unknown key 'camera.fxx' (did you mean 'fx'?)");
  EXPECT_EQ(ErrorOf("sweeep: {}\n"), "r.yaml:1:1: unknown key 'sweeep' (did you mean 'sweep'?)");
  EXPECT_EQ(ErrorOf("exposure: 3\n"), "r.yaml:1:1: unknown key 'exposure'");
  EXPECT_EQ(
      ErrorOf("sweep:\n  radius: 1 parsec\n"),
      "r.yaml:2:11: sweep.radius: unknown length unit 'parsec' (use um, mm, cm, m, in or ft)");
  EXPECT_EQ(ErrorOf("camera: {fx: fast}\n"),
            "r.yaml:1:14: camera.fx: expected a number, got 'fast'");
  EXPECT_EQ(ErrorOf("camera: {width: 0}\n"),
            "r.yaml:1:9: camera: image size 0x480 must be between 1 and 16384 pixels");
  EXPECT_EQ(ErrorOf("sweep: {pitch: {from: 0, to: 90}}\n"),
            "r.yaml:1:16: sweep.pitch: a range needs 'from', 'to' and 'step' (no 'step')");
  EXPECT_EQ(ErrorOf("sweep: {pitch: 120}\n"),
            "r.yaml:1:16: sweep.pitch: pitch must lie between -90 and 90 degrees");
  EXPECT_EQ(ErrorOf("camera: [1, 2\n").rfind("r.yaml:", 0), 0u);  // YAML syntax errors too
  EXPECT_EQ(ErrorOf("- just\n- a list\n"),
            "r.yaml: a recipe is a mapping of sections (parts, sweep, ...)");
}

TEST(Recipe, PartsResolveRelativeToTheRecipe) {
  testing::ScratchDir dir;
  std::ofstream(dir / "part.stp") << "ISO-10303-21;\n";
  const RunSpec spec = ParseRecipe(
      "parts:\n  - file: part.stp\n    unit: inch\n  - family: washer\n", "r.yaml", dir.path());
  ASSERT_EQ(spec.scenes.size(), 1u);
  const std::vector<PartSource>& sources = spec.scenes[0].sources;
  ASSERT_EQ(sources.size(), 2u);
  EXPECT_EQ(sources[0].kind, PartSource::Kind::kFile);
  EXPECT_EQ(sources[0].unit, "inch");
  EXPECT_EQ(sources[0].path, dir / "part.stp");
  EXPECT_EQ(sources[0].where, "r.yaml:2:11");
  EXPECT_EQ(sources[1].kind, PartSource::Kind::kFamily);
  EXPECT_EQ(spec.scenes[0].arrangement.layout, Layout::kAssembled);
  EXPECT_EQ(ErrorOf("parts:\n  - file: nope.stp\n", dir.path()),
            "r.yaml:2:11: parts[0].file: " + (dir / "nope.stp").string() + ": no such file");
  EXPECT_EQ(
      ErrorOf("parts:\n  - file: part.stp\n    unit: cubits\n", dir.path()),
      "r.yaml:3:11: parts[0].unit: unknown length unit 'cubits' (use um, mm, cm, m, in or ft)");
  std::ofstream(dir / "notes.txt") << "bolts, nuts\n";
  EXPECT_NE(
      ErrorOf("parts:\n  - file: notes.txt\n", dir.path()).find("r.yaml:2:11: parts[0].file: "),
      std::string::npos);
  EXPECT_EQ(ErrorOf("parts:\n  - {family: washer, file: part.stp}\n", dir.path()),
            "r.yaml:2:5: parts[0]: give exactly one of 'file' or 'family'");
  EXPECT_EQ(ErrorOf("parts:\n  - fiel: part.stp\n", dir.path()),
            "r.yaml:2:5: unknown key 'parts[0].fiel' (did you mean 'file'?)");
}

TEST(Recipe, LoadRecipeNamesTheFile) {
  testing::ScratchDir dir;
  try {
    LoadRecipe(dir / "nope.yaml");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), (dir / "nope.yaml").string() + ": no such recipe file");
  }
  std::ofstream(dir / "bad.yaml") << "output:\n  dirr: x\n";
  try {
    LoadRecipe(dir / "bad.yaml");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), (dir / "bad.yaml").string() +
                                         ":2:3: unknown key 'output.dirr' (did you mean 'dir'?)");
  }
}

// A recipe path that is a device or a pipe is refused at once (it was read without end, or
// blocked for ever because the recipe was opened twice), and so is a huge file.
TEST(Recipe, OnlyRegularFilesOfBoundedSizeAreRead) {
  for (const char* device : {"/dev/zero", "/dev/urandom", "/dev/null"}) {
    try {
      LoadRecipe(device);
      ADD_FAILURE() << device;
    } catch (const Error& e) {
      EXPECT_EQ(std::string(e.what()),
                std::string(device) + ": not a regular file (a recipe is a YAML file)");
    }
  }
  testing::ScratchDir dir;
  ASSERT_EQ(::mkfifo((dir / "pipe.yaml").c_str(), 0600), 0);
  EXPECT_THROW(LoadRecipe(dir / "pipe.yaml"), Error);  // returns: nothing opens the pipe
  {
    std::ofstream big(dir / "big.yaml");
    big << "# " << std::string(17 << 20, 'x') << "\n";
  }
  try {
    LoadRecipe(dir / "big.yaml");
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("too large for a recipe"), std::string::npos) << e.what();
  }
  // The text read is kept: the run key takes it from the spec, never from the path again.
  std::ofstream(dir / "ok.yaml") << "sweep: {yaw: 0, pitch: 45, radius: 0.5 m}\n";
  EXPECT_EQ(LoadRecipe(dir / "ok.yaml").recipe_text, "sweep: {yaw: 0, pitch: 45, radius: 0.5 m}\n");
}

// A key or a section written twice is an error naming both lines (yaml-cpp silently used the
// first one).
TEST(Recipe, DuplicateKeysAreErrors) {
  EXPECT_EQ(ErrorOf("sweep: {yaw: 0}\nsweep: {yaw: 10}\n"),
            "r.yaml:2:1: 'sweep' is given twice (first at line 1)");
  EXPECT_EQ(ErrorOf("output:\n  coco: true\n  split: val\n  coco: false\n"),
            "r.yaml:4:3: 'coco' is given twice (first at line 2)");
  EXPECT_EQ(ErrorOf("parts:\n  - {family: washer, family: hex_nut}\n"),
            "r.yaml:2:22: 'family' is given twice (first at line 2)");
}

// A camera a light-year away made Embree abort the process; the sweep refuses it.
TEST(Recipe, FarCamerasAndTargetsAreRefused) {
  EXPECT_EQ(
      ErrorOf("sweep: {radius: 1e19 mm}\n"),
      "r.yaml:1:17: sweep.radius: radius must be at most 1 km (the tracer's single precision would "
      "lose the parts)");
  SweepOptions sweep;
  sweep.yaw_rad = {0};
  sweep.pitch_rad = {0.5};
  sweep.radius_mm = {500};
  sweep.target = Eigen::Vector3d(0, 0, 2e6);
  std::string why;
  EXPECT_FALSE(sweep.Check(&why));
  EXPECT_EQ(why, "the target must lie within 1 km of the origin");
  sweep.target = Eigen::Vector3d(0, std::nan(""), 0);
  EXPECT_FALSE(sweep.Check(&why));
  sweep.target = Eigen::Vector3d(0, 0, 100);
  EXPECT_TRUE(sweep.Check(&why));
}

// `up:` names the axis a file was drawn with as up; it is turned to +z.
TEST(Recipe, UpAxisTurnsToZ) {
  for (const char* axis : {"x", "y", "z", "-x", "-y", "-z"}) {
    const RunSpec spec = ParseRecipe(
        "parts:\n  - {family: hex_nut, up: " + std::string(axis) + "}\n", "r.yaml", ".");
    Eigen::Vector3d up = Eigen::Vector3d::Zero();
    up[std::string(axis).back() - 'x'] = axis[0] == '-' ? -1 : 1;
    const Eigen::Matrix3d& turn = spec.scenes[0].sources[0].z_from_up;
    EXPECT_TRUE((turn * up).isApprox(Eigen::Vector3d::UnitZ(), 1e-12)) << axis;
    EXPECT_NEAR(turn.determinant(), 1.0, 1e-12) << axis;
  }
  EXPECT_EQ(ErrorOf("parts:\n  - {family: hex_nut, up: w}\n"),
            "r.yaml:2:27: parts[0].up: expected x, y, z, -x, -y or -z, got 'w'");
}

// A typo that asks for minutes of work is an error at once, with the limit to raise.
TEST(Recipe, LimitsStopRunawayRecipes) {
  EXPECT_EQ(ErrorOf("parts:\n  - {family: spur_gear, params: {teeth: 5000}}\n"),
            "r.yaml:2:14: spur_gear: teeth = 5000 is more than 1000 (building it would take "
            "minutes); if you mean it, raise limits.max_count");
  EXPECT_EQ(ErrorOf("parts:\n  - family: ball_bearing\n    grid: {bore: {from: 1, to: 30, "
                    "step: 0.01}}\n"),
            "r.yaml:2:13: the recipe asks for more than 2000 parts and variants; if you mean it, "
            "raise limits.max_variants");
  EXPECT_EQ(ErrorOf("tessellation: {linear_deflection: 0.0001 mm}\n"),
            "r.yaml: tessellation.linear_deflection 0.0001 mm is finer than 0.001 mm (millions "
            "of triangles per part); if you mean it, lower limits.min_deflection");
  const RunSpec raised = ParseRecipe(
      "parts:\n  - {family: spur_gear, params: {teeth: 1200}}\nlimits: {max_count: 1500}\n",
      "r.yaml", ".");
  EXPECT_EQ(raised.limits.max_count, 1500);
  EXPECT_EQ(ErrorOf("limits: {max_variants: 0}\n"),
            "r.yaml:1:24: limits.max_variants: max_variants and max_count must be at least 1");
}

// A split name becomes a folder and JSON text: raw bytes (not UTF-8) ended in "internal:
// json.exception"; now only plain names pass.
TEST(Recipe, SplitNamesArePlainFolderNames) {
  EXPECT_EQ(ErrorOf("output: {split: \"tr\xe9in\"}\n"),
            "r.yaml:1:17: output.split: split must be a plain folder name: up to 64 letters, "
            "digits, '_', '-' or '.'");
  EXPECT_NE(ErrorOf("output: {split: \"a b\"}\n").find("plain folder name"), std::string::npos);
  EXPECT_EQ(ParseRecipe("output: {split: train_pbr}\n", "r.yaml", ".").bop.split, "train_pbr");
}

TEST(Recipe, PhysicallyBasedMaterialsAndLights) {
  const RunSpec spec = ParseRecipe(
      "render: {mode: pbr, samples: 32, bounces: 2, exposure: -1, view: standard}\n"
      "materials:\n"
      "  floor: {preset: concrete, roughness: 0.9}\n"
      "  default: {preset: abs}\n"
      "  assign:\n"
      "    - {family: planetary, preset: steel, roughness: 0.2}\n"
      "    - {name: 'hex*', preset: black_oxide, texture: none}\n"
      "    - {file: '*.stl', base_color: [1, 0, 0], metallic: 0, texture: {type: checker, scale: 5 "
      "mm}}\n"
      "lighting:\n"
      "  lights:\n"
      "    - {type: rect, position: [0, 0, 2 m], target: [0, 0, 0], size: [1 m, 0.5 m], power: "
      "40}\n"
      "    - {type: spot, position: [1 m, 0, 1 m], target: [0, 0, 0], power: 100, spot_size: 30}\n"
      "    - {type: sun, direction: [0, 0, -1], strength: 2, angle: 1}\n"
      "  environment: {type: sky, strength: 0.5}\n",
      "r.yaml", ".");
  EXPECT_EQ(spec.render.mode, RenderOptions::Mode::kPbr);
  EXPECT_EQ(spec.render.samples, 32);
  EXPECT_EQ(spec.render.view, RenderOptions::View::kStandard);
  EXPECT_FLOAT_EQ(spec.look.floor_material.surface.roughness, 0.9f);
  ASSERT_TRUE(spec.default_material.has_value());
  EXPECT_TRUE(spec.default_material->base_from_part);  // plastics take the part's colour
  ASSERT_EQ(spec.material_rules.size(), 3u);
  EXPECT_EQ(spec.material_rules[0].family, "planetary");
  EXPECT_FLOAT_EQ(spec.material_rules[0].material.surface.metallic, 1.0f);
  EXPECT_FLOAT_EQ(spec.material_rules[0].material.surface.roughness, 0.2f);
  EXPECT_EQ(spec.material_rules[1].material.texture.kind, Texture::Kind::kNone);
  EXPECT_EQ(spec.material_rules[2].file, "*.stl");
  EXPECT_FLOAT_EQ(spec.material_rules[2].material.surface.base_color[0], 1.0f);
  EXPECT_EQ(spec.material_rules[2].material.texture.kind, Texture::Kind::kChecker);
  EXPECT_DOUBLE_EQ(spec.material_rules[2].material.texture.scale_mm, 5.0);
  ASSERT_EQ(spec.look.light_sources.size(), 3u);
  EXPECT_EQ(spec.look.light_sources[0].kind, LightSource::Kind::kRect);
  EXPECT_DOUBLE_EQ(spec.look.light_sources[0].size_y_mm, 500.0);
  EXPECT_NEAR(spec.look.light_sources[0].direction.normalized().z(), -1.0, 1e-12);  // at target
  EXPECT_NEAR(spec.look.light_sources[1].spot_size_rad, 30 * M_PI / 180, 1e-12);
  EXPECT_DOUBLE_EQ(spec.look.light_sources[2].power, 2.0);  // the sun's W/m2
  EXPECT_EQ(spec.look.environment.kind, Environment::Kind::kSky);
}

// Numbers are linear, as Blender's Python and BlenderProc take them (a Principled BSDF's default
// Base Color 0.8 is 0.8 here too); "#RRGGBB" is sRGB, as Blender's Hex field (0.8 shows as E7).
TEST(Recipe, PhysicallyBasedColoursAreLinearAndHexIsSrgb) {
  const RunSpec spec = ParseRecipe(
      "render: {mode: pbr}\n"
      "materials:\n"
      "  floor: {base_color: '#E7E7E7', texture: {type: wood, color: [0.2, 0.1, 0.05]}}\n"
      "  assign: [{name: '*', base_color: [0.8, 0.5, 0.2]}]\n"
      "lighting:\n"
      "  lights: [{type: point, position: [0, 0, 1 m], power: 10, color: '#FF8000'}]\n"
      "  environment: {type: uniform, color: [0.35, 0.35, 0.35]}\n",
      "r.yaml", ".");
  const Eigen::Vector3f& rule = spec.material_rules.at(0).material.surface.base_color;
  EXPECT_FLOAT_EQ(rule[0], 0.8f);
  EXPECT_FLOAT_EQ(rule[1], 0.5f);
  EXPECT_FLOAT_EQ(rule[2], 0.2f);
  // sRGB 231/255 = 0.9059: ((0.9059 + 0.055) / 1.055)^2.4 = 0.7991.
  EXPECT_NEAR(spec.look.floor_material.surface.base_color[0], 0.7991f, 1e-4f);
  EXPECT_FLOAT_EQ(spec.look.floor_material.texture.color[1], 0.1f);
  const Eigen::Vector3f& light = spec.look.light_sources.at(0).color;
  EXPECT_FLOAT_EQ(light[0], 1.0f);
  EXPECT_NEAR(light[1], 0.2159f, 1e-4f);  // sRGB 128/255 = 0.502
  EXPECT_FLOAT_EQ(light[2], 0.0f);
  EXPECT_FLOAT_EQ(spec.look.environment.color[0], 0.35f);
  // Anisotropy's tangent: Blender's default (radial) unless a preset or the rule says x.
  EXPECT_EQ(spec.material_rules.at(0).material.tangent, Material::Tangent::kRadial);
  const RunSpec brushed = ParseRecipe(
      "materials: {assign: [{name: a, preset: stainless}, {name: b, preset: steel, anisotropic: "
      "0.5}, {name: c, preset: steel, tangent: x}]}\n",
      "r.yaml", ".");
  EXPECT_EQ(brushed.material_rules[0].material.tangent, Material::Tangent::kModelX);
  EXPECT_EQ(brushed.material_rules[1].material.tangent, Material::Tangent::kRadial);
  EXPECT_EQ(brushed.material_rules[2].material.tangent, Material::Tangent::kModelX);
  EXPECT_EQ(ErrorOf("materials: {assign: [{name: a, tangent: along}]}\n"),
            "r.yaml:1:41: materials.assign[0].tangent: expected 'radial' or 'x', got 'along'");
  EXPECT_EQ(ErrorOf("materials: {assign: [{name: '*', base_color: '#E7E7G7'}]}\n"),
            "r.yaml:1:46: materials.assign[0].base_color: expected linear [r, g, b] in 0..1 or an "
            "sRGB hex colour \"#RRGGBB\"");
  EXPECT_NE(ErrorOf("materials: {assign: [{name: '*', base_color: [1.5, 0, 0]}]}\n").find("0..1"),
            std::string::npos);
  // Unquoted, YAML reads the hex colour as a comment: the key is there, its value is not.
  EXPECT_NE(ErrorOf("materials:\n  floor:\n    base_color: #E7E7E7\n").find("quote a hex colour"),
            std::string::npos);
}

// The collision shapes' options (CollisionOptions, one set for the run): read with their units,
// checked, and an impossible one named at its key and line.
TEST(Recipe, CollisionShapesReadTheirOptions) {
  const RunSpec spec = ParseRecipe(
      "collision: {time_limit: 5, max_pieces: 12, merge_volume: 0, tolerance: 0.02 cm,\n"
      "            concavity: 0.05}\n",
      "r.yaml", ".");
  EXPECT_DOUBLE_EQ(spec.collision.time_limit_s, 5.0);
  EXPECT_EQ(spec.collision.max_pieces, 12);
  EXPECT_DOUBLE_EQ(spec.collision.merge_volume, 0.0);
  EXPECT_DOUBLE_EQ(spec.collision.tolerance_mm, 0.2);
  EXPECT_DOUBLE_EQ(spec.collision.concavity, 0.05);
  EXPECT_DOUBLE_EQ(DefaultRunSpec().collision.time_limit_s, 60.0);
  EXPECT_EQ(ErrorOf("collision:\n  max_pieces: 0\n"),
            "r.yaml:2:15: collision.max_pieces: max_pieces must be 1 to 256");
  EXPECT_EQ(ErrorOf("collision: {time_limit: -2}\n"),
            "r.yaml:1:25: collision.time_limit: must not be negative");
  EXPECT_EQ(
      ErrorOf("collision: {pieces: 3}\n").rfind("r.yaml:1:13: unknown key 'collision.pieces'", 0),
      0u)
      << ErrorOf("collision: {pieces: 3}\n");
}

TEST(Recipe, PileScenesReadTheirContainerAndPhysics) {
  const RunSpec spec = ParseRecipe(
      "scenes:\n"
      "  - name: bin\n"
      "    parts: [{family: hex_nut}]\n"
      "    layout: pile\n"
      "    copies: 40\n"
      "    seed: 3\n"
      "    drop_height: 5 cm\n"
      "    settle_time: 12\n"
      "    container: {type: tote, inner: [300 mm, 200 mm], height: 0.1 m, corner_radius: 0,\n"
      "                color: [0.8, 0.1, 0.1], friction: 0.4, material: {preset: plastic_sheet}}\n"
      "    physics: {density: 2700, friction: 0.3, restitution: 0.2}\n",
      "r.yaml", ".");
  ASSERT_EQ(spec.scenes.size(), 1u);
  const SceneSpec& s = spec.scenes[0];
  EXPECT_EQ(s.arrangement.layout, Layout::kPile);
  EXPECT_EQ(s.arrangement.copies, 40);
  EXPECT_DOUBLE_EQ(s.arrangement.drop_height_mm, 50.0);
  EXPECT_DOUBLE_EQ(s.arrangement.settle_time_s, 12.0);
  EXPECT_EQ(s.arrangement.container.kind, Container::Kind::kTote);
  EXPECT_EQ(s.arrangement.container.inner_mm, Eigen::Vector2d(300, 200));
  EXPECT_DOUBLE_EQ(s.arrangement.container.height_mm, 100.0);
  EXPECT_DOUBLE_EQ(s.arrangement.container.corner_radius_mm, 0.0);
  EXPECT_DOUBLE_EQ(s.arrangement.container.material.friction, 0.4);
  EXPECT_FLOAT_EQ(s.container_color.x(), 0.8f);
  ASSERT_TRUE(s.container_material.has_value());
  EXPECT_DOUBLE_EQ(s.arrangement.physics.low.density_kg_m3, 2700.0);
  EXPECT_DOUBLE_EQ(s.arrangement.physics.high.density_kg_m3, 2700.0);
  EXPECT_DOUBLE_EQ(s.arrangement.physics.low.restitution, 0.2);
  EXPECT_TRUE(s.physics_rules.empty());

  EXPECT_EQ(ErrorOf("parts: [{family: hex_nut}]\nscene: {layout: pile, container: tote}\n"),
            "r.yaml:2:34: scene.container: expected a mapping of keys to values");
  EXPECT_EQ(ErrorOf("scenes:\n  - {parts: [{family: hex_nut}], container: {type: tote}}\n"),
            "r.yaml:2:45: scenes[0].container: only a pile (layout: pile) has one");
  EXPECT_EQ(ErrorOf("scenes:\n  - {parts: [{family: hex_nut}], layout: pile, container: {type: "
                    "bucket}}\n"),
            "r.yaml:2:66: scenes[0].container.type: unknown container 'bucket' (known: tote, "
            "floor, file)");
  EXPECT_EQ(ErrorOf("scenes:\n  - {parts: [{family: hex_nut}], layout: pile, physics: {friction: "
                    "-1}}\n"),
            "r.yaml:2:68: scenes[0].physics.friction: friction must lie in [0, 10]");
  EXPECT_EQ(ErrorOf("scenes:\n  - {parts: [{family: hex_nut}], layout: pile, container: {type: "
                    "tote, inner: [100 mm, 50 mm], corner_radius: 40 mm}}\n"),
            "r.yaml:2:111: scenes[0].container.corner_radius: corner_radius must lie between 0 and "
            "half the tote's inner width (25 mm)");
}

// Physics per part (rules matched like material rules) with values drawn from ranges, and
// pose: dropped for the other layouts, which may give physics but no container.
TEST(Recipe, PhysicsRulesRangesAndDroppedPoses) {
  const RunSpec spec = ParseRecipe(
      "scenes:\n"
      "  - name: mixed\n"
      "    parts: [{family: hex_nut}, {family: spur_gear}]\n"
      "    layout: pile\n"
      "    physics:\n"
      "      - {family: hex_nut, friction: [0.3, 0.9], density: 7850}\n"
      "      - {name: '*gear*', density: [1000, 1200], restitution: 0.3}\n"
      "  - name: fallen\n"
      "    parts: [{family: hex_nut}]\n"
      "    layout: grid\n"
      "    pose: dropped\n"
      "    copies: 5\n"
      "    physics: {friction: [0.2, 0.4]}\n",
      "r.yaml", ".");
  ASSERT_EQ(spec.scenes.size(), 2u);
  const std::vector<PhysicsRule>& rules = spec.scenes[0].physics_rules;
  ASSERT_EQ(rules.size(), 2u);
  EXPECT_EQ(rules[0].family, "hex_nut");
  EXPECT_DOUBLE_EQ(rules[0].physics.low.friction, 0.3);
  EXPECT_DOUBLE_EQ(rules[0].physics.high.friction, 0.9);
  EXPECT_DOUBLE_EQ(rules[0].physics.high.density_kg_m3, 7850.0);
  EXPECT_EQ(rules[1].name, "*gear*");
  EXPECT_DOUBLE_EQ(rules[1].physics.low.density_kg_m3, 1000.0);
  EXPECT_DOUBLE_EQ(rules[1].physics.high.restitution, 0.3);
  EXPECT_DOUBLE_EQ(rules[1].physics.low.friction, PhysicsMaterial{}.friction);  // left out
  EXPECT_EQ(rules[1].where, "r.yaml:7:9");
  const SceneSpec& fallen = spec.scenes[1];
  EXPECT_EQ(fallen.arrangement.pose, PoseMode::kDropped);
  EXPECT_DOUBLE_EQ(fallen.arrangement.physics.low.friction, 0.2);
  EXPECT_DOUBLE_EQ(fallen.arrangement.physics.high.friction, 0.4);

  EXPECT_EQ(ErrorOf("scenes:\n  - {parts: [{family: hex_nut}], physics: {friction: 0.5}}\n"),
            "r.yaml:2:43: scenes[0].physics: only a pile (layout: pile) or dropped parts (pose: "
            "dropped) have physics");
  EXPECT_EQ(ErrorOf("scenes:\n  - {parts: [{family: hex_nut}], pose: dropped, container: {type: "
                    "tote}}\n"),
            "r.yaml:2:60: scenes[0].container: only a pile (layout: pile) has one");
  EXPECT_EQ(ErrorOf("scenes:\n  - {parts: [{family: hex_nut}], layout: pile, physics: {friction: "
                    "[0.9, 0.3]}}\n"),
            "r.yaml:2:68: scenes[0].physics.friction: the range's low end exceeds its high end");
  EXPECT_EQ(ErrorOf("scenes:\n  - {parts: [{family: hex_nut}], layout: pile, physics: [{friction: "
                    "0.3}]}\n"),
            "r.yaml:2:58: scenes[0].physics[0]: say which parts: 'name', 'family' or 'file' (a "
            "pattern)");
  EXPECT_EQ(ErrorOf("scenes:\n  - {parts: [{family: hex_nut}], layout: pile, container: {type: "
                    "tote, friction: [0.2, 0.5]}}\n"),
            "r.yaml:2:82: scenes[0].container.friction: expected a number (a container's is not "
            "drawn)");
}

TEST(Recipe, PhysicallyBasedErrorsPointAtTheKey) {
  EXPECT_EQ(ErrorOf("materials: {assign: [{name: '*', preset: steal}]}\n").substr(0, 89),
            "r.yaml:1:42: materials.assign[0].preset: unknown material 'steal' (did you mean "
            "'steel'?)");
  EXPECT_EQ(ErrorOf("materials:\n  floor: {roughness: 1.5}\n"),
            "r.yaml:2:22: materials.floor.roughness: must lie in [0, 1], got 1.5");
  EXPECT_EQ(ErrorOf("materials:\n  floor: {distribution: beckmann}\n"),
            "r.yaml:2:25: materials.floor.distribution: expected 'ggx' or 'multiscatter_ggx', got "
            "'beckmann'");
  const RunSpec multi = ParseRecipe(
      "materials:\n  floor: {preset: steel, distribution: multiscatter_ggx, anisotropic: 1}\n",
      "r.yaml", ".");
  EXPECT_TRUE(multi.look.floor_material.surface.multiscatter);
  EXPECT_EQ(multi.look.floor_material.surface.anisotropic, 1.0f);  // Blender's range, [0, 1]
  EXPECT_EQ(ErrorOf("materials:\n  floor: {texture: {type: image, file: no_such.png}}\n"),
            "r.yaml:2:40: materials.floor.texture.file: no_such.png: no such file");
  EXPECT_EQ(ErrorOf("lighting:\n  lights: [{type: point, position: [0, 0, 1 m], power: -5}]\n"),
            "r.yaml:2:56: lighting.lights[0].power: must not be negative");
  EXPECT_EQ(ErrorOf("lighting:\n  lights: [{type: sun, power: 3}]\n"),
            "r.yaml:2:31: lighting.lights[0].power: a sun's is 'strength' (irradiance, W/m2, as "
            "Blender's)");
  EXPECT_EQ(ErrorOf("lighting:\n  lights: [{type: laser}]\n"),
            "r.yaml:2:19: lighting.lights[0].type: unknown light 'laser' (known: point, spot, "
            "rect, disc, sun)");
  EXPECT_EQ(ErrorOf("lighting:\n  lights: [{type: disc, power: 5}]\n"),
            "r.yaml:2:12: lighting.lights[0]: a disc light needs a 'radius'");
  EXPECT_EQ(ErrorOf("render: {mode: photoreal}\n").substr(0, 38),
            "r.yaml:1:16: render.mode: expected 'fa");
  EXPECT_EQ(ErrorOf("render: {samples: 0}\n"),
            "r.yaml:1:19: render.samples: samples must be 1 to 65536 paths per pixel");

  // An environment image that is not one: a named file, line and column.
  testing::ScratchDir dir;
  std::ofstream(dir / "sky.hdr") << "#?RADIANCE\nnot really\n";
  const std::string error =
      ErrorOf("lighting:\n  environment: {type: image, file: sky.hdr}\n", dir.path());
  EXPECT_EQ(error.rfind("r.yaml:2:36: lighting.environment.file: ", 0), 0u) << error;
  EXPECT_NE(error.find("sky.hdr"), std::string::npos) << error;
  EXPECT_NE(error.find("not a readable Radiance HDR image"), std::string::npos) << error;

  // Projections: only image textures have one, the floor has no texture coordinates.
  testing::WriteSolidPng(dir / "tile.png", 2, 2, 0x80);
  EXPECT_EQ(ErrorOf("materials:\n  floor: {texture: {type: image, file: tile.png, projection: "
                    "uv}}\n",
                    dir.path()),
            "r.yaml:2:10: materials.floor: the floor has no texture coordinates: use projection "
            "'triplanar' (or 'auto')");
  EXPECT_EQ(ErrorOf("materials:\n  default: {texture: {type: image, file: tile.png, projection: "
                    "cylinder}}\n",
                    dir.path()),
            "r.yaml:2:64: materials.default.texture.projection: unknown projection 'cylinder' "
            "(known: auto, triplanar, uv)");
  EXPECT_EQ(ErrorOf("materials:\n  default: {texture: {type: noise, projection: uv}}\n"),
            "r.yaml:2:36: materials.default.texture.projection: goes with type: image, not noise");
  const RunSpec uv = ParseRecipe(
      "materials:\n  assign: [{file: '*.obj', texture: {type: image, file: tile.png, projection: "
      "uv}}]\n",
      "r.yaml", dir.path());
  EXPECT_EQ(uv.material_rules[0].material.texture.projection, Texture::Projection::kUv);
  EXPECT_EQ(uv.material_rules[0].where, "r.yaml:2:12");
}

TEST(Recipe, RandomizeReadsDistributionsPerGroupAndPerScene) {
  const RunSpec spec = ParseRecipe(R"(
scenes:
  - {name: a, parts: [{family: hex_bolt}]}
  - name: b
    parts: [{family: hex_bolt}]
    randomize:
      lights: {count: 2, per: scene}
render: {mode: pbr}
randomize:
  seed: 9
  parts:
    - {family: hex_bolt, each: instance, preset: {choice: [steel, brass]}, roughness: {uniform: [0.2, 0.6]}}
  floor: {preset: concrete, texture_scale: {log_uniform: [0.5, 2]}}
  lights: {count: {choice: [1, 2]}, type: [rect, spot], distance: {uniform: [1 m, 2 m]}}
  environment: {strength: {normal: [0.3, 0.05]}}
  camera: {exposure: {normal: [0, 0.5]}, rotation: 1, translation: 2 cm}
)",
                                   "r.yaml", ".");
  const Randomization& d = spec.randomize.draws;
  EXPECT_EQ(d.seed, 9u);
  ASSERT_EQ(d.parts.size(), 1u);
  EXPECT_TRUE(d.parts[0].per_instance);
  EXPECT_EQ(d.parts[0].material.preset_names, (std::vector<std::string>{"steel", "brass"}));
  EXPECT_EQ(d.parts[0].material.roughness->kind, Distribution::Kind::kUniform);
  EXPECT_EQ(d.parts[0].material.roughness->b, 0.6);
  EXPECT_EQ(spec.randomize.part_rules[0].family, "hex_bolt");
  EXPECT_EQ(spec.randomize.part_rules[0].where, "r.yaml:12:7");
  EXPECT_EQ(d.floor->preset_names, std::vector<std::string>{"concrete"});
  EXPECT_EQ(d.lights->kinds.size(), 2u);
  EXPECT_EQ(d.lights->distance_mm.a, 1000.0);  // lengths in their units
  EXPECT_EQ(d.lights->count.values, (std::vector<double>{1, 2}));
  EXPECT_EQ(d.environment->strength->kind, Distribution::Kind::kNormal);
  EXPECT_EQ(d.camera->translation_mm->a, 20.0);
  EXPECT_EQ(d.lights_per, DrawPer::kFrame);
  // Scene b replaces the lights only.
  EXPECT_FALSE(spec.scenes[0].randomize.has_value());
  ASSERT_TRUE(spec.scenes[1].randomize.has_value());
  const Randomization& b = spec.scenes[1].randomize->draws;
  EXPECT_EQ(b.lights->count.kind, Distribution::Kind::kFixed);
  EXPECT_EQ(b.lights->count.a, 2.0);
  EXPECT_EQ(b.lights->kinds.size(), 1u);  // the scene's own lights, from the defaults
  EXPECT_EQ(b.lights_per, DrawPer::kScene);
  EXPECT_EQ(b.parts.size(), 1u);
  EXPECT_TRUE(b.camera.has_value());
}

TEST(Recipe, RandomizeTexturesComeFromAFolder) {
  testing::ScratchDir dir;
  std::filesystem::create_directories(dir / "tex");
  std::filesystem::create_directories(dir / "empty");
  for (const char* name : {"b.png", "a.png"}) {
    testing::WriteSolidPng(dir / "tex" / name, 2, 2, 0x40);
  }
  std::ofstream(dir / "tex" / "notes.txt") << "not an image\n";
  const RunSpec spec = ParseRecipe(
      "render: {mode: pbr}\nrandomize:\n  floor: {textures: {folder: tex, scale: 0.5 m}}\n",
      "r.yaml", dir.path());
  const MaterialRandomization& floor = *spec.randomize.draws.floor;
  EXPECT_EQ(floor.texture_names, (std::vector<std::string>{"a.png", "b.png"}));
  ASSERT_EQ(floor.textures.size(), 2u);
  EXPECT_EQ(floor.textures[0].scale_mm, 500.0);
  ASSERT_TRUE(floor.textures[1].pixels);
  EXPECT_EQ(floor.textures[1].pixels->width, 2);
  EXPECT_EQ(ErrorOf("render: {mode: pbr}\nrandomize:\n  floor: {textures: {folder: empty}}\n",
                    dir.path()),
            "r.yaml:3:30: randomize.floor.textures.folder: " + (dir / "empty").string() +
                ": no PNG, JPEG, EXR or HDR images in the folder");
  // Environment images and background photos come from folders the same way.
  const RunSpec worlds = ParseRecipe(
      "render: {mode: pbr, floor: false}\nrandomize:\n  environment: {images: {folder: tex}, "
      "rotation: {uniform: [0, 360]}}\n  background: {folder: tex, per: scene}\n",
      "r.yaml", dir.path());
  const Randomization& w = worlds.randomize.draws;
  EXPECT_EQ(w.environment->images->names, (std::vector<std::string>{"a.png", "b.png"}));
  EXPECT_EQ(w.background->images.pixels.size(), 2u);
  EXPECT_EQ(w.background_per, DrawPer::kScene);
  EXPECT_EQ(ErrorOf("render: {mode: pbr}\nrandomize:\n  background: {folder: tex}\n", dir.path()),
            "r.yaml:3:24: randomize.background: pastes photos where nothing is hit, but the floor "
            "fills every downward view: set render.floor: false");
  EXPECT_EQ(ErrorOf("render: {mode: pbr, floor: false}\nrandomize:\n  background: {folder: tex}\n",
                    dir.path() / "empty"),
            "r.yaml:3:24: randomize.background.folder: " + (dir / "empty" / "tex").string() +
                ": no such folder");
  EXPECT_EQ(ErrorOf("render: {mode: pbr}\nrandomize:\n  environment: {images: {folder: tex}, "
                    "temperature: 5000}\n",
                    dir.path()),
            "r.yaml:3:53: randomize.environment.temperature: tints a uniform environment's colour "
            "(images are drawn)");
  EXPECT_EQ(
      ErrorOf("randomize:\n  background: {folder: tex}\n", dir.path()),
      "r.yaml:2:3: randomize: materials, lights, the environment, exposure, white balance and "
      "background photos are randomised in render.mode: pbr (the fast mode takes the "
      "camera's pose jitter and distractors)");
  EXPECT_EQ(ErrorOf("render: {mode: pbr}\nrandomize:\n  fixtures: {textures: {folder: nowhere}}\n",
                    dir.path()),
            "r.yaml:3:33: randomize.fixtures.textures.folder: " + (dir / "nowhere").string() +
                ": no such folder");
}

TEST(Recipe, RandomizeDistractorsAreListedObjectsAndFolders) {
  testing::ScratchDir dir;
  std::filesystem::create_directories(dir / "clutter");
  std::filesystem::create_directories(dir / "nothing");
  const std::string cube =
      "solid c\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
      "vertex 0 1 0\nendloop\nendfacet\nendsolid c\n";
  for (const char* name : {"b.stl", "a.STL"}) std::ofstream(dir / "clutter" / name) << cube;
  std::ofstream(dir / "clutter" / "readme.txt") << "not a mesh\n";
  std::ofstream(dir / "nothing" / "readme.txt") << "not a mesh\n";
  const RunSpec spec = ParseRecipe(R"(
randomize:
  distractors:
    count: {uniform: [2, 5]}
    size: {uniform: [1 cm, 4 cm]}
    objects: [box, {primitive: sphere}, {folder: clutter, unit: cm}, {family: hex_nut}]
)",
                                   "r.yaml", dir.path());
  const RandomizeSpec& r = spec.randomize;
  ASSERT_TRUE(r.draws.distractors);
  EXPECT_EQ(r.draws.distractors->count.b, 5.0);
  EXPECT_EQ(r.draws.distractors->size_mm.a, 10.0);  // lengths in their units
  EXPECT_FALSE(r.draws.distractors->material);
  ASSERT_EQ(r.distractor_objects.size(), 5u);  // the folder's two meshes, sorted by name
  EXPECT_EQ(r.distractor_objects[0].kind, DistractorObject::Kind::kBox);
  EXPECT_EQ(r.distractor_objects[1].kind, DistractorObject::Kind::kSphere);
  EXPECT_EQ(r.distractor_objects[2].source.path.filename(), "a.STL");
  EXPECT_EQ(r.distractor_objects[3].source.path.filename(), "b.stl");
  EXPECT_EQ(r.distractor_objects[3].source.unit, "cm");
  EXPECT_EQ(r.distractor_objects[4].source.family, "hex_nut");
  // Without a list: a box, a cylinder and a sphere. Geometry needs no pbr; their materials do.
  const RunSpec plain = ParseRecipe("randomize: {distractors: {count: 3}}\n", "r.yaml", ".");
  EXPECT_EQ(plain.randomize.distractor_objects.size(), 3u);
  EXPECT_EQ(
      ErrorOf("randomize: {distractors: {material: {roughness: 0.5}}}\n"),
      "r.yaml:1:12: randomize: materials, lights, the environment, exposure, white balance and "
      "background photos are randomised in render.mode: pbr (the fast mode takes the "
      "camera's pose jitter and distractors)");
  EXPECT_EQ(ErrorOf("randomize:\n  distractors: {objects: [cube]}\n"),
            "r.yaml:2:27: randomize.distractors.objects[0]: unknown primitive 'cube' (known: box, "
            "cylinder, sphere; files and families go in a map such as {file: part.stl})");
  EXPECT_EQ(ErrorOf("randomize:\n  distractors: {objects: [{folder: nothing}]}\n", dir.path()),
            "r.yaml:2:36: randomize.distractors.objects[0].folder: " + (dir / "nothing").string() +
                ": no CAD or mesh files in the folder (STEP, IGES, BREP, STL, OBJ, PLY, DAE, "
                "glTF, 3MF, OFF)");
  EXPECT_EQ(ErrorOf("randomize:\n  distractors: {count: {uniform: [6, 2]}}\n"),
            "r.yaml:2:24: randomize.distractors.count: uniform: [low, high] with low <= high, got "
            "[6.000000, 2.000000]");
  EXPECT_EQ(
      ErrorOf("randomize:\n  distractors: {count: 500}\n"),
      "r.yaml:2:16: randomize.distractors: count: draws must lie in [0.000000, 200.000000] (a "
      "normal's mean; its tails are clipped to them)");
  EXPECT_EQ(ErrorOf("randomize:\n  distractors: {objects: [{file: a.stl, family: hex_nut}]}\n"),
            "r.yaml:2:27: randomize.distractors.objects[0]: give one of 'primitive', 'file', "
            "'folder' or 'family'");
}

TEST(Recipe, GraspsSectionSetsTheGripperAndSampling) {
  const RunSpec spec = ParseRecipe(
      "grasps: {gripper: franka, friction: 0.4, samples: 300, approaches: 4, seed: 7}\n", "r.yaml",
      ".");
  EXPECT_TRUE(spec.grasps.enabled);
  EXPECT_EQ(spec.grasps.gripper.max_opening_mm, 80.0);
  EXPECT_EQ(spec.grasps.sampling.friction, 0.4);
  EXPECT_EQ(spec.grasps.sampling.samples, 300);
  EXPECT_EQ(spec.grasps.sampling.approaches, 4);
  EXPECT_EQ(spec.grasps.sampling.seed, 7u);
  EXPECT_FALSE(ParseRecipe("parts: [{family: hex_nut}]\n", "r.yaml", ".").grasps.enabled);
  EXPECT_EQ(ErrorOf("grasps: {gripper: robotiq}\n"),
            "r.yaml:1:19: grasps.gripper: unknown gripper 'robotiq' (known: franka, "
            "robotiq_2f85)");
  EXPECT_EQ(ErrorOf("grasps: {friction: 0}\n"),
            "r.yaml:1:9: grasps: friction (mu) must lie in (0, 10]");
  EXPECT_EQ(ErrorOf("grasps: {sample: 3}\n"),
            "r.yaml:1:10: unknown key 'grasps.sample' (did you mean 'samples'?)");
  // Defaults: ACRONYM files and GraspNet rows, no cup.
  EXPECT_TRUE(spec.grasps.acronym);
  EXPECT_TRUE(spec.grasps.labels.graspnet);
  EXPECT_FALSE(spec.grasps.suction);
  EXPECT_FALSE(spec.grasps.labels.suctionnet);
}

TEST(Recipe, GraspsSectionReadsGrippersCupsAndFormats) {
  const RunSpec robotiq = ParseRecipe("grasps: {gripper: robotiq_2f85}\n", "r.yaml", ".");
  EXPECT_EQ(robotiq.grasps.gripper.name, "robotiq_2f85");
  EXPECT_EQ(robotiq.grasps.gripper.max_opening_mm, 85.0);
  const RunSpec custom = ParseRecipe(
      "grasps:\n"
      "  gripper: {preset: franka, name: wide, max_opening: 12 cm, pad: 5}\n"
      "  suction: {diameter: 30, vacuum: 60, density: 2700, samples: 50}\n"
      "  approach_distance: 80\n"
      "  per_part: 500\n"
      "  per_instance: 0\n"
      "  formats: [suctionnet]\n",
      "r.yaml", ".");
  const GraspSpec& g = custom.grasps;
  EXPECT_EQ(g.gripper.name, "wide");
  EXPECT_EQ(g.gripper.max_opening_mm, 120.0);
  EXPECT_EQ(g.gripper.pad_mm, 5.0);
  EXPECT_EQ(g.gripper.finger_length_mm, 46.2);  // the preset's
  EXPECT_TRUE(g.suction);
  EXPECT_EQ(g.cup.diameter_mm, 30.0);
  EXPECT_EQ(g.cup.vacuum_kpa, 60.0);
  EXPECT_EQ(g.suction_sampling.density_kg_m3, 2700.0);
  EXPECT_EQ(g.suction_sampling.samples, 50);
  EXPECT_EQ(g.scene.approach_mm, 80.0);
  EXPECT_EQ(g.sampling.max_grasps, 500);
  EXPECT_EQ(g.suction_sampling.max_grasps, 500);
  EXPECT_EQ(g.labels.max_per_instance, 0);
  EXPECT_FALSE(g.acronym);
  EXPECT_FALSE(g.labels.graspnet);
  EXPECT_TRUE(g.labels.suctionnet);
  EXPECT_TRUE(ParseRecipe("grasps: {suction: true}\n", "r.yaml", ".").grasps.labels.suctionnet);
  EXPECT_EQ(ErrorOf("grasps: {formats: [suctionnet]}\n"),
            "r.yaml:1:20: grasps.formats: suctionnet needs a cup (grasps.suction)");
  EXPECT_EQ(ErrorOf("grasps: {formats: [dexnet]}\n"),
            "r.yaml:1:20: grasps.formats: unknown format 'dexnet' (known: acronym, graspnet, "
            "suctionnet)");
  EXPECT_EQ(ErrorOf("grasps: {suction: {vacuum: 200}}\n"),
            "r.yaml:1:19: grasps.suction: vacuum must lie in (0, 101.325] kPa (a pressure "
            "difference below one atmosphere)");
  EXPECT_EQ(ErrorOf("grasps: {gripper: {pad: 60}}\n"),
            "r.yaml:1:19: grasps.gripper: pad must lie on the finger (0 to finger_length below "
            "the tip)");
  EXPECT_EQ(ErrorOf("grasps: {per_instance: -1}\n"),
            "r.yaml:1:24: grasps.per_instance: per_instance must be 0 (all) to 1,000,000");
  // With both label keys given, the error points at the one at fault.
  EXPECT_EQ(ErrorOf("grasps: {per_instance: 5, visibility_tolerance: 0}\n"),
            "r.yaml:1:49: grasps.visibility_tolerance: visibility tolerance must lie in (0, 1000] "
            "mm");
}

TEST(Recipe, RandomizeErrorsPointAtTheKey) {
  const std::string pbr = "render: {mode: pbr}\n";
  EXPECT_EQ(ErrorOf(pbr + "randomize:\n  lights: {power: {uniform: [50, 10]}}\n"),
            "r.yaml:3:19: randomize.lights.power: uniform: [low, high] with low <= high, got "
            "[50.000000, 10.000000]");
  EXPECT_EQ(ErrorOf(pbr + "randomize:\n  environment: {strength: {gauss: [1, 0.1]}}\n"),
            "r.yaml:3:28: randomize.environment.strength: unknown distribution 'gauss'; known: "
            "uniform, normal, log_uniform, choice");
  EXPECT_EQ(ErrorOf(pbr + "randomize:\n  camera: {exposure: {normall: [0, 1]}}\n"),
            "r.yaml:3:23: randomize.camera.exposure: unknown distribution 'normall' (did you mean "
            "'normal'?); known: uniform, normal, log_uniform, choice");
  EXPECT_EQ(ErrorOf(pbr + "randomize:\n  floor: {preset: {choice: [wood, steal]}}\n"),
            "r.yaml:3:35: randomize.floor.preset: unknown material 'steal' (did you mean "
            "'steel'?)");
  EXPECT_EQ(ErrorOf(pbr + "randomize:\n  lights: {count: {choice: []}}\n"),
            "r.yaml:3:19: randomize.lights.count: choice: the list is empty");
  EXPECT_EQ(ErrorOf(pbr + "randomize:\n  lights: {temperature: {uniform: [800, 5000]}}\n"),
            "r.yaml:3:11: randomize.lights: temperature: draws must lie in [1667.000000, "
            "25000.000000] (a normal's mean; its tails are clipped to them)");
  EXPECT_EQ(ErrorOf(pbr + "randomize:\n  parts: [{name: '*', each: copy}]\n"),
            "r.yaml:3:29: randomize.parts[0].each: expected 'part' or 'instance', got 'copy'");
  EXPECT_EQ(ErrorOf(pbr + "randomize:\n  parts: [{roughness: 0.5}]\n"),
            "r.yaml:3:11: randomize.parts[0]: say which parts: 'name', 'family' or 'file' (a "
            "pattern)");
  EXPECT_EQ(ErrorOf(pbr + "randomize:\n  parts: [{name: '*', roughness: {uniform: [2, 5]}}]\n"),
            "r.yaml:3:11: randomize.parts[0]: roughness: draws must lie in [0.000000, 1.000000] "
            "(a normal's mean; its tails are clipped to them)");
  EXPECT_EQ(ErrorOf(pbr + "randomize:\n  lights: {elevation: {uniform: [-30, 60]}}\n"),
            "r.yaml:3:11: randomize.lights: elevation: draws must lie in [0.000000, 90.000000] "
            "(a normal's mean; its tails are clipped to them)");
  EXPECT_EQ(ErrorOf(pbr + "randomize:\n  environment: {rotation: {uniform: [0, 360]}}\n"),
            "r.yaml:3:27: randomize.environment.rotation: turns an image environment "
            "(lighting.environment is not an image)");
  EXPECT_EQ(ErrorOf(pbr + "camera: {imager: {full_well: 500000000}}\nrandomize:\n  camera: "
                          "{noise_gain: {uniform: [0.5, 2]}}\n"),
            "r.yaml:4:24: randomize.camera.noise_gain: a gain of 0.500000: full_well must lie "
            "between 0 (no noise) and 1e9 electrons");
  EXPECT_EQ(ErrorOf(pbr + "randomize:\n  sky: {}\n"), "r.yaml:3:3: unknown key 'randomize.sky'");
  // What the rest of the recipe must allow.
  EXPECT_EQ(
      ErrorOf("randomize:\n  lights: {count: 2}\n"),
      "r.yaml:2:3: randomize: materials, lights, the environment, exposure, white balance and "
      "background photos are randomised in render.mode: pbr (the fast mode takes the "
      "camera's pose jitter and distractors)");
  EXPECT_NO_THROW(
      ParseRecipe("randomize:\n  camera: {rotation: {normal: [0, 1]}}\n", "r.yaml", "."));
  EXPECT_EQ(ErrorOf(pbr + "randomize:\n  camera: {noise_gain: 2}\n"),
            "r.yaml:3:24: randomize.camera.noise_gain: scales the image noise: camera has none "
            "(give it imager.full_well)");
  EXPECT_EQ(ErrorOf(pbr + "randomize:\n  camera: {f_number: {uniform: [2, 8]}}\n"),
            "r.yaml:3:22: randomize.camera: focus_distance and f_number draw the lens's: camera "
            "has no lens (give it lens.focal_length)");
  EXPECT_EQ(ErrorOf(pbr + "scenes:\n  - {name: a, parts: [{family: hex_bolt}], randomize: {lights: "
                          "{size: {uniform: [2, 1]}}}}\n"),
            "r.yaml:3:71: scenes[0].randomize.lights.size: uniform: [low, high] with low <= high, "
            "got [2.000000, 1.000000]");
}

TEST(Recipe, ShippedRecipesParse) {
  const bool have_data = std::filesystem::exists(testing::DataDir() / "step");
  int parsed = 0;
  for (const auto& entry : std::filesystem::directory_iterator(
           std::filesystem::path(CADSYNTH_SOURCE_DIR) / "recipes")) {
    if (entry.path().extension() != ".yaml") continue;
    std::ifstream in(entry.path());
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (!have_data && text.find("shared/data") != std::string::npos)
      continue;  // needs the shared data
    if (entry.path().filename() == "my_part_in_a_tote.yaml") {
      // The template for the user's own file: read beside a stand-in my_part.step.
      testing::ScratchDir dir;
      std::ofstream(dir / "my_part.step") << "ISO-10303-21;\n";
      EXPECT_NO_THROW(ParseRecipe(text, "my_part_in_a_tote.yaml", dir.path()));
      ++parsed;
      continue;
    }
    EXPECT_NO_THROW(LoadRecipe(entry.path())) << entry.path();
    ++parsed;
  }
  EXPECT_GE(parsed, 1);
  const RunSpec paper =
      LoadRecipe(std::filesystem::path(CADSYNTH_SOURCE_DIR) / "recipes" / "paper_sweep.yaml");
  EXPECT_EQ(paper.sweep.NumViews(), 3330u);
  EXPECT_TRUE(paper.bop.paper_layout && paper.bop.pvn3d_meta && paper.bop.grasp_points &&
              paper.bop.coco);
  EXPECT_EQ(paper.bop.test_every, 4);
  EXPECT_EQ(paper.bop.model_points, 3000);
}

TEST(Recipe, SymmetryListsAreReadInTheFilesFrame) {
  testing::ScratchDir dir;
  std::ofstream(dir / "nut.step") << "ISO-10303-21;\n";
  const RunSpec spec = ParseRecipe(R"(parts:
  - file: nut.step
    symmetry:
      - {axis: [0, 0, 2], order: 6}
      - {axis: [1, 0, 0], order: 2, through: [0, 0, 0.5 in]}
      - {axis: [0, 0, 1], continuous: true}
)",
                                   "r.yaml", dir.path());
  const PartSource& source = spec.scenes.at(0).sources.at(0);
  ASSERT_EQ(source.given_symmetries.size(), 3u);
  EXPECT_FALSE(source.detect_symmetry);
  EXPECT_TRUE(source.given_symmetries[0].axis.isApprox(Eigen::Vector3d::UnitZ()));
  EXPECT_EQ(source.given_symmetries[0].order, 6);
  EXPECT_EQ(source.given_symmetries[0].where, "r.yaml:4:9");
  ASSERT_TRUE(source.given_symmetries[1].through.has_value());
  EXPECT_NEAR(source.given_symmetries[1].through->z(), 12.7, 1e-12);
  EXPECT_EQ(source.given_symmetries[2].order, 0);
  const auto error = [](const std::string& list) {
    return ErrorOf("parts: [{file: a.stl, symmetry: " + list + "}]\n");
  };
  EXPECT_EQ(error("[{axis: [0, 0, 1]}]"),
            "r.yaml:1:34: parts[0].symmetry[0]: give 'order: n' (an n-fold turn) or "
            "'continuous: true'");
  EXPECT_EQ(error("[{axis: [0, 0, 0], order: 2}]"),
            "r.yaml:1:41: parts[0].symmetry[0].axis: must not be zero");
  EXPECT_EQ(error("[{axis: [0, 0, 1], order: 1}]"),
            "r.yaml:1:59: parts[0].symmetry[0].order: must be 2 to 360 (2: a half-turn, a flip)");
  EXPECT_EQ(error("[{order: 2}]"),
            "r.yaml:1:34: parts[0].symmetry[0]: give the 'axis' to turn about, e.g. [0, 0, 1]");
  EXPECT_EQ(error("[]"), "r.yaml:1:33: parts[0].symmetry: an empty list: write 'none'");
  EXPECT_EQ(ErrorOf("parts: [{family: hex_nut, symmetry: [{axis: [0, 0, 1], order: 6}]}]\n"),
            "r.yaml:1:37: parts[0].symmetry: a list goes with 'file' (families declare theirs)");
}

// Each described field's text and whether it is a per-run seed, in order.
template <class Options>
std::vector<std::pair<std::string, bool>> FieldTexts(const Options& options) {
  std::vector<std::pair<std::string, bool>> texts;
  Options::Fields(options, [&](const auto& value, const Field& field) {
    texts.push_back(
        {std::string(field.Name()) + "=" + FieldText(value, field), field.per_run_seed});
  });
  return texts;
}

// Reseed moves every field marked as a run's seed (Field::per_run_seed) and no other described
// field: the model clouds' and grasps' seeds stay (a dataset holds them once).
TEST(Reseed, MovesExactlyTheSeedsMarkedPerRun) {
  RunSpec spec = DefaultRunSpec();
  spec.rig = {RigSensor{"a", spec.intrinsics, spec.sensor}};
  const RunSpec out = Reseed(spec, 5);
  int moved = 0;
  const auto compare = [&](const auto& before, const auto& after) {
    const auto a = FieldTexts(before), b = FieldTexts(after);
    ASSERT_EQ(a.size(), b.size());
    for (size_t i = 0; i < a.size(); ++i) {
      EXPECT_EQ(a[i].first != b[i].first, a[i].second) << a[i].first << " -> " << b[i].first;
      moved += a[i].first != b[i].first;
    }
  };
  for (size_t s = 0; s < spec.scenes.size(); ++s)
    compare(spec.scenes[s].arrangement, out.scenes[s].arrangement);
  compare(spec.render, out.render);
  compare(spec.sampler, out.sampler);
  compare(spec.bop, out.bop);
  compare(spec.tessellation, out.tessellation);
  compare(spec.limits, out.limits);
  for (const auto& [a, b] :
       {std::pair{&spec.sensor, &out.sensor}, std::pair{&spec.rig[0].sensor, &out.rig[0].sensor}}) {
    compare(a->imager, b->imager);
    compare(a->depth, b->depth);
    compare(a->lens, b->lens);
  }
  compare(spec.grasps.gripper, out.grasps.gripper);
  compare(spec.grasps.sampling, out.grasps.sampling);
  compare(spec.grasps.cup, out.grasps.cup);
  compare(spec.grasps.suction_sampling, out.grasps.suction_sampling);
  // One arrangement seed per scene, the render and view sampler seeds, and each camera's imager
  // and depth seeds.
  EXPECT_EQ(moved, static_cast<int>(spec.scenes.size()) + 2 + 2 * 2);
  EXPECT_NE(out.randomize.draws.seed, spec.randomize.draws.seed);
  EXPECT_EQ(Reseed(spec, 5).render.seed, out.render.seed);  // a stream is a function of its number
  EXPECT_GE(out.render.seed, 0);
}

}  // namespace
}  // namespace cadsynth
