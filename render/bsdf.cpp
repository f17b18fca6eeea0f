#include "render/bsdf.h"
#include "render/image.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>

#if defined(__SSE__)
#include <xmmintrin.h>
#endif

namespace cadsynth {

namespace {

constexpr float kPi = 3.14159265358979323846f;
constexpr float kMinAlpha = 1e-4f;  // roughness 0: a mirror to the eye, still a finite lobe
constexpr float kCoatF0 = 0.04f;    // the clear coat: a dielectric of IOR 1.5

float Pow5(float x) {
  const float x2 = x * x;
  return x2 * x2 * x;
}

// A microfacet normal seen from wo, distributed as D_wo(m) = G1(wo) max(0, wo.m) D(m) / wo.z
// (Heitz 2018, "Sampling the GGX distribution of visible normals").
Eigen::Vector3f SampleVisibleNormal(const Eigen::Vector3f& wo, float ax, float ay,
                                    const Eigen::Vector2f& u) {
  const Eigen::Vector3f vh = Eigen::Vector3f(ax * wo.x(), ay * wo.y(), wo.z()).normalized();
  const float lensq = vh.x() * vh.x() + vh.y() * vh.y();
  const Eigen::Vector3f t1 =
      lensq > 0 ? Eigen::Vector3f(-vh.y(), vh.x(), 0) / std::sqrt(lensq) : Eigen::Vector3f(1, 0, 0);
  const Eigen::Vector3f t2 = vh.cross(t1);
  const float r = std::sqrt(u.x());
  const float phi = 2 * kPi * u.y();
  const float p1 = r * std::cos(phi);
  float p2 = r * std::sin(phi);
  const float s = 0.5f * (1 + vh.z());
  p2 = (1 - s) * std::sqrt(std::max(0.0f, 1 - p1 * p1)) + s * p2;
  const Eigen::Vector3f nh =
      p1 * t1 + p2 * t2 + std::sqrt(std::max(0.0f, 1 - p1 * p1 - p2 * p2)) * vh;
  return Eigen::Vector3f(ax * nh.x(), ay * nh.y(), std::max(1e-7f, nh.z())).normalized();
}

Eigen::Vector3f Reflect(const Eigen::Vector3f& w, const Eigen::Vector3f& m) {
  return 2 * w.dot(m) * m - w;
}

// The albedo table: E(mu, alpha; F0) = F0 A + B, over mu in [0, 1] and roughness sqrt(alpha) in
// [0, 1], from 64 x 24 visible normals per cell, E = mean of G2/G1 * F(wo.m).
constexpr int kTable = 32;
struct AlbedoTable {
  std::array<float, kTable * kTable> a{}, b{};
  std::array<float, kTable> a_avg{}, b_avg{};  // 2 * integral of A(mu) mu over mu, per roughness
  // 2 * integral of A(mu) M(mu) mu and of B(mu) M(mu) mu, M = (1 - E1) / E1 and E1 = A + B (the
  // multiscatter compensation's share, which multiplies the layer's albedo by 1 + F_avg M).
  std::array<float, kTable> am_avg{}, bm_avg{};
};

const AlbedoTable& Table() {
  static const AlbedoTable table = [] {
    AlbedoTable t;
    constexpr int kStrataT = 64, kStrataV = 24;
    for (int r = 0; r < kTable; ++r) {
      const float roughness = static_cast<float>(r) / (kTable - 1);
      const float alpha = std::max(kMinAlpha, roughness * roughness);
      for (int j = 0; j < kTable; ++j) {
        const float mu = std::max(1e-3f, static_cast<float>(j) / (kTable - 1));
        const Eigen::Vector3f wo(std::sqrt(1 - mu * mu), 0, mu);
        // Midpoints in (t, v) with u.x = 1 - (1 - t)^2: the samples crowd where u.x nears 1,
        // the steep microfacets whose reflections graze the surface (the lossy tail).
        double a = 0, b = 0;
        for (int k = 0; k < kStrataT * kStrataV; ++k) {
          const double tt = (k % kStrataT + 0.5) / kStrataT;
          const double v = (static_cast<double>(k / kStrataT) + 0.5) / kStrataV;
          const double jacobian = 2 * (1 - tt);
          const Eigen::Vector2f u(static_cast<float>(1 - (1 - tt) * (1 - tt)),
                                  static_cast<float>(v));
          const Eigen::Vector3f m = SampleVisibleNormal(wo, alpha, alpha, u);
          const Eigen::Vector3f wi = Reflect(wo, m);
          if (wi.z() <= 0) continue;
          const float lo = GgxLambda(wo, alpha, alpha), li = GgxLambda(wi, alpha, alpha);
          const double weight = jacobian * (1 + lo) / (1 + lo + li);  // G2 / G1
          const double c5 = Pow5(1 - std::clamp(wo.dot(m), 0.0f, 1.0f));
          a += weight * (1 - c5);
          b += weight * c5;
        }
        t.a[r * kTable + j] = static_cast<float>(a / (kStrataT * kStrataV));
        t.b[r * kTable + j] = static_cast<float>(b / (kStrataT * kStrataV));
      }
      // Cosine-weighted averages by the trapezoid rule on the mu grid.
      const auto missing = [&](int j) {
        const double e1 = static_cast<double>(t.a[r * kTable + j]) + t.b[r * kTable + j];
        return (1 - e1) / std::max(e1, 1e-6);
      };
      double a_avg = 0, b_avg = 0, am_avg = 0, bm_avg = 0;
      for (int j = 0; j + 1 < kTable; ++j) {
        const double m0 = static_cast<double>(j) / (kTable - 1), m1 = (j + 1.0) / (kTable - 1);
        const double a0 = t.a[r * kTable + j], a1 = t.a[r * kTable + j + 1];
        const double b0 = t.b[r * kTable + j], b1 = t.b[r * kTable + j + 1];
        a_avg += (a0 * m0 + a1 * m1) * (m1 - m0);
        b_avg += (b0 * m0 + b1 * m1) * (m1 - m0);
        am_avg += (a0 * missing(j) * m0 + a1 * missing(j + 1) * m1) * (m1 - m0);
        bm_avg += (b0 * missing(j) * m0 + b1 * missing(j + 1) * m1) * (m1 - m0);
      }
      t.a_avg[r] = static_cast<float>(a_avg);  // 2 * integral with the trapezoid's 1/2
      t.b_avg[r] = static_cast<float>(b_avg);
      t.am_avg[r] = static_cast<float>(am_avg);
      t.bm_avg[r] = static_cast<float>(bm_avg);
    }
    return t;
  }();
  return table;
}

// Bilinear lookup of a table over (roughness, mu).
float Lookup(const std::array<float, kTable * kTable>& table, float roughness, float mu) {
  const float x = std::clamp(mu, 0.0f, 1.0f) * (kTable - 1);
  const float y = std::clamp(roughness, 0.0f, 1.0f) * (kTable - 1);
  const int x0 = std::min(static_cast<int>(x), kTable - 2),
            y0 = std::min(static_cast<int>(y), kTable - 2);
  const float fx = x - x0, fy = y - y0;
  const auto at = [&](int yy, int xx) { return table[yy * kTable + xx]; };
  return (1 - fy) * ((1 - fx) * at(y0, x0) + fx * at(y0, x0 + 1)) +
         fy * ((1 - fx) * at(y0 + 1, x0) + fx * at(y0 + 1, x0 + 1));
}

float LookupAverage(const std::array<float, kTable>& table, float roughness) {
  const float y = std::clamp(roughness, 0.0f, 1.0f) * (kTable - 1);
  const int y0 = std::min(static_cast<int>(y), kTable - 2);
  const float fy = y - y0;
  return (1 - fy) * table[y0] + fy * table[y0 + 1];
}

}  // namespace

float GgxD(const Eigen::Vector3f& m, float ax, float ay) {
  if (m.z() <= 0) return 0;
  const float e = m.x() * m.x() / (ax * ax) + m.y() * m.y() / (ay * ay) + m.z() * m.z();
  return 1 / (kPi * ax * ay * e * e);
}

float GgxLambda(const Eigen::Vector3f& w, float ax, float ay) {
  const float z2 = w.z() * w.z();
  if (z2 <= 0) return 1e30f;
  const float t = (ax * ax * w.x() * w.x() + ay * ay * w.y() * w.y()) / z2;
  return 0.5f * (std::sqrt(1 + t) - 1);
}

float GgxAlbedo(float mu, float alpha, float f0) {
  const float roughness = std::sqrt(std::max(alpha, 0.0f));
  const AlbedoTable& t = Table();
  return f0 * Lookup(t.a, roughness, mu) + Lookup(t.b, roughness, mu);
}

PrincipledBsdf::PrincipledBsdf(const PrincipledParams& params, float min_alpha) : params_(params) {
  const float alpha = params.roughness * params.roughness;
  const float aspect = std::sqrt(1 - 0.9f * std::clamp(params.anisotropic, 0.0f, 1.0f));
  alpha_x_ = std::max(std::max(kMinAlpha, min_alpha), alpha / aspect);
  alpha_y_ = std::max(std::max(kMinAlpha, min_alpha), alpha * aspect);
  dielectric_f0_ = 0.08f * params.specular;
  const AlbedoTable& t = Table();
  r_ = std::sqrt(std::sqrt(alpha_x_ * alpha_y_));  // isotropic equivalent
  e_avg_ = dielectric_f0_ * LookupAverage(t.a_avg, r_) + LookupAverage(t.b_avg, r_);
  if (params.multiscatter) {
    // Schlick's F = F0 + (1 - F0) (1 - mu)^5 has the cosine-weighted mean F0 + (1 - F0) / 21.
    dielectric_favg_ = (20 * dielectric_f0_ + 1) / 21;
    metal_favg_ = (20 * params.base_color + Eigen::Vector3f::Ones()) / 21;
    // The compensated layer's albedo (F0 A + B)(1 + F_avg M), averaged over mu like E itself.
    e_avg_ += dielectric_favg_ *
              (dielectric_f0_ * LookupAverage(t.am_avg, r_) + LookupAverage(t.bm_avg, r_));
  }
  coat_ = std::clamp(params.clearcoat, 0.0f, 1.0f);
  coat_r_ = std::clamp(params.clearcoat_roughness, 0.0f, 1.0f);
  coat_alpha_ = std::max(kMinAlpha, coat_r_ * coat_r_);
  if (min_alpha > coat_alpha_) {
    coat_alpha_ = min_alpha;
    coat_r_ = std::sqrt(min_alpha);  // the tables' roughness
  }
  if (coat_ > 0)
    coat_avg_ =
        coat_ * (kCoatF0 * LookupAverage(t.a_avg, coat_r_) + LookupAverage(t.b_avg, coat_r_));
}

float PrincipledBsdf::CoatAlbedo(float mu) const {
  const AlbedoTable& t = Table();
  return kCoatF0 * Lookup(t.a, coat_r_, mu) + Lookup(t.b, coat_r_, mu);
}

float PrincipledBsdf::DielectricAlbedo(float a, float b) const {
  if (params_.specular <= 0) return 0;
  const float e = dielectric_f0_ * a + b;
  if (!params_.multiscatter) return e;
  const float e1 = a + b;
  return e * (1 + dielectric_favg_ * (1 - e1) / std::max(e1, 1e-6f));
}

const PrincipledBsdf::ViewTerms& PrincipledBsdf::View(const Eigen::Vector3f& wo) const {
  if (wo == view_.wo) return view_;
  view_.wo = wo;
  const float mu_o = wo.z();
  view_.lambda_o = GgxLambda(wo, alpha_x_, alpha_y_);
  const AlbedoTable& t = Table();
  const float a = Lookup(t.a, r_, mu_o), b = Lookup(t.b, r_, mu_o);
  view_.missing = params_.multiscatter ? (1 - (a + b)) / std::max(a + b, 1e-6f) : 0.0f;
  const float e_dielectric = DielectricAlbedo(a, b);
  view_.e_dielectric = e_dielectric;
  // The metal's albedo (by its luminance), compensated when asked.
  const float metal_albedo =
      (Luminance(params_.base_color) * a + b) * (1 + Luminance(metal_favg_) * view_.missing);
  if (params_.specular <= 0 && params_.metallic <= 0) {
    view_.p_specular = 0;
  } else if (params_.metallic >= 1) {
    view_.p_specular = 1;
  } else {
    const float m = params_.metallic;
    const float specular = m * metal_albedo + (1 - m) * e_dielectric;
    const float diffuse = (1 - m) * Luminance(params_.base_color) * (1 - e_dielectric);
    view_.p_specular =
        specular + diffuse <= 0 ? 0.5f : std::clamp(specular / (specular + diffuse), 0.1f, 0.9f);
  }
  // What the base reflects: the metal, or the dielectric layer and the diffuse light under it.
  const float m = params_.metallic;
  const float glossy = m * metal_albedo + (1 - m) * e_dielectric;
  const float diffuse = (1 - m) * Luminance(params_.base_color) * (1 - e_dielectric);
  const float base = glossy + diffuse;
  view_.albedo = base;
  view_.p_coat = 0;
  if (coat_ > 0) {
    view_.lambda_coat_o = GgxLambda(wo, coat_alpha_, coat_alpha_);
    view_.e_coat = coat_ * CoatAlbedo(mu_o);
    // The coat's share of what is reflected, against an estimate of what the base reflects.
    const float under = (1 - view_.e_coat) * base;
    view_.p_coat = std::clamp(view_.e_coat / std::max(1e-6f, view_.e_coat + under), 0.05f, 0.95f);
    // What the base reflects has passed the coat on its way in too, (1 - c E_c(mu_i)): about at
    // mu_o for its glossy lobe, and the cosine-weighted mean over the hemisphere for its diffuse.
    view_.albedo = view_.e_coat +
                   (1 - view_.e_coat) * (glossy * (1 - view_.e_coat) + diffuse * (1 - coat_avg_));
  }
  return view_;
}

float PrincipledBsdf::Albedo(const Eigen::Vector3f& wo) const {
  return wo.z() > 0 ? View(wo).albedo : 0.0f;
}

float PrincipledBsdf::DiffuseScale(const ViewTerms& view, float mu_i) const {
  if (params_.specular <= 0) return 1;  // no dielectric layer above the diffuse one
  const AlbedoTable& t = Table();
  const float e_i = DielectricAlbedo(Lookup(t.a, r_, mu_i), Lookup(t.b, r_, mu_i));
  return (1 - view.e_dielectric) * (1 - e_i) / std::max(1e-6f, 1 - e_avg_);
}

Eigen::Vector3f PrincipledBsdf::EvalWithPdf(const Eigen::Vector3f& wo, const Eigen::Vector3f& wi,
                                            float* pdf) const {
  *pdf = 0;
  if (wo.z() <= 0 || wi.z() <= 0) return Eigen::Vector3f::Zero();
  const ViewTerms& view = View(wo);
  Eigen::Vector3f f = Eigen::Vector3f::Zero();
  float specular_pdf = 0;
  if (view.p_specular > 0) {
    const Eigen::Vector3f h = (wo + wi).normalized();
    const float d = GgxD(h, alpha_x_, alpha_y_);
    const float o_h = wo.dot(h);
    const float g2 = 1 / (1 + view.lambda_o + GgxLambda(wi, alpha_x_, alpha_y_));
    const float c5 = Pow5(1 - std::clamp(o_h, 0.0f, 1.0f));
    // Schlick's Fresnel of the metal and, when there is one, of the dielectric layer.
    const float m = params_.metallic;
    Eigen::Vector3f metal =
        params_.base_color + (Eigen::Vector3f::Ones() - params_.base_color) * c5;
    float dielectric = params_.specular > 0 ? dielectric_f0_ + (1 - dielectric_f0_) * c5 : 0;
    if (params_.multiscatter) {  // what single scattering loses, given back along the same lobe
      metal = metal.cwiseProduct(Eigen::Vector3f::Ones() + metal_favg_ * view.missing);
      dielectric *= 1 + dielectric_favg_ * view.missing;
    }
    f = (m * metal + Eigen::Vector3f::Constant((1 - m) * dielectric)) *
        (d * g2 / (4 * wo.z() * wi.z()));
    // Visible normals, D_wo(h) = G1(wo) (wo.h) D(h) / wo.z, reflected: / (4 wo.h).
    if (o_h > 0) specular_pdf = d / ((1 + view.lambda_o) * 4 * wo.z());
  }
  if (params_.metallic < 1) {
    f += (1 - params_.metallic) * params_.base_color * (DiffuseScale(view, wi.z()) / kPi);
  }
  *pdf = view.p_specular * specular_pdf + (1 - view.p_specular) * wi.z() / kPi;
  if (coat_ > 0) {
    // The clear coat on top: a GGX dielectric layer of F0 0.04 (IOR 1.5) and weight c; what it
    // does not reflect at either direction reaches the base, so the sum never exceeds the base's
    // energy: c E_c(mu_o) + (1 - c E_c(mu_o)) * (at most 1).
    const float e_coat_i = coat_ * CoatAlbedo(wi.z());
    f *= (1 - view.e_coat) * (1 - e_coat_i);
    const Eigen::Vector3f h = (wo + wi).normalized();
    const float d = GgxD(h, coat_alpha_, coat_alpha_);
    const float g2 = 1 / (1 + view.lambda_coat_o + GgxLambda(wi, coat_alpha_, coat_alpha_));
    const float fresnel = kCoatF0 + (1 - kCoatF0) * Pow5(1 - std::clamp(wo.dot(h), 0.0f, 1.0f));
    f += Eigen::Vector3f::Constant(coat_ * fresnel * d * g2 / (4 * wo.z() * wi.z()));
    const float coat_pdf = wo.dot(h) > 0 ? d / ((1 + view.lambda_coat_o) * 4 * wo.z()) : 0;
    *pdf = view.p_coat * coat_pdf + (1 - view.p_coat) * *pdf;
  }
  return f;
}

Eigen::Vector3f PrincipledBsdf::Eval(const Eigen::Vector3f& wo, const Eigen::Vector3f& wi) const {
  float pdf;
  return EvalWithPdf(wo, wi, &pdf);
}

float PrincipledBsdf::Pdf(const Eigen::Vector3f& wo, const Eigen::Vector3f& wi) const {
  float pdf;
  EvalWithPdf(wo, wi, &pdf);
  return pdf;
}

std::optional<Eigen::Vector3f> PrincipledBsdf::SampleDirection(const Eigen::Vector3f& wo,
                                                               float u_lobe,
                                                               const Eigen::Vector2f& u,
                                                               bool* glossy) const {
  if (wo.z() <= 0) return std::nullopt;
  const ViewTerms& view = View(wo);
  float unused;
  return SampleLobe(wo, PickLobe(view, u_lobe, &unused), u, glossy);
}

std::optional<Eigen::Vector3f> PrincipledBsdf::SampleDirection(const Eigen::Vector3f& wo,
                                                               const Eigen::Vector2f& u,
                                                               bool* glossy) const {
  if (wo.z() <= 0) return std::nullopt;
  const ViewTerms& view = View(wo);
  float x;
  const Lobe lobe = PickLobe(view, u.x(), &x);
  return SampleLobe(wo, lobe, Eigen::Vector2f(x, u.y()), glossy);
}

PrincipledBsdf::Lobe PrincipledBsdf::PickLobe(const ViewTerms& view, float u, float* rescaled) {
  // The lobes' shares of [0, 1): the coat's p_coat, then of the rest the specular layer's
  // p_specular, then the diffuse one's. The rescaled number stays below 1 (floats round).
  const auto within = [](float v) { return std::min(std::max(v, 0.0f), 0x1.fffffep-1f); };
  if (u < view.p_coat) {
    *rescaled = within(u / view.p_coat);
    return Lobe::kCoat;
  }
  const float rest = (u - view.p_coat) / (1 - view.p_coat);
  if (rest < view.p_specular) {
    *rescaled = within(rest / view.p_specular);
    return Lobe::kSpecular;
  }
  *rescaled = within((rest - view.p_specular) / (1 - view.p_specular));
  return Lobe::kDiffuse;
}

std::optional<Eigen::Vector3f> PrincipledBsdf::SampleLobe(const Eigen::Vector3f& wo, Lobe lobe,
                                                          const Eigen::Vector2f& u,
                                                          bool* glossy) const {
  Eigen::Vector3f wi;
  if (lobe == Lobe::kCoat) {
    wi = Reflect(wo, SampleVisibleNormal(wo, coat_alpha_, coat_alpha_, u));
  } else if (lobe == Lobe::kSpecular) {
    wi = Reflect(wo, SampleVisibleNormal(wo, alpha_x_, alpha_y_, u));
  } else {  // cosine-weighted
    const float r = std::sqrt(u.x()), phi = 2 * kPi * u.y();
    wi =
        Eigen::Vector3f(r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0f, 1 - u.x())));
  }
  if (wi.z() <= 0) return std::nullopt;
  if (glossy) *glossy = lobe != Lobe::kDiffuse;
  return wi;
}

std::optional<PrincipledBsdf::Sampled> PrincipledBsdf::Sample(const Eigen::Vector3f& wo,
                                                              float u_lobe,
                                                              const Eigen::Vector2f& u) const {
  const std::optional<Eigen::Vector3f> wi = SampleDirection(wo, u_lobe, u);
  if (!wi) return std::nullopt;
  Sampled s;
  s.wi = *wi;
  const Eigen::Vector3f f = EvalWithPdf(wo, s.wi, &s.pdf);
  if (!(s.pdf > 0)) return std::nullopt;
  s.weight = f * (s.wi.z() / s.pdf);
  return s;
}

void PrincipledBsdf::ToLanes(const Eigen::Vector3f& wo, const Eigen::Vector3f& wi, BsdfLanes* lanes,
                             int i) const {
  BsdfLanes& l = *lanes;
  const ViewTerms& view = View(wo);
  for (int c = 0; c < 3; ++c) {
    l.wo[c][i] = wo[c];
    l.wi[c][i] = wi[c];
    l.base[c][i] = params_.base_color[c];
    l.metal_favg[c][i] = metal_favg_[c];
  }
  l.metallic[i] = params_.metallic;
  l.alpha_x[i] = alpha_x_;
  l.alpha_y[i] = alpha_y_;
  l.r[i] = r_;
  l.f0[i] = dielectric_f0_;
  l.diffuse_norm[i] = std::max(1e-6f, 1 - e_avg_);
  l.dielectric_favg[i] = dielectric_favg_;
  l.coat[i] = coat_;
  l.coat_r[i] = coat_r_;
  l.coat_alpha[i] = coat_alpha_;
  l.has_specular[i] = params_.specular > 0 ? -1 : 0;
  l.multiscatter[i] = params_.multiscatter ? -1 : 0;
  l.lambda_o[i] = view.lambda_o;
  l.e_dielectric[i] = view.e_dielectric;
  l.missing[i] = view.missing;
  l.p_specular[i] = view.p_specular;
  l.lambda_coat_o[i] = view.lambda_coat_o;
  l.e_coat[i] = view.e_coat;
  l.p_coat[i] = view.p_coat;
}

namespace {

// kWidth lanes of EvalWithPdf at a time (GCC's vector extension, which clang shares). Every
// helper is its scalar twin's operations in its order, std::max and std::clamp's comparisons
// included.
constexpr int kWidth = 4;
typedef float FV __attribute__((vector_size(4 * kWidth)));
typedef int32_t IV __attribute__((vector_size(4 * kWidth)));

FV Load(const float* p) {
  FV v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
IV LoadMask(const int32_t* p) {
  IV v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
void Store(float* p, FV v) { std::memcpy(p, &v, sizeof v); }
FV Splat(float x) { return FV{} + x; }
FV Select(IV mask, FV a, FV b) {
  // (A cast between vector types of one size keeps the bits.)
  return (FV)((mask & (IV)a) | (~mask & (IV)b));
}
FV Max(FV a, FV b) { return Select(a < b, b, a); }  // std::max(a, b)
FV Clamp01(FV v) { return Select(v < Splat(0), Splat(0), Select(Splat(1) < v, Splat(1), v)); }
FV Sqrt(FV v) {
#if defined(__SSE__)
  __m128 quarter[kWidth / 4];
  std::memcpy(quarter, &v, sizeof v);
  for (__m128& q : quarter) q = _mm_sqrt_ps(q);
  std::memcpy(&v, quarter, sizeof v);
  return v;
#else
  for (int i = 0; i < kWidth; ++i) v[i] = std::sqrt(v[i]);
  return v;
#endif
}
FV Pow5(FV x) {
  const FV x2 = x * x;
  return x2 * x2 * x;
}

struct V3 {
  FV x, y, z;
};
// Eigen's dot and squaredNorm of three: a0 + (a1 + a2).
FV Dot(const V3& a, const V3& b) { return a.x * b.x + (a.y * b.y + a.z * b.z); }
V3 Normalized(const V3& v) {  // Eigen's normalized(): unchanged when the norm is not positive
  const FV n2 = Dot(v, v);
  const IV positive = n2 > Splat(0);
  const FV n = Sqrt(n2);
  return {Select(positive, v.x / n, v.x), Select(positive, v.y / n, v.y),
          Select(positive, v.z / n, v.z)};
}
FV D(const V3& m, FV ax, FV ay) {
  const FV e = m.x * m.x / (ax * ax) + m.y * m.y / (ay * ay) + m.z * m.z;
  return Select(m.z <= Splat(0), Splat(0), 1 / (kPi * ax * ay * e * e));
}
FV Lambda(const V3& w, FV ax, FV ay) {
  const FV z2 = w.z * w.z;
  const FV t = (ax * ax * w.x * w.x + ay * ay * w.y * w.y) / z2;
  return Select(z2 <= Splat(0), Splat(1e30f), 0.5f * (Sqrt(1 + t) - 1));
}
// Lookup() of two tables at the same (roughness, mu). The indices are also clamped to the table
// where the conversion gives INT_MIN (x86's answer for a NaN mu, where Lookup would read
// outside the table).
void Lookup2(const std::array<float, kTable * kTable>& ta,
             const std::array<float, kTable * kTable>& tb, FV roughness, FV mu, FV* a, FV* b) {
  constexpr float kLast = kTable - 1;
  const FV x = Clamp01(mu) * kLast;
  const FV y = Clamp01(roughness) * kLast;
  IV x0 = __builtin_convertvector(x, IV), y0 = __builtin_convertvector(y, IV);
  const IV top = IV{} + (kTable - 2), zero = IV{};
  const auto clamp = [&](IV v) {
    const IV below = top < v;  // std::min(v, top), then at least 0
    v = (below & top) | (~below & v);
    const IV negative = v < zero;
    return ~negative & v;
  };
  x0 = clamp(x0);
  y0 = clamp(y0);
  const FV fx = x - __builtin_convertvector(x0, FV), fy = y - __builtin_convertvector(y0, FV);
  FV a00, a01, a10, a11, b00, b01, b10, b11;
  for (int i = 0; i < kWidth; ++i) {
    const int k = y0[i] * kTable + x0[i];
    a00[i] = ta[k], a01[i] = ta[k + 1], a10[i] = ta[k + kTable], a11[i] = ta[k + kTable + 1];
    b00[i] = tb[k], b01[i] = tb[k + 1], b10[i] = tb[k + kTable], b11[i] = tb[k + kTable + 1];
  }
  *a = (1 - fy) * ((1 - fx) * a00 + fx * a01) + fy * ((1 - fx) * a10 + fx * a11);
  *b = (1 - fy) * ((1 - fx) * b00 + fx * b01) + fy * ((1 - fx) * b10 + fx * b11);
}

// Lanes [i, i + kWidth).
void EvalVector(BsdfLanes* lanes, int i) {
  BsdfLanes& l = *lanes;
  const AlbedoTable& table = Table();
  const V3 wo{Load(&l.wo[0][i]), Load(&l.wo[1][i]), Load(&l.wo[2][i])};
  const V3 wi{Load(&l.wi[0][i]), Load(&l.wi[1][i]), Load(&l.wi[2][i])};
  const FV base[3] = {Load(&l.base[0][i]), Load(&l.base[1][i]), Load(&l.base[2][i])};
  const FV m = Load(&l.metallic[i]), ax = Load(&l.alpha_x[i]), ay = Load(&l.alpha_y[i]);
  const FV f0 = Load(&l.f0[i]), lambda_o = Load(&l.lambda_o[i]), missing = Load(&l.missing[i]);
  const FV p_specular = Load(&l.p_specular[i]);
  const IV has_specular = LoadMask(&l.has_specular[i]);
  const IV multiscatter = LoadMask(&l.multiscatter[i]);

  // The specular lobes (EvalWithPdf's branch where p_specular > 0).
  const V3 h = Normalized({wo.x + wi.x, wo.y + wi.y, wo.z + wi.z});
  const FV d = D(h, ax, ay);
  const FV o_h = Dot(wo, h);
  const FV g2 = 1 / (1 + lambda_o + Lambda(wi, ax, ay));
  const FV c5 = Pow5(1 - Clamp01(o_h));
  FV dielectric = Select(has_specular, f0 + (1 - f0) * c5, Splat(0));
  dielectric =
      Select(multiscatter, dielectric * (1 + Load(&l.dielectric_favg[i]) * missing), dielectric);
  const FV scale = d * g2 / (4 * wo.z * wi.z);
  const IV specular = p_specular > Splat(0);
  // The diffuse layer's share, DiffuseScale().
  FV a_i, b_i;
  Lookup2(table.a, table.b, Load(&l.r[i]), wi.z, &a_i, &b_i);
  FV e_i = f0 * a_i + b_i;
  const FV e1 = a_i + b_i;
  e_i = Select(multiscatter,
               e_i * (1 + Load(&l.dielectric_favg[i]) * (1 - e1) / Max(e1, Splat(1e-6f))), e_i);
  const FV diffuse_scale =
      Select(has_specular, (1 - Load(&l.e_dielectric[i])) * (1 - e_i) / Load(&l.diffuse_norm[i]),
             Splat(1));
  const IV diffuse = m < Splat(1);
  FV f[3];
  for (int c = 0; c < 3; ++c) {
    FV metal = base[c] + (1 - base[c]) * c5;
    metal = Select(multiscatter, metal * (1 + Load(&l.metal_favg[c][i]) * missing), metal);
    const FV lobe = Select(specular, (m * metal + (1 - m) * dielectric) * scale, Splat(0));
    f[c] = Select(diffuse, lobe + (1 - m) * base[c] * (diffuse_scale / kPi), lobe);
  }
  const FV specular_pdf =
      Select(specular & (o_h > Splat(0)), d / ((1 + lambda_o) * 4 * wo.z), Splat(0));
  FV pdf = p_specular * specular_pdf + (1 - p_specular) * wi.z / kPi;

  // The clear coat on top, where there is one.
  const FV coat = Load(&l.coat[i]);
  const IV coated = coat > Splat(0);
  const int any_coat = [&] {
    int any = 0;
    for (int k = 0; k < kWidth; ++k) any |= coated[k];
    return any;
  }();
  if (any_coat) {
    const FV ca = Load(&l.coat_alpha[i]), e_coat = Load(&l.e_coat[i]);
    const FV lambda_coat_o = Load(&l.lambda_coat_o[i]), p_coat = Load(&l.p_coat[i]);
    FV ca_i, cb_i;
    Lookup2(table.a, table.b, Load(&l.coat_r[i]), wi.z, &ca_i, &cb_i);
    const FV e_coat_i = coat * (kCoatF0 * ca_i + cb_i);
    const FV through = (1 - e_coat) * (1 - e_coat_i);
    const FV dc = D(h, ca, ca);
    const FV g2c = 1 / (1 + lambda_coat_o + Lambda(wi, ca, ca));
    const FV fresnel = kCoatF0 + (1 - kCoatF0) * Pow5(1 - Clamp01(o_h));
    const FV top = coat * fresnel * dc * g2c / (4 * wo.z * wi.z);
    for (int c = 0; c < 3; ++c) f[c] = Select(coated, f[c] * through + top, f[c]);
    const FV coat_pdf = Select(o_h > Splat(0), dc / ((1 + lambda_coat_o) * 4 * wo.z), Splat(0));
    pdf = Select(coated, p_coat * coat_pdf + (1 - p_coat) * pdf, pdf);
  }
  // Nothing where either direction is below the surface (as EvalWithPdf's early return).
  const IV below = (wo.z <= Splat(0)) | (wi.z <= Splat(0));
  for (int c = 0; c < 3; ++c) Store(&l.f[c][i], Select(below, Splat(0), f[c]));
  Store(&l.pdf[i], Select(below, Splat(0), pdf));
}

}  // namespace

void EvalLanes(BsdfLanes* lanes) {
  BsdfLanes& l = *lanes;
  if (l.count <= 0) return;
  // The last vector's unused lanes repeat lane 0 (numbers a table lookup can take).
  const int end = (l.count + kWidth - 1) / kWidth * kWidth;
  for (int i = l.count; i < end; ++i) {
    for (int c = 0; c < 3; ++c) {
      l.wo[c][i] = l.wo[c][0], l.wi[c][i] = l.wi[c][0], l.base[c][i] = l.base[c][0];
      l.metal_favg[c][i] = l.metal_favg[c][0];
    }
    l.metallic[i] = l.metallic[0], l.alpha_x[i] = l.alpha_x[0], l.alpha_y[i] = l.alpha_y[0];
    l.r[i] = l.r[0], l.f0[i] = l.f0[0], l.diffuse_norm[i] = l.diffuse_norm[0];
    l.dielectric_favg[i] = l.dielectric_favg[0], l.coat[i] = l.coat[0];
    l.coat_r[i] = l.coat_r[0], l.coat_alpha[i] = l.coat_alpha[0];
    l.has_specular[i] = l.has_specular[0], l.multiscatter[i] = l.multiscatter[0];
    l.lambda_o[i] = l.lambda_o[0], l.e_dielectric[i] = l.e_dielectric[0];
    l.missing[i] = l.missing[0], l.p_specular[i] = l.p_specular[0];
    l.lambda_coat_o[i] = l.lambda_coat_o[0], l.e_coat[i] = l.e_coat[0], l.p_coat[i] = l.p_coat[0];
  }
  for (int i = 0; i < end; i += kWidth) EvalVector(lanes, i);
}

}  // namespace cadsynth
