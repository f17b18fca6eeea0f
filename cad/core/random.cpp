#include "cad/core/random.h"

namespace cadsynth {

double UniformDraw(uint64_t seed, std::string_view stream_name, uint64_t index) {
  return random_detail::Draw(seed, Fnv1a64(stream_name), index);
}

}  // namespace cadsynth
