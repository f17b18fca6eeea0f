// The part families' Boolean operations on OpenCASCADE solids (variants/ only; the public headers
// speak cadsynth::Shape).
#pragma once

#include <string>

#include <BRepAlgoAPI_BooleanOperation.hxx>
#include <TopoDS_Shape.hxx>

#include "cad/core/error.h"

namespace cadsynth {

// Runs `op` (a fuse, cut or common built with its arguments) and returns its result; throws
// Error("OpenCASCADE could not <what>") when OpenCASCADE reports that it failed.
inline TopoDS_Shape RunBoolean(BRepAlgoAPI_BooleanOperation&& op, const std::string& what) {
  op.Build();
  if (!op.IsDone()) throw Error("OpenCASCADE could not " + what);
  return op.Shape();
}

}  // namespace cadsynth
