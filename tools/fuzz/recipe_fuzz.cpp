// libFuzzer harness: any bytes given as a recipe become a RunSpec or one cadsynth::Error, never a
// crash, a hang or another exception. Build with -DCADSYNTH_FUZZ=ON (clang); see README.
#include <cstddef>
#include <cstdint>
#include <string>

#include "cad/error.h"
#include "recipes/recipe.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    cadsynth::ParseRecipe(std::string(reinterpret_cast<const char*>(data), size), "fuzz.yaml",
                          "/nonexistent");
  } catch (const cadsynth::Error&) {
  }
  return 0;
}
