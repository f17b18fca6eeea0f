#include "cad/core/random.h"

#include <cmath>
#include <cstring>

namespace cadsynth {

double UniformDraw(uint64_t seed, std::string_view stream_name, uint64_t index) {
  return random_detail::Draw(seed, Fnv1a64(stream_name), index);
}

void NormalPairsFloat(const uint64_t* bits, int n, float* z0, float* z1) {
  // Blocks of 64 pairs through plain loops that the compiler vectorises: no branches, the
  // quadrant's choices as selects.
  constexpr int kBlock = 64;
  for (int b = 0; b < n; b += kBlock) {
    const int m = std::min(kBlock, n - b);
    alignas(64) float u1[kBlock], u2[kBlock], r[kBlock];
    for (int i = 0; i < m; ++i) {
      const uint64_t x = bits[b + i];
      // 23 bits each: the centres of the steps, (k + 1/2) 2^-23, are all floats below 1.
      u1[i] = (static_cast<float>(static_cast<int32_t>(x >> 41)) + 0.5f) * 0x1.0p-23f;
      u2[i] = (static_cast<float>(static_cast<int32_t>((x >> 18) & 0x7fffff)) + 0.5f) * 0x1.0p-23f;
    }
    // r = sqrt(-2 ln u1): u1 = m 2^e with m in [sqrt(1/2), sqrt(2)), ln m = 2 atanh(s) =
    // 2 s (1 + s^2/3 + s^4/5 + s^6/7), s = (m - 1) / (m + 1), |s| <= 0.172 (the rest is below
    // 1e-7).
    alignas(64) int32_t word[kBlock];
    std::memcpy(word, u1, sizeof(float) * kBlock);
    for (int i = 0; i < m; ++i) {
      const int32_t w = word[i];
      // The mantissa, scaled into [sqrt(1/2), sqrt(2)) by comparing the word: 0x3fb504f3 is
      // sqrt(2)'s bits with a biased exponent of 0.
      const int32_t mantissa = (w & 0x007fffff) | 0x3f800000;
      const int32_t high = mantissa > 0x3fb504f3 ? 1 : 0;
      word[i] = mantissa - (high << 23);  // halves m when it is above sqrt(2)
      r[i] = static_cast<float>(((w >> 23) & 0xff) - 127 + high);
    }
    alignas(64) float mant[kBlock];
    std::memcpy(mant, word, sizeof(float) * kBlock);
    for (int i = 0; i < m; ++i) {
      const float s = (mant[i] - 1.0f) / (mant[i] + 1.0f), s2 = s * s;
      const float ln = r[i] * 0.693147181f +
                       2.0f * s * (1.0f + s2 * (1.0f / 3 + s2 * (1.0f / 5 + s2 * (1.0f / 7))));
      r[i] = std::sqrt(std::max(0.0f, -2.0f * ln));
    }
    // cos and sin of 2 pi u2 = q pi/2 + t, |t| <= pi/4: Taylor series to t^8 and t^9.
    for (int i = 0; i < m; ++i) {
      const float quarter = 4.0f * u2[i];
      const int32_t q = static_cast<int32_t>(quarter + 0.5f);
      const float t = (quarter - static_cast<float>(q)) * 1.57079633f, t2 = t * t;
      const float sin_t =
          t *
          (1.0f - t2 * (1.0f / 6 - t2 * (1.0f / 120 - t2 * (1.0f / 5040 - t2 * (1.0f / 362880)))));
      const float cos_t =
          1.0f - t2 * (0.5f - t2 * (1.0f / 24 - t2 * (1.0f / 720 - t2 * (1.0f / 40320))));
      const bool odd = q & 1;
      const float c = (odd ? sin_t : cos_t) * (((q + 1) & 2) ? -1.0f : 1.0f);
      const float sn = (odd ? cos_t : sin_t) * ((q & 2) ? -1.0f : 1.0f);
      z0[b + i] = r[i] * c;
      z1[b + i] = r[i] * sn;
    }
  }
}

}  // namespace cadsynth
