// libFuzzer harness for cadsynth's own reader of AP242 tessellated geometry
// (cad/step_tessellated.h): any bytes give an assembly or one cadsynth::Error. The bytes go through
// a file, as the reader takes a path.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>

#include "cad/error.h"
#include "cad/step_tessellated.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::string path = "/tmp/cadsynth_fuzz_" + std::to_string(::getpid()) + ".stp";
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  try {
    cadsynth::internal::ReadStepTessellated(path, 1.0);
  } catch (const cadsynth::Error&) {
  }
  return 0;
}
