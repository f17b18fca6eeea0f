// Fuzz targets: each takes any bytes and must end in a result or one cadsynth::Error, never a
// crash, a hang, another exception or (under the sanitizers) undefined behaviour. They are built
// in every build: libFuzzer harnesses (tools/fuzz/harness.cpp, -DCADSYNTH_FUZZ=ON with clang) call
// them, and ctest replays the committed corpus (tests/fuzz_corpus/TARGET/) through them in the
// normal build and the sanitizer build.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace cadsynth::fuzz {

using Target = int (*)(const uint8_t* data, size_t size);

int Recipe(const uint8_t* data, size_t size);           // recipes/recipe.h, the YAML recipe reader
int StepTessellated(const uint8_t* data, size_t size);  // cad/step_tessellated.h (AP242 meshes)
int PartCacheHull(const uint8_t* data, size_t size);    // cad/part_cache.h, the hull decoder
// First byte: 0 STL, 1 PLY, 2 OFF (mod 3); the rest is the file. Our checked readers, then what
// import and prepare do with the mesh: crease normals, topology, mass, hull, stable poses.
int MeshFormats(const uint8_t* data, size_t size);
// First byte: OBJ, glTF, GLB, COLLADA, 3MF (mod 5): assimp's readers and our checks of what they
// return, in this process (cadsynth itself reads these formats in a guarded child process).
int MeshAssimp(const uint8_t* data, size_t size);
// First byte: STEP, IGES, BREP (mod 3): OpenCASCADE's readers through ImportCad, in this process
// (cadsynth itself reads these formats in a guarded child process).
int CadEntry(const uint8_t* data, size_t size);
// First byte: results CSV, scene_gt.json, models_info.json, a frame fragment, a point-cloud PLY
// (mod 5): the BOP readers of eval and merge.
int BopReaders(const uint8_t* data, size_t size);

struct NamedTarget {
  const char* name;  // also the corpus folder's name
  Target target;
  // Targets that read files of several formats: the first byte picks one of these extensions
  // (byte % count), the rest is the file.
  std::vector<std::string> extensions;
  // False for third-party readers (assimp, OpenCASCADE) that may crash on an input: their corpus
  // is replayed through `cadsynth inspect`, which reads such files in a guarded child process.
  bool in_process_safe = true;
};
const std::vector<NamedTarget>& Targets();

}  // namespace cadsynth::fuzz
