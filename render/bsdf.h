// The surface model of the physically based mode (issue 15): the subset of Blender's Principled
// BSDF that industrial parts need, base colour, metallic, roughness, specular and anisotropy.
// Specular: anisotropic GGX (Trowbridge-Reitz) microfacets with height-correlated Smith masking
// and Schlick's Fresnel, sampled by visible normals (Heitz 2018). Diffuse: Lambert, coupled to the
// specular layer so that energy is conserved exactly (Kelemen and Szirmay-Kalos 2001): what the
// specular layer does not reflect at either direction goes to the diffuse layer,
//   f_d = (1 - metallic) base / pi * (1 - E(mu_o)) (1 - E(mu_i)) / (1 - E_avg),
// where E(mu) is the dielectric specular layer's directional albedo. So a white dielectric
// reflects all light at every angle and roughness (its white furnace test), a metal loses what
// single-scattering GGX loses at high roughness, and nothing ever reflects more than it receives.
//
// Directions are unit vectors in the local shading frame: normal +z, tangent +x (where
// anisotropic highlights stretch: Material::tangent). All colours are linear RGB.
#pragma once

#include <cstdint>
#include <optional>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "cad/core/schema.h"

namespace cadsynth {

struct PrincipledParams {
  Eigen::Vector3f base_color = Eigen::Vector3f::Constant(0.8f);  // linear RGB in [0, 1]
  float metallic = 0.0f;                                         // [0, 1]
  float roughness = 0.5f;  // [0, 1], perceptual: GGX alpha = roughness^2 (as Blender)
  float specular = 0.5f;   // [0, 1]: dielectric F0 = 0.08 specular (0.5: IOR 1.5); 0: no layer
  // [0, 1]: longer highlights along the tangent (brushed metal); alpha_x = alpha / a,
  // alpha_y = alpha a with a = sqrt(1 - 0.9 anisotropic), as Blender's.
  float anisotropic = 0.0f;
  // A clear coat over everything (paint, lacquer): weight [0, 1] and its own roughness, a GGX
  // dielectric of IOR 1.5 (Blender's Coat Weight and Coat Roughness, default 0.03).
  float clearcoat = 0.0f;
  float clearcoat_roughness = 0.03f;
  // Blender's Multiscatter GGX (its default distribution; false: GGX): the light single
  // scattering loses between microfacets is given back by scaling each specular lobe (metal and
  // dielectric; not the coat) by 1 + F_avg (1 - E(mu_o)) / E(mu_o) (Turquin 2019, as Cycles 4),
  // E the lobe's albedo with F = 1 and F_avg Schlick's cosine-weighted mean, (20 F0 + 1) / 21. A
  // white metal then reflects all light at every roughness; the diffuse layer is coupled to the
  // compensated albedo, so a white dielectric still does. Like Cycles', the scale depends on the
  // viewing direction only: f(wo, wi) is no longer reciprocal.
  bool multiscatter = false;

  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    // base_color: cad (the part's colour) is Material::base_from_part's: read by hand.
    visit(o.base_color,
          Field{.key = "base_color",
                .kind = "linear_color",
                .doc = "linear [r, g, b], sRGB \"#RRGGBB\", or cad (the part's own colour)",
                .by_hand = true});
    visit(o.metallic, UnitNumber("metallic", "0 (dielectric) to 1 (metal)"));
    visit(o.roughness, UnitNumber("roughness", "microfacet roughness (0-1)"));
    visit(o.specular, UnitNumber("specular", "dielectric specular level (0-1; 0.5 is IOR 1.5)"));
    visit(o.anisotropic,
          UnitNumber("anisotropic", "stretch of highlights along the tangent (0-1)"));
    visit(o.clearcoat, UnitNumber("clearcoat", "a clear coat's weight (0-1)"));
    visit(o.clearcoat_roughness,
          UnitNumber("clearcoat_roughness", "the clear coat's roughness (0-1)"));
    visit(o.multiscatter, Field{"distribution",
                                "choice",
                                "Blender's microfacet distribution",
                                {"ggx", "multiscatter_ggx"}});
  }
};

struct BsdfLanes;

class PrincipledBsdf {
 public:
  // min_alpha: the GGX alphas of the specular lobe and the clear coat are at least this (Cycles'
  // bsdf_blur, for Filter Glossy; 0: the material's own).
  explicit PrincipledBsdf(const PrincipledParams& params, float min_alpha = 0.0f);

  // f(wo, wi) in 1/sr (no cosine); zero unless both directions are above the surface.
  Eigen::Vector3f Eval(const Eigen::Vector3f& wo, const Eigen::Vector3f& wi) const;
  // The density (1/sr) with which Sample picks wi for wo.
  float Pdf(const Eigen::Vector3f& wo, const Eigen::Vector3f& wi) const;
  // Both at once (they share the half vector and the microfacet terms).
  Eigen::Vector3f EvalWithPdf(const Eigen::Vector3f& wo, const Eigen::Vector3f& wi,
                              float* pdf) const;

  struct Sampled {
    Eigen::Vector3f wi;
    Eigen::Vector3f weight;  // f(wo, wi) cos(wi) / pdf
    float pdf = 0;
  };
  // A direction for wo from three uniform numbers in [0, 1): u_lobe chooses diffuse or specular
  // (in proportion to their expected reflectance), u the direction. Nothing below the surface.
  // The path tracer does the same in two steps (SampleDirection, then EvalLanes for the whole
  // packet); this one-step form is what the tests integrate the sampler's weights with.
  std::optional<Sampled> Sample(const Eigen::Vector3f& wo, float u_lobe,
                                const Eigen::Vector2f& u) const;
  // Sample's direction alone (wi.z > 0), for a caller that evaluates it later (in EvalLanes):
  // Sample is this, then EvalWithPdf, refused where the density is not positive. `glossy`, if
  // given, tells whether a glossy lobe (the specular layer or the coat) drew it rather than the
  // diffuse one: Blender's glossy and diffuse bounces.
  std::optional<Eigen::Vector3f> SampleDirection(const Eigen::Vector3f& wo, float u_lobe,
                                                 const Eigen::Vector2f& u,
                                                 bool* glossy = nullptr) const;
  // The same from one pair, as Cycles picks a closure: u.x chooses the lobe, then, rescaled into
  // that lobe's share of [0, 1), is the lobe's own first coordinate. Each lobe's directions then
  // keep the pair's stratification, where a separate u_lobe would hand each lobe a random subset
  // of a stratified sequence's points (what the path tracer uses).
  std::optional<Eigen::Vector3f> SampleDirection(const Eigen::Vector3f& wo,
                                                 const Eigen::Vector2f& u,
                                                 bool* glossy = nullptr) const;
  // Writes the pair (wo, wi) and what this BSDF's evaluation needs at wo into lane i of `lanes`.
  void ToLanes(const Eigen::Vector3f& wo, const Eigen::Vector3f& wi, BsdfLanes* lanes, int i) const;

  float alpha_x() const { return alpha_x_; }
  float alpha_y() const { return alpha_y_; }
  // An estimate of the directional albedo at wo (luminance: the share of light from every
  // direction that leaves towards wo), from the lobes' tabulated albedos; what the light
  // selection weighs a surface's reflectance by, never part of an estimate.
  float Albedo(const Eigen::Vector3f& wo) const;
  // Whether a glossy lobe dominates what it reflects (metal, or a clear coat), so that where the
  // light comes from matters more than how much arrives.
  bool Glossy() const { return params_.metallic > 0 || coat_ > 0; }

 private:
  // What depends only on the outgoing direction, computed once per direction (a shading point
  // asks for it several times: sampling, evaluation and density).
  struct ViewTerms {
    Eigen::Vector3f wo = Eigen::Vector3f::Zero();
    float lambda_o = 0;       // Smith's Lambda(wo)
    float e_dielectric = 0;   // the dielectric layer's directional albedo E(mu_o)
    float missing = 0;        // multiscatter: (1 - E1(mu_o)) / E1(mu_o), E1 the albedo at F = 1
    float p_specular = 0;     // probability of sampling the specular lobe (of the base)
    float lambda_coat_o = 0;  // the coat's Lambda(wo)
    float e_coat = 0;         // the coat's weight times its directional albedo at wo
    float p_coat = 0;         // probability of sampling the coat
    float albedo = 0;         // Albedo(wo)
  };
  const ViewTerms& View(const Eigen::Vector3f& wo) const;
  enum class Lobe { kCoat, kSpecular, kDiffuse };
  // The lobe u in [0, 1) picks at wo (in proportion to view's probabilities), and u rescaled into
  // that lobe's share of [0, 1) (uniform again, for the lobe's own sampling).
  static Lobe PickLobe(const ViewTerms& view, float u, float* rescaled);
  std::optional<Eigen::Vector3f> SampleLobe(const Eigen::Vector3f& wo, Lobe lobe,
                                            const Eigen::Vector2f& u, bool* glossy) const;
  // The diffuse layer's share: (1 - E(mu_o)) (1 - E(mu_i)) / (1 - E_avg), 1 without a layer.
  float DiffuseScale(const ViewTerms& view, float mu_i) const;
  // The dielectric layer's directional albedo at mu from the table's A and B there (compensated
  // for multiple scattering when asked).
  float DielectricAlbedo(float a, float b) const;

  PrincipledParams params_;
  float alpha_x_, alpha_y_;
  float r_;  // the isotropic roughness equivalent, (alpha_x alpha_y)^(1/4)
  mutable ViewTerms view_;
  float dielectric_f0_;  // 0.08 specular; specular 0: no dielectric layer at all (pure Lambert)
  float e_avg_;          // cosine-weighted average of the dielectric layer's albedo E(mu)
  float dielectric_favg_ = 0;  // multiscatter: Schlick's mean Fresnel of the dielectric layer
  Eigen::Vector3f metal_favg_ = Eigen::Vector3f::Zero();  // and of the metal, per channel
  float coat_ = 0, coat_r_ = 0, coat_alpha_ = 1;          // clear coat weight, roughness and alpha
  float coat_avg_ = 0;  // the coat's weight times the cosine-weighted mean of its albedo
  float CoatAlbedo(float mu) const;  // the coat's directional albedo (F0 0.04)
};

// Many evaluations at once, structure of arrays (issue 44, item 3): the path tracer gathers every
// lane of a packet that needs its BSDF evaluated (the light sample's direction and the BSDF
// sample's) and evaluates them four at a time in SIMD, lanes of different materials side by
// side. Lane i holds one pair (wo, wi) and its BSDF's constants (PrincipledBsdf::ToLanes);
// EvalLanes gives each lane what EvalWithPdf gives its pair, by the same operations in the same
// order (so the same floats, unless a build contracts the two differently into fused multiply-
// adds). EvalWithPdf stays the reference: tests check the two against each other.
struct BsdfLanes {
  static constexpr int kMax = 32;  // two per lane of a packet; a multiple of the vector width, 4
  int count = 0;
  // The pair, local shading frame.
  alignas(32) float wo[3][kMax];
  alignas(32) float wi[3][kMax];
  // The BSDF's constants.
  alignas(32) float base[3][kMax];        // base colour
  alignas(32) float metal_favg[3][kMax];  // multiscatter: the metal's mean Fresnel
  alignas(32) float metallic[kMax], alpha_x[kMax], alpha_y[kMax];
  alignas(32) float r[kMax];             // isotropic roughness equivalent (the tables' row)
  alignas(32) float f0[kMax];            // the dielectric layer's F0
  alignas(32) float diffuse_norm[kMax];  // max(1e-6, 1 - E_avg)
  alignas(32) float dielectric_favg[kMax];
  alignas(32) float coat[kMax], coat_r[kMax], coat_alpha[kMax];
  alignas(32) int32_t has_specular[kMax];  // -1 where specular > 0 (a dielectric layer), else 0
  alignas(32) int32_t multiscatter[kMax];  // -1 or 0
  // Its terms at wo (PrincipledBsdf's ViewTerms).
  alignas(32) float lambda_o[kMax], e_dielectric[kMax], missing[kMax], p_specular[kMax];
  alignas(32) float lambda_coat_o[kMax], e_coat[kMax], p_coat[kMax];
  // Out: f(wo, wi) (1/sr) and the density Sample picks wi with; zero unless both are above.
  alignas(32) float f[3][kMax];
  alignas(32) float pdf[kMax];
};
void EvalLanes(BsdfLanes* lanes);

// The GGX pieces, exposed for tests: the distribution of normals D(m) (1/sr), Smith's Lambda(w)
// and the masking G1(w) = 1 / (1 + Lambda(w)).
float GgxD(const Eigen::Vector3f& m, float alpha_x, float alpha_y);
float GgxLambda(const Eigen::Vector3f& w, float alpha_x, float alpha_y);

// Directional albedo of a GGX layer with Schlick Fresnel of reflectance F0 at normal incidence,
// E(mu; alpha, F0) = F0 A(mu, alpha) + B(mu, alpha) (Schlick's Fresnel is linear in F0); A and B
// come from a table integrated once (32 x 32, interpolated). Isotropic alpha.
float GgxAlbedo(float mu, float alpha, float f0);

}  // namespace cadsynth
