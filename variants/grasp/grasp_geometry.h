// Geometry the grasp samplers and the scene check share (internal to variants/grasp/): ray
// queries on a part's mesh (CGAL's AABB tree) and the tools' collision shapes (FCL).
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/geometry/collision_geometry.h>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "cad/grasp.h"
#include "cad/mesh.h"

namespace cadsynth::grasp_detail {

// First hits of rays with a mesh's triangles (both sides), through CGAL's AABB tree.
class MeshRays {
 public:
  explicit MeshRays(const Mesh& mesh);
  ~MeshRays();
  MeshRays(const MeshRays&) = delete;
  MeshRays& operator=(const MeshRays&) = delete;
  // The nearest hit of o + t d (d unit) with t > t_min: true, with t and the triangle's index.
  bool First(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min, double* t,
             size_t* triangle) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Points drawn uniformly by area on a mesh's triangles.
class SurfaceSampler {
 public:
  explicit SurfaceSampler(const Mesh& mesh);
  double area() const { return cumulative_.empty() ? 0.0 : cumulative_.back(); }
  // The point for three uniform numbers in [0, 1): r0 picks the triangle by area, r1 and r2 the
  // barycentrics (folded into the triangle); its triangle in *triangle.
  Eigen::Vector3d Point(double r0, double r1, double r2, size_t* triangle) const;
  // The unit normal of triangle i (its winding's; outward for an outward-wound mesh).
  Eigen::Vector3d Normal(size_t i) const;

 private:
  const Mesh& mesh_;
  std::vector<double> cumulative_;
};

// A mesh's triangles as an FCL bounding-volume hierarchy of oriented boxes, in the mesh's frame.
// OBBs, not FCL's usual OBBRSS: collision tests use only the OBB either way, and FCL bounds a
// box or cylinder tool in an OBB directly but fits an OBBRSS to its corners by an eigen
// decomposition in every test (half the time of placing a pile's grasps).
std::shared_ptr<fcl::BVHModel<fcl::OBBd>> FclMesh(const Mesh& mesh);

// A solid of a tool in the tool's frame.
struct ToolShape {
  std::shared_ptr<fcl::CollisionGeometryd> shape;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
};

// The parallel-jaw gripper opened to `opening_mm` (the fingers' inner faces at +-opening / 2) as
// boxes in its frame, each stretched `back_mm` further along -z: the volume it sweeps coming in
// from back_mm away.
std::vector<ToolShape> GripperShapes(const ParallelJawGripper& gripper, double opening_mm,
                                     double back_mm = 0);

// How far above the rim's highest point the suction tool's body is checked against its own part.
inline constexpr double kRimClearanceMm = 0.5;

// The suction tool in the frame of its contact (origin at the cup's centre on the surface, +z the
// approach): the cup, a cylinder from z = -cup_length to -lift_mm, and the shaft behind it, each
// stretched back_mm further along -z.
std::vector<ToolShape> SuctionShapes(const SuctionCup& cup, double lift_mm, double back_mm = 0);

// A rotation whose z column is `z` (unit); x is the world x (or y, when z is near x) made
// perpendicular to it.
Eigen::Matrix3d FrameFromZ(const Eigen::Vector3d& z);

}  // namespace cadsynth::grasp_detail
