// Adaptive sampling (render.noise_threshold): a pixel stops once the standard error of its
// displayed value is below the threshold. Checked against answers worked out by hand (a furnace,
// the irradiance under a disc light and under the sun, which adaptive stopping must not bias),
// against where the noise is (a flat lit floor stops early, a glossy sphere's edge goes on), and
// for the same bytes on any thread count.
#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "tests/render/render_support.h"

#include "cad/shape.h"
#include "render/path_tracer.h"
#include "render/renderer.h"

namespace cadsynth {
namespace {

using testing::Dark;
using testing::DownwardDisc;
using testing::kPi;
using testing::Lambert;
using testing::LookingDown;
using testing::RenderOnThreads;
using testing::WhiteFloorUnderDisc;

RenderOptions Adaptive(int samples, double threshold, int min_samples, int bounces) {
  RenderOptions o = testing::Pbr(samples, bounces);
  o.noise_threshold = threshold;
  o.min_samples = min_samples;
  return o;
}

double MeanRed(const Frame& frame) {
  double sum = 0;
  for (size_t p = 0; p < frame.samples.size(); ++p) sum += frame.radiance[3 * p];
  return sum / static_cast<double>(frame.samples.size());
}

double MeanSamples(const Frame& frame) {
  double sum = 0;
  for (uint32_t n : frame.samples) sum += n;
  return sum / static_cast<double>(frame.samples.size());
}

// Adaptive sampling at threshold 0.01 through the sRGB curve (no filmic), from 4 paths.
AdaptiveSampling Srgb(int samples) {
  AdaptiveSampling a;
  a.samples = samples;
  a.min_samples = 4;
  a.threshold = 0.01f;
  a.filmic = false;
  return a;
}

TEST(AdaptiveSampling, ConvergedFollowsTheStandardErrorOfTheDisplayedValue) {
  AdaptiveSampling a = Srgb(64);
  // Every path 0.5: no spread, done. One path says nothing of the spread: not done.
  EXPECT_TRUE(a.Converged(8, 8 * 0.5, 8 * 0.25));
  EXPECT_FALSE(a.Converged(1, 0.5, 0.25));
  // Paths of 0 and 1 alternating, n = 16: mean 0.5, sample variance 16/15 * 1/4, standard error
  // 0.129: the sRGB curve's slope at 0.5 is 1.055 / 2.4 * 0.5^(-0.583) = 0.66, so the displayed
  // error is about 0.085. With n = 10000 the standard error is 0.005 (displayed 0.0033): done at
  // 0.01, not at 0.003.
  EXPECT_FALSE(a.Converged(16, 8, 8));
  EXPECT_TRUE(a.Converged(10000, 5000, 5000));
  a.threshold = 0.003f;
  EXPECT_FALSE(a.Converged(10000, 5000, 5000));
  // Exposure: paths of 0 and 1, n = 400: standard error 0.025 about a mean of 0.5, displayed
  // about 0.66 * 0.025 = 0.017, not done. Four stops darker (x 1/16): 0.0016 about 0.031, where
  // the sRGB curve's slope is 1.055 / 2.4 * 0.031^(-0.583) = 3.3, so about 0.0052: done.
  a.threshold = 0.01f;
  EXPECT_FALSE(a.Converged(400, 200, 200));
  a.exposure_scale = 1.0f / 16;
  EXPECT_TRUE(a.Converged(400, 200, 200));
  a.threshold = 0.004f;
  EXPECT_FALSE(a.Converged(400, 200, 200));
}

TEST(AdaptiveSampling, ABrightPathNearbyKeepsADarkPixelSampling) {
  // A dark pixel (every path 0.02, no spread of its own) next to one that has drawn a path of 2.0
  // (a rough metal part's highlight, which the dark pixel's paths may find too). Laplace's rule
  // of succession gives such a path probability 1 / (n + 2) after n without it: a path variance
  // of 1.98^2 / (n + 2), a standard error of about 1.98 / n, displayed through the sRGB curve's
  // slope at 0.02, 1.055 / 2.4 * 0.02^(-0.583) = 4.3: about 8.5 / n against 0.01.
  const AdaptiveSampling a = Srgb(4096);
  const auto dark = [&](int n, double peak) { return a.Converged(n, 0.02 * n, 4e-4 * n, peak); };
  EXPECT_TRUE(dark(4, 0.0));   // alone: no spread, done after 4
  EXPECT_TRUE(dark(4, 0.02));  // a neighbour no brighter changes nothing
  EXPECT_FALSE(dark(4, 2.0));
  EXPECT_FALSE(dark(400, 2.0));  // about 0.021
  EXPECT_TRUE(dark(2000, 2.0));  // about 0.0043
  // A peak the pixel has drawn itself counts once more: 8 paths, one of them 2.0.
  EXPECT_FALSE(a.Converged(8, 7 * 0.02 + 2.0, 7 * 4e-4 + 4.0, 2.0));
}

TEST(AdaptiveSampling, FurnaceStopsAtTheMinimumAndStaysExact) {
  // The white furnace (path_tracer_test.cpp): every path of every pixel returns the sky's
  // radiance, so every pixel's spread is 0 and it stops after min_samples.
  std::vector<Part> parts = {MakePart("ball", MakeSphere(50.0), TessellationOptions{0.02, 0.05})};
  Scene scene = Dark();
  scene.floor = false;
  scene.instances = {Instance{0, "ball", Eigen::Isometry3d::Identity()}};
  scene.materials = {Lambert(1.0f)};
  scene.instance_material = {0};
  scene.environment.color = Eigen::Vector3f::Constant(0.5f);
  Camera camera;
  camera.intrinsics = Intrinsics::FromFov(64, 64, 0.5);
  camera.world_from_cam = LookingDown({0, 0, 300});
  const Renderer renderer(parts, scene, Adaptive(256, 0.01, 8, 2));
  const Frame frame = renderer.Render(camera);
  // A pixel whose path lost one ray below a facet (WhiteLambertSphereInAUniformSkyIsInvisible)
  // has a spread and samples on: at most a few, each within one lost ray of the sky's radiance.
  size_t kept_on = 0;
  for (size_t p = 0; p < frame.samples.size(); ++p) {
    const float n = static_cast<float>(frame.samples[p]);
    if (frame.samples[p] != 8u) {
      ++kept_on;
      EXPECT_GE(frame.radiance[3 * p], 0.5f * (1 - 1 / (2 * n)) - 0.005f) << p;
      EXPECT_LE(frame.radiance[3 * p], 0.505f) << p;
    } else {
      EXPECT_NEAR(frame.radiance[3 * p], 0.5f, 0.005f) << p;
    }
  }
  EXPECT_LE(kept_on, 4u);
}

// A white Lambert floor seen straight down through a 32 x 32 pixel patch (4 mm across), lit by
// `light` only: every pixel sees the same radiance, and the mean over all of them must be the
// answer worked out by hand although each pixel stopped when its own noise looked small enough.
Frame FloorPatch(const LightSource& light, const RenderOptions& options) {
  Scene scene = Dark();
  scene.floor_material = Lambert(1.0f);
  scene.light_sources = {light};
  Camera camera;
  camera.intrinsics = Intrinsics::FromFov(32, 32, 0.004);
  camera.world_from_cam = LookingDown({0, 0, 1000});
  const Renderer renderer({}, scene, options);
  return renderer.Render(camera);
}

TEST(AdaptiveSampling, DiscLightIrradianceIsUnbiased) {
  // pi L sin^2(alpha) / pi with L = P / (4 A) (Blender's area light), as in path_tracer_test.cpp.
  const LightSource disc = DownwardDisc(200.0, 300.0, 50.0);
  const double expected = WhiteFloorUnderDisc(200.0, 300.0, 50.0);
  // 30.6 W/(m^2 sr): exposed by 2^-6.5 it shows about 0.6 (unexposed it would clip to white,
  // where no noise shows and every pixel stops at once).
  RenderOptions o = Adaptive(1024, 0.005, 16, 0);
  o.exposure = -6.5;
  const Frame frame = FloorPatch(disc, o);
  const double mean_samples = MeanSamples(frame);
  EXPECT_GT(mean_samples, 16.5);
  EXPECT_LT(mean_samples, 1000.0);
  EXPECT_NEAR(MeanRed(frame), expected, 0.003 * expected) << mean_samples << " samples";
}

TEST(AdaptiveSampling, SunIrradianceIsUnbiased) {
  // A sun of strength S (W/m^2 on a surface facing it) and angular diameter 10 deg, 40 deg from
  // the zenith: the integral of cos over a uniform cone is pi sin^2(a) times the cosine of its
  // axis, so E = S cos(40 deg) exactly, and the white floor's radiance is E / pi.
  LightSource sun;
  sun.kind = LightSource::Kind::kSun;
  sun.power = 3.0;
  const double theta = 40 * kPi / 180;
  sun.direction = {std::sin(theta), 0.0, -std::cos(theta)};
  sun.angle_rad = 10 * kPi / 180;
  const double expected = sun.power * std::cos(theta) / kPi;
  const Frame frame = FloorPatch(sun, Adaptive(1024, 0.0005, 8, 0));
  const double mean_samples = MeanSamples(frame);
  EXPECT_GT(mean_samples, 8.5);
  EXPECT_LT(mean_samples, 1000.0);
  EXPECT_NEAR(MeanRed(frame), expected, 0.002 * expected) << MeanSamples(frame) << " samples";
}

// A glossy metal sphere on a dark Lambert floor under a uniform sky, seen from the side. Far from
// the sphere the floor's every path returns albedo * sky (the BSDF's cosine-weighted sample finds
// the sky, the only light): no noise there. The sphere's silhouette mixes sphere and floor within
// its pixels, and the sphere mirrors the floor and its own shadow.
struct GlossySphere {
  std::vector<Part> parts = {MakePart("ball", MakeSphere(50.0), TessellationOptions{0.02, 0.05})};
  Scene scene;
  Camera camera;
  GlossySphere() {
    Material metal;
    metal.surface.base_color = Eigen::Vector3f::Constant(0.9f);
    metal.surface.metallic = 1;
    metal.surface.roughness = 0.25f;
    scene.instances = {
        Instance{0, "ball", Eigen::Translation3d(0, 0, 50) * Eigen::Isometry3d::Identity()}};
    scene.materials = {metal};
    scene.instance_material = {0};
    scene.floor_material = Lambert(0.1f);
    scene.light_sources.clear();
    scene.environment.color = Eigen::Vector3f::Constant(0.4f);
    camera.intrinsics = Intrinsics::FromFov(96, 72, 0.6);
    camera.world_from_cam = WorldFromCamOnSphere({0, 0, 50}, 0.4, 0.9, 450.0);
  }
};

TEST(AdaptiveSampling, FlatFloorStopsEarlyWhileAGlossyEdgeGoesOn) {
  const GlossySphere view;
  const Renderer renderer(view.parts, view.scene, Adaptive(256, 0.02, 8, 3));
  const Frame frame = renderer.Render(view.camera);
  const int w = frame.width(), h = frame.height();
  // Floor pixels at least 12 pixels from the sphere, and the sphere's silhouette pixels.
  std::vector<uint32_t> floor, edge;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const size_t p = static_cast<size_t>(v) * w + u;
      bool near_sphere = false, near_floor = false;
      for (int dv = -12; dv <= 12; ++dv) {
        for (int du = -12; du <= 12; ++du) {
          const int x = u + du, y = v + dv;
          if (x < 0 || y < 0 || x >= w || y >= h) continue;
          const bool sphere = frame.instance[static_cast<size_t>(y) * w + x] != 0;
          near_sphere |= sphere;
          if (std::abs(du) <= 1 && std::abs(dv) <= 1) near_floor |= !sphere;
        }
      }
      if (frame.instance[p] == 0 && frame.depth[p] > 0 && !near_sphere)
        floor.push_back(frame.samples[p]);
      if (frame.instance[p] != 0 && near_floor) edge.push_back(frame.samples[p]);
    }
  }
  ASSERT_GT(floor.size(), 500u);
  ASSERT_GT(edge.size(), 50u);
  const auto median = [](std::vector<uint32_t> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  const uint32_t floor_median = median(floor), edge_median = median(edge);
  EXPECT_EQ(floor_median, 8u);  // no noise: stopped at the first check
  EXPECT_GE(edge_median, 3 * floor_median) << "floor " << floor_median;
  for (uint32_t n : frame.samples) {
    EXPECT_GE(n, 8u);
    EXPECT_LE(n, 256u);
  }
}

TEST(AdaptiveSampling, SameBytesForAnyThreadCount) {
  const GlossySphere view;
  const Renderer renderer(view.parts, view.scene, Adaptive(64, 0.02, 4, 3));
  const Frame one = RenderOnThreads(renderer, view.camera, 3, 1);
  const Frame two = RenderOnThreads(renderer, view.camera, 3, 2);
  EXPECT_EQ(one.rgb, two.rgb);
  EXPECT_EQ(one.radiance, two.radiance);
  EXPECT_EQ(one.samples, two.samples);
  EXPECT_LT(MeanSamples(one), 63.0);
}

TEST(AdaptiveSampling, AThresholdNoPixelReachesChangesNothing) {
  // The floor under a disc light: every pixel's paths spread (the points drawn on the disc).
  const LightSource disc = DownwardDisc(200.0, 300.0, 50.0);
  RenderOptions o = Adaptive(6, 0.0, 0, 0);
  o.exposure = -6.5;  // not clipped to white
  const Frame fixed = FloorPatch(disc, o);
  for (uint32_t n : fixed.samples) EXPECT_EQ(n, 6u);
  // Checked after 2 paths, then path by path: the same paths summed in the same order.
  o.noise_threshold = 1e-9;
  o.min_samples = 2;
  const Frame capped = FloorPatch(disc, o);
  for (uint32_t n : capped.samples) EXPECT_EQ(n, 6u);
  EXPECT_EQ(fixed.radiance, capped.radiance);
}

TEST(AdaptiveSampling, BadOptionsAreRefused) {
  std::string why;
  RenderOptions o = Adaptive(16, -0.1, 0, 3);
  EXPECT_FALSE(o.Check(&why));
  EXPECT_NE(why.find("noise_threshold"), std::string::npos) << why;
  o = Adaptive(16, 1.01, 0, 3);
  EXPECT_FALSE(o.Check(&why));
  o = Adaptive(16, 0.01, 32, 3);
  EXPECT_FALSE(o.Check(&why));
  EXPECT_NE(why.find("min_samples"), std::string::npos) << why;
  o = Adaptive(16, 0.01, 0, 3);
  EXPECT_TRUE(o.Check(&why)) << why;
  EXPECT_EQ(o.FirstSamples(), 8);  // sqrt(samples), at least 8, at most samples
  o.samples = 1024;
  EXPECT_EQ(o.FirstSamples(), 32);
  o.samples = 4;
  EXPECT_EQ(o.FirstSamples(), 4);
  o = Adaptive(16, 0.0, 0, 3);
  o.background_samples = 17;
  EXPECT_FALSE(o.Check(&why));
  EXPECT_NE(why.find("background_samples"), std::string::npos) << why;
  o.background_samples = -1;
  EXPECT_FALSE(o.Check(&why));
  o.background_samples = 16;
  EXPECT_TRUE(o.Check(&why)) << why;
}

// Whether each 4 x 4 tile of `frame` shows an instance or touches (8-neighbours) a tile that does.
std::vector<bool> NearObjectTiles(const Frame& frame) {
  const int w = frame.width(), h = frame.height(), tx = (w + 3) / 4, ty = (h + 3) / 4;
  std::vector<bool> object(static_cast<size_t>(tx * ty), false), near(object.size(), false);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      if (frame.instance[static_cast<size_t>(v) * w + u] != 0)
        object[static_cast<size_t>(v / 4 * tx + u / 4)] = true;
    }
  }
  for (int y = 0; y < ty; ++y) {
    for (int x = 0; x < tx; ++x) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const int nx = x + dx, ny = y + dy;
          if (nx >= 0 && ny >= 0 && nx < tx && ny < ty && object[static_cast<size_t>(ny * tx + nx)])
            near[static_cast<size_t>(y * tx + x)] = true;
        }
      }
    }
  }
  return near;
}

// render.background_samples: a 4 x 4 tile that neither shows an object nor touches a tile that
// does takes at most that many paths. Each tile's paths are those it takes without the cap (near
// an object) or with `samples` set to the cap (elsewhere): the same paths, summed in the same
// order, so every pixel's estimate is exactly as unbiased as a plain render's.
TEST(BackgroundSamples, TilesWithoutAnObjectTakeTheirOwnCountAndTheSamePaths) {
  const GlossySphere view;
  RenderOptions o = testing::Pbr(8, 3);
  const Frame all8 = Renderer(view.parts, view.scene, o).Render(view.camera, 5);
  o.background_samples = 2;
  const Frame capped = Renderer(view.parts, view.scene, o).Render(view.camera, 5);
  o = testing::Pbr(2, 3);
  const Frame all2 = Renderer(view.parts, view.scene, o).Render(view.camera, 5);
  const int w = capped.width(), h = capped.height();
  const std::vector<bool> near = NearObjectTiles(capped);
  int object_tiles = 0, background_tiles = 0;
  for (int v0 = 0; v0 < h; v0 += 4) {
    for (int u0 = 0; u0 < w; u0 += 4) {
      const bool object = near[static_cast<size_t>(v0 / 4 * ((w + 3) / 4) + u0 / 4)];
      ++(object ? object_tiles : background_tiles);
      const Frame& like = object ? all8 : all2;
      for (int v = v0; v < std::min(h, v0 + 4); ++v) {
        for (int u = u0; u < std::min(w, u0 + 4); ++u) {
          const size_t p = static_cast<size_t>(v) * w + u;
          ASSERT_EQ(capped.samples[p], object ? 8u : 2u) << u << ", " << v;
          for (int c = 0; c < 3; ++c)
            ASSERT_EQ(capped.radiance[3 * p + c], like.radiance[3 * p + c]) << u << ", " << v;
        }
      }
    }
  }
  EXPECT_GT(object_tiles, 20);
  EXPECT_GT(background_tiles, 100);
  // The labels do not depend on it.
  EXPECT_EQ(capped.instance, all8.instance);
  EXPECT_EQ(capped.depth, all8.depth);
}

TEST(BackgroundSamples, CapsAdaptiveSamplingAndKeepsTheBytesOnAnyThreadCount) {
  const GlossySphere view;
  RenderOptions o = Adaptive(64, 0.02, 8, 3);
  o.background_samples = 4;
  const Renderer renderer(view.parts, view.scene, o);
  const Frame one = RenderOnThreads(renderer, view.camera, 3, 1);
  const Frame two = RenderOnThreads(renderer, view.camera, 3, 2);
  EXPECT_EQ(one.radiance, two.radiance);
  EXPECT_EQ(one.samples, two.samples);
  const int w = one.width();
  const std::vector<bool> near = NearObjectTiles(one);
  size_t object_pixels = 0;
  for (size_t p = 0; p < one.samples.size(); ++p) {
    // Pixels near objects have adaptive counts (8-64), the floor far from them 4.
    const int u = static_cast<int>(p % w), v = static_cast<int>(p / w);
    if (near[static_cast<size_t>(v / 4 * ((w + 3) / 4) + u / 4)]) {
      object_pixels += one.instance[p] != 0;
      EXPECT_GE(one.samples[p], 8u) << u << ", " << v;
    } else {
      EXPECT_EQ(one.samples[p], 4u) << u << ", " << v;
    }
    EXPECT_LE(one.samples[p], 64u);
  }
  EXPECT_GT(object_pixels, 200u);
  EXPECT_GT(std::count(one.samples.begin(), one.samples.end(), 4u), 2000);
}

TEST(BackgroundSamples, AnAnalyticFloorIsUnbiasedAtTheCap) {
  // The floor under a disc light (DiscLightIrradianceIsUnbiased's): no object anywhere, so every
  // pixel takes 4 paths of the 64 asked for, and the mean over 32 x 32 pixels is still
  // pi L sin^2(alpha) / pi.
  const LightSource disc = DownwardDisc(200.0, 300.0, 50.0);
  const double expected = WhiteFloorUnderDisc(200.0, 300.0, 50.0);
  RenderOptions o = testing::Pbr(64, 0);
  o.background_samples = 4;
  const Frame frame = FloorPatch(disc, o);
  for (uint32_t n : frame.samples) ASSERT_EQ(n, 4u);
  EXPECT_NEAR(MeanRed(frame), expected, 0.01 * expected);
}

TEST(BackgroundSamples, AFixtureMarkedAsAnObjectIsSampledAsOne) {
  // The glossy sphere as a fixture (a distractor: drawn, not labelled): capped like the floor
  // unless Scene::Fixture::object says it is sampled as the instances are.
  GlossySphere view;
  Scene::Fixture ball;
  ball.name = "ball";
  ball.mesh = view.parts[0].mesh;
  ball.mesh.Transform(view.scene.instances[0].world_from_model);
  ball.material = view.scene.materials[0];
  view.scene.instances.clear();
  view.scene.fixtures = {ball};
  RenderOptions o = testing::Pbr(8, 3);
  o.background_samples = 2;
  const Frame floor_like = Renderer({}, view.scene, o).Render(view.camera, 5);
  view.scene.fixtures[0].object = true;
  const Frame object = Renderer({}, view.scene, o).Render(view.camera, 5);
  EXPECT_EQ(object.instance, floor_like.instance);  // no labels either way
  const size_t eights = std::count(object.samples.begin(), object.samples.end(), 8u);
  EXPECT_EQ(std::count(floor_like.samples.begin(), floor_like.samples.end(), 8u), 0);
  EXPECT_GT(eights, 500u);  // the ball's pixels and the tiles around them
  EXPECT_LT(eights, object.samples.size() / 2);
}

}  // namespace
}  // namespace cadsynth
