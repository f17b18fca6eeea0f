// The opaque handle to an exact B-rep shape. OpenCASCADE types never leave cad/ and variants/:
// its Impl is defined in cad/occt_shape.h, for their .cpp files only.
#pragma once

#include <memory>

#include <Eigen/Geometry>

namespace cadsynth {

// A B-rep shape (solid, compound of solids, shell...). Cheap to copy: copies share the geometry.
class Shape {
 public:
  struct Impl;  // defined in cad/occt_shape.h, for cad/ and variants/ sources only

  Shape();
  explicit Shape(std::shared_ptr<const Impl> impl);

  bool IsNull() const;
  // True when the shape has at least one face (wires and points have none).
  bool HasFaces() const;
  // Axis-aligned bounds in mm (from the exact geometry, with OpenCASCADE's small tolerance gap).
  Eigen::AlignedBox3d Bounds() const;
  const Impl& impl() const { return *impl_; }

 private:
  std::shared_ptr<const Impl> impl_;
};

}  // namespace cadsynth
