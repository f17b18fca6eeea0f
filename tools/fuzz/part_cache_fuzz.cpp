// libFuzzer harness for the part cache's decoder of convex hulls (cad/part_cache.h): damaged bytes
// give one cadsynth::Error, never a read out of bounds or a hull that names a missing corner.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "cad/error.h"
#include "cad/part_cache.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    const cadsynth::ConvexHull hull =
        cadsynth::DecodeHull(std::string_view(reinterpret_cast<const char*>(data), size));
    for (const auto& t : hull.triangles) {
      for (int v : t) {
        if (v < 0 || static_cast<size_t>(v) >= hull.vertices.size()) __builtin_trap();
      }
    }
  } catch (const cadsynth::Error&) {
  }
  return 0;
}
