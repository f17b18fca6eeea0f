// The physically based mode against answers worked out by hand: furnaces, a point light's inverse
// square law, the irradiance under a disc light and a rectangular panel, a mirror, the
// single-scattering energy loss of rough metal, and the convergence rate of the stratified sampler.
#include "render/path_tracer.h"

#include <cmath>
#include <set>

#include <gtest/gtest.h>

#include "tests/render/render_support.h"

#include "cad/core/error.h"
#include "cad/shape.h"
#include "render/bsdf.h"
#include "render/image.h"
#include "render/material.h"
#include "render/renderer.h"
#include "render/sampling.h"

namespace cadsynth {
namespace {

using testing::Dark;
using testing::kPi;
using testing::Lambert;
using testing::LookingDown;
using testing::Pbr;
using testing::RenderOnThreads;

Material Metal(float roughness) {
  Material m;
  m.surface.base_color = Eigen::Vector3f::Ones();
  m.surface.metallic = 1;
  m.surface.roughness = roughness;
  return m;
}

// Radiance (red channel) of pixel (u, v).
float At(const Frame& frame, int u, int v) {
  return frame.radiance[3 * (static_cast<size_t>(v) * frame.width() + u)];
}

// A sphere of radius 50 mm at the origin (no floor), seen from above.
struct SphereView {
  std::vector<Part> parts = {MakePart("ball", MakeSphere(50.0), TessellationOptions{0.02, 0.05})};
  Scene scene = Dark();
  Camera camera;
  SphereView(const Material& material, float sky) {
    scene.floor = false;
    scene.instances = {Instance{0, "ball", Eigen::Isometry3d::Identity()}};
    scene.materials = {material};
    scene.instance_material = {0};
    scene.environment.color = Eigen::Vector3f::Constant(sky);
    camera.intrinsics = Intrinsics::FromFov(64, 64, 0.5);
    camera.world_from_cam = LookingDown({0, 0, 300});
  }
};

TEST(PathTracer, WhiteLambertSphereInAUniformSkyIsInvisible) {
  // The white furnace: a closed convex surface of albedo 1 under radiance L everywhere reflects
  // exactly L at every point. The BSDF's cosine-weighted sample, which alone finds a uniform sky,
  // makes this exact sample by sample; the facets of the tessellated sphere (smooth normals)
  // leave well under 1 %. A cosine-sampled direction within the facet's tilt of the horizon,
  // above the smooth normal but below the flat triangle, is lost (Cycles loses it too): rare, so
  // at most a few pixels may lose one of their 4 paths (1/4 of the pixel). Which pixels depends
  // on the sample pattern, so the test allows a few rather than none.
  SphereView view(Lambert(1.0f), 0.5f);
  const Renderer renderer(view.parts, view.scene, Pbr(4, 2));
  const Frame frame = renderer.Render(view.camera);
  int on_sphere = 0, lost = 0;
  for (int v = 0; v < 64; ++v) {
    for (int u = 0; u < 64; ++u) {
      const float value = At(frame, u, v);
      if (std::abs(value - 0.5f) > 0.005f) {
        ++lost;
        EXPECT_NEAR(value, 0.5f * (1 - 1.0f / 4), 0.005f) << u << "," << v;
      }
      on_sphere += frame.instance[v * 64 + u] != 0;
    }
  }
  EXPECT_GT(on_sphere, 1000);
  EXPECT_LE(lost, 4);
}

// A uniform sky is found by the BSDF's rays only, so the lights get every light sample. Under a
// parallel sun (irradiance E at 40 degrees from the zenith) and a uniform sky L, an open Lambert
// floor of albedo rho returns rho (E cos 40 / pi + L) from every single path: the sun, the only
// strategy, is picked with probability 1 and its sample gives rho E cos / pi exactly, and the
// BSDF's cosine-weighted direction escapes to the sky and gives rho L exactly (f cos / pdf =
// rho). One path a pixel is then exact. With the sky as a second strategy the sun was picked only
// most of the time, and each pixel's one path had its light or lacked it.
TEST(PathTracer, AUniformSkyLeavesEveryLightSampleToTheLights) {
  Scene scene = Dark();
  scene.floor_material = Lambert(0.5f);
  scene.environment.color = Eigen::Vector3f::Constant(0.2f);
  LightSource sun;
  sun.kind = LightSource::Kind::kSun;
  sun.power = 3.0;
  const double theta = 40 * kPi / 180;
  sun.direction = {std::sin(theta), 0.0, -std::cos(theta)};
  sun.angle_rad = 0;
  scene.light_sources = {sun};
  Camera camera;
  camera.intrinsics = Intrinsics::FromFov(32, 32, 0.004);
  camera.world_from_cam = LookingDown({0, 0, 1000});
  const Frame frame = Renderer({}, scene, Pbr(1, 1)).Render(camera);
  const double expected = 0.5 * (3.0 * std::cos(theta) / kPi + 0.2);
  for (int v = 0; v < 32; ++v) {
    for (int u = 0; u < 32; ++u) {
      ASSERT_GT(frame.depth[v * 32 + u], 0) << "the floor fills the view";
      EXPECT_NEAR(At(frame, u, v), expected, 1e-4 * expected) << u << "," << v;
    }
  }
}

TEST(PathTracer, WhiteRoughDielectricSphereInAUniformSkyIsInvisible) {
  // The same furnace with a specular layer on top (specular 0.5, roughness 0.5): the layered
  // model conserves energy exactly, so the sphere still returns L, up to sampling noise.
  Material m = Lambert(1.0f);
  m.surface.specular = 0.5f;
  m.surface.roughness = 0.5f;
  SphereView view(m, 0.5f);
  const Renderer renderer(view.parts, view.scene, Pbr(64, 3));
  const Frame frame = renderer.Render(view.camera);
  double sum = 0;
  int n = 0;
  for (int v = 0; v < 64; ++v) {
    for (int u = 0; u < 64; ++u) {
      if (frame.instance[v * 64 + u] == 0) continue;
      EXPECT_NEAR(At(frame, u, v), 0.5f, 0.1f) << u << "," << v;
      sum += At(frame, u, v);
      ++n;
    }
  }
  EXPECT_NEAR(sum / n, 0.5, 0.005);
}

TEST(PathTracer, RoughWhiteMetalLosesWhatSingleScatteringGgxLoses) {
  // White metal at roughness 1 seen straight on reflects 1 - ln 2 of a uniform sky (worked out by
  // hand in bsdf_test.cpp): single-scattering GGX loses the light that would bounce between
  // microfacets. The centre of the sphere faces the camera.
  SphereView view(Metal(1.0f), 1.0f);
  view.camera.intrinsics = Intrinsics::FromFov(8, 8, 0.02);  // 2 mm of the sphere's top
  const Renderer renderer(view.parts, view.scene, Pbr(1024, 0));
  const Frame frame = renderer.Render(view.camera);
  double sum = 0;
  for (int v = 0; v < 8; ++v) {
    for (int u = 0; u < 8; ++u) sum += At(frame, u, v);
  }
  EXPECT_NEAR(sum / 64, 1 - std::log(2.0), 0.01);
  // Blender's Multiscatter GGX gives that light back: the white furnace again.
  Material multi = Metal(1.0f);
  multi.surface.multiscatter = true;
  SphereView again(multi, 1.0f);
  again.camera = view.camera;
  const Frame back = Renderer(again.parts, again.scene, Pbr(1024, 0)).Render(again.camera);
  sum = 0;
  for (int v = 0; v < 8; ++v) {
    for (int u = 0; u < 8; ++u) sum += At(back, u, v);
  }
  EXPECT_NEAR(sum / 64, 1.0, 0.015);
}

TEST(PathTracer, LambertPlaneUnderAPointLightFollowsTheInverseSquareLaw) {
  // L = rho / pi * I cos(theta) / r^2 with I = P / (4 pi) (Blender's point light of power P),
  // r in metres. No sampling noise: the light is a point and nothing else lights the floor.
  const float rho = 0.8f;
  const double power = 100.0, height = 1000.0;  // W, mm
  Scene scene = Dark();
  scene.floor_material = Lambert(rho);
  LightSource light;
  light.kind = LightSource::Kind::kPoint;
  light.power = power;
  light.position = {100.0, -50.0, height};
  scene.light_sources = {light};
  Camera camera;
  camera.intrinsics = Intrinsics::FromFov(160, 120, 1.2);
  camera.world_from_cam = LookingDown({0, 0, 1500});
  const Renderer renderer({}, scene, Pbr(4, 1));
  const Frame frame = renderer.Render(camera);
  int checked = 0;
  for (int v = 0; v < 120; v += 7) {
    for (int u = 0; u < 160; u += 7) {
      const Eigen::Vector3d d =
          camera.world_from_cam.linear() *
          Eigen::Vector3d((u + 0.5 - camera.intrinsics.cx) / camera.intrinsics.fx,
                          (v + 0.5 - camera.intrinsics.cy) / camera.intrinsics.fy, 1);
      const Eigen::Vector3d p = camera.world_from_cam.translation() + 1500.0 / -d.z() * d;
      const Eigen::Vector3d to_light = light.position - p;
      const double r_m = to_light.norm() / 1000.0;
      const double cos_theta = to_light.z() / to_light.norm();
      const double expected = rho / kPi * (power / (4 * kPi)) * cos_theta / (r_m * r_m);
      EXPECT_NEAR(At(frame, u, v), expected, 0.003 * expected) << u << "," << v;
      ++checked;
    }
  }
  EXPECT_GT(checked, 300);
}

// A white Lambert floor under a disc light of radius R at height h facing down, seen through a
// tiny patch of floor straight under its centre: the irradiance there is pi L sin^2(alpha), with
// L = P / (4 A) (Blender's area light) and sin^2(alpha) = R^2 / (R^2 + h^2); the floor's radiance
// is E / pi.
struct DiscLightView {
  double radius = 200.0, height = 300.0, power = 50.0;
  Scene scene = Dark();
  Camera camera;
  DiscLightView() {
    scene.floor_material = Lambert(1.0f);
    scene.light_sources = {testing::DownwardDisc(radius, height, power)};
    camera.intrinsics = Intrinsics::FromFov(4, 4, 0.0004);  // 0.4 mm of floor
    camera.world_from_cam = LookingDown({0, 0, 1000});
  }
  double Expected() const { return testing::WhiteFloorUnderDisc(radius, height, power); }
};

TEST(PathTracer, IrradianceUnderADiscLightIsPiLSinSquared) {
  const DiscLightView view;
  const Renderer renderer({}, view.scene, Pbr(4096, 0));
  const Frame frame = renderer.Render(view.camera);
  double sum = 0;
  for (int i = 0; i < 16; ++i) sum += At(frame, i % 4, i / 4);
  EXPECT_NEAR(sum / 16, view.Expected(), 0.002 * view.Expected());
}

// A white Lambert floor under a 400 x 200 mm panel 150 mm above it, facing down, seen through a
// tiny patch straight under its centre. The floor's radiance is L F, F the view factor of the
// panel: four rectangles a x b = 200 x 100 mm with a corner overhead, each
// F = 1/(2 pi) [A/sqrt(1+A^2) atan(B/sqrt(1+A^2)) + B/sqrt(1+B^2) atan(A/sqrt(1+B^2))],
// A = a/h, B = b/h. Sampled uniformly in the panel's solid angle, a light sample's estimate is
// L Omega cos(theta) / pi: only the floor's cosine varies (from 1 to 0.56 here). Sampled by
// area it would be L A cos^4(theta) / (pi h^2), which varies from 1 to 0.1 of its largest.
// A white Lambert floor under a rect light of 2a x 2b mm and `power` W facing down from height h,
// seen straight down from 1 m over 8 x 8 pixels of 0.4 mm, and the radiance the floor under its
// centre has: L times the view factor of the rectangle from there (two right-angle corners'
// closed form, four of them).
struct PanelOverFloor {
  Scene scene = Dark();
  Camera camera;
  double expected = 0;
  PanelOverFloor(double a, double b, double h, double power) {
    scene.floor_material = Lambert(1.0f);
    LightSource panel;
    panel.kind = LightSource::Kind::kRect;
    panel.size_x_mm = 2 * a;
    panel.size_y_mm = 2 * b;
    panel.position = {0, 0, h};
    panel.direction = {0, 0, -1};
    panel.x_axis = {1, 0, 0};
    panel.power = power;
    scene.light_sources = {panel};
    camera.intrinsics = Intrinsics::FromFov(8, 8, 0.0004);  // 0.4 mm of floor
    camera.world_from_cam = LookingDown({0, 0, 1000});
    const double l = power / (4 * (2 * a) * (2 * b) * 1e-6);
    const double ka = a / h, kb = b / h;
    const double view_factor = 4 / (2 * kPi) *
                               (ka / std::hypot(1, ka) * std::atan(kb / std::hypot(1, ka)) +
                                kb / std::hypot(1, kb) * std::atan(ka / std::hypot(1, kb)));
    expected = l * view_factor;
  }
};

TEST(PathTracer, RectLightIsSampledUniformlyInItsSolidAngle) {
  const PanelOverFloor view(200.0, 100.0, 150.0, 40.0);
  const Scene& scene = view.scene;
  const Camera& camera = view.camera;
  const double expected = view.expected;
  const Frame one = Renderer({}, scene, Pbr(1, 0)).Render(camera);
  double sum = 0, sum_sq = 0;
  for (int i = 0; i < 64; ++i) {
    const double value = At(one, i % 8, i / 8);
    sum += value;
    sum_sq += value * value;
  }
  const double mean = sum / 64, spread = std::sqrt(std::max(0.0, sum_sq / 64 - mean * mean));
  // 64 pixels of one path each: independent samples (each pixel scrambles its own sequence), so
  // the mean is within 4 standard errors (spread / 8); the 1,024-sample image below pins it.
  EXPECT_NEAR(mean, expected, 4 * spread / 8);
  // One sample a pixel (MIS with the floor's cosine-sampled rays): the spread is a fifth of the
  // mean; sampled by area, with the same MIS, it was half the mean.
  EXPECT_LT(spread, 0.3 * mean);
  const Frame many = Renderer({}, scene, Pbr(1024, 0)).Render(camera);
  sum = 0;
  for (int i = 0; i < 64; ++i) sum += At(many, i % 8, i / 8);
  EXPECT_NEAR(sum / 64, expected, 0.001 * expected);
}

// The same analytic irradiance where the panel is small for its distance: 20 x 10 mm at 0.8 m
// (about 3e-4 sr, where the spherical rectangle's angles are summed in double) and 2 x 1 mm
// (3e-6 sr, below which it is sampled by area).
TEST(PathTracer, SmallAndFarRectLightsGiveTheirViewFactor) {
  for (const double a : {10.0, 1.0}) {
    const PanelOverFloor view(a, a / 2, 800.0, 1.0);
    const Frame frame = Renderer({}, view.scene, Pbr(64, 0)).Render(view.camera);
    double sum = 0;
    for (int i = 0; i < 64; ++i) sum += At(frame, i % 8, i / 8);
    SCOPED_TRACE("panel " + std::to_string(2 * a) + " mm");
    EXPECT_NEAR(sum / 64, view.expected, 0.002 * view.expected);
  }
}

TEST(PathTracer, SeveralLightsAddUpWhateverTheSelection) {
  // The disc above, plus a point light 300 mm off to the side that gives the patch about ten
  // times the disc's irradiance, plus a uniform sky of radiance 0.05: the floor's radiance is
  // rho / pi * (pi L_disc sin^2(alpha) + I cos(theta) / r^2 + pi L_sky). Next-event estimation
  // picks among the three by importance, and the disc is also found by BSDF rays (MIS): the sum
  // must come out right whatever the probabilities.
  DiscLightView view;
  LightSource point;
  point.kind = LightSource::Kind::kPoint;
  point.power = 5000.0;
  point.position = {300.0, 0.0, 400.0};
  view.scene.light_sources.push_back(point);
  view.scene.environment.color = Eigen::Vector3f::Constant(0.05f);
  const double r_m = point.position.norm() / 1000.0, cos_theta = 400.0 / point.position.norm();
  const double from_point = (point.power / (4 * kPi)) * cos_theta / (r_m * r_m) / kPi;
  const double expected = view.Expected() + from_point + 0.05;
  EXPECT_GT(from_point, 5 * view.Expected());
  const Renderer renderer({}, view.scene, Pbr(4096, 0));
  const Frame frame = renderer.Render(view.camera);
  double sum = 0;
  for (int i = 0; i < 16; ++i) sum += At(frame, i % 4, i / 4);
  EXPECT_NEAR(sum / 16, expected, 0.003 * expected);
}

// A glossy metal floor (roughness 0.3) under two equal 200 x 100 mm panels seen from 45 degrees:
// one where the floor mirrors the camera, one off to the side. The floor's radiance is the sum of
// the panels' radiance times f(wo, wi) cos(wi) over their solid angles, integrated here by the
// midpoint rule on a 400 x 200 grid of each panel (dw = cos_l dA / d^2) with the BSDF itself.
// The light selection rates each panel by the BSDF towards it: the sum must come out right, and
// the mirrored panel gets the samples, so that one sample a pixel spreads by less than the mean.
TEST(PathTracer, GlossyMetalUnderTwoPanelsSumsUpAndSamplesTheMirroredOne) {
  Scene scene = Dark();
  Material metal = Metal(0.3f);
  metal.surface.base_color = Eigen::Vector3f::Constant(0.9f);
  scene.floor_material = metal;
  Camera camera;
  camera.intrinsics = Intrinsics::FromFov(8, 8, 0.0004);  // 0.4 mm of floor
  camera.world_from_cam = WorldFromCamOnSphere({0, 0, 0}, 0.0, kPi / 4, 1000.0);
  const Eigen::Vector3d eye = camera.world_from_cam.translation();
  const Eigen::Vector3d mirrored = Eigen::Vector3d(-eye.x(), -eye.y(), eye.z()).normalized();
  const Eigen::Vector3d side =
      Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitZ()) *
      Eigen::Vector3d(mirrored.x(), mirrored.y(), 2 * mirrored.z()).normalized();
  const double power = 40.0, a = 100.0, b = 50.0;  // half sides (mm)
  const double radiance = power / (4 * (2 * a) * (2 * b) * 1e-6);
  const PrincipledBsdf bsdf(metal.surface);
  const Eigen::Vector3f wo = eye.normalized().cast<float>();
  double expected = 0;
  for (const Eigen::Vector3d& towards : {mirrored, side}) {
    LightSource panel;
    panel.kind = LightSource::Kind::kRect;
    panel.size_x_mm = 2 * a;
    panel.size_y_mm = 2 * b;
    panel.position = 500.0 * towards;
    panel.direction = -towards;
    panel.x_axis = towards.cross(Eigen::Vector3d::UnitZ()).normalized();
    panel.power = power;
    scene.light_sources.push_back(panel);
    const Eigen::Vector3d x = panel.x_axis, y = panel.direction.cross(x);
    const int nx = 400, ny = 200;
    double sum = 0;
    for (int i = 0; i < nx; ++i) {
      for (int j = 0; j < ny; ++j) {
        const Eigen::Vector3d q =
            panel.position + (-a + (i + 0.5) * 2 * a / nx) * x + (-b + (j + 0.5) * 2 * b / ny) * y;
        const double d2 = q.squaredNorm();
        const Eigen::Vector3d wi = q / std::sqrt(d2);
        const double cos_l = -wi.dot(panel.direction);
        const double dw = cos_l * (2 * a / nx) * (2 * b / ny) / d2;
        sum += bsdf.Eval(wo, wi.cast<float>())[0] * wi.z() * dw;
      }
    }
    expected += radiance * sum;
  }
  const Frame many = Renderer({}, scene, Pbr(1024, 0)).Render(camera);
  double sum = 0;
  for (int i = 0; i < 64; ++i) sum += At(many, i % 8, i / 8);
  EXPECT_NEAR(sum / 64, expected, 0.005 * expected);
  const Frame one = Renderer({}, scene, Pbr(1, 0)).Render(camera);
  double sum_sq = 0;
  sum = 0;
  for (int i = 0; i < 64; ++i) {
    const double value = At(one, i % 8, i / 8);
    sum += value;
    sum_sq += value * value;
  }
  const double mean = sum / 64, spread = std::sqrt(std::max(0.0, sum_sq / 64 - mean * mean));
  EXPECT_NEAR(mean, expected, 0.2 * expected);
  // Rated by irradiance alone (both panels alike) the spread was 0.91 of the mean; 0.55 now.
  EXPECT_LT(spread, 0.7 * mean);
}

TEST(PathTracer, StratifiedSamplesConvergeFasterThanRandomOnes) {
  // The RMS error of the disc light's estimate over 16 pixels x 8 seeds: independent random
  // samples would fall as N^-1/2 (a factor 4 from 16 to 256 samples); Owen-scrambled Sobol points
  // with the light's edge in the integrand fall as about N^-3/4 (a factor 8). Require 6.
  const DiscLightView view;
  const double expected = view.Expected();
  double rms[2];
  for (int k = 0; k < 2; ++k) {
    double sq = 0;
    int n = 0;
    for (int seed = 0; seed < 8; ++seed) {
      RenderOptions o = Pbr(k == 0 ? 16 : 256, 0);
      o.seed = seed;
      const Renderer renderer({}, view.scene, o);
      const Frame frame = renderer.Render(view.camera);
      for (int i = 0; i < 16; ++i) {
        const double e = At(frame, i % 4, i / 4) - expected;
        sq += e * e;
        ++n;
      }
    }
    rms[k] = std::sqrt(sq / n);
  }
  EXPECT_GT(rms[0] / rms[1], 6.0) << rms[0] << " " << rms[1];
}

TEST(PathTracer, SobolPointsAreStratifiedAndUniform) {
  // Every power-of-two prefix of 2^k points holds one point in each of the 2^k elementary
  // intervals of every shape (the (0, 2)-sequence property survives Owen scrambling).
  for (uint64_t seed : {0u, 7u, 12345u}) {
    for (int k = 2; k <= 8; k += 2) {
      const int n = 1 << k;
      for (int log_w = 0; log_w <= k; ++log_w) {
        const int cols = 1 << log_w, rows = n / cols;
        std::vector<int> count(n, 0);
        for (int i = 0; i < n; ++i) {
          const Eigen::Vector2f p = SobolOwen2D(static_cast<uint32_t>(i), seed);
          ASSERT_GE(p.minCoeff(), 0.0f);
          ASSERT_LT(p.maxCoeff(), 1.0f);
          ++count[static_cast<int>(p.y() * rows) * cols + static_cast<int>(p.x() * cols)];
        }
        for (int c : count) ASSERT_EQ(c, 1) << "seed " << seed << " n " << n << " cols " << cols;
      }
    }
  }
}

TEST(PathTracer, PolishedMetalMirrorsTheSky) {
  // A white metal floor at roughness 0 reflects the sky exactly (Fresnel of a white metal is 1):
  // each pixel shows the sky along the mirrored view direction.
  Scene scene = Dark();
  scene.floor_material = Metal(0.0f);
  scene.environment.kind = Environment::Kind::kSky;
  scene.environment.strength = 2.0f;
  Camera camera;
  camera.intrinsics = Intrinsics::FromFov(64, 48, 1.0);
  camera.world_from_cam = WorldFromCamOnSphere({0, 0, 0}, 0.3, 50.0 * kPi / 180.0, 800.0);
  // Enough samples that the rare visible normal drawn far from the mirror direction (about one
  // sample in 3,000 at roughness 0) cannot move a pixel by 1 %.
  const Renderer renderer({}, scene, Pbr(256, 1));
  const Frame frame = renderer.Render(camera);
  const Intrinsics& k = camera.intrinsics;
  int checked = 0;
  for (int v = 0; v < k.height; v += 3) {
    for (int u = 0; u < k.width; u += 3) {
      if (frame.depth[v * k.width + u] == 0) continue;
      const Eigen::Vector3d d =
          (camera.world_from_cam.linear() *
           Eigen::Vector3d((u + 0.5 - k.cx) / k.fx, (v + 0.5 - k.cy) / k.fy, 1))
              .normalized();
      const Eigen::Vector3d r(d.x(), d.y(), -d.z());
      // Near the horizon the sky changes too fast for the pixel's centre to stand for it.
      if (r.z() < 0.3) continue;
      const double t = std::sqrt(r.z());
      const Eigen::Vector3f sky = (1 - t) * scene.environment.horizon.cast<float>() +
                                  t * scene.environment.zenith.cast<float>();
      const float expected = 2.0f * static_cast<float>(sky[0]);
      EXPECT_NEAR(At(frame, u, v), expected, 0.01f * expected) << u << "," << v;
      ++checked;
    }
  }
  EXPECT_GT(checked, 200);
}

// An image texture on a mesh with texture coordinates: a 100 mm square facing a uniform sky of
// radiance L is a Lambertian plane that sees the whole sky, so each pixel is exactly texel * L.
// Texels: red top-left, green top-right, blue bottom-left, white bottom-right; the square maps the
// whole image with v up (OpenGL), and the camera looks down with image x = world x, image y =
// world -y, so the render shows the image upright. The triplanar projection of the same image
// (tiles of 100 mm from the world origin) puts other texels there.
TEST(PathTracer, ImageTextureFollowsTheMeshTextureCoordinates) {
  Part square;
  square.name = "square";
  square.mesh.positions = {{-50, -50, 0}, {50, -50, 0}, {50, 50, 0}, {-50, 50, 0}};
  square.mesh.normals.assign(4, Eigen::Vector3f::UnitZ());
  square.mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  square.mesh.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  auto image = std::make_shared<LinearImage>();
  image->width = image->height = 8;
  for (int y = 0; y < 8; ++y) {
    for (int x = 0; x < 8; ++x) {
      const Eigen::Vector3f c = y < 4
                                    ? (x < 4 ? Eigen::Vector3f(1, 0, 0) : Eigen::Vector3f(0, 1, 0))
                                    : (x < 4 ? Eigen::Vector3f(0, 0, 1) : Eigen::Vector3f(1, 1, 1));
      image->rgb.insert(image->rgb.end(), {c.x(), c.y(), c.z()});
    }
  }
  Material m = Lambert(0.5f);
  m.texture.kind = Texture::Kind::kImage;
  m.texture.image = "quadrants.png";
  m.texture.pixels = image;
  m.texture.scale_mm = 100;
  const float sky = 0.5f;
  Scene scene = Dark();
  scene.floor = false;
  scene.instances = {Instance{0, "square", Eigen::Isometry3d::Identity()}};
  scene.instance_material = {0};
  scene.environment.color = Eigen::Vector3f::Constant(sky);
  Camera camera;
  camera.intrinsics = Intrinsics::FromFov(64, 64, 0.5);
  camera.world_from_cam = LookingDown({0, 0, 150});
  const auto rgb = [](const Frame& f, int u, int v) {
    const float* c = &f.radiance[3 * (static_cast<size_t>(v) * f.width() + u)];
    return Eigen::Vector3f(c[0], c[1], c[2]);
  };
  // Pixels at the quadrants' centres (world x, y = -+25 mm); 64 px span 2 * 150 tan(0.25) mm.
  const double px_per_mm = 32.0 / (150.0 * std::tan(0.25));
  const int lo = static_cast<int>(32 - 25 * px_per_mm), hi = static_cast<int>(32 + 25 * px_per_mm);
  for (const Texture::Projection projection :
       {Texture::Projection::kAuto, Texture::Projection::kUv, Texture::Projection::kTriplanar}) {
    m.texture.projection = projection;
    scene.materials = {m};
    const Frame frame = Renderer({square}, scene, Pbr(4, 1)).Render(camera);
    const Eigen::Vector3f top_left = rgb(frame, lo, lo), top_right = rgb(frame, hi, lo);
    const Eigen::Vector3f bottom_left = rgb(frame, lo, hi), bottom_right = rgb(frame, hi, hi);
    if (projection != Texture::Projection::kTriplanar) {
      EXPECT_TRUE(top_left.isApprox(Eigen::Vector3f(sky, 0, 0), 1e-4f)) << top_left.transpose();
      EXPECT_TRUE(top_right.isApprox(Eigen::Vector3f(0, sky, 0), 1e-4f)) << top_right.transpose();
      EXPECT_TRUE(bottom_left.isApprox(Eigen::Vector3f(0, 0, sky), 1e-4f))
          << bottom_left.transpose();
      EXPECT_TRUE(bottom_right.isApprox(Eigen::Vector3f::Constant(sky), 1e-4f))
          << bottom_right.transpose();
    } else {
      // Top view: u = x / 100, image row v = -y / 100, wrapped: world (-25, 25) reads texel
      // (0.75, 0.75), the white quadrant.
      EXPECT_TRUE(top_left.isApprox(Eigen::Vector3f::Constant(sky), 1e-4f)) << top_left.transpose();
      EXPECT_TRUE(bottom_right.isApprox(Eigen::Vector3f(sky, 0, 0), 1e-4f))
          << bottom_right.transpose();
    }
  }
}

TEST(PathTracer, SameBytesForAnyThreadCountAndTileOrder) {
  SphereView view(Metal(0.3f), 0.4f);
  view.scene.floor = true;
  view.scene.light_sources = Scene::DefaultLightSources();
  view.camera.world_from_cam = WorldFromCamOnSphere({0, 0, 0}, 0.4, 0.7, 500.0);
  const Renderer renderer(view.parts, view.scene, Pbr(8, 3));
  const Frame one = RenderOnThreads(renderer, view.camera, 5, 1);
  const Frame two = RenderOnThreads(renderer, view.camera, 5, 2);
  EXPECT_EQ(one.rgb, two.rgb);
  EXPECT_EQ(one.radiance, two.radiance);
  // Another view number is another noise pattern; the labels stay the same.
  const Frame other = renderer.Render(view.camera, 6);
  EXPECT_NE(one.rgb, other.rgb);
  EXPECT_EQ(one.depth, other.depth);
  EXPECT_EQ(one.instance, other.instance);
}

// The SIMD shading (a packet's BSDF evaluations four lanes at a time) against the scalar
// reference, on spheres of every material preset over a floor under the default lights and a
// grey sky (so that bounces between them count too). On x86-64 without FMA the two are the same
// operations on the same numbers: the same bytes. Elsewhere a last-bit difference may send a
// path another way, so the check allows a few pixels to differ by noise.
TEST(PathTracer, SimdAndScalarShadingAgreeOnEveryPreset) {
  const std::vector<std::string> presets = MaterialPresetNames();
  SphereView view(Metal(0.3f), 0.3f);
  view.scene.floor = true;
  view.scene.light_sources = Scene::DefaultLightSources();
  view.scene.instances.clear();
  view.scene.materials.clear();
  view.scene.instance_material.clear();
  const int columns = 5;
  for (size_t i = 0; i < presets.size(); ++i) {
    Material m;
    ASSERT_TRUE(MaterialPreset(presets[i], &m));
    if (m.base_from_part) m.surface.base_color = Eigen::Vector3f(0.6f, 0.3f, 0.2f);
    view.scene.materials.push_back(m);
    view.scene.instance_material.push_back(static_cast<int>(i));
    const double x = 110.0 * (static_cast<int>(i % columns) - (columns - 1) / 2.0);
    const double y = 110.0 * (static_cast<int>(i / columns) - 1.0);
    view.scene.instances.push_back(
        Instance{0, presets[i], Eigen::Isometry3d(Eigen::Translation3d(x, y, 50.0))});
  }
  view.camera.intrinsics = Intrinsics::FromFov(160, 120, 1.0);
  view.camera.world_from_cam = WorldFromCamOnSphere({0, 0, 0}, 0.3, 0.9, 900.0);
  RenderOptions simd = Pbr(4, 3), scalar = simd;
  scalar.shading = RenderOptions::Shading::kScalar;
  const Frame a = Renderer(view.parts, view.scene, simd).Render(view.camera, 3);
  const Frame b = Renderer(view.parts, view.scene, scalar).Render(view.camera, 3);
  ASSERT_EQ(a.radiance.size(), b.radiance.size());
  // Every preset is in the picture.
  std::set<int> seen;
  for (const uint16_t id : a.instance) {  // Scene::instances index + 1
    if (id > 0 && id <= presets.size()) seen.insert(id);
  }
  EXPECT_EQ(seen.size(), presets.size());
  size_t differ = 0;
  double sum_a = 0, sum_b = 0;
  for (size_t i = 0; i < a.radiance.size(); ++i) {
    sum_a += a.radiance[i], sum_b += b.radiance[i];
    differ += std::abs(a.radiance[i] - b.radiance[i]) > 1e-4f * (std::abs(b.radiance[i]) + 1e-3f);
  }
#if defined(__x86_64__) && !defined(__FMA__)
  EXPECT_EQ(a.radiance, b.radiance);  // the same operations on the same numbers
  EXPECT_EQ(a.rgb, b.rgb);
#endif
  EXPECT_LE(differ, a.radiance.size() / 200) << "values that differ beyond rounding";
  EXPECT_NEAR(sum_a, sum_b, 0.01 * sum_b);
  EXPECT_GT(sum_b, 0);
}

// A near-mirror ball (metal, roughness 0.05) resting above a Lambert floor (albedo 0.8) under a
// panel, in a black world, seen from the side and above: light reaches the floor directly,
// through the ball's reflection (a caustic) and off the floor again. The panel is large enough
// (200 mm square, 370 mm from the ball) that its image in the ball, seen from the floor, is found
// by a few of each floor pixel's paths: the caustic is noisy in every render, not only in those
// whose sample pattern happens to find a tiny panel's image (a 40 mm panel's was found in 4 of 12
// renders).
SphereView MirrorBallOnAFloor() {
  SphereView view(Metal(0.05f), 0.0f);
  view.scene.floor = true;
  view.scene.floor_material = Scene::DefaultMaterial(Eigen::Vector3f::Constant(0.8f));
  view.scene.floor_material.surface.specular = 0;  // Lambert
  view.scene.instances[0].world_from_model =
      Eigen::Translation3d(0, 0, 60) * Eigen::Isometry3d::Identity();
  LightSource panel;
  panel.kind = LightSource::Kind::kRect;
  panel.size_x_mm = panel.size_y_mm = 200;
  panel.position = {150, 0, 400};
  panel.direction = Eigen::Vector3d(-150, 0, -400).normalized();
  panel.x_axis = Eigen::Vector3d::UnitY();
  panel.power = 80;
  view.scene.light_sources = {panel};
  view.camera.intrinsics = Intrinsics::FromFov(48, 48, 1.0);
  view.camera.world_from_cam = WorldFromCamOnSphere({0, 0, 0}, 0.5, 0.9, 600.0);
  return view;
}

// Filter Glossy (render.filter_glossy, Cycles' blur_glossy): a near-mirror ball on a Lambert floor
// under a small panel. The floor sees the panel in the ball (a caustic: floor, ball, light),
// which paths from the camera find rarely, so its pixels sparkle; after the floor's diffuse
// bounce the ball's lobe is widened and the sparkle goes. What the camera sees first is never
// changed: with no bounce after the first hit the images are the same bytes.
TEST(PathTracer, FilterGlossyQuietsCausticsAndLeavesTheFirstHit) {
  SphereView view = MirrorBallOnAFloor();
  const auto render = [&](double filter, int bounces, int seed) {
    RenderOptions o = Pbr(16, bounces);
    o.filter_glossy = filter;
    o.seed = seed;
    return Renderer(view.parts, view.scene, o).Render(view.camera, 0);
  };
  EXPECT_EQ(render(0.0, 0, 1).radiance, render(1.0, 0, 1).radiance);
  // The floor's noise: half the mean squared difference between two seeds' images, per value,
  // over the floor's pixels (the ball's own, lit by the panel's reflection, are left as they
  // were); and their mean.
  const auto floor_pixel = [](const Frame& a, size_t i) {
    return a.instance[i / 3] == 0 && a.depth[i / 3] > 0;
  };
  const auto noise = [&](const Frame& a, const Frame& b) {
    double sum = 0;
    size_t n = 0;
    for (size_t i = 0; i < a.radiance.size(); ++i) {
      if (!floor_pixel(a, i)) continue;
      const double d = a.radiance[i] - b.radiance[i];
      sum += 0.5 * d * d, ++n;
    }
    return sum / n;
  };
  const auto mean = [&](const Frame& a) {
    double sum = 0;
    size_t n = 0;
    for (size_t i = 0; i < a.radiance.size(); ++i) {
      if (floor_pixel(a, i)) sum += a.radiance[i], ++n;
    }
    return sum / n;
  };
  const Frame off1 = render(0.0, 3, 1), off2 = render(0.0, 3, 2);
  const Frame on1 = render(1.0, 3, 1), on2 = render(1.0, 3, 2);
  const double noise_off = noise(off1, off2), noise_on = noise(on1, on2);
  // Measured: 0.167 against 3.20 (the floor's mean 10.79 against 10.88); over five seed pairs
  // the ratio was 12.5 to 19.
  EXPECT_LT(noise_on, noise_off / 6) << noise_on << " against " << noise_off;
  // Widening a lobe moves light about, it does not make or lose much of it.
  EXPECT_NEAR(mean(on1), mean(off1), 0.1 * mean(off1));
}

// render.glossy_bounces (Blender's Glossy bounces): with 0, a path that leaves a surface by its
// glossy lobe only gathers the light and sky its next segment finds. The metal ball has no other
// lobe, so its pixels are those of a render with no bounce at all, to the byte (the same samples
// drawn in the same order; Russian roulette only from the third interaction); the floor keeps
// its diffuse bounces (the caustic, floor then ball then panel, stays: the ball's bounce is its
// first glossy one and finds the panel). A limit at or above `bounces` changes nothing.
TEST(PathTracer, GlossyBouncesEndPathsAfterTheirGlossyBounce) {
  SphereView view = MirrorBallOnAFloor();
  view.camera.intrinsics = Intrinsics::FromFov(128, 128, 0.5);
  const auto render = [&](int bounces, int glossy_bounces) {
    RenderOptions o = Pbr(8, bounces);
    o.glossy_bounces = glossy_bounces;
    return Renderer(view.parts, view.scene, o).Render(view.camera, 0);
  };
  const Frame direct = render(0, 64), glossy0 = render(3, 0), full = render(3, 64);
  EXPECT_EQ(render(3, 3).radiance, full.radiance);
  const int w = direct.width(), h = direct.height();
  // The ball's pixels whose 3 x 3 neighbourhood is all ball (no sample of theirs meets the
  // floor), and the floor's.
  size_t ball = 0, differ = 0;
  double floor_direct = 0, floor_glossy0 = 0, ball_full = 0, ball_glossy0 = 0;
  for (int v = 1; v + 1 < h; ++v) {
    for (int u = 1; u + 1 < w; ++u) {
      const size_t i = static_cast<size_t>(v) * w + u;
      bool inside = true;
      for (int dv = -1; dv <= 1; ++dv) {
        for (int du = -1; du <= 1; ++du) inside &= direct.instance[i + dv * w + du] == 1;
      }
      if (inside) {
        ++ball;
        for (int c = 0; c < 3; ++c)
          differ += glossy0.radiance[3 * i + c] != direct.radiance[3 * i + c];
        ball_full += full.radiance[3 * i], ball_glossy0 += glossy0.radiance[3 * i];
      } else if (direct.instance[i] == 0 && direct.depth[i] > 0) {
        floor_direct += direct.radiance[3 * i], floor_glossy0 += glossy0.radiance[3 * i];
      }
    }
  }
  ASSERT_GT(ball, 500u);
  EXPECT_EQ(differ, 0u) << "ball values that differ from the render without bounces";
  // The ball mirrors the lit floor only with glossy bounces to spare; the floor's light off the
  // floor again and through the ball is kept. Measured: the ball's red sum 29,031 against 21,496,
  // the floor's 222,619 against 216,969 without bounces.
  EXPECT_GT(ball_full, 1.2 * ball_glossy0);
  EXPECT_GT(floor_glossy0, 1.02 * floor_direct);
}

// render.clamp_indirect (Cycles' Clamp Indirect): a path's contributions of light that met more
// than one surface (found by its third segment or later, or sampled from its second vertex on)
// are scaled to an RGB sum of at most the limit; direct light never is. So a vanishing limit
// leaves the image with no bounces (the same samples), a huge one changes nothing, and since
// clamping only scales contributions down, every value grows with the limit.
TEST(PathTracer, ClampIndirectScalesOnlyIndirectLight) {
  SphereView view = MirrorBallOnAFloor();
  const auto render = [&](int bounces, double clamp) {
    RenderOptions o = Pbr(8, bounces);
    o.clamp_indirect = clamp;
    return Renderer(view.parts, view.scene, o).Render(view.camera, 0);
  };
  const Frame direct = render(0, 0), full = render(3, 0);
  EXPECT_EQ(render(3, 1e8).radiance, full.radiance);
  const Frame tiny = render(3, 1e-12), low = render(3, 2), high = render(3, 20);
  size_t not_monotone = 0;
  double sum_direct = 0, sum_low = 0, sum_high = 0, sum_full = 0;
  for (size_t i = 0; i < full.radiance.size(); ++i) {
    // At most 2 x 3 indirect contributions of 1e-12 a path.
    EXPECT_NEAR(tiny.radiance[i], direct.radiance[i], 1e-5f * direct.radiance[i] + 1e-9f);
    not_monotone += !(direct.radiance[i] <= low.radiance[i] + 1e-6f * low.radiance[i] &&
                      low.radiance[i] <= high.radiance[i] && high.radiance[i] <= full.radiance[i]);
    sum_direct += direct.radiance[i], sum_low += low.radiance[i];
    sum_high += high.radiance[i], sum_full += full.radiance[i];
  }
  EXPECT_EQ(not_monotone, 0u);
  // The caustic's paths (floor, ball, panel) carry far more than these limits, the floor's light
  // off the floor less: some is cut, not all. Measured: the image's sum 73,843 direct, 73,918 at
  // 2, 74,496 at 20, 76,437 unclamped (over five seeds the three ratios were 1.0010-1.0011,
  // 1.0078-1.0084 and 0.973-0.984).
  EXPECT_GT(sum_low, sum_direct * 1.0005);
  EXPECT_GT(sum_high, sum_low * 1.004);
  EXPECT_LT(sum_high, sum_full * 0.99);
}

// A surface that sees nothing but the sky receives no indirect light: clamping leaves it alone.
TEST(PathTracer, ClampIndirectLeavesAFloorUnderTheSky) {
  Scene scene = Dark();
  scene.floor = true;
  scene.environment.color = Eigen::Vector3f::Constant(0.5f);
  Camera camera;
  camera.intrinsics = Intrinsics::FromFov(32, 32, 0.8);
  camera.world_from_cam = WorldFromCamOnSphere({0, 0, 0}, 0.5, 0.9, 600.0);
  RenderOptions o = Pbr(4, 3);
  const Frame off = Renderer({}, scene, o).Render(camera, 0);
  o.clamp_indirect = 1e-9;
  EXPECT_EQ(Renderer({}, scene, o).Render(camera, 0).radiance, off.radiance);
}

TEST(PathTracer, PbrChangesOnlyTheColourImage) {
  SphereView view(Metal(0.3f), 0.4f);
  view.scene.floor = true;
  view.camera.world_from_cam = WorldFromCamOnSphere({0, 0, 0}, 0.4, 0.7, 500.0);
  RenderOptions fast;
  fast.amodal_masks = true;
  RenderOptions pbr = Pbr(2, 1);
  pbr.amodal_masks = true;
  const Frame a = Renderer(view.parts, view.scene, fast).Render(view.camera);
  const Frame b = Renderer(view.parts, view.scene, pbr).Render(view.camera);
  EXPECT_EQ(a.depth, b.depth);
  EXPECT_EQ(a.instance, b.instance);
  ASSERT_EQ(a.instances.size(), b.instances.size());
  EXPECT_EQ(a.instances[0].amodal_mask, b.instances[0].amodal_mask);
  EXPECT_NE(a.rgb, b.rgb);
  // hdr in the fast mode keeps the colour before it is rounded to bytes.
  fast.hdr = true;
  const Frame c = Renderer(view.parts, view.scene, fast).Render(view.camera);
  EXPECT_EQ(c.rgb, a.rgb);
  ASSERT_EQ(c.radiance.size(), c.rgb.size());
  for (size_t i = 0; i < c.rgb.size(); i += 97) {
    EXPECT_EQ(static_cast<int>(std::lround(std::clamp(c.radiance[i], 0.0f, 1.0f) * 255.0f)),
              static_cast<int>(c.rgb[i]));
  }
}

TEST(PathTracer, DisplayTransforms) {
  // Standard: sRGB's encoding of the clipped value; filmic: the curve, then sRGB.
  EXPECT_FLOAT_EQ(DisplayValue(0.0f, false), 0.0f);
  EXPECT_FLOAT_EQ(DisplayValue(1.0f, false), 1.0f);
  EXPECT_FLOAT_EQ(DisplayValue(4.0f, false), 1.0f);
  EXPECT_NEAR(DisplayValue(0.18f, false), 0.4614f, 1e-4);
  EXPECT_NEAR(FilmicCurve(0.18f),
              0.18f * (2.51f * 0.18f + 0.03f) / (0.18f * (2.43f * 0.18f + 0.59f) + 0.14f), 1e-6);
  EXPECT_LT(FilmicCurve(4.0f), 1.0f);
  EXPECT_FLOAT_EQ(FilmicCurve(7.3f), 1.0f);
  for (float x = 0; x < 10; x += 0.01f) EXPECT_LE(FilmicCurve(x), FilmicCurve(x + 0.01f));
  EXPECT_NEAR(SrgbToLinear(LinearToSrgb(0.3f)), 0.3f, 1e-6);
}

// An equirectangular world of 64 x 32 pixels: red 2 over the upper hemisphere (rows 0-15) and 0
// below; green the column's u = (x + 0.5) / 64, blue 0.
Environment HalfSkyImage(double rotation_rad) {
  auto image = std::make_shared<LinearImage>();
  image->width = 64;
  image->height = 32;
  for (int y = 0; y < 32; ++y) {
    for (int x = 0; x < 64; ++x)
      image->rgb.insert(image->rgb.end(), {y < 16 ? 2.0f : 0.0f, (x + 0.5f) / 64, 0.0f});
  }
  Environment e;
  e.kind = Environment::Kind::kImage;
  e.pixels = image;
  e.image = "half_sky";
  e.strength = 1.0;
  e.rotation_rad = rotation_rad;
  return e;
}

// An anisotropic metal floor (roughness 0.3, anisotropic 0.9: GGX alphas 0.206 along the tangent
// and 0.039 across it) under a point light 300 mm above a floor point, seen from 600 mm straight
// above it: the highlight stretches along the tangent, where the microfacet normals spread
// 5.3x wider. The radiance-weighted spread of the highlight's floor points along x and y.
// With `plate`, the surface is instead the top of a 2.4 m square plate part, 2 mm thick (its model
// frame centred on its box, as MakePart makes it), turned 90 degrees about z at the world origin.
Eigen::Vector2d HighlightSpread(Material::Tangent tangent, const Eigen::Vector3d& at,
                                bool plate = false) {
  Scene scene = Dark();
  Material metal;
  metal.surface.base_color = Eigen::Vector3f::Ones();
  metal.surface.metallic = 1;
  metal.surface.roughness = 0.3f;
  metal.surface.anisotropic = 0.9f;
  metal.tangent = tangent;
  scene.floor_material = metal;
  std::vector<Part> parts;
  if (plate) {
    parts = {MakePart("plate", MakeBox(2400, 2400, 2), TessellationOptions{})};
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    scene.floor = false;
    scene.instances = {Instance{0, "plate", pose}};
    scene.materials = {metal};
    scene.instance_material = {0};
  }
  LightSource point;
  point.kind = LightSource::Kind::kPoint;
  point.power = 100;
  point.position = at + Eigen::Vector3d(0, 0, 300);
  scene.light_sources = {point};
  Camera camera;
  camera.intrinsics = Intrinsics::FromFov(64, 64, 2 * std::atan(150.0 / 600.0));
  camera.world_from_cam = LookingDown(at + Eigen::Vector3d(0, 0, 600));
  const Frame frame = Renderer(parts, scene, Pbr(64, 0)).Render(camera);
  double w = 0;
  Eigen::Vector2d m2 = Eigen::Vector2d::Zero();
  for (int v = 0; v < 64; ++v) {
    for (int u = 0; u < 64; ++u) {
      const Eigen::Vector3d d =
          camera.world_from_cam.linear() *
          Eigen::Vector3d((u + 0.5 - camera.intrinsics.cx) / camera.intrinsics.fx,
                          (v + 0.5 - camera.intrinsics.cy) / camera.intrinsics.fy, 1.0);
      const Eigen::Vector3d p = camera.world_from_cam.translation() +
                                d * ((at.z() - camera.world_from_cam.translation().z()) / d.z());
      const double l = At(frame, u, v);
      w += l;
      m2 += l * Eigen::Vector2d((p - at).x() * (p - at).x(), (p - at).y() * (p - at).y());
    }
  }
  return (m2 / w).cwiseSqrt();
}

TEST(PathTracer, AnisotropicHighlightsStretchAlongBlendersDefaultTangent) {
  // x: along the model's (here the world's) x axis wherever the point is.
  const Eigen::Vector2d x = HighlightSpread(Material::Tangent::kModelX, {1000, 0, 0});
  EXPECT_GT(x.x(), 2.5 * x.y()) << x.transpose();
  // Radial (Blender's default, Cycles' tangent from Generated coordinates): around the floor's
  // centre, so along y at (1000, 0) and along x at (0, 1000) (far enough from the centre that the
  // tangent turns by under 5 degrees over the highlight).
  const Eigen::Vector2d on_x = HighlightSpread(Material::Tangent::kRadial, {1000, 0, 0});
  EXPECT_GT(on_x.y(), 2.5 * on_x.x()) << on_x.transpose();
  const Eigen::Vector2d on_y = HighlightSpread(Material::Tangent::kRadial, {0, 1000, 0});
  EXPECT_GT(on_y.x(), 2.5 * on_y.y()) << on_y.transpose();
  // A part's tangent turns with the part: at world (0, 1000) on the turned plate, model point
  // (1000, 0) from its box's centre, where the radial tangent is model y, which the turn makes
  // world -x. (Taking the model's tangent for the world's would give y.)
  const Eigen::Vector2d part = HighlightSpread(Material::Tangent::kRadial, {0, 1000, 1}, true);
  EXPECT_GT(part.x(), 2.5 * part.y()) << part.transpose();
  // Along the model's x axis, which the turn makes world y.
  const Eigen::Vector2d part_x = HighlightSpread(Material::Tangent::kModelX, {0, 1000, 1}, true);
  EXPECT_GT(part_x.y(), 2.5 * part_x.x()) << part_x.transpose();
}

TEST(PathTracer, ImageWorldIsMappedAndLightsAsBlendersIs) {
  // Blender's mapping: looking along +x one sees the image's centre column (u = 0.5); a rotation of
  // 90 degrees (a Mapping node's Z, BlenderProc's rotation_euler) looks the image up at the
  // direction turned by 90 degrees, +y, whose column is u = 0.25. Between pixel centres the image
  // is interpolated, so green reads u itself.
  for (const double degrees : {0.0, 90.0}) {
    Scene scene = Dark();
    scene.floor = false;
    scene.environment = HalfSkyImage(degrees * kPi / 180);
    Camera camera;
    camera.intrinsics = Intrinsics::FromFov(9, 9, 0.001);
    camera.world_from_cam.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;  // optical axis along +x
    const Frame frame = Renderer({}, scene, Pbr(4, 0)).Render(camera);
    const size_t centre = 4 * 9 + 4;
    EXPECT_NEAR(frame.radiance[3 * centre + 1], degrees == 0 ? 0.5f : 0.25f, 1e-3) << degrees;
    EXPECT_NEAR(frame.radiance[3 * centre], 1.0f, 0.05f) << degrees;  // the horizon: half way
  }
  // A white Lambert floor under radiance L over the upper hemisphere (and none below) reflects L,
  // whatever the rotation: the image is sampled by its pixels' luminance, BSDF rays by the cosine,
  // and MIS weighs the two.
  for (const double degrees : {0.0, 90.0}) {
    Scene scene = Dark();
    scene.floor_material = Lambert(1.0f);
    scene.environment = HalfSkyImage(degrees * kPi / 180);
    Camera camera;
    camera.intrinsics = Intrinsics::FromFov(16, 16, 0.2);
    camera.world_from_cam = LookingDown({0, 0, 300});
    const Frame frame = Renderer({}, scene, Pbr(64, 1)).Render(camera);
    double sum = 0;
    for (int v = 0; v < 16; ++v) {
      for (int u = 0; u < 16; ++u) sum += At(frame, u, v);
    }
    EXPECT_NEAR(sum / 256, 2.0, 0.03) << degrees;
  }
}

TEST(PathTracer, BadScenesAreRefused) {
  Scene scene = Dark();
  LightSource light;
  light.power = -1;
  scene.light_sources = {light};
  EXPECT_THROW(Renderer({}, scene, Pbr(1, 0)), Error);
  scene = Dark();
  scene.floor_material.surface.roughness = 1.5f;
  EXPECT_THROW(Renderer({}, scene, Pbr(1, 0)), Error);
  scene = Dark();
  scene.environment.kind = Environment::Kind::kImage;
  scene.environment.image = "/nonexistent/sky.hdr";
  try {
    Renderer({}, scene, Pbr(1, 0));
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/sky.hdr"), std::string::npos) << e.what();
  }
  RenderOptions o = Pbr(1, 0);
  o.supersampling = 2;
  std::string why;
  EXPECT_FALSE(o.Check(&why));
  // Light path limits: each refused with a reason that names it.
  const auto refused = [](RenderOptions o, const char* key) {
    std::string why;
    return !o.Check(&why) && why.find(key) != std::string::npos;
  };
  o = Pbr(1, 3);
  std::string ok;
  EXPECT_TRUE(o.Check(&ok)) << ok;
  o.glossy_bounces = -1;
  EXPECT_TRUE(refused(o, "glossy_bounces"));
  o.glossy_bounces = 1025;
  EXPECT_TRUE(refused(o, "glossy_bounces"));
  o = Pbr(1, 3);
  o.clamp_indirect = -1;
  EXPECT_TRUE(refused(o, "clamp_indirect"));
  o.clamp_indirect = std::nan("");
  EXPECT_TRUE(refused(o, "clamp_indirect"));
}

}  // namespace
}  // namespace cadsynth
