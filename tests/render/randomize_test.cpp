// Domain randomisation: the distributions' draws against their CDFs (Kolmogorov-Smirnov,
// chi-square), black-body colours against the CIE Planckian locus, draws that stay put when other
// distributions change, and a frame's own look that changes the colour image and nothing else.
#include "render/randomize.h"

#include <algorithm>
#include <cmath>
#include <map>

#include <gtest/gtest.h>

#include "tests/render/render_support.h"

#include "cad/core/error.h"
#include "cad/core/random.h"
#include "cad/shape.h"
#include "render/renderer.h"
#include "render/sampling.h"

namespace cadsynth {
namespace {

using testing::LookingDown;

// The largest gap between the empirical CDF of `draws` and `cdf` (Kolmogorov-Smirnov D).
template <typename Cdf>
double KolmogorovSmirnov(std::vector<double> draws, Cdf cdf) {
  std::sort(draws.begin(), draws.end());
  const double n = static_cast<double>(draws.size());
  double d = 0;
  for (size_t i = 0; i < draws.size(); ++i) {
    const double f = cdf(draws[i]);
    d = std::max({d, f - i / n, (i + 1) / n - f});
  }
  return d;
}

std::vector<double> Draws(const Distribution& d, int n) {
  std::vector<double> v;
  for (int i = 0; i < n; ++i) v.push_back(d.Draw(Hash(99, static_cast<uint64_t>(i)), "test"));
  return v;
}

// Critical value of D at the 0.1% level for n draws: 1.95 / sqrt(n).
double Critical(int n) { return 1.95 / std::sqrt(static_cast<double>(n)); }

TEST(Distribution, UniformNormalAndLogUniformDrawsFollowTheirCdfs) {
  const int n = 4000;
  const Distribution uniform = Distribution::Uniform(-2, 5);
  EXPECT_LT(KolmogorovSmirnov(Draws(uniform, n), [](double x) { return (x + 2) / 7; }),
            Critical(n));
  const Distribution normal{Distribution::Kind::kNormal, 3, 0.5, {}};
  EXPECT_LT(KolmogorovSmirnov(Draws(normal, n),
                              [](double x) { return 0.5 * std::erfc(-(x - 3) / (0.5 * M_SQRT2)); }),
            Critical(n));
  const Distribution log_uniform{Distribution::Kind::kLogUniform, 10, 1000, {}};
  EXPECT_LT(KolmogorovSmirnov(Draws(log_uniform, n),
                              [](double x) { return std::log(x / 10) / std::log(100.0); }),
            Critical(n));
  // A wrong CDF is told apart: the normal's draws against a sigma 20% too wide.
  EXPECT_GT(KolmogorovSmirnov(Draws(normal, n),
                              [](double x) { return 0.5 * std::erfc(-(x - 3) / (0.6 * M_SQRT2)); }),
            Critical(n));
}

TEST(Distribution, ChoicesAreEquallyLikely) {
  const Distribution choice{Distribution::Kind::kChoice, 0, 0, {1, 2, 3}};
  std::map<double, int> counts;
  const int n = 3000;
  for (double v : Draws(choice, n)) ++counts[v];
  ASSERT_EQ(counts.size(), 3u);
  double chi2 = 0;
  for (const auto& [v, c] : counts) chi2 += (c - n / 3.0) * (c - n / 3.0) / (n / 3.0);
  EXPECT_LT(chi2, 13.82);  // 0.1% critical value, 2 degrees of freedom
}

TEST(Distribution, ImpossibleParametersAreRefused) {
  std::string why;
  EXPECT_FALSE(Distribution::Uniform(2, 1).Check(&why));
  EXPECT_NE(why.find("low <= high"), std::string::npos) << why;
  EXPECT_FALSE((Distribution{Distribution::Kind::kLogUniform, 0, 1, {}}.Check(&why)));
  EXPECT_FALSE((Distribution{Distribution::Kind::kNormal, 0, -1, {}}.Check(&why)));
  EXPECT_FALSE((Distribution{Distribution::Kind::kChoice, 0, 0, {}}.Check(&why)));
  EXPECT_TRUE(Distribution::Uniform(1, 1).Check(&why));
  // A factor whose mean is below zero.
  MaterialRandomization m;
  m.texture_scale = Distribution{Distribution::Kind::kNormal, -1, 0.2, {}};
  EXPECT_FALSE(m.Check(&why));
  m.texture_scale = Distribution{Distribution::Kind::kNormal, 1, 0.5, {}};  // tails clipped
  EXPECT_TRUE(m.Check(&why)) << why;
  LightRandomization l;
  l.temperature_k = Distribution::Uniform(1000, 5000);  // below the locus fit's 1,667 K
  EXPECT_FALSE(l.Check(&why));
}

// Linear sRGB back to CIE xy (the inverse of BlackbodyColor's matrix).
Eigen::Vector2d Chromaticity(const Eigen::Vector3f& rgb) {
  const double X = 0.4124564 * rgb[0] + 0.3575761 * rgb[1] + 0.1804375 * rgb[2];
  const double Y = 0.2126729 * rgb[0] + 0.7151522 * rgb[1] + 0.0721750 * rgb[2];
  const double Z = 0.0193339 * rgb[0] + 0.1191920 * rgb[1] + 0.9503041 * rgb[2];
  return {X / (X + Y + Z), Y / (X + Y + Z)};
}

TEST(Blackbody, ColoursLieOnThePlanckianLocus) {
  // CIE illuminant A is a 2,856 K black body: x = 0.44757, y = 0.40745; the locus at 5,000 K
  // and 6,500 K: (0.3451, 0.3516) and (0.3135, 0.3237) (Wyszecki and Stiles).
  const Eigen::Vector2d a = Chromaticity(BlackbodyColor(2856));
  EXPECT_NEAR(a.x(), 0.44757, 1e-3);
  EXPECT_NEAR(a.y(), 0.40745, 1e-3);
  const Eigen::Vector2d k5 = Chromaticity(BlackbodyColor(5000));
  EXPECT_NEAR(k5.x(), 0.3451, 1e-3);
  EXPECT_NEAR(k5.y(), 0.3516, 1e-3);
  const Eigen::Vector2d k65 = Chromaticity(BlackbodyColor(6500));
  EXPECT_NEAR(k65.x(), 0.3135, 1e-3);
  EXPECT_NEAR(k65.y(), 0.3237, 1e-3);
  // Warm light is red-heavy, cold light blue-heavy; the largest component is 1.
  const Eigen::Vector3f warm = BlackbodyColor(3000), cold = BlackbodyColor(10000);
  EXPECT_FLOAT_EQ(warm.maxCoeff(), 1.0f);
  EXPECT_GT(warm[0], warm[1]);
  EXPECT_GT(warm[1], warm[2]);
  EXPECT_FLOAT_EQ(cold[2], 1.0f);
  EXPECT_GT(cold[2], cold[0]);
}

TEST(Blackbody, WhiteBalanceMakesItsTemperatureNeutral) {
  const Eigen::Vector3f same = WhiteBalanceGains(6504);
  EXPECT_NEAR((same - Eigen::Vector3f::Ones()).norm(), 0.0f, 1e-6f);
  // Balanced for 3,000 K: light of 3,000 K reads as the 6,504 K white does.
  const Eigen::Vector3f g = WhiteBalanceGains(3000);
  const Eigen::Vector3f seen = g.cwiseProduct(BlackbodyColor(3000));
  const Eigen::Vector3f white = BlackbodyColor(6504);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(seen[c] / seen[1], white[c] / white[1], 1e-5f);
  EXPECT_FLOAT_EQ(g[1], 1.0f);
  EXPECT_GT(g[2], g[0]);  // a warm balance lifts blue
}

// Three instances of two parts, steel by default.
FrameLook BaseLook() {
  FrameLook look;
  Material steel;
  EXPECT_TRUE(MaterialPreset("steel", &steel));
  look.instance_materials = {steel, steel, steel};
  look.instance_colors = {Eigen::Vector3f(0.8f, 0.1f, 0.1f), Eigen::Vector3f(0.8f, 0.1f, 0.1f),
                          Eigen::Vector3f(0.1f, 0.1f, 0.8f)};
  look.floor = Scene::DefaultFloorMaterial(Eigen::Vector3f::Constant(0.5f));
  look.lights = Scene::DefaultLightSources();
  return look;
}

Randomization PartsOnly(bool per_instance) {
  Randomization r;
  r.seed = 4;
  PartRandomization p;
  p.per_instance = per_instance;
  p.material.roughness = Distribution::Uniform(0, 1);
  p.material.hue = Distribution::Uniform(-0.5, 0.5);
  r.parts = {p};
  r.instance_rule = {0, 0, 0};
  r.instance_part = {0, 0, 1};
  return r;
}

double Recorded(const FrameDraw& d, const std::string& key) {
  for (const Drawn& x : d.record) {
    if (x.key == key) return x.values.at(0);
  }
  ADD_FAILURE() << "no draw " << key;
  return NAN;
}

FrameDraw Draw(const Randomization& r, uint64_t scene, uint64_t view) {
  return DrawFrame(r, BaseLook(), LookingDown({0, 0, 500}), SensorOptions{},
                   Eigen::Vector3d::Zero(), scene, view);
}

TEST(DrawFrame, SameKeySameDrawsAndOtherDistributionsDoNotMoveThem) {
  const Randomization r = PartsOnly(false);
  const FrameDraw a = Draw(r, 0, 7), b = Draw(r, 0, 7);
  EXPECT_EQ(Recorded(a, "part.0.roughness"), Recorded(b, "part.0.roughness"));
  EXPECT_NE(Recorded(a, "part.0.roughness"), Recorded(Draw(r, 0, 8), "part.0.roughness"));
  EXPECT_NE(Recorded(a, "part.0.roughness"), Recorded(Draw(r, 1, 7), "part.0.roughness"));
  // Adding lights and a camera, and another distribution for the hue, leaves the roughness.
  Randomization more = r;
  more.lights = LightRandomization{};
  more.camera = CameraRandomization{};
  more.camera->exposure = Distribution::Uniform(-1, 1);
  more.parts[0].material.hue = Distribution::Uniform(-0.1, 0.1);
  const FrameDraw c = Draw(more, 0, 7);
  EXPECT_EQ(Recorded(a, "part.0.roughness"), Recorded(c, "part.0.roughness"));
  EXPECT_EQ(a.look.instance_materials[0].surface.roughness,
            c.look.instance_materials[0].surface.roughness);
  // Nothing randomised keeps its base value.
  EXPECT_EQ(a.look.lights.size(), BaseLook().lights.size());
  EXPECT_EQ(a.look.floor.surface.roughness, BaseLook().floor.surface.roughness);
  EXPECT_EQ(a.world_from_cam.matrix(), LookingDown({0, 0, 500}).matrix());
}

// Distractors are drawn per scene: the same scene gives the same picks, another scene others; the
// count is uniform on its range (rounded), objects are equally likely, and a changed size
// distribution changes sizes only. Their materials are redrawn per frame, apart from the
// fixtures before them (a tote), which keep theirs unless `fixtures` is set.
TEST(DrawDistractors, PerSceneAndEachQuantityOnItsOwn) {
  Randomization r;
  r.seed = 2;
  r.distractors = DistractorRandomization{};
  r.distractors->count = Distribution::Uniform(2, 6);
  const std::vector<std::string> names = {"box", "sphere", "nut"};
  const std::vector<int> sizes = {3, 1, 0};
  std::vector<Drawn> rec_a, rec_b, rec_c;
  const auto a = DrawDistractors(r, 0, names, sizes, &rec_a);
  const auto b = DrawDistractors(r, 0, names, sizes, &rec_b);
  ASSERT_EQ(a.size(), b.size());
  for (size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].object, b[k].object);
    EXPECT_EQ(a[k].size_mm, b[k].size_mm);
  }
  std::map<size_t, int> counts;
  std::vector<int> objects(3, 0);
  for (uint64_t scene = 0; scene < 2000; ++scene) {
    std::vector<Drawn> rec;
    const auto picks = DrawDistractors(r, scene, names, sizes, &rec);
    ++counts[picks.size()];
    for (const DistractorPick& p : picks) {
      ++objects[static_cast<size_t>(p.object)];
      EXPECT_GE(p.size_mm.minCoeff(), 20.0);
      EXPECT_LE(p.size_mm.maxCoeff(), 80.0);
    }
    // The record: the count, and per distractor its object, the sizes it takes, its colour.
    if (!picks.empty()) {
      size_t sizes_recorded = 99;
      for (const Drawn& d : rec) {
        if (d.key == "distractor.0.size") sizes_recorded = d.values.size();
      }
      const size_t expected[] = {3, 1, 99};  // box, sphere, a part (none recorded)
      EXPECT_EQ(sizes_recorded, expected[picks[0].object]) << names[picks[0].object];
    }
  }
  // lround of a uniform on [2, 6]: 2 and 6 take half a unit each, 3, 4, 5 a whole one (of 4).
  ASSERT_EQ(counts.size(), 5u);
  EXPECT_NEAR(counts[2] / 2000.0, 0.125, 0.03);
  EXPECT_NEAR(counts[4] / 2000.0, 0.25, 0.04);
  EXPECT_NEAR(counts[6] / 2000.0, 0.125, 0.03);
  const int total = objects[0] + objects[1] + objects[2];
  for (int n : objects) EXPECT_NEAR(n / static_cast<double>(total), 1.0 / 3, 0.03);
  // Another size distribution: the same objects and colours, other sizes.
  Randomization big = r;
  big.distractors->size_mm = Distribution::Uniform(100, 200);
  const auto c = DrawDistractors(big, 0, names, sizes, &rec_c);
  ASSERT_EQ(c.size(), a.size());
  for (size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(c[k].object, a[k].object);
    EXPECT_EQ(c[k].color, a[k].color);
    EXPECT_GE(c[k].size_mm.minCoeff(), 100.0);
  }
  // Materials: a tote (fixture 0) keeps its own, the distractors (fixtures 1, 2) draw theirs.
  r.distractors->material = MaterialRandomization{};
  r.distractors->material->roughness = Distribution::Uniform(0, 1);
  r.first_distractor = 1;
  r.scene_record = rec_a;
  FrameLook base = BaseLook();
  base.fixture_materials.assign(3, Scene::DefaultMaterial(Eigen::Vector3f::Constant(0.5f)));
  const FrameDraw f =
      DrawFrame(r, base, LookingDown({0, 0, 500}), SensorOptions{}, Eigen::Vector3d::Zero(), 0, 0);
  EXPECT_EQ(f.look.fixture_materials[0].surface.roughness,
            base.fixture_materials[0].surface.roughness);
  EXPECT_FLOAT_EQ(f.look.fixture_materials[1].surface.roughness,
                  Recorded(f, "distractor.0.roughness"));
  EXPECT_FLOAT_EQ(f.look.fixture_materials[2].surface.roughness,
                  Recorded(f, "distractor.1.roughness"));
  // The scene's record comes first in every frame's.
  ASSERT_GE(f.record.size(), rec_a.size());
  EXPECT_EQ(f.record[0].key, "distractor.count");
  EXPECT_EQ(f.record[0].values, rec_a[0].values);
}

// Environment images and background photos are picked equally often from their folders (chi
// square, 1 degree of freedom, 3.84 at 5%), recorded by name, and a per-scene pick is the
// scene's for all its frames.
TEST(DrawFrame, EnvironmentImagesAndBackgroundsArePickedEquallyOften) {
  const auto image = [](float v) {
    auto p = std::make_shared<LinearImage>();
    p->width = 2;
    p->height = 1;
    p->rgb.assign(6, v);
    return std::shared_ptr<const LinearImage>(p);
  };
  ImageChoice two;
  two.files = {"a.png", "b.png"};
  two.names = {"a.png", "b.png"};
  two.pixels = {image(0.2f), image(0.7f)};
  Randomization r;
  r.environment = EnvironmentRandomization{};
  r.environment->images = two;
  r.background = BackgroundRandomization{two};
  std::string why;
  ASSERT_TRUE(r.Check(&why)) << why;
  int env_a = 0, bg_a = 0;
  const int n = 2000;
  for (int view = 0; view < n; ++view) {
    const FrameDraw d = Draw(r, 0, static_cast<uint64_t>(view));
    ASSERT_EQ(d.look.environment.kind, Environment::Kind::kImage);
    const bool ea = d.look.environment.pixels == two.pixels[0];
    const bool ba = d.look.background == two.pixels[0];
    env_a += ea;
    bg_a += ba;
    for (const Drawn& x : d.record) {
      if (x.key == "environment.image") {
        EXPECT_EQ(x.text, ea ? "a.png" : "b.png");
      }
      if (x.key == "background") {
        EXPECT_EQ(x.text, ba ? "a.png" : "b.png");
      }
    }
  }
  for (const int a : {env_a, bg_a}) {
    const double chi2 = 2 * std::pow(a - n / 2.0, 2) / (n / 2.0);
    EXPECT_LT(chi2, 3.84) << a;
  }
  r.background_per = DrawPer::kScene;
  for (uint64_t scene = 0; scene < 4; ++scene) {
    const auto first = Draw(r, scene, 0).look.background;
    for (uint64_t view = 1; view < 6; ++view)
      EXPECT_EQ(Draw(r, scene, view).look.background, first);
  }
  ImageChoice empty;
  r.background = BackgroundRandomization{empty};
  EXPECT_FALSE(r.Check(&why));
}

TEST(DrawFrame, PerPartCopiesMatchPerInstanceCopiesDiffer) {
  const FrameDraw part = Draw(PartsOnly(false), 0, 3);
  const auto& m = part.look.instance_materials;
  EXPECT_EQ(m[0].surface.roughness, m[1].surface.roughness);  // two copies of part 0
  EXPECT_NE(m[0].surface.roughness, m[2].surface.roughness);  // part 1
  const FrameDraw inst = Draw(PartsOnly(true), 0, 3);
  const auto& n = inst.look.instance_materials;
  EXPECT_NE(n[0].surface.roughness, n[1].surface.roughness);
  EXPECT_FLOAT_EQ(static_cast<float>(Recorded(inst, "instance.1.roughness")),
                  n[1].surface.roughness);
  // The hue turned: steel's grey has no hue, so only roughness shows; per part, recorded once.
  int count = 0;
  for (const Drawn& d : part.record) count += d.key == "part.0.roughness";
  EXPECT_EQ(count, 1);
}

TEST(DrawFrame, TexturesArePickedAndRecordedByName) {
  Randomization r;
  r.floor = MaterialRandomization{};
  auto pixels = std::make_shared<LinearImage>();
  pixels->width = pixels->height = 1;
  pixels->rgb = {0.5f, 0.5f, 0.5f};
  for (const char* name : {"a.png", "b.png", "c.png"}) {
    Texture t;
    t.kind = Texture::Kind::kImage;
    t.pixels = pixels;
    t.image = name;
    r.floor->textures.push_back(t);
    r.floor->texture_names.push_back(name);
  }
  std::string why;
  ASSERT_TRUE(r.Check(&why)) << why;
  std::map<std::string, int> picked;
  for (uint64_t view = 0; view < 300; ++view) {
    const FrameDraw d = Draw(r, 0, view);
    const auto it = std::find_if(d.record.begin(), d.record.end(),
                                 [](const Drawn& x) { return x.key == "floor.texture"; });
    ASSERT_NE(it, d.record.end());
    EXPECT_EQ(d.look.floor.texture.image.string(), it->text);
    ++picked[it->text];
  }
  ASSERT_EQ(picked.size(), 3u);
  for (const auto& [name, n] : picked) EXPECT_GT(n, 60) << name;  // about 100 each
}

TEST(DrawFrame, PerSceneDrawsAreSharedByTheScenesFrames) {
  Randomization r = PartsOnly(false);
  r.parts[0].per = DrawPer::kScene;
  r.lights = LightRandomization{};
  EXPECT_EQ(Recorded(Draw(r, 2, 0), "part.0.roughness"),
            Recorded(Draw(r, 2, 9), "part.0.roughness"));
  EXPECT_NE(Recorded(Draw(r, 2, 0), "light.0.power"), Recorded(Draw(r, 2, 9), "light.0.power"));
}

TEST(DrawFrame, LightsSitOnTheirShellAimedAtTheCentre) {
  Randomization r;
  r.lights = LightRandomization{};
  r.lights->count = Distribution::Fixed(3);
  const Eigen::Vector3d centre(100, -50, 0);
  for (uint64_t view = 0; view < 20; ++view) {
    const FrameDraw d =
        DrawFrame(r, BaseLook(), LookingDown({0, 0, 500}), SensorOptions{}, centre, 0, view);
    ASSERT_EQ(d.look.lights.size(), 3u);
    for (int i = 0; i < 3; ++i) {
      const LightSource& l = d.look.lights[i];
      const std::string p = "light." + std::to_string(i);
      const Eigen::Vector3d offset = l.position - centre;
      EXPECT_NEAR(offset.norm(), Recorded(d, p + ".distance"), 1e-6);
      EXPECT_NEAR(std::asin(offset.z() / offset.norm()) * 180 / M_PI, Recorded(d, p + ".elevation"),
                  1e-6);
      EXPECT_NEAR(l.direction.normalized().dot(-offset.normalized()), 1.0, 1e-12);
      EXPECT_GE(Recorded(d, p + ".power"), 10.0);
      EXPECT_LE(Recorded(d, p + ".power"), 200.0);
      std::string why;
      EXPECT_TRUE(l.Check(&why)) << why;
    }
  }
}

TEST(DrawFrame, CameraJitterMovesThePoseByTheRecordedAmounts) {
  Randomization r;
  r.camera = CameraRandomization{};
  r.camera->rotation_deg = Distribution::Uniform(1, 2);
  r.camera->translation_mm = Distribution::Uniform(3, 4);
  const Eigen::Isometry3d pose = LookingDown({10, 20, 500});
  const FrameDraw d =
      DrawFrame(r, BaseLook(), pose, SensorOptions{}, Eigen::Vector3d::Zero(), 0, 5);
  const auto find = [&](const std::string& key) {
    for (const Drawn& x : d.record) {
      if (x.key == key) return x.values;
    }
    return std::vector<double>{};
  };
  const std::vector<double> rot = find("camera.rotation"), shift = find("camera.translation");
  ASSERT_EQ(rot.size(), 4u);
  ASSERT_EQ(shift.size(), 4u);
  const Eigen::AngleAxisd turned(pose.linear().transpose() * d.world_from_cam.linear());
  EXPECT_NEAR(turned.angle() * 180 / M_PI, rot[0], 1e-9);
  EXPECT_NEAR((d.world_from_cam.translation() - pose.translation()).norm(), shift[0], 1e-9);
  EXPECT_GE(rot[0], 1.0);
  EXPECT_LE(rot[0], 2.0);
}

// A 30 mm cube on the floor under the default light, pbr.
struct CubeScene {
  std::vector<Part> parts = {MakePart("cube", MakeBox(30, 30, 30), TessellationOptions{})};
  Scene scene;
  RenderOptions options;
  Camera camera;
  CubeScene() {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation().z() = 15;
    scene.instances = {Instance{0, "cube", pose}};
    options.mode = RenderOptions::Mode::kPbr;
    options.samples = 2;
    options.bounces = 1;
    camera.intrinsics = Intrinsics::FromFov(48, 40, 0.6);
    camera.world_from_cam = LookingDown({0, 0, 200});
  }
};

TEST(RendererLook, TheBaseLookRendersTheSameBytesAndAnotherOnlyChangesTheColour) {
  CubeScene c;
  const Renderer renderer(c.parts, c.scene, c.options);
  const Frame plain = renderer.Render(c.camera, 3);
  const FrameLook base = renderer.BaseLook();
  ASSERT_EQ(base.instance_materials.size(), 1u);
  const Frame same = renderer.Render(c.camera, 3, {}, &base);
  EXPECT_EQ(plain.rgb, same.rgb);
  Randomization r = PartsOnly(false);
  r.instance_rule = {0};
  r.instance_part = {0};
  r.lights = LightRandomization{};
  r.camera = CameraRandomization{};
  r.camera->white_balance_k = Distribution::Fixed(3000);
  const FrameDraw d =
      DrawFrame(r, base, c.camera.world_from_cam, {}, Eigen::Vector3d::Zero(), 0, 3);
  const Frame other = renderer.Render(c.camera, 3, {}, &d.look);
  EXPECT_NE(plain.rgb, other.rgb);
  EXPECT_EQ(plain.depth, other.depth);
  EXPECT_EQ(plain.instance, other.instance);
  ASSERT_EQ(other.instances.size(), 1u);
  EXPECT_EQ(plain.instances[0].amodal_mask, other.instances[0].amodal_mask);
  EXPECT_EQ(plain.instances[0].px_count_visib, other.instances[0].px_count_visib);
  // A look is for the pbr mode only.
  CubeScene fast;
  fast.options.mode = RenderOptions::Mode::kFast;
  const Renderer lambert(fast.parts, fast.scene, fast.options);
  EXPECT_THROW(lambert.Render(fast.camera, 0, {}, &base), Error);
}

}  // namespace
}  // namespace cadsynth
