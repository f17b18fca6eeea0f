// Internal to cad/: turning an OpenCASCADE XDE document (from STEP or IGES) into an Assembly.
#pragma once

#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <Standard_Failure.hxx>
#include <TDocStd_Document.hxx>

#include "cad/part.h"
#include "cad/shape.h"

namespace cadsynth::internal {

// Silences OpenCASCADE's console chatter and sets the translators to millimetres. Idempotent.
void InitOcct();

// What an OpenCASCADE exception says about the file, in plain words: its own message when that is
// a sentence, else what its kind means ("a value out of range (a damaged index?)" for
// Standard_OutOfRange, whose message is only a class name such as "NCollection_Sequence::Value").
std::string PlainFailure(const Standard_Failure& failure);

// XDE documents come from a process-wide application object: create and read them one at a time.
std::mutex& XdeMutex();

// A new XDE document, closed when the guard goes out of scope. Create under XdeMutex().
struct DocumentGuard {
  Handle(TDocStd_Document) doc;
  DocumentGuard();
  ~DocumentGuard();
  DocumentGuard(const DocumentGuard&) = delete;
  DocumentGuard& operator=(const DocumentGuard&) = delete;
};

// What an XDE document holds, before tessellation.
struct CadContents {
  std::string name;
  std::vector<std::string> part_names;
  std::vector<Shape> part_shapes;
  std::vector<std::optional<Eigen::Vector3f>> part_colors;
  std::vector<Instance> instances;  // world_from_model = placement in the root frame (no centring)
};

// Walks the free shapes and their assembly structure: one part per distinct prototype label, one
// instance per occurrence, names and colours (an instance's colour wins over its part's).
CadContents CollectDocument(const Handle(TDocStd_Document) & doc, const std::string& file);

// Tessellates the parts in parallel (parts that yield no triangles are dropped with a warning),
// moves each into its model frame and fixes the instance poses to match. Throws when nothing is
// left.
Assembly BuildAssembly(const std::string& file, CadContents contents,
                       const TessellationOptions& options);

// Throws Error("FILE: ...") unless `path` names a non-empty regular file.
void RequireReadableFile(const std::string& file);

}  // namespace cadsynth::internal
