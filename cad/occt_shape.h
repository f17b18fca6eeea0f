// Access to the OpenCASCADE shape inside cadsynth::Shape. Include only from .cpp files of cad/
// and variants/: it pulls in OpenCASCADE headers.
#pragma once

#include <memory>

#include <Eigen/Geometry>
#include <TopoDS_Shape.hxx>
#include <gp_Trsf.hxx>

#include "cad/brep.h"

namespace cadsynth {

struct Shape::Impl {
  TopoDS_Shape shape;
};

inline Shape WrapShape(const TopoDS_Shape& shape) {
  return Shape(std::make_shared<const Shape::Impl>(Shape::Impl{shape}));
}

inline const TopoDS_Shape& OcctShape(const Shape& shape) { return shape.impl().shape; }

// The same rigid transform as OpenCASCADE's gp_Trsf.
inline gp_Trsf ToTrsf(const Eigen::Isometry3d& t) {
  const Eigen::Matrix3d& r = t.linear();
  const Eigen::Vector3d& p = t.translation();
  gp_Trsf trsf;
  trsf.SetValues(r(0, 0), r(0, 1), r(0, 2), p.x(), r(1, 0), r(1, 1), r(1, 2), p.y(), r(2, 0),
                 r(2, 1), r(2, 2), p.z());
  return trsf;
}

}  // namespace cadsynth
