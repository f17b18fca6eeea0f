#include "render/sampling.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace cadsynth {

namespace {

// Bit reversal: the bytes swapped, then nibbles, bit pairs and bits within each byte.
inline uint32_t ReverseBits(uint32_t x) {
  x = __builtin_bswap32(x);
  x = ((x >> 4) & 0x0F0F0F0Fu) | ((x & 0x0F0F0F0Fu) << 4);
  x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
  return ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
}

// A hash that only ever carries information from lower bits to higher ones (Laine and Karras
// 2011), so applied to bit-reversed numbers it is a nested uniform (Owen) scramble.
uint32_t LaineKarras(uint32_t x, uint32_t seed) {
  x += seed;
  x ^= x * 0x6c50b47cu;
  x ^= x * 0xb82f1e52u;
  x ^= x * 0xc7afe638u;
  x ^= x * 0x8d22f6e6u;
  return x;
}

uint32_t OwenScramble(uint32_t x, uint32_t seed) {
  return ReverseBits(LaineKarras(ReverseBits(x), seed));
}

// The second Sobol dimension, generator matrix built by v_{k+1} = v_k ^ (v_k >> 1), v_0 = 2^31:
// the XOR of the columns of the index's set bits, eight bits at a time from tables built at
// compile time.
constexpr std::array<std::array<uint32_t, 256>, 4> kSobolDim1 = [] {
  std::array<uint32_t, 32> column{};
  uint32_t v = 1u << 31;
  for (int k = 0; k < 32; ++k, v ^= v >> 1) column[k] = v;
  std::array<std::array<uint32_t, 256>, 4> t{};
  for (int byte = 0; byte < 4; ++byte) {
    for (int x = 0; x < 256; ++x) {
      uint32_t r = 0;
      for (int b = 0; b < 8; ++b) {
        if (x & (1 << b)) r ^= column[8 * byte + b];
      }
      t[byte][x] = r;
    }
  }
  return t;
}();

inline uint32_t SobolDim1(uint32_t index) {
  return kSobolDim1[0][index & 255] ^ kSobolDim1[1][(index >> 8) & 255] ^
         kSobolDim1[2][(index >> 16) & 255] ^ kSobolDim1[3][index >> 24];
}

}  // namespace

Eigen::Vector2f SobolOwen2D(uint32_t index, uint64_t seed) {
  const uint64_t h = Mix64(seed);
  // Shuffle the order of the points (an Owen scramble of the index), then scramble each axis.
  const uint32_t i = OwenScramble(index, static_cast<uint32_t>(h));
  // The first dimension is the bit-reversed index, so its scramble needs no reversal at all:
  // OwenScramble(ReverseBits(i), s) = ReverseBits(LaineKarras(i, s)).
  const uint32_t x = ReverseBits(LaineKarras(i, static_cast<uint32_t>(h >> 32)));
  const uint32_t y = OwenScramble(SobolDim1(i), static_cast<uint32_t>(Mix64(h)));
  return {UnitFloat(x), UnitFloat(y)};
}

Eigen::Vector2f ConcentricDisc(const Eigen::Vector2f& u) {
  const float a = 2 * u.x() - 1, b = 2 * u.y() - 1;
  if (a == 0 && b == 0) return {0, 0};
  float r, phi;
  if (std::abs(a) > std::abs(b)) {
    r = a;
    phi = (kPiF / 4) * (b / a);
  } else {
    r = b;
    phi = kPiF / 2 - (kPiF / 4) * (a / b);
  }
  return {r * std::cos(phi), r * std::sin(phi)};
}

Eigen::Vector3f UniformCone(const Eigen::Vector2f& u, float cos_max) {
  const float cos_theta = 1 - u.x() * (1 - cos_max);
  const float sin_theta = std::sqrt(std::max(0.0f, 1 - cos_theta * cos_theta));
  const float phi = 2 * kPiF * u.y();
  return {sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta};
}

void OrthonormalBasis(const Eigen::Vector3f& n, Eigen::Vector3f* t, Eigen::Vector3f* b) {
  const float sign = std::copysign(1.0f, n.z());
  const float a = -1.0f / (sign + n.z());
  const float c = n.x() * n.y() * a;
  *t = Eigen::Vector3f(1 + sign * n.x() * n.x() * a, sign * c, -sign * n.x());
  *b = Eigen::Vector3f(c, sign + n.y() * n.y() * a, -n.y());
}

}  // namespace cadsynth
