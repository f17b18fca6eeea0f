#include "render/material.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "cad/core/error.h"
#include "cad/core/random.h"
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
  } else if (!(s.anisotropic >= 0.0f && s.anisotropic <= 1.0f)) {
    *why = "anisotropic must lie in [0, 1]";
  } else if (!unit(s.clearcoat) || !unit(s.clearcoat_roughness)) {
    *why = "clearcoat and clearcoat_roughness must lie in [0, 1]";
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
    p["steel"].texture = Tex(K::kNoise, 6.0, 0.05f, 0.08f);
    p["stainless"] = Make({0.67f, 0.64f, 0.60f}, 1.0f, 0.30f, 0.5f, 0.6f);
    p["stainless"].texture = Tex(K::kBrushed, 4.0, 0.06f, 0.10f, 0.05f);
    p["stainless"].tangent = Material::Tangent::kModelX;  // along the brushed streaks
    p["aluminium"] = Make({0.91f, 0.92f, 0.92f}, 1.0f, 0.32f, 0.5f, 0.4f);
    p["aluminium"].texture = Tex(K::kBrushed, 6.0, 0.04f, 0.06f);
    p["aluminium"].tangent = Material::Tangent::kModelX;
    // A ground and polished plate: the mirror-like metal that real depth sensors lose.
    p["polished_steel"] = Make({0.56f, 0.57f, 0.58f}, 1.0f, 0.05f);
    p["brass"] = Make({0.91f, 0.78f, 0.42f}, 1.0f, 0.28f);
    p["brass"].texture = Tex(K::kNoise, 8.0, 0.08f, 0.10f);
    p["cast_iron"] = Make({0.42f, 0.41f, 0.40f}, 1.0f, 0.62f);
    p["cast_iron"].texture = Tex(K::kConcrete, 3.0, 0.25f, 0.15f, 0.3f);
    p["black_oxide"] = Make({0.05f, 0.05f, 0.055f}, 0.8f, 0.45f);
    p["black_oxide"].texture = Tex(K::kNoise, 5.0, 0.15f, 0.10f);
    p["painted"] = Make({0.60f, 0.08f, 0.05f}, 0.0f, 0.30f, 0.5f);
    p["painted"].base_from_part = true;
    p["painted"].surface.clearcoat = 0.5f;
    p["painted"].surface.clearcoat_roughness = 0.1f;
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
    p["wood"] = Make({0.30f, 0.17f, 0.08f}, 0.0f, 0.55f, 0.5f);
    p["wood"].texture = Tex(K::kWood, 12.0, 0.6f, 0.10f);
    p["wood"].texture.color = {0.09f, 0.04f, 0.018f};
    p["plastic_sheet"] = Make({0.30f, 0.32f, 0.35f}, 0.0f, 0.45f, 0.5f);
    p["plastic_sheet"].texture = Tex(K::kNoise, 40.0, 0.05f, 0.05f);
    p["rubber_mat"] = Make({0.03f, 0.03f, 0.03f}, 0.0f, 0.80f, 0.3f);
    p["rubber_mat"].texture = Tex(K::kNoise, 3.0, 0.25f, 0.08f, 0.2f);
    return p;
  }();
  return presets;
}

float Smooth(float t) { return t * t * t * (t * (t * 6 - 15) + 10); }  // quintic fade, C2

// A value in [0, 1) per lattice point: the coordinates folded into one word by odd multipliers,
// then a 32-bit finaliser with good avalanche (Wellons' lowbias32), cheap enough for the eight
// corners of every noise evaluation.
constexpr uint32_t kLatticeX = 0x8DA6B343u, kLatticeY = 0xD8163841u, kLatticeZ = 0xCB1AB31Fu;

template <typename Word>
Word LowBias32(Word h) {
  h ^= h >> 16;
  h *= 0x7FEB352Du;
  h ^= h >> 15;
  h *= 0x846CA68Bu;
  h ^= h >> 16;
  return h;
}

float Lattice(uint32_t x, uint32_t y, uint32_t z, uint32_t seed) {
  return UnitFloat(LowBias32(seed ^ (x * kLatticeX) ^ (y * kLatticeY) ^ (z * kLatticeZ)));
}

// Four lanes of 32-bit words or floats (GCC's and Clang's vector extensions: SSE2 on the baseline
// x86-64 instruction set, plain code elsewhere).
typedef uint32_t U32x4 __attribute__((vector_size(16)));
typedef int32_t I32x4 __attribute__((vector_size(16)));
typedef float F32x4 __attribute__((vector_size(16)));

// Lattice() of four folded words: UnitFloat(LowBias32(h)) lane by lane (below 2^24, so the
// signed conversion is exact).
F32x4 LatticeUnit(U32x4 h) {
  const I32x4 top = reinterpret_cast<I32x4>(LowBias32(h) >> 8);
  return __builtin_convertvector(top, F32x4) * (1.0f / 16777216.0f);
}

// floor() for the textures' inner loops (a library call on the baseline x86-64 instruction set):
// truncation, corrected below zero; arguments beyond +-1e9 are clamped (texture coordinates
// never reach them meaningfully), NaN gives -1e9.
float FastFloor(float f) {
  if (!(f >= -1.0e9f)) f = -1.0e9f;
  if (f > 1.0e9f) f = 1.0e9f;
  const float t = static_cast<float>(static_cast<int32_t>(f));
  return t > f ? t - 1 : t;
}

float SmoothStep(float a, float b, float x) {
  const float t = std::clamp((x - a) / (b - a), 0.0f, 1.0f);
  return t * t * (3 - 2 * t);
}

// The scalar pattern of a procedural texture at p (mm), in [0, 1].
// `seed` is the texture's seed on the texture.pattern stream.
float Pattern(const Texture& t, const Eigen::Vector3f& p, float footprint_mm, uint64_t seed) {
  const float s = static_cast<float>(t.scale_mm);
  // Octaves finer than the footprint average out over it: FractalNoise replaces them by their
  // mean. `cell` is the size (mm) of a call's first octave along its finest axis.
  const auto fractal = [&](const Eigen::Vector3f& q, int octaves, uint64_t seed, float cell) {
    return FractalNoise(q, octaves, seed, footprint_mm / cell);
  };
  switch (t.kind) {
    case Texture::Kind::kNoise:
      return fractal(p / s, 4, seed, s);
    case Texture::Kind::kBrushed:
      // Long along x, fine across: streaks `scale` long and a fiftieth of that wide.
      return fractal(Eigen::Vector3f(p.x() / (4 * s), p.y() * 50 / s, p.z() * 50 / s), 3, seed,
                     s / 50);
    case Texture::Kind::kTurned: {
      const float r = std::hypot(p.x(), p.y());
      return fractal(Eigen::Vector3f(r * 50 / s, p.z() / s, std::atan2(p.y(), p.x()) * 0.5f), 3,
                     seed, s / 50);
    }
    case Texture::Kind::kChecker: {
      const int parity =
          static_cast<int>(FastFloor(p.x() / s) + FastFloor(p.y() / s) + FastFloor(p.z() / s));
      return static_cast<float>(parity & 1);
    }
    case Texture::Kind::kConcrete: {
      const float blotch = fractal(p / s, 5, seed, s);
      const float speckle = fractal(p * (12 / s), 1, Hash(seed, 1), s / 12);
      const float pit = SmoothStep(0.80f, 0.90f, speckle);
      return std::clamp(0.75f * blotch + 0.25f * speckle - 0.35f * pit, 0.0f, 1.0f);
    }
    case Texture::Kind::kWood: {
      // Boards 8 `scale` wide along y, each its own tone and grain: long thin streaks along y,
      // faint growth rings, and a dark seam between boards.
      const float board = FastFloor(p.x() / (8 * s));
      const uint64_t board_seed = Hash(seed, static_cast<uint64_t>(static_cast<int64_t>(board)));
      const float tone = UnitFloat(static_cast<uint32_t>(board_seed >> 32));
      const float grain = fractal(Eigen::Vector3f(p.x() * 20 / s, p.y() / (4 * s), p.z() * 20 / s),
                                  4, board_seed, s / 20);
      const float w =
          p.x() / (1.5f * s) + 2.0f * fractal(p / (10 * s), 3, Hash(board_seed, 1), 10 * s);
      const float ring = w - FastFloor(w);
      const float band = SmoothStep(0.0f, 0.3f, ring) * (1 - SmoothStep(0.5f, 1.0f, ring));
      const float across = p.x() / (8 * s) - board;
      const float seam = 1 - SmoothStep(0.0f, 0.004f, std::min(across, 1 - across));
      return std::clamp(0.45f * grain + 0.2f * band + 0.35f * tone + seam, 0.0f, 1.0f);
    }
    case Texture::Kind::kRust: {
      const float m = fractal(p / s, 5, seed, s);
      // Noise sums concentrate near 0.5: map `amount` to a threshold that covers about it.
      const float threshold = 0.5f + 0.35f * (1 - 2 * t.amount);
      return SmoothStep(threshold - 0.04f, threshold + 0.04f, m);
    }
    case Texture::Kind::kScratches: {
      // Segments of random direction and length up to a cell, up to three per cell (each
      // present with probability `amount`), centred in cells of `scale`; a segment reaches only
      // the 2 x 2 x 2 block of cells nearest p. 1 on a scratch, fading over its width.
      const float width = 0.03f * s;
      if (footprint_mm > 4 * width) {
        // Finer than the footprint: what a scratch covers of it, on average (a faint sheen).
        return std::min(1.0f, width / footprint_mm) * t.amount;
      }
      const Eigen::Vector3f q = p / s;
      const int bx = static_cast<int>(FastFloor(q.x() - 0.5f)),
                by = static_cast<int>(FastFloor(q.y() - 0.5f)),
                bz = static_cast<int>(FastFloor(q.z() - 0.5f));
      float best = 1e9f;
      for (int c = 0; c < 8; ++c) {
        const int cx = bx + (c & 1), cy = by + ((c >> 1) & 1), cz = bz + (c >> 2);
        for (uint32_t k = 0; k < 3; ++k) {
          const uint32_t line = static_cast<uint32_t>(Hash(seed, k));
          if (Lattice(cx, cy, cz, line) >= t.amount) continue;
          const Eigen::Vector3f centre(cx + Lattice(cx, cy, cz, line + 1),
                                       cy + Lattice(cx, cy, cz, line + 2),
                                       cz + Lattice(cx, cy, cz, line + 3));
          const float phi = 6.2831853f * Lattice(cx, cy, cz, line + 4);
          const float cos_t = 2 * Lattice(cx, cy, cz, line + 5) - 1;
          const float sin_t = std::sqrt(std::max(0.0f, 1 - cos_t * cos_t));
          const Eigen::Vector3f dir(sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t);
          const float half = 0.5f * Lattice(cx, cy, cz, line + 6);
          const float along = std::clamp((q - centre).dot(dir), -half, half);
          best = std::min(best, (q - centre - along * dir).squaredNorm());
        }
      }
      const float distance_mm = std::sqrt(best) * s;
      return 1 - SmoothStep(0.3f * width, width, distance_mm);
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
  // The lattice cell (points beyond 1e9 cells from the origin share the last cell's values).
  const float fx = FastFloor(p.x()), fy = FastFloor(p.y()), fz = FastFloor(p.z());
  const uint32_t x = static_cast<uint32_t>(static_cast<int32_t>(fx)),
                 y = static_cast<uint32_t>(static_cast<int32_t>(fy)),
                 z = static_cast<uint32_t>(static_cast<int32_t>(fz));
  const uint32_t s = static_cast<uint32_t>(seed ^ (seed >> 32));
  const float tx = Smooth(p.x() - fx), ty = Smooth(p.y() - fy), tz = Smooth(p.z() - fz);
  // Lattice() of the eight corners, four at a time: lanes (dy, dz) = (0, 0), (1, 0), (0, 1),
  // (1, 1), at x (a) and x + 1 (b). (y + 1) k = y k + k modulo 2^32, so the corners' words need
  // no vector multiply; the integer and float operations are Lattice()'s and the scalar
  // interpolation's, lane by lane, so the value is the same to the bit.
  const uint32_t kx = x * kLatticeX, ky = y * kLatticeY, kz = z * kLatticeZ;
  const U32x4 corner = {s ^ ky ^ kz, s ^ (ky + kLatticeY) ^ kz, s ^ ky ^ (kz + kLatticeZ),
                        s ^ (ky + kLatticeY) ^ (kz + kLatticeZ)};
  const F32x4 a = LatticeUnit(corner ^ kx), b = LatticeUnit(corner ^ (kx + kLatticeX));
  const F32x4 c = a + tx * (b - a);
  const float near = c[0] + ty * (c[1] - c[0]);
  const float far = c[2] + ty * (c[3] - c[2]);
  return near + tz * (far - near);
}

namespace {

// ValueNoise of four points at once, lane by lane its operations in its order (the same floats).
F32x4 FastFloor4(F32x4 f) {
  const I32x4 in_range = f >= -1.0e9f;  // false for NaN too
  f = in_range ? f : F32x4{} - 1.0e9f;
  f = f > 1.0e9f ? F32x4{} + 1.0e9f : f;
  const F32x4 t = __builtin_convertvector(__builtin_convertvector(f, I32x4), F32x4);
  return t > f ? t - 1 : t;
}
F32x4 Smooth4(F32x4 t) { return t * t * t * (t * (t * 6 - 15) + 10); }

F32x4 ValueNoise4(F32x4 px, F32x4 py, F32x4 pz, U32x4 s) {
  const F32x4 fx = FastFloor4(px), fy = FastFloor4(py), fz = FastFloor4(pz);
  const U32x4 x = reinterpret_cast<U32x4>(__builtin_convertvector(fx, I32x4)),
              y = reinterpret_cast<U32x4>(__builtin_convertvector(fy, I32x4)),
              z = reinterpret_cast<U32x4>(__builtin_convertvector(fz, I32x4));
  const F32x4 tx = Smooth4(px - fx), ty = Smooth4(py - fy), tz = Smooth4(pz - fz);
  const U32x4 kx = x * kLatticeX, ky = y * kLatticeY, kz = z * kLatticeZ;
  const U32x4 ky1 = ky + kLatticeY, kz1 = kz + kLatticeZ, kx1 = kx + kLatticeX;
  // The corners (dy, dz) = (0, 0), (1, 0), (0, 1), (1, 1) at x (a) and x + 1 (b).
  const U32x4 corner[4] = {s ^ ky ^ kz, s ^ ky1 ^ kz, s ^ ky ^ kz1, s ^ ky1 ^ kz1};
  F32x4 c[4];
  for (int k = 0; k < 4; ++k) {
    const F32x4 a = LatticeUnit(corner[k] ^ kx), b = LatticeUnit(corner[k] ^ kx1);
    c[k] = a + tx * (b - a);
  }
  const F32x4 near = c[0] + ty * (c[1] - c[0]);
  const F32x4 far = c[2] + ty * (c[3] - c[2]);
  return near + tz * (far - near);
}

}  // namespace

float FractalNoise(const Eigen::Vector3f& p, int octaves, uint64_t seed, float footprint) {
  // Octave o's seed is Hash(seed, o) = Mix64(seed ^ Mix64(o)); the inner half is a constant.
  static constexpr uint64_t kOctave[8] = {Mix64(0), Mix64(1), Mix64(2), Mix64(3),
                                          Mix64(4), Mix64(5), Mix64(6), Mix64(7)};
  // An octave whose cells are smaller than the footprint counts as its mean: only the first
  // `live` are evaluated, four at a time (ValueNoise4), and summed in order.
  int live = 0;
  for (float cell = 1; live < octaves && !(cell < footprint); cell *= 0.5f) ++live;
  float sum = 0, amplitude = 0.5f, total = 0;
  Eigen::Vector3f q = p;
  for (int o0 = 0; o0 < octaves; o0 += 4) {
    const int n = std::min(4, octaves - o0);
    F32x4 value = {0.5f, 0.5f, 0.5f, 0.5f};
    if (o0 < live) {
      F32x4 qx{}, qy{}, qz{};
      U32x4 s{};
      for (int i = 0; i < n && o0 + i < live; ++i) {
        const int o = o0 + i;
        const uint64_t octave_seed =
            o < 8 ? Mix64(seed ^ kOctave[o]) : Hash(seed, static_cast<uint64_t>(o));
        qx[i] = q.x(), qy[i] = q.y(), qz[i] = q.z();
        s[i] = static_cast<uint32_t>(octave_seed ^ (octave_seed >> 32));
        // Rotate a little between octaves so that lattice axes do not line up.
        q = Eigen::Vector3f(1.6f * q.x() + 1.2f * q.y(), -1.2f * q.x() + 1.6f * q.y(),
                            2.0f * q.z());
      }
      value = ValueNoise4(qx, qy, qz, s);
    }
    for (int i = 0; i < n; ++i) {
      sum += amplitude * (o0 + i < live ? value[i] : 0.5f);
      total += amplitude;
      amplitude *= 0.5f;
    }
  }
  return sum / total;
}

TextureSample EvalTexture(const Texture& t, const Eigen::Vector3f& p, const Eigen::Vector3f& n,
                          const LinearImage* image, float footprint_mm, const Eigen::Vector2f* uv) {
  TextureSample out;
  if (t.kind == Texture::Kind::kNone) return out;
  if (t.kind == Texture::Kind::kImage) {
    if (image == nullptr || image->width == 0) return out;
    if (uv != nullptr && t.projection != Texture::Projection::kTriplanar) {
      // Image rows run downwards, v upwards.
      out.color_mix = ImageAt(*image, uv->x(), 1.0f - uv->y());
      out.mix = 1.0f;
      out.mix_is_coating = false;
      return out;
    }
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
    out.mix_is_coating = false;
    return out;
  }
  const uint64_t seed = Hash(streams::kTexturePattern.id(), t.seed);
  const float v = Pattern(t, p, footprint_mm, seed);
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
    case Texture::Kind::kScratches:
      // Burnished: a little brighter and smoother along a scratch.
      out.color_scale = Eigen::Vector3f::Constant(1 + 0.6f * v);
      out.roughness_offset = -t.roughness_amount * v;
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
      grad[a] =
          (Pattern(t, p + d, footprint_mm, seed) - Pattern(t, p - d, footprint_mm, seed)) / (2 * h);
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
  // A coating blended in (rust, a checker's paint, wood) is not metal; an image is the base colour.
  p.metallic = sample.mix_is_coating ? surface.metallic * (1 - sample.mix) : surface.metallic;
  p.roughness = std::clamp(surface.roughness + sample.roughness_offset, 0.0f, 1.0f);
  return p;
}

}  // namespace cadsynth
