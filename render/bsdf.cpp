#include "render/bsdf.h"
#include "render/image.h"

#include <algorithm>
#include <array>
#include <cmath>

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

PrincipledBsdf::PrincipledBsdf(const PrincipledParams& params) : params_(params) {
  const float alpha = params.roughness * params.roughness;
  const float aspect = std::sqrt(1 - 0.9f * std::clamp(params.anisotropic, 0.0f, 1.0f));
  alpha_x_ = std::max(kMinAlpha, alpha / aspect);
  alpha_y_ = std::max(kMinAlpha, alpha * aspect);
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

std::optional<PrincipledBsdf::Sampled> PrincipledBsdf::Sample(const Eigen::Vector3f& wo,
                                                              float u_lobe,
                                                              const Eigen::Vector2f& u) const {
  if (wo.z() <= 0) return std::nullopt;
  Sampled s;
  const ViewTerms& view = View(wo);
  if (u_lobe < view.p_coat) {
    s.wi = Reflect(wo, SampleVisibleNormal(wo, coat_alpha_, coat_alpha_, u));
  } else if ((u_lobe - view.p_coat) / (1 - view.p_coat) < view.p_specular) {
    s.wi = Reflect(wo, SampleVisibleNormal(wo, alpha_x_, alpha_y_, u));
  } else {  // cosine-weighted
    const float r = std::sqrt(u.x()), phi = 2 * kPi * u.y();
    s.wi =
        Eigen::Vector3f(r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0f, 1 - u.x())));
  }
  if (s.wi.z() <= 0) return std::nullopt;
  const Eigen::Vector3f f = EvalWithPdf(wo, s.wi, &s.pdf);
  if (!(s.pdf > 0)) return std::nullopt;
  s.weight = f * (s.wi.z() / s.pdf);
  return s;
}

}  // namespace cadsynth
