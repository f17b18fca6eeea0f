#include "cad/random.h"

namespace cadsynth {

namespace {

double Draw(uint64_t seed, uint64_t stream, uint64_t index) {
  uint64_t x = seed * 0x9E3779B97F4A7C15ull ^
               (stream + 0x632BE59BD9B4E019ull) * 0xBF58476D1CE4E5B9ull ^
               (index + 0x85EBCA77C2B2AE63ull) * 0x94D049BB133111EBull;
  for (int round = 0; round < 2; ++round) {
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    x ^= x >> 31;
  }
  return static_cast<double>(x >> 11) * 0x1.0p-53;
}

}  // namespace

double UniformDraw(uint64_t seed, const RandomStream& stream, uint64_t index) {
  return Draw(seed, stream.id(), index);
}

double UniformDraw(uint64_t seed, std::string_view stream_name, uint64_t index) {
  return Draw(seed, Fnv1a64(stream_name), index);
}

}  // namespace cadsynth
