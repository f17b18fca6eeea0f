#include "render/material.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "cad/error.h"
#include "render/sampling.h"

namespace cadsynth {

bool Material::Check(std::string* why) const {
  const PrincipledParams& s = surface;
  const auto unit = [](float x) { return x >= 0.0f && x <= 1.0f; };
  if (!unit(s.base_color.minCoeff()) || !unit(s.base_color.maxCoeff())) {
    *why = "base_color components lie in 0..1";
  } else if (!unit(s.metallic)) {
    *why = "metallic must lie in [0, 1]";
  } else if (!unit(s.roughness)) {
    *why = "roughness must lie in [0, 1]";
  } else if (!unit(s.specular)) {
    *why = "specular must lie in [0, 1]";
  } else if (!(s.anisotropic >= 0.0f && s.anisotropic < 1.0f)) {
    *why = "anisotropic must lie in [0, 1)";
  } else if (!(texture.scale_mm > 0) || !std::isfinite(texture.scale_mm)) {
    *why = "texture scale must be a positive length";
  } else if (!unit(texture.amount) || !unit(texture.roughness_amount) || !unit(texture.bump)) {
    *why = "texture amount, roughness and bump must lie in [0, 1]";
  } else if (!unit(texture.color.minCoeff()) || !unit(texture.color.maxCoeff())) {
    *why = "texture color components lie in 0..1";
  } else if (texture.kind == Texture::Kind::kImage && texture.image.empty()) {
    *why = "an image texture needs a file";
  } else {
    return true;
  }
  return false;
}

namespace {

Material Make(Eigen::Vector3f base, float metallic, float roughness, float specular = 0.5f,
              float anisotropic = 0.0f) {
  Material m;
  m.surface.base_color = base;
  m.surface.metallic = metallic;
  m.surface.roughness = roughness;
  m.surface.specular = specular;
  m.surface.anisotropic = anisotropic;
  return m;
}

Texture Tex(Texture::Kind kind, double scale_mm, float amount, float roughness_amount,
            float bump = 0.0f) {
  Texture t;
  t.kind = kind;
  t.scale_mm = scale_mm;
  t.amount = amount;
  t.roughness_amount = roughness_amount;
  t.bump = bump;
  return t;
}

// Metals' base colours are their reflectance at normal incidence (linear sRGB primaries), from
// spectral data (Hoffman, "Physics and math of shading", SIGGRAPH 2013 course): iron 0.56-0.58,
// aluminium 0.91-0.92; brass and stainless steel from their alloys' measured reflectance.
const std::map<std::string, Material>& Presets() {
  static const std::map<std::string, Material> presets = [] {
    using K = Texture::Kind;
    std::map<std::string, Material> p;
    p["steel"] = Make({0.56f, 0.57f, 0.58f}, 1.0f, 0.35f);
    p["steel"].texture = Tex(K::kNoise, 8.0, 0.08f, 0.12f);
    p["stainless"] = Make({0.67f, 0.64f, 0.60f}, 1.0f, 0.30f, 0.5f, 0.6f);
    p["stainless"].texture = Tex(K::kBrushed, 4.0, 0.06f, 0.10f, 0.05f);
    p["aluminium"] = Make({0.91f, 0.92f, 0.92f}, 1.0f, 0.30f);
    p["aluminium"].texture = Tex(K::kNoise, 6.0, 0.05f, 0.10f);
    p["brass"] = Make({0.91f, 0.78f, 0.42f}, 1.0f, 0.28f);
    p["brass"].texture = Tex(K::kNoise, 8.0, 0.08f, 0.10f);
    p["cast_iron"] = Make({0.42f, 0.41f, 0.40f}, 1.0f, 0.62f);
    p["cast_iron"].texture = Tex(K::kConcrete, 3.0, 0.25f, 0.15f, 0.3f);
    p["black_oxide"] = Make({0.05f, 0.05f, 0.055f}, 0.8f, 0.45f);
    p["black_oxide"].texture = Tex(K::kNoise, 5.0, 0.15f, 0.10f);
    p["painted"] = Make({0.60f, 0.08f, 0.05f}, 0.0f, 0.30f, 0.5f);
    p["painted"].base_from_part = true;
    p["painted"].texture = Tex(K::kNoise, 10.0, 0.04f, 0.06f);
    p["abs"] = Make({0.80f, 0.80f, 0.80f}, 0.0f, 0.40f, 0.5f);
    p["abs"].base_from_part = true;
    p["nylon"] = Make({0.85f, 0.83f, 0.78f}, 0.0f, 0.55f, 0.45f);
    p["nylon"].base_from_part = true;
    p["rubber"] = Make({0.02f, 0.02f, 0.02f}, 0.0f, 0.85f, 0.3f);
    p["rubber"].texture = Tex(K::kNoise, 2.0, 0.2f, 0.05f, 0.15f);
    // Floors and tables.
    p["concrete"] = Make({0.42f, 0.41f, 0.39f}, 0.0f, 0.85f, 0.4f);
    p["concrete"].texture = Tex(K::kConcrete, 60.0, 0.35f, 0.10f, 0.2f);
    p["wood"] = Make({0.40f, 0.22f, 0.09f}, 0.0f, 0.55f, 0.5f);
    p["wood"].texture = Tex(K::kWood, 25.0, 0.6f, 0.10f);
    p["wood"].texture.color = {0.16f, 0.07f, 0.025f};
    p["plastic_sheet"] = Make({0.30f, 0.32f, 0.35f}, 0.0f, 0.45f, 0.5f);
    p["plastic_sheet"].texture = Tex(K::kNoise, 40.0, 0.05f, 0.05f);
    p["rubber_mat"] = Make({0.03f, 0.03f, 0.03f}, 0.0f, 0.80f, 0.3f);
    p["rubber_mat"].texture = Tex(K::kNoise, 3.0, 0.25f, 0.08f, 0.2f);
    return p;
  }();
  return presets;
}

float Smooth(float t) { return t * t * t * (t * (t * 6 - 15) + 10); }  // quintic fade, C2

float Lattice(int x, int y, int z, uint64_t seed) {
  const uint64_t h = Hash(Hash(Hash(seed, static_cast<uint32_t>(x)), static_cast<uint32_t>(y)),
                          static_cast<uint32_t>(z));
  return UnitFloat(static_cast<uint32_t>(h >> 32));
}

float SmoothStep(float a, float b, float x) {
  const float t = std::clamp((x - a) / (b - a), 0.0f, 1.0f);
  return t * t * (3 - 2 * t);
}

// The scalar pattern of a procedural texture at p (mm), in [0, 1].
float Pattern(const Texture& t, const Eigen::Vector3f& p) {
  const float s = static_cast<float>(t.scale_mm);
  switch (t.kind) {
    case Texture::Kind::kNoise:
      return FractalNoise(p / s, 4, t.seed);
    case Texture::Kind::kBrushed:
      // Long along x, fine across: streaks `scale` long and a fiftieth of that wide.
      return FractalNoise(Eigen::Vector3f(p.x() / (4 * s), p.y() * 50 / s, p.z() * 50 / s), 3,
                          t.seed);
    case Texture::Kind::kTurned: {
      const float r = std::hypot(p.x(), p.y());
      return FractalNoise(Eigen::Vector3f(r * 50 / s, p.z() / s, std::atan2(p.y(), p.x()) * 0.5f),
                          3, t.seed);
    }
    case Texture::Kind::kChecker: {
      const int parity =
          static_cast<int>(std::floor(p.x() / s) + std::floor(p.y() / s) + std::floor(p.z() / s));
      return static_cast<float>(parity & 1);
    }
    case Texture::Kind::kConcrete: {
      const float blotch = FractalNoise(p / s, 5, t.seed);
      const float speckle = ValueNoise(p * (12 / s), Hash(t.seed, 1));
      const float pit = SmoothStep(0.80f, 0.90f, speckle);
      return std::clamp(0.75f * blotch + 0.25f * speckle - 0.35f * pit, 0.0f, 1.0f);
    }
    case Texture::Kind::kWood: {
      const float r = std::hypot(p.x(), p.z()) / s + 2.0f * FractalNoise(p / (4 * s), 3, t.seed);
      const float ring = r - std::floor(r);
      return SmoothStep(0.0f, 0.25f, ring) * (1 - SmoothStep(0.55f, 1.0f, ring));
    }
    case Texture::Kind::kRust: {
      const float m = FractalNoise(p / s, 5, t.seed);
      // Noise sums concentrate near 0.5: map `amount` to a threshold that covers about it.
      const float threshold = 0.5f + 0.35f * (1 - 2 * t.amount);
      return SmoothStep(threshold - 0.04f, threshold + 0.04f, m);
    }
    case Texture::Kind::kNone:
    case Texture::Kind::kImage:
      break;
  }
  return 0.5f;
}

Eigen::Vector3f ImageAt(const LinearImage& image, float u, float v) {
  // Bilinear, wrapping.
  const float x = (u - std::floor(u)) * image.width - 0.5f;
  const float y = (v - std::floor(v)) * image.height - 0.5f;
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const float fx = x - x0, fy = y - y0;
  const auto at = [&](int xi, int yi) {
    xi = ((xi % image.width) + image.width) % image.width;
    yi = ((yi % image.height) + image.height) % image.height;
    const float* c = image.at(xi, yi);
    return Eigen::Vector3f(c[0], c[1], c[2]);
  };
  return (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) +
         fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1));
}

}  // namespace

bool MaterialPreset(const std::string& name, Material* material) {
  const auto it = Presets().find(name);
  if (it == Presets().end()) return false;
  *material = it->second;
  return true;
}

std::vector<std::string> MaterialPresetNames() {
  std::vector<std::string> names;
  for (const auto& [name, m] : Presets()) names.push_back(name);
  return names;
}

float ValueNoise(const Eigen::Vector3f& p, uint64_t seed) {
  const float fx = std::floor(p.x()), fy = std::floor(p.y()), fz = std::floor(p.z());
  // Lattice coordinates wrap at 2^31; points farther than that from the origin repeat.
  const int x = static_cast<int>(std::fmod(fx, 2147483648.0f)),
            y = static_cast<int>(std::fmod(fy, 2147483648.0f)),
            z = static_cast<int>(std::fmod(fz, 2147483648.0f));
  const float tx = Smooth(p.x() - fx), ty = Smooth(p.y() - fy), tz = Smooth(p.z() - fz);
  float c[2][2];
  for (int dz = 0; dz < 2; ++dz) {
    for (int dy = 0; dy < 2; ++dy) {
      const float a = Lattice(x, y + dy, z + dz, seed), b = Lattice(x + 1, y + dy, z + dz, seed);
      c[dz][dy] = a + tx * (b - a);
    }
  }
  const float near = c[0][0] + ty * (c[0][1] - c[0][0]);
  const float far = c[1][0] + ty * (c[1][1] - c[1][0]);
  return near + tz * (far - near);
}

float FractalNoise(const Eigen::Vector3f& p, int octaves, uint64_t seed) {
  float sum = 0, amplitude = 0.5f, total = 0;
  Eigen::Vector3f q = p;
  for (int o = 0; o < octaves; ++o) {
    sum += amplitude * ValueNoise(q, Hash(seed, static_cast<uint64_t>(o)));
    total += amplitude;
    amplitude *= 0.5f;
    // Rotate a little between octaves so that lattice axes do not line up.
    q = Eigen::Vector3f(1.6f * q.x() + 1.2f * q.y(), -1.2f * q.x() + 1.6f * q.y(), 2.0f * q.z());
  }
  return sum / total;
}

TextureSample EvalTexture(const Texture& t, const Eigen::Vector3f& p, const Eigen::Vector3f& n,
                          const LinearImage* image) {
  TextureSample out;
  if (t.kind == Texture::Kind::kNone) return out;
  if (t.kind == Texture::Kind::kImage) {
    if (image == nullptr || image->width == 0) return out;
    // Triplanar: three projections along the axes, weighted by the normal's components^4.
    const Eigen::Vector3f w = n.cwiseAbs().array().pow(4.0f).matrix();
    const float sum = std::max(w.sum(), 1e-8f);
    const float s = static_cast<float>(t.scale_mm);
    const Eigen::Vector3f c = (w.x() * ImageAt(*image, p.y() / s, -p.z() / s) +
                               w.y() * ImageAt(*image, p.x() / s, -p.z() / s) +
                               w.z() * ImageAt(*image, p.x() / s, -p.y() / s)) /
                              sum;
    out.color_mix = c;
    out.mix = 1.0f;
    return out;
  }
  const float v = Pattern(t, p);
  switch (t.kind) {
    case Texture::Kind::kChecker:
    case Texture::Kind::kWood:
    case Texture::Kind::kRust:
      out.color_mix = t.color;
      out.mix = t.kind == Texture::Kind::kChecker
                    ? v
                    : (t.kind == Texture::Kind::kWood ? t.amount * v : v);
      out.roughness_offset =
          t.roughness_amount * (t.kind == Texture::Kind::kRust ? 2 * v : v - 0.5f);
      break;
    default:
      out.color_scale = Eigen::Vector3f::Constant(1 + 2 * t.amount * (v - 0.5f));
      out.roughness_offset = 2 * t.roughness_amount * (v - 0.5f);
      break;
  }
  if (t.bump > 0) {
    // The pattern as a height field: tilt the normal against its gradient in the tangent plane,
    // by central differences a tenth of the feature size apart.
    const float h = 0.02f * static_cast<float>(t.scale_mm);
    Eigen::Vector3f grad;
    for (int a = 0; a < 3; ++a) {
      Eigen::Vector3f d = Eigen::Vector3f::Zero();
      d[a] = h;
      grad[a] = (Pattern(t, p + d) - Pattern(t, p - d)) / (2 * h);
    }
    const Eigen::Vector3f tangential = grad - grad.dot(n) * n;
    // Dimensionless slope: a unit change of the pattern over the feature size tilts by `bump`.
    out.normal_offset = -t.bump * static_cast<float>(t.scale_mm) * 0.1f * tangential;
  }
  return out;
}

PrincipledParams ApplyTexture(const PrincipledParams& surface, const TextureSample& sample) {
  PrincipledParams p = surface;
  p.base_color = ((1 - sample.mix) * surface.base_color.cwiseProduct(sample.color_scale) +
                  sample.mix * sample.color_mix)
                     .cwiseMax(0.0f)
                     .cwiseMin(1.0f);
  // What is blended in (rust, paint, a wood or image colour) is not metal.
  p.metallic = surface.metallic * (1 - sample.mix);
  p.roughness = std::clamp(surface.roughness + sample.roughness_offset, 0.0f, 1.0f);
  return p;
}

}  // namespace cadsynth
