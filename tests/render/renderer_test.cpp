#include "render/renderer.h"

#include <tbb/global_control.h>

#include <gtest/gtest.h>

#include "tests/render/render_support.h"

#include "cad/core/error.h"
#include "cad/shape.h"

namespace cadsynth {
namespace {

using testing::LookingDown;

// An instance whose model frame (its bounding-box centre) sits at `where`.
Instance Place(int part, const Part&, const Eigen::Vector3d& where) {
  return Instance{part, "i", Eigen::Isometry3d(Eigen::Translation3d(where))};
}

int Count(const std::vector<uint8_t>& mask) {
  return static_cast<int>(std::count(mask.begin(), mask.end(), 1));
}

TEST(Renderer, DepthOfATiltedFloorIsTheCameraZ) {
  Scene scene;  // floor only
  const Renderer renderer({}, scene);
  Camera camera;
  camera.world_from_cam = WorldFromCamOnSphere({0, 0, 0}, 0.4, 35.0 * M_PI / 180.0, 1200.0);
  const Frame frame = renderer.Render(camera);
  const Eigen::Isometry3d& T = camera.world_from_cam;
  const Intrinsics& k = camera.intrinsics;
  int checked = 0;
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const Eigen::Vector3d d =
          T.linear() * Eigen::Vector3d((u + 0.5 - k.cx) / k.fx, (v + 0.5 - k.cy) / k.fy, 1.0);
      const float depth = frame.depth[v * k.width + u];
      if (d.z() >= 0) {
        EXPECT_EQ(depth, 0.0f);  // above the horizon: no return
        continue;
      }
      const double z = -T.translation().z() / d.z();  // ray parameter with d_cam.z = 1: the depth
      const Eigen::Vector3d hit = T.translation() + z * d;
      if (hit.head<2>().cwiseAbs().maxCoeff() > scene.floor_half_size_mm - 1) continue;
      ASSERT_NEAR(depth, z, 0.01) << "pixel " << u << "," << v;
      ++checked;
    }
  }
  EXPECT_GT(checked, 100000);
}

TEST(Renderer, DepthOfASphereMatchesTheAnalyticIntersection) {
  const double r = 50.0;
  const std::vector<Part> parts = {
      MakePart("ball", MakeSphere(r), TessellationOptions{0.004, 0.1})};
  Scene scene;
  scene.floor = false;
  const Eigen::Vector3d centre(12.0, -7.0, 50.0);
  scene.instances = {Place(0, parts[0], centre)};
  const Renderer renderer(parts, scene);
  Camera camera;
  camera.world_from_cam = WorldFromCamOnSphere(centre, 0.7, 50.0 * M_PI / 180.0, 400.0);
  camera.world_from_cam.translation() += Eigen::Vector3d(5, 3, 0);  // off-axis on purpose
  const Frame frame = renderer.Render(camera);
  const Intrinsics& k = camera.intrinsics;
  const Eigen::Vector3d c = camera.world_from_cam.inverse() * centre;  // centre in camera frame
  int checked = 0;
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const Eigen::Vector3d d((u + 0.5 - k.cx) / k.fx, (v + 0.5 - k.cy) / k.fy, 1.0);
      // |t d - c|^2 = r^2  ->  t = (d.c - sqrt((d.c)^2 - |d|^2 (|c|^2 - r^2))) / |d|^2
      const double a = d.squaredNorm(), b = d.dot(c), disc = b * b - a * (c.squaredNorm() - r * r);
      const float depth = frame.depth[v * k.width + u];
      if (disc <= 0) {
        if (disc < -1e-2 * a * r) {
          EXPECT_EQ(depth, 0.0f);  // clearly outside the silhouette
        }
        continue;
      }
      const double t = (b - std::sqrt(disc)) / a;
      const Eigen::Vector3d normal = (t * d - c) / r;
      // Chords lie at most 0.004 mm inside the sphere along the normal, 0.008 mm along a ray
      // within 60 degrees of it; skip grazing rays, where the error grows as 1 / cos.
      if (-normal.dot(d.normalized()) < 0.5) continue;
      ASSERT_NEAR(depth, t, 0.01) << "pixel " << u << "," << v;
      EXPECT_EQ(frame.instance[v * k.width + u], 1);
      ++checked;
    }
  }
  EXPECT_GT(checked, 10000);
}

TEST(Renderer, BoxFaceSeenHeadOnCoversExactlyItsPixels) {
  // A 100 x 100 mm top face 525 mm in front of a camera with f = 525 px spans exactly 100 px; with
  // cx = cy = 320 its edges fall on pixel borders, so pixel centres (u + 0.5) decide cleanly.
  const std::vector<Part> parts = {MakePart("box", MakeBox(100, 100, 40), TessellationOptions{})};
  Scene scene;
  scene.floor = false;
  scene.instances = {Place(0, parts[0], {0, 0, 20})};  // top face at z = 40, centred on the axis
  const Renderer renderer(parts, scene);
  Camera camera;
  camera.intrinsics = Intrinsics{640, 640, 525.0, 525.0, 320.0, 320.0};
  camera.world_from_cam = LookingDown({0, 0, 40 + 525});
  const Frame frame = renderer.Render(camera);
  EXPECT_EQ(frame.instances[0].px_count_visib, 100 * 100);
  EXPECT_EQ(frame.instances[0].px_count_all, 100 * 100);
  EXPECT_EQ(Count(frame.instances[0].amodal_mask), 100 * 100);
  // Corners: pixel (270, 270) is inside, (269, 270) and (370, 270) are not.
  EXPECT_EQ(frame.instance[270 * 640 + 270], 1);
  EXPECT_EQ(frame.instance[270 * 640 + 269], 0);
  EXPECT_EQ(frame.instance[270 * 640 + 370], 0);
  EXPECT_EQ(frame.instance[369 * 640 + 369], 1);
  EXPECT_FLOAT_EQ(frame.depth[300 * 640 + 300], 525.0f);
}

TEST(Renderer, FrontObjectOwnsThePixelAndTheHiddenOneKeepsItsFullMask) {
  const std::vector<Part> parts = {MakePart("big", MakeBox(100, 100, 20), TessellationOptions{}),
                                   MakePart("small", MakeBox(40, 40, 20), TessellationOptions{})};
  Scene scene;
  scene.floor = false;
  scene.instances = {Place(0, parts[0], {0, 0, 10}), Place(1, parts[1], {0, 0, 100})};
  const Renderer renderer(parts, scene);
  Camera camera;
  camera.world_from_cam = LookingDown({0, 0, 600});
  const Frame frame = renderer.Render(camera);
  const int centre = 240 * 640 + 320;
  EXPECT_EQ(frame.instance[centre], 2);  // the small box is nearer the camera
  EXPECT_NEAR(frame.depth[centre], 600.0 - 110.0, 1e-3);

  // Rendering the big box alone gives exactly its amodal mask from the occluded scene.
  Scene alone = scene;
  alone.instances = {scene.instances[0]};
  const Frame solo = Renderer(parts, alone).Render(camera);
  int differ = 0;  // the mask is stored for its rectangle: compare every pixel of the image
  for (int v = 0; v < 480; ++v) {
    for (int u = 0; u < 640; ++u)
      differ += frame.instances[0].Covers(u, v, 640, 480) != (solo.instance[v * 640 + u] == 1);
  }
  EXPECT_EQ(differ, 0);
  EXPECT_EQ(frame.instances[0].px_count_all, solo.instances[0].px_count_visib);
  EXPECT_EQ(frame.instances[0].px_count_visib + frame.instances[1].px_count_visib,
            solo.instances[0].px_count_visib);  // the small box hides part of the big one
  EXPECT_GT(frame.instances[1].px_count_visib, 0);
}

// A fixture (a tote's wall, here a slab above the box) hides the box where it lies in front and
// shows in the depth, but has no instance id: the box's visible mask loses those pixels, its
// amodal mask keeps them. The same in both shading modes.
TEST(Renderer, FixturesOccludeButAreNotObjects) {
  const std::vector<Part> parts = {MakePart("box", MakeBox(100, 100, 20), TessellationOptions{})};
  Scene scene;
  scene.floor = false;
  scene.instances = {Place(0, parts[0], {0, 0, 10})};
  Scene::Fixture slab;
  slab.name = "slab";
  slab.mesh = MakePart("slab", MakeBox(40, 200, 10), TessellationOptions{}).mesh;
  slab.mesh.Transform(Eigen::Isometry3d(Eigen::Translation3d(0, 0, 100)));  // x in [-20, 20]
  scene.fixtures = {slab};
  Camera camera;
  camera.world_from_cam = LookingDown({0, 0, 600});
  const int centre = 240 * 640 + 320;
  const int side = 240 * 640 + 320 + 40;  // world x = 40 * 580 / 525 = 44 mm: the box only
  for (const auto mode : {RenderOptions::Mode::kFast, RenderOptions::Mode::kPbr}) {
    RenderOptions o;
    o.mode = mode;
    o.samples = 1;
    const Frame frame = Renderer(parts, scene, o).Render(camera);
    EXPECT_EQ(frame.instance[centre], 0);
    EXPECT_NEAR(frame.depth[centre], 600.0 - 105.0, 1e-3);  // the slab's top
    EXPECT_EQ(frame.instance[side], 1);
    EXPECT_NEAR(frame.depth[side], 600.0 - 20.0, 1e-3);
    EXPECT_TRUE(frame.instances[0].Covers(320, 240, 640, 480));
    EXPECT_LT(frame.instances[0].px_count_visib, frame.instances[0].px_count_all);
    // The slab is drawn (lit), not the background.
    const uint8_t* c = &frame.rgb[3 * centre];
    EXPECT_GT(c[0] + c[1] + c[2], 30) << int(mode);
  }
  Scene empty = scene;
  empty.fixtures[0].mesh = Mesh();
  EXPECT_THROW(Renderer(parts, empty), Error);
}

// A distractor (a fixture: domain randomisation drops them among the parts) hiding part of a
// target, worked out by hand: the camera 600 mm above a 100 x 100 x 20 mm box looks straight
// down; a bar 40 mm wide (x in [-20, 20]) and 10 mm thick, its underside 100 mm up, runs across
// it. Seen from the camera, its top edges (490 mm away) shadow |x| < 20 * 580 / 490 = 23.67 mm of
// the box's top (580 mm away): the box's side faces are not seen, so the visible fraction of
// its silhouette is 1 - 47.35 / 100 = 0.5265.
TEST(Renderer, DistractorHidesTheFractionOfATargetGeometryPredicts) {
  const std::vector<Part> parts = {MakePart("box", MakeBox(100, 100, 20), TessellationOptions{})};
  Scene scene;
  scene.floor = false;
  scene.instances = {Place(0, parts[0], {0, 0, 10})};
  Scene::Fixture bar;
  bar.name = "distractor 0 (box)";
  bar.mesh = MakePart("bar", MakeBox(40, 300, 10), TessellationOptions{}).mesh;
  bar.mesh.Transform(Eigen::Isometry3d(Eigen::Translation3d(0, 0, 105)));
  scene.fixtures = {bar};
  Camera camera;
  camera.world_from_cam = LookingDown({0, 0, 600});
  const Frame frame = Renderer(parts, scene).Render(camera);
  ASSERT_EQ(frame.instances.size(), 1u);
  const double visib = static_cast<double>(frame.instances[0].px_count_visib) /
                       static_cast<double>(frame.instances[0].px_count_all);
  // The box's top is 90.5 pixels across: a pixel column either side is 0.011.
  EXPECT_NEAR(visib, 1.0 - 2 * 20.0 * 580.0 / 490.0 / 100.0, 0.012);
  Scene alone = scene;
  alone.fixtures.clear();
  const Frame solo = Renderer(parts, alone).Render(camera);
  EXPECT_EQ(solo.instances[0].px_count_all, frame.instances[0].px_count_all);  // amodal: the same
  EXPECT_EQ(solo.instances[0].px_count_visib, solo.instances[0].px_count_all);
}

// A background photo shows exactly where the pixel's centre ray hits nothing, as its sRGB
// bytes (a uniform photo of linear 0.5 is byte round(255 * 0.7354) = 188 everywhere there), and
// leaves every pixel that sees the part as it was; the labels do not change.
TEST(Renderer, BackgroundPhotoFillsWhatNothingCovers) {
  const std::vector<Part> parts = {MakePart("box", MakeBox(100, 100, 20), TessellationOptions{})};
  Scene scene;
  scene.floor = false;
  scene.instances = {Place(0, parts[0], {0, 0, 10})};
  Camera camera;
  camera.world_from_cam = LookingDown({0, 0, 600});
  RenderOptions o;
  o.mode = RenderOptions::Mode::kPbr;
  o.samples = 2;
  const Renderer renderer(parts, scene, o);
  FrameLook look = renderer.BaseLook();
  const Frame plain = renderer.Render(camera, 0, SensorOptions{}, &look);
  auto photo = std::make_shared<LinearImage>();
  photo->width = 30;
  photo->height = 20;
  photo->rgb.assign(3 * 30 * 20, 0.5f);
  look.background = photo;
  const Frame pasted = renderer.Render(camera, 0, SensorOptions{}, &look);
  size_t background = 0;
  for (size_t p = 0; p < plain.depth.size(); ++p) {
    for (int c = 0; c < 3; ++c) {
      if (plain.depth[p] == 0.0f) {
        EXPECT_EQ(pasted.rgb[3 * p + c], 188) << p;
      } else {
        EXPECT_EQ(pasted.rgb[3 * p + c], plain.rgb[3 * p + c]) << p;
      }
    }
    background += plain.depth[p] == 0.0f;
  }
  EXPECT_GT(background, plain.depth.size() / 2);
  EXPECT_EQ(pasted.instance, plain.instance);
  EXPECT_EQ(pasted.depth, plain.depth);
}

TEST(Renderer, PosesComposeFromCameraAndInstance) {
  const std::vector<Part> parts = {MakePart("box", MakeBox(30, 20, 10), TessellationOptions{})};
  Scene scene;
  scene.instances = {Instance{
      0, "b", Eigen::Translation3d(40, 10, 5) * Eigen::AngleAxisd(0.6, Eigen::Vector3d::UnitZ())}};
  const Renderer renderer(parts, scene);
  Camera camera;
  camera.world_from_cam = WorldFromCamOnSphere({0, 0, 0}, 1.1, 0.8, 900.0);
  const Frame frame = renderer.Render(camera);
  const Eigen::Isometry3d expected =
      camera.world_from_cam.inverse() * scene.instances[0].world_from_model;
  EXPECT_TRUE(frame.instances[0].cam_from_model.isApprox(expected, 1e-12));
  // And the model origin projects into the silhouette.
  const Eigen::Vector3d o = frame.instances[0].cam_from_model.translation();
  const int u = static_cast<int>(std::floor(525.0 * o.x() / o.z() + 319.5));
  const int v = static_cast<int>(std::floor(525.0 * o.y() / o.z() + 239.5));
  EXPECT_TRUE(frame.instances[0].Covers(u, v, 640, 480));
}

TEST(Renderer, OutputDoesNotDependOnTheThreadCount) {
  const std::vector<Part> parts = {MakePart("cyl", MakeCylinder(20, 60), TessellationOptions{}),
                                   MakePart("box", MakeBox(50, 40, 30), TessellationOptions{})};
  Scene scene;
  scene.instances = {Place(0, parts[0], {-30, 0, 30}), Place(1, parts[1], {30, 10, 15})};
  scene.part_colors = {PaletteColor(0), PaletteColor(1)};
  const Renderer renderer(parts, scene);
  Camera camera;
  camera.world_from_cam = WorldFromCamOnSphere({0, 0, 0}, 0.3, 0.5, 700.0);
  const auto render_with = [&](size_t threads) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    return renderer.Render(camera);
  };
  const Frame one = render_with(1), two = render_with(2);
  EXPECT_EQ(one.rgb, two.rgb);
  EXPECT_EQ(one.depth, two.depth);
  EXPECT_EQ(one.instance, two.instance);
  for (int i = 0; i < 2; ++i) EXPECT_EQ(one.instances[i].amodal_mask, two.instances[i].amodal_mask);
}

TEST(Renderer, InstanceColourWinsOverPartColour) {
  const std::vector<Part> parts = {MakePart("box", MakeBox(100, 100, 20), TessellationOptions{})};
  Scene scene;
  scene.floor = false;
  scene.ambient = 1.0f;  // flat: the pixel is the albedo
  scene.lights.clear();
  scene.part_colors = {Eigen::Vector3f(0, 0, 1)};
  scene.instances = {Place(0, parts[0], {-60, 0, 10}), Place(0, parts[0], {60, 0, 10})};
  scene.instances[1].color = Eigen::Vector3f(1, 0, 0);
  Camera camera;
  camera.world_from_cam = LookingDown({0, 0, 800});
  const Frame frame = Renderer(parts, scene).Render(camera);
  const auto rgb = [&](int u, int v) {
    const uint8_t* p = &frame.rgb[3 * (v * 640 + u)];
    return std::array<int, 3>{p[0], p[1], p[2]};
  };
  // World -x is image left (image x = world x when looking down).
  EXPECT_EQ(rgb(320 - 40, 240), (std::array<int, 3>{0, 0, 255}));
  EXPECT_EQ(rgb(320 + 40, 240), (std::array<int, 3>{255, 0, 0}));
}

// Floor pixel (u, v) of a camera LookingDown from `height` (f = 525, c = (319.5, 239.5)).
int FloorPixel(double x, double y, double height, int* u) {
  *u = static_cast<int>(std::floor(319.5 + 525.0 * x / height));
  return static_cast<int>(std::floor(239.5 - 525.0 * y / height));
}

TEST(Renderer, ShadowFallsWhereGeometrySays) {
  // A 40 x 40 x 20 mm box floating at z = 100..120 over the origin, lit along (1, 0, -1): its
  // shadow on the floor covers x in [-20 + 100, 20 + 120] = [80, 140], y in [-20, 20].
  const std::vector<Part> parts = {MakePart("box", MakeBox(40, 40, 20), TessellationOptions{})};
  Scene scene;
  scene.floor_color = Eigen::Vector3f(0.5f, 0.5f, 0.5f);
  scene.ambient = 0.2f;
  scene.lights = {Scene::Light{Scene::Light::Kind::kDirectional, Eigen::Vector3d(1, 0, -1)}};
  scene.lights[0].intensity = 0.8f;
  scene.instances = {Place(0, parts[0], {0, 0, 110})};
  const Renderer renderer(parts, scene);
  Camera camera;
  camera.world_from_cam = LookingDown({0, 0, 1000});
  const Frame frame = renderer.Render(camera);
  const auto grey = [&](double x, double y) {
    int u;
    const int v = FloorPixel(x, y, 1000, &u);
    return int(frame.rgb[3 * (v * 640 + u)]);
  };
  const int shadowed = std::lround(255 * 0.5 * 0.2);                          // ambient only
  const int lit = std::lround(255 * 0.5 * (0.2 + 0.8 * std::cos(M_PI / 4)));  // 45 degree light
  EXPECT_EQ(grey(110, 0), shadowed);
  EXPECT_EQ(grey(85, 15), shadowed);
  EXPECT_EQ(grey(135, -15), shadowed);
  EXPECT_EQ(grey(110, 30), lit);  // beside the shadow
  EXPECT_EQ(grey(150, 0), lit);   // beyond it
  EXPECT_EQ(grey(60, 0), lit);    // between the box and its shadow
  scene.shadows = false;
  const Frame unshadowed = Renderer(parts, scene).Render(camera);
  int u;
  const int v = FloorPixel(110, 0, 1000, &u);
  EXPECT_EQ(int(unshadowed.rgb[3 * (v * 640 + u)]), lit);
}

TEST(Renderer, PointLightFollowsTheCosine) {
  Scene scene;  // floor only
  scene.floor_color = Eigen::Vector3f(1, 1, 1);
  scene.ambient = 0.0f;
  scene.lights = {Scene::Light{Scene::Light::Kind::kPoint, Eigen::Vector3d::Zero(),
                               Eigen::Vector3d(0, 0, 300), 1.0f}};
  Camera camera;
  camera.world_from_cam = LookingDown({0, 0, 1000});
  const Frame frame = Renderer({}, scene).Render(camera);
  const auto grey = [&](double x) {
    int u;
    const int v = FloorPixel(x, 0, 1000, &u);
    return int(frame.rgb[3 * (v * 640 + u)]);
  };
  // Under the light cos = 1; 300 mm aside cos = 300 / sqrt(300^2 + 300^2) = 0.707.
  EXPECT_NEAR(grey(0.5), 255, 1);
  EXPECT_NEAR(grey(300), 255 * std::sqrt(0.5), 2);
  EXPECT_NEAR(grey(-150), 255 * 300 / std::hypot(300.0, 150.0), 2);
}

TEST(Renderer, ClipNormalsAndSupersampling) {
  const std::vector<Part> parts = {MakePart("box", MakeBox(100, 100, 40), TessellationOptions{})};
  Scene scene;
  scene.instances = {Place(0, parts[0], {0.3, 0.2, 20})};  // edges off the pixel grid
  Camera camera;
  camera.world_from_cam = LookingDown({0, 0, 600});
  RenderOptions options;
  options.normals = true;
  const Frame plain = Renderer(parts, scene, options).Render(camera);
  // The box top faces the camera: normal (0, 0, -1) in the camera frame; the floor too.
  EXPECT_TRUE(plain.normals[240 * 640 + 320].isApprox(Eigen::Vector3f(0, 0, -1), 1e-5f));
  EXPECT_TRUE(plain.normals[5 * 640 + 5].isApprox(Eigen::Vector3f(0, 0, -1), 1e-5f));
  // Clipping at 570 mm: the box top (560 mm away) is gone; the ray starts inside the solid box and
  // next meets its bottom face, at the floor's 600 mm.
  EXPECT_EQ(plain.depth[240 * 640 + 320], 560.0f);
  options.near_mm = 570;
  options.far_mm = 700;
  const Frame clipped = Renderer(parts, scene, options).Render(camera);
  EXPECT_EQ(clipped.depth[240 * 640 + 320], 600.0f);
  options.far_mm = 590;
  EXPECT_EQ(Renderer(parts, scene, options).Render(camera).depth[5 * 640 + 5], 0.0f);  // no floor
  // Supersampling softens RGB at the box edge and leaves depth and ids alone.
  RenderOptions ss;
  ss.supersampling = 4;
  const Frame smooth = Renderer(parts, scene, ss).Render(camera);
  EXPECT_EQ(smooth.depth, plain.depth);
  EXPECT_EQ(smooth.instance, plain.instance);
  int differing = 0;
  for (size_t p = 0; p < plain.rgb.size(); ++p) differing += plain.rgb[p] != smooth.rgb[p];
  EXPECT_GT(differing, 100);                         // edge pixels blend box and floor
  EXPECT_LT(differing, int(plain.rgb.size()) / 20);  // interiors stay as they were
  RenderOptions bad;
  bad.near_mm = 10;
  bad.far_mm = 5;
  EXPECT_THROW(Renderer(parts, scene, bad), Error);
}

TEST(Renderer, RejectsInstancesOfMissingParts) {
  Scene scene;
  scene.instances = {Instance{3, "ghost", Eigen::Isometry3d::Identity()}};
  EXPECT_THROW(Renderer({}, scene), Error);
}

// Embree's kernel width is a setting: never wider than asked for, never wider than the CPU's.
TEST(Renderer, KernelWidthFollowsTheSettingAndTheCpu) {
  const std::vector<std::string> order = {"sse2", "sse4.2", "avx", "avx2", "avx512"};
  const auto rank = [&](const std::string& isa) {
    return std::find(order.begin(), order.end(), isa) - order.begin();
  };
  const std::string widest = TracingIsa("auto");
  ASSERT_LT(rank(widest), 5) << widest;
  for (const std::string& isa : order) {
    EXPECT_EQ(rank(TracingIsa(isa)), std::min(rank(isa), rank(widest))) << isa;
  }
  RenderOptions options;
  std::string why;
  options.isa = "avx3";
  EXPECT_FALSE(options.Check(&why));
  EXPECT_NE(why.find("isa must be"), std::string::npos);
  // The narrowest kernels trace the same picture (BoxFaceSeenHeadOnCoversExactlyItsPixels).
  const std::vector<Part> parts = {MakePart("box", MakeBox(100, 100, 40), TessellationOptions{})};
  Scene scene;
  scene.floor = false;
  scene.instances = {Place(0, parts[0], {0, 0, 20})};
  options.isa = "sse2";
  Camera camera;
  camera.intrinsics = Intrinsics{640, 640, 525.0, 525.0, 320.0, 320.0};
  camera.world_from_cam = LookingDown({0, 0, 40 + 525});
  const Frame frame = Renderer(parts, scene, options).Render(camera);
  EXPECT_EQ(frame.instances[0].px_count_visib, 100 * 100);
  EXPECT_EQ(Count(frame.instances[0].amodal_mask), 100 * 100);
  EXPECT_FLOAT_EQ(frame.depth[300 * 640 + 300], 525.0f);
}

}  // namespace
}  // namespace cadsynth
