// Random numbers and warps for the physically based mode. Every number a path uses is a pure
// function of (seed, pixel, sample index, dimension), so images do not depend on the thread count,
// the tile order or the shard.
#pragma once

#include <cstdint>

#include <Eigen/Core>

namespace cadsynth {

inline constexpr float kPiF = 3.14159265358979323846f;

// SplitMix64's finaliser: a bijection of 64-bit words whose output bits all depend on every input
// bit. Hash(a, b) chains it.
constexpr uint64_t Mix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}
inline uint64_t Hash(uint64_t a, uint64_t b) { return Mix64(a ^ Mix64(b)); }

// A number in [0, 1) from the top 24 bits of x (exactly representable floats, never 1).
inline float UnitFloat(uint32_t x) { return static_cast<float>(x >> 8) * (1.0f / 16777216.0f); }

// Point `index` of the first two dimensions of the Sobol sequence (a (0, 2)-sequence: every
// power-of-two run of 2^k points starting at a multiple of 2^k puts one point in each of the
// 2^k elementary intervals of any shape), shuffled and Owen-scrambled by `seed` (Burley 2020,
// "Practical hash-based Owen scrambling"). Scrambling keeps the stratification and makes every
// point uniform on [0, 1)^2, so estimates are unbiased; different seeds are independent.
Eigen::Vector2f SobolOwen2D(uint32_t index, uint64_t seed);

// The per-pixel sampler of one path: sample `index` of the pixel's sequence, dimension pair `dim`
// (0: the position in the pixel, then two pairs per bounce: the light, the BSDF). Pairs with
// different `dim` are scrambled and shuffled with seeds SobolOwen2D hashes apart, so they do not
// correlate.
class PixelSampler {
 public:
  PixelSampler(uint64_t pixel_seed, uint32_t index) : seed_(pixel_seed), index_(index) {}
  Eigen::Vector2f Get2D(uint32_t dim) const {
    return SobolOwen2D(index_, seed_ + 0x9E3779B97F4A7C15ull * (dim + 1));
  }

 private:
  uint64_t seed_;
  uint32_t index_;
};

// Warps of the unit square, each with its density.
// Concentric map to the unit disc (Shirley and Chiu 1997): area-preserving, density 1/pi.
Eigen::Vector2f ConcentricDisc(const Eigen::Vector2f& u);
// Uniform direction in the cone about +z of half-angle acos(cos_max): density
// 1 / (2 pi (1 - cos_max)).
Eigen::Vector3f UniformCone(const Eigen::Vector2f& u, float cos_max);

// An orthonormal basis (t, b, n) with n given (Duff et al. 2017, no branch on a threshold).
void OrthonormalBasis(const Eigen::Vector3f& n, Eigen::Vector3f* t, Eigen::Vector3f* b);

// Veach's power heuristic (beta = 2) for a sample from strategy a also reachable by strategy b.
inline float PowerHeuristic(float pdf_a, float pdf_b) {
  const float a = pdf_a * pdf_a, b = pdf_b * pdf_b;
  return a + b > 0 ? a / (a + b) : 0.0f;
}

}  // namespace cadsynth
