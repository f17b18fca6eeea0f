// Access to the OpenCASCADE shape inside cadsynth::Shape. Include only from .cpp files of cad/
// and variants/: it pulls in OpenCASCADE headers.
#pragma once

#include <memory>

#include <TopoDS_Shape.hxx>

#include "cad/shape.h"

namespace cadsynth {

struct Shape::Impl {
  TopoDS_Shape shape;
};

inline Shape WrapShape(const TopoDS_Shape& shape) {
  return Shape(std::make_shared<const Shape::Impl>(Shape::Impl{shape}));
}

inline const TopoDS_Shape& OcctShape(const Shape& shape) { return shape.impl().shape; }

}  // namespace cadsynth
