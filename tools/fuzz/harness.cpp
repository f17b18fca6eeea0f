// The libFuzzer entry point of one target of tools/fuzz/targets.h, chosen at compile time
// (CADSYNTH_FUZZ_TARGET). Build with -DCADSYNTH_FUZZ=ON and clang; docs/testing.md, "Sanitizers and
// fuzzing".
#include "tools/fuzz/targets.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return cadsynth::fuzz::CADSYNTH_FUZZ_TARGET(data, size);
}
