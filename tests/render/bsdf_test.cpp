// The physically based surface model against answers known without it: a normalised distribution
// of normals, Smith's projected-area identity, a white furnace, a mirror, Lambert, reciprocity and
// two independent integrations (importance sampling and a deterministic quadrature) agreeing.
#include "render/bsdf.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>

#include <gtest/gtest.h>

#include "tests/render/render_support.h"

#include "render/image.h"
#include "render/material.h"

namespace cadsynth {
namespace {

using testing::kPi;

Eigen::Vector3f Direction(double mu, double phi) {
  const double s = std::sqrt(std::max(0.0, 1 - mu * mu));
  return Eigen::Vector3d(s * std::cos(phi), s * std::sin(phi), mu).cast<float>();
}

// The integral of g over the upper hemisphere by the midpoint rule in (cos theta, phi).
double Hemisphere(const std::function<double(const Eigen::Vector3f&)>& g, int n_mu, int n_phi) {
  double sum = 0;
  for (int i = 0; i < n_mu; ++i) {
    const double mu = (i + 0.5) / n_mu;
    for (int j = 0; j < n_phi; ++j) sum += g(Direction(mu, 2 * kPi * (j + 0.5) / n_phi));
  }
  return sum * (1.0 / n_mu) * (2 * kPi / n_phi);
}

// Directional albedo by importance sampling: stratified directions, lobe choices spread evenly.
Eigen::Vector3d SampledAlbedo(const PrincipledBsdf& bsdf, const Eigen::Vector3f& wo,
                              int strata = 128) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int k = 0; k < strata * strata; ++k) {
    const Eigen::Vector2f u((k % strata + 0.5f) / strata, (k / strata + 0.5f) / strata);
    const float lobe = static_cast<float>(std::fmod(k * 0.6180339887498949, 1.0));
    if (const auto s = bsdf.Sample(wo, lobe, u)) sum += s->weight.cast<double>();
  }
  return sum / (strata * strata);
}

Eigen::Vector3d QuadratureAlbedo(const PrincipledBsdf& bsdf, const Eigen::Vector3f& wo, int c) {
  return Eigen::Vector3d(
      Hemisphere([&](const Eigen::Vector3f& wi) { return bsdf.Eval(wo, wi)[c] * wi.z(); }, 1500,
                 300),
      0, 0);
}

PrincipledParams Params(float base, float metallic, float roughness, float specular = 0.5f) {
  PrincipledParams p;
  p.base_color = Eigen::Vector3f::Constant(base);
  p.metallic = metallic;
  p.roughness = roughness;
  p.specular = specular;
  return p;
}

TEST(Ggx, DistributionOfNormalsIsNormalised) {
  // The projected microfacet area is the macro surface: the integral of D(m) m.z is 1.
  for (const auto& alpha :
       {std::pair{0.09f, 0.09f}, {0.25f, 0.25f}, {0.64f, 0.64f}, {0.15f, 0.45f}}) {
    const float ax = alpha.first, ay = alpha.second;  // (clang 14 cannot capture a binding)
    const double total =
        Hemisphere([&](const Eigen::Vector3f& m) { return GgxD(m, ax, ay) * m.z(); }, 4000, 400);
    EXPECT_NEAR(total, 1.0, 2e-3) << ax << " " << ay;
  }
}

TEST(Ggx, VisibleNormalsProjectOntoTheViewDirection) {
  // Smith's masking makes the visible microfacets' projected area that of the macro surface:
  // integral of G1(wo) max(0, wo.m) D(m) over m = wo.z.
  for (const float mu : {0.2f, 0.6f, 1.0f}) {
    const Eigen::Vector3f wo = Direction(mu, 0.3);
    const float ax = 0.3f, ay = 0.5f;
    const double g1 = 1 / (1 + GgxLambda(wo, ax, ay));
    const double projected = Hemisphere(
        [&](const Eigen::Vector3f& m) { return g1 * std::max(0.0f, wo.dot(m)) * GgxD(m, ax, ay); },
        4000, 400);
    EXPECT_NEAR(projected, mu, 2e-3) << mu;
  }
}

TEST(PrincipledBsdf, WithoutSpecularItIsLambert) {
  PrincipledParams p = Params(0.6f, 0, 0.4f, /*specular=*/0);
  p.base_color = Eigen::Vector3f(0.6f, 0.3f, 0.1f);
  const PrincipledBsdf bsdf(p);
  const Eigen::Vector3f wo = Direction(0.7, 1.0), wi = Direction(0.4, 2.5);
  EXPECT_TRUE(bsdf.Eval(wo, wi).isApprox(p.base_color / static_cast<float>(kPi), 1e-6f));
  const auto s = bsdf.Sample(wo, 0.5f, Eigen::Vector2f(0.3f, 0.8f));
  ASSERT_TRUE(s);
  EXPECT_TRUE(s->weight.isApprox(p.base_color, 1e-5f));  // base/pi * cos / (cos/pi)
}

TEST(PrincipledBsdf, OnePairPicksTheLobeAndKeepsEachLobesStratification) {
  // SampleDirection(wo, u): u.x picks the lobe as u_lobe would, then, rescaled into the lobe's
  // share, is the lobe's first coordinate. N stratified u.x (one per 1/N of [0, 1)): the diffuse
  // lobe's share [c, 1) holds M of them, a regular progression, so its M directions (cosine-
  // weighted: 1 - z^2 is that coordinate) fall one in each 1/M of [0, 1), as stratified as the
  // pair, instead of a random subset of it.
  const PrincipledBsdf bsdf(Params(0.8f, 0, 0.5f));
  const Eigen::Vector3f wo = Direction(0.8, 0.3);
  constexpr int kN = 256;
  std::vector<float> diffuse;
  int glossy_count = 0;
  for (int i = 0; i < kN; ++i) {
    const Eigen::Vector2f u((i + 0.5f) / kN, 0.37f);
    bool glossy = false, glossy_apart = false;
    const auto wi = bsdf.SampleDirection(wo, u, &glossy);
    // The same lobe as a separate u_lobe equal to u.x picks.
    const auto apart = bsdf.SampleDirection(wo, u.x(), u, &glossy_apart);
    if (!wi) {  // a microfacet's mirror direction below the surface: the glossy lobe's only
      ++glossy_count;
      continue;
    }
    ASSERT_TRUE(apart) << i;
    EXPECT_EQ(glossy, glossy_apart) << i;
    if (glossy) {
      ++glossy_count;
    } else {
      diffuse.push_back(1 - wi->z() * wi->z());
    }
  }
  // Both lobes drawn (a dielectric of specular 0.5 at roughness 0.5), the glossy ones first.
  ASSERT_GT(glossy_count, 4);
  const int m = static_cast<int>(diffuse.size());
  ASSERT_GT(m, kN / 2);
  std::sort(diffuse.begin(), diffuse.end());
  for (int k = 0; k < m; ++k) {
    EXPECT_NEAR(diffuse[k], (k + 0.5) / m, 1.0 / m + 1e-5) << k << " of " << m;
  }
}

TEST(PrincipledBsdf, WhiteDielectricReflectsAllLightAtEveryAngleAndRoughness) {
  // The white furnace of the surface model: nothing absorbs, and the diffuse layer gets exactly
  // what the specular layer leaves.
  for (const float roughness : {0.05f, 0.3f, 0.6f, 1.0f}) {
    const PrincipledBsdf bsdf(Params(1, 0, roughness));
    for (const float mu : {0.15f, 0.5f, 1.0f}) {
      const Eigen::Vector3f wo = Direction(mu, 0);
      EXPECT_NEAR(SampledAlbedo(bsdf, wo)[0], 1.0, 0.01) << roughness << " " << mu;
      if (roughness >= 0.3f) {
        EXPECT_NEAR(QuadratureAlbedo(bsdf, wo, 0)[0], 1.0, 0.01) << roughness << " " << mu;
      }
    }
  }
}

TEST(PrincipledBsdf, PolishedMetalIsAMirrorWithSchlickFresnel) {
  PrincipledParams p = Params(0, 1, 0);
  p.base_color = Eigen::Vector3f(0.9f, 0.6f, 0.3f);
  const PrincipledBsdf bsdf(p);
  for (const float mu : {1.0f, 0.7071f, 0.3f}) {
    const Eigen::Vector3f wo = Direction(mu, 0.5);
    const Eigen::Vector3f mirror(-wo.x(), -wo.y(), wo.z());
    const float c5 = std::pow(1 - mu, 5.0f);
    const Eigen::Vector3f fresnel = p.base_color + (Eigen::Vector3f::Ones() - p.base_color) * c5;
    for (const Eigen::Vector2f& u : {Eigen::Vector2f(0.1f, 0.2f), Eigen::Vector2f(0.9f, 0.7f)}) {
      const auto s = bsdf.Sample(wo, 0.5f, u);
      ASSERT_TRUE(s);
      EXPECT_LT((s->wi - mirror).norm(), 1e-2f) << mu;
      EXPECT_TRUE(s->weight.isApprox(fresnel, 2e-3f)) << mu << ": " << s->weight.transpose();
    }
  }
}

TEST(PrincipledBsdf, PolishedClearCoatOnBlackIsADielectricMirror) {
  // A black base under a clear coat of roughness 0 reflects only at the coat: a mirror with
  // Schlick's Fresnel of IOR 1.5, F = 0.04 + 0.96 (1 - mu)^5 (4 % straight on).
  PrincipledParams p = Params(0, 0, 0.5f, /*specular=*/0);
  p.clearcoat = 1;
  p.clearcoat_roughness = 0;
  const PrincipledBsdf bsdf(p);
  for (const float mu : {1.0f, 0.5f, 0.2f}) {
    const Eigen::Vector3f wo = Direction(mu, 0.3);
    const double fresnel = 0.04 + 0.96 * std::pow(1.0 - mu, 5.0);
    EXPECT_NEAR(SampledAlbedo(bsdf, wo)[0], fresnel, 2e-3 + 0.01 * fresnel) << mu;
  }
  // Over a white base the coat takes its share and the base the rest: nothing is created, and
  // little is lost (only what the coat's and the base's single scattering lose).
  PrincipledParams white = Params(1, 0, 0.5f);
  white.clearcoat = 1;
  white.clearcoat_roughness = 0.2f;
  const PrincipledBsdf coated(white);
  for (const float mu : {1.0f, 0.5f, 0.2f}) {
    const double albedo = SampledAlbedo(coated, Direction(mu, 0.3))[0];
    EXPECT_LE(albedo, 1.005) << mu;
    EXPECT_GT(albedo, 0.9) << mu;
  }
}

TEST(PrincipledBsdf, RoughMetalLosesWhatSingleScatteringLoses) {
  // A white metal (F = 1) reflects all light when smooth; single-scattering GGX loses the light
  // that bounces more than once between microfacets, more the rougher and the more grazing.
  const PrincipledBsdf smooth(Params(1, 1, 0.1f));
  EXPECT_NEAR(SampledAlbedo(smooth, Direction(1, 0))[0], 1.0, 2e-3);
  double previous = 1.0;
  for (const float roughness : {0.4f, 0.7f, 1.0f}) {
    const PrincipledBsdf bsdf(Params(1, 1, roughness));
    const double sampled = SampledAlbedo(bsdf, Direction(1, 0))[0];
    const double quadrature = QuadratureAlbedo(bsdf, Direction(1, 0), 0)[0];
    EXPECT_NEAR(sampled, quadrature, 0.005) << roughness;
    EXPECT_NEAR(GgxAlbedo(1, roughness * roughness, 1), quadrature, 0.005) << roughness;
    EXPECT_LT(sampled, previous) << roughness;
    previous = sampled;
  }
  // Worked out by hand at roughness 1 (alpha = 1: D = 1/pi, G2 = 2 cos(i) / (1 + cos(i))), looking
  // straight on: half of all microfacet normals lie beyond 45 degrees and reflect below the
  // horizon, and E = 2 * integral over cos(m) from 1/sqrt(2) to 1 of (2 c^2 - 1) / c dc = 1 - ln 2.
  EXPECT_NEAR(previous, 1 - std::log(2.0), 2e-3);
}

TEST(PrincipledBsdf, FilterGlossyWidensTheGlossyLobesOnly) {
  // Cycles' bsdf_blur: the specular lobe's and the clear coat's alphas become at least min_alpha.
  PrincipledParams p = Params(1, 1, 0.2f);
  p.anisotropic = 0.5f;
  EXPECT_FLOAT_EQ(PrincipledBsdf(p, 0.3f).alpha_x(), 0.3f);
  EXPECT_FLOAT_EQ(PrincipledBsdf(p, 0.3f).alpha_y(), 0.3f);
  EXPECT_FLOAT_EQ(PrincipledBsdf(p, 0.02f).alpha_x(), PrincipledBsdf(p).alpha_x());
  // A Lambert surface (no specular layer) has no lobe to widen: the same values.
  const PrincipledParams lambert = Params(0.7f, 0, 0.3f, 0);
  const Eigen::Vector3f wo_l = Direction(0.7, 0.3), wi_l = Direction(0.4, 2.5);
  float pdf_plain = 0, pdf_widened = 0;
  EXPECT_EQ(PrincipledBsdf(lambert).EvalWithPdf(wo_l, wi_l, &pdf_plain),
            PrincipledBsdf(lambert, 0.5f).EvalWithPdf(wo_l, wi_l, &pdf_widened));
  EXPECT_EQ(pdf_plain, pdf_widened);
  // Widened, a white metal lobe is that of the rougher metal: at alpha 0.49 (roughness 0.7) it
  // loses what roughness 0.7 loses (single scattering), and multiscatter gives it back.
  const Eigen::Vector3f wo = Direction(0.6, 0.2);
  const PrincipledBsdf widened(Params(1, 1, 0.1f), 0.49f), rough(Params(1, 1, 0.7f));
  EXPECT_NEAR(SampledAlbedo(widened, wo)[0], QuadratureAlbedo(rough, wo, 0)[0], 0.01);
  PrincipledParams m = Params(1, 1, 0.1f);
  m.multiscatter = true;
  EXPECT_NEAR(SampledAlbedo(PrincipledBsdf(m, 0.49f), wo)[0], 1.0, 0.01);
  // A polished clear coat on black, widened, is the rough coat.
  PrincipledParams coat = Params(0, 0, 0.6f);
  coat.specular = 0;
  coat.clearcoat = 1;
  coat.clearcoat_roughness = 0.03f;
  PrincipledParams rough_coat = coat;
  rough_coat.clearcoat_roughness = 0.6f;
  for (const float mu : {1.0f, 0.4f}) {
    const Eigen::Vector3f w = Direction(mu, 0.1);
    float pdf_a = 0, pdf_b = 0;
    const Eigen::Vector3f wi = Direction(0.8, 2.0);
    const Eigen::Vector3f fa = PrincipledBsdf(coat, 0.36f).EvalWithPdf(w, wi, &pdf_a);
    const Eigen::Vector3f fb = PrincipledBsdf(rough_coat).EvalWithPdf(w, wi, &pdf_b);
    EXPECT_NEAR(fa[0], fb[0], 1e-5f * (1 + fb[0])) << mu;
    EXPECT_NEAR(pdf_a, pdf_b, 1e-5f * (1 + pdf_b)) << mu;
  }
}

TEST(PrincipledBsdf, MultiscatterGgxGivesBackWhatSingleScatteringLoses) {
  // Blender's Multiscatter GGX (Turquin's compensation): a white metal reflects all light at every
  // roughness and angle, where single scattering lost up to 1 - ln 2 straight on at roughness 1.
  for (const float roughness : {0.0f, 0.4f, 0.7f, 1.0f}) {
    PrincipledParams p = Params(1, 1, roughness);
    p.multiscatter = true;
    const PrincipledBsdf bsdf(p);
    for (const float mu : {1.0f, 0.5f, 0.2f}) {
      const Eigen::Vector3f wo = Direction(mu, 0.4);
      EXPECT_NEAR(SampledAlbedo(bsdf, wo)[0], 1.0, 0.01) << roughness << " " << mu;
      if (roughness >= 0.4f) {
        EXPECT_NEAR(QuadratureAlbedo(bsdf, wo, 0)[0], 1.0, 0.01) << roughness << " " << mu;
      }
    }
  }
  // A white dielectric (diffuse under a specular layer) still reflects all light: the diffuse
  // layer is coupled to the compensated layer's albedo.
  for (const float roughness : {0.3f, 0.7f, 1.0f}) {
    PrincipledParams p = Params(1, 0, roughness);
    p.multiscatter = true;
    const PrincipledBsdf bsdf(p);
    for (const float mu : {1.0f, 0.5f, 0.15f}) {
      EXPECT_NEAR(SampledAlbedo(bsdf, Direction(mu, 0))[0], 1.0, 0.01) << roughness << " " << mu;
    }
  }
  // A grey metal of F0 = 0.5 gains less, by F_avg = (20 F0 + 1) / 21 of what white metal gains:
  // E = E(F0) (1 + F_avg (1 - E1) / E1), E1 the single-scattering albedo at F = 1 (worked out by
  // hand at roughness 1 straight on: E1 = 1 - ln 2, and E(F0) by the quadrature of the single
  // scattering lobe).
  PrincipledParams single = Params(0.5f, 1, 1.0f), multi = single;
  multi.multiscatter = true;
  const Eigen::Vector3f up = Direction(1, 0);
  const double e_single = QuadratureAlbedo(PrincipledBsdf(single), up, 0)[0];
  const double e1 = 1 - std::log(2.0), favg = (20 * 0.5 + 1) / 21.0;
  EXPECT_NEAR(QuadratureAlbedo(PrincipledBsdf(multi), up, 0)[0],
              e_single * (1 + favg * (1 - e1) / e1), 0.01);
}

TEST(PrincipledBsdf, NothingReflectsMoreThanItReceives) {
  for (const float metallic : {0.0f, 0.5f, 1.0f}) {
    for (const float roughness : {0.0f, 0.2f, 0.5f, 1.0f}) {
      for (const float specular : {0.0f, 0.5f, 1.0f}) {
        PrincipledParams p = Params(1, metallic, roughness, specular);
        p.anisotropic = 0.5f;
        p.clearcoat = specular;  // with and without a coat
        p.clearcoat_roughness = roughness;
        p.multiscatter = specular == 1.0f;  // and with multiple scattering given back
        const PrincipledBsdf bsdf(p);
        for (const float mu : {0.1f, 0.5f, 1.0f}) {
          const double albedo = SampledAlbedo(bsdf, Direction(mu, 0.7), 64)[0];
          EXPECT_LE(albedo, 1.01) << metallic << " " << roughness << " " << specular << " " << mu;
        }
      }
    }
  }
}

// Albedo(wo), the light selection's estimate, is the directional albedo (the luminance of what
// it reflects of a uniform white sky, here importance-sampled) within 2 % for every mix of metal,
// dielectric layer and roughness, at grazing and normal views; within 15 % under a clear coat,
// whose second passage it takes at the view's angle for the glossy lobes (12 % off for rough
// metal seen at 78 degrees).
TEST(PrincipledBsdf, AlbedoEstimateIsTheDirectionalAlbedo) {
  for (const float metallic : {0.0f, 0.5f, 1.0f}) {
    for (const float roughness : {0.1f, 0.35f, 0.8f}) {
      for (const float coat : {0.0f, 1.0f}) {
        PrincipledParams p = Params(0.6f, metallic, roughness);
        p.base_color = {0.8f, 0.5f, 0.2f};
        p.clearcoat = coat;
        p.clearcoat_roughness = 0.1f;
        p.multiscatter = coat > 0;
        const PrincipledBsdf bsdf(p);
        for (const float mu : {0.2f, 0.6f, 1.0f}) {
          const Eigen::Vector3f wo = Direction(mu, 0.3);
          const double sampled = Luminance(SampledAlbedo(bsdf, wo).cast<float>());
          EXPECT_NEAR(bsdf.Albedo(wo), sampled, (coat > 0 ? 0.15 : 0.02) * sampled + 0.002)
              << metallic << " " << roughness << " " << coat << " " << mu;
        }
      }
    }
  }
}

TEST(PrincipledBsdf, ReciprocalAndItsDensityIsTheOneItSamplesWith) {
  std::mt19937 random(7);
  std::uniform_real_distribution<float> uniform(0, 1);
  for (int trial = 0; trial < 200; ++trial) {
    PrincipledParams p = Params(uniform(random), uniform(random), uniform(random), uniform(random));
    p.anisotropic = 0.8f * uniform(random);
    if (trial % 2 == 1) {
      p.clearcoat = uniform(random);
      p.clearcoat_roughness = uniform(random);
    }
    const PrincipledBsdf bsdf(p);
    const Eigen::Vector3f wo = Direction(0.05 + 0.95 * uniform(random), 6.28 * uniform(random));
    const Eigen::Vector3f wi = Direction(0.05 + 0.95 * uniform(random), 6.28 * uniform(random));
    EXPECT_TRUE(bsdf.Eval(wo, wi).isApprox(bsdf.Eval(wi, wo), 1e-4f)) << trial;
    const auto s =
        bsdf.Sample(wo, uniform(random), Eigen::Vector2f(uniform(random), uniform(random)));
    if (!s) continue;
    EXPECT_NEAR(s->pdf, bsdf.Pdf(wo, s->wi), 1e-4f * s->pdf) << trial;
  }
  // The density integrates to one (less what falls below the surface).
  const PrincipledBsdf bsdf(Params(0.5f, 0.3f, 0.6f));
  const Eigen::Vector3f wo = Direction(0.8, 0);
  const double total =
      Hemisphere([&](const Eigen::Vector3f& wi) { return bsdf.Pdf(wo, wi); }, 1500, 300);
  EXPECT_GT(total, 0.95);
  EXPECT_LT(total, 1.001);
}

// The SIMD evaluation (EvalLanes) against the scalar one (EvalWithPdf), lane by lane (to the bit
// on x86-64 without fused multiply-adds), for every
// material preset and random materials (coats, multiscatter, anisotropy, no specular layer), lanes
// of different materials side by side, directions above and below the surface, and a count that
// leaves the last vector part empty.
TEST(PrincipledBsdf, EvalLanesIsEvalWithPdfOnEveryPreset) {
  std::vector<PrincipledParams> materials;
  for (const std::string& name : MaterialPresetNames()) {
    Material m;
    ASSERT_TRUE(MaterialPreset(name, &m)) << name;
    materials.push_back(m.surface);
    m.surface.multiscatter = !m.surface.multiscatter;
    materials.push_back(m.surface);
  }
  std::mt19937 random(11);
  std::uniform_real_distribution<float> uniform(0, 1);
  for (int k = 0; k < 40; ++k) {
    PrincipledParams p = Params(uniform(random), uniform(random), uniform(random),
                                k % 5 == 0 ? 0.0f : uniform(random));
    p.anisotropic = k % 3 == 0 ? uniform(random) : 0.0f;
    p.clearcoat = k % 2 == 0 ? uniform(random) : 0.0f;
    p.clearcoat_roughness = uniform(random);
    p.multiscatter = k % 4 < 2;
    p.base_color = Eigen::Vector3f(uniform(random), uniform(random), uniform(random));
    materials.push_back(p);
  }
  const auto direction = [&] {
    // Mostly above, some grazing, some below the surface.
    const float mu = uniform(random) < 0.1f ? -0.5f * uniform(random) : uniform(random);
    return Direction(mu, 2 * kPi * uniform(random));
  };
  int compared = 0, nonzero = 0;
  for (int round = 0; round < 60; ++round) {
    BsdfLanes lanes;
    lanes.count = 1 + round % BsdfLanes::kMax;
    std::vector<PrincipledBsdf> bsdfs;
    std::vector<std::pair<Eigen::Vector3f, Eigen::Vector3f>> pairs;
    for (int i = 0; i < lanes.count; ++i) {
      bsdfs.emplace_back(materials[(round * 7 + i * 3) % materials.size()]);
      Eigen::Vector3f wo = direction(), wi = direction();
      if (i % 4 == 1) wi = Eigen::Vector3f(-wo.x(), -wo.y(), wo.z());  // the mirror direction
      pairs.emplace_back(wo, wi);
      bsdfs.back().ToLanes(wo, wi, &lanes, i);
    }
    EvalLanes(&lanes);
    for (int i = 0; i < lanes.count; ++i) {
      float pdf;
      const Eigen::Vector3f f = bsdfs[i].EvalWithPdf(pairs[i].first, pairs[i].second, &pdf);
      // The same operations in the same order: the same floats, unless the build may fuse
      // multiply-adds (then each side may round differently).
      const auto near = [](float a, float b) {
#if defined(__x86_64__) && !defined(__FMA__)
        return a == b || (std::isnan(a) && std::isnan(b));
#else
        return std::abs(a - b) <= 1e-5f * std::max(std::abs(a), std::abs(b)) + 1e-30f;
#endif
      };
      for (int c = 0; c < 3; ++c) {
        EXPECT_PRED2(near, lanes.f[c][i], f[c]) << "round " << round << " lane " << i;
      }
      EXPECT_PRED2(near, lanes.pdf[i], pdf) << "round " << round << " lane " << i;
      ++compared;
      nonzero += f.maxCoeff() > 0;
    }
  }
  EXPECT_GT(compared, 900);
  EXPECT_GT(nonzero, compared / 2);
}

}  // namespace
}  // namespace cadsynth
