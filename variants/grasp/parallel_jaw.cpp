#include "variants/grasp/parallel_jaw.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>

#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/collision_object.h>

#include "cad/core/error.h"
#include "cad/core/random.h"
#include "variants/grasp/grasp_geometry.h"

namespace cadsynth {

bool AntipodalOptions::Check(std::string* why) const {
  if (!(friction > 0 && friction <= 10)) {
    *why = "friction (mu) must lie in (0, 10]";
  } else if (samples < 1 || samples > 10000000) {
    *why = "samples must be 1 to 10,000,000";
  } else if (approaches < 1 || approaches > 360) {
    *why = "approaches must be 1 to 360";
  } else if (!(clearance_mm >= 0 && clearance_mm <= 1000)) {
    *why = "clearance must lie in [0, 1000] mm";
  } else if (depths_mm.size() > 64) {
    *why = "at most 64 depths";
  } else if (max_grasps < 0) {
    *why = "the number of grasps per part must not be negative";
  } else {
    return true;
  }
  return false;
}

std::vector<ParallelJawGrasp> SampleAntipodalGrasps(const Part& part,
                                                    const ParallelJawGripper& gripper,
                                                    const AntipodalOptions& o) {
  std::string why;
  if (!gripper.Check(&why)) throw Error("gripper '" + gripper.name + "': " + why);
  if (!o.Check(&why)) throw Error("grasps: " + why);
  const Mesh& mesh = part.mesh;
  if (mesh.triangles.empty()) throw Error("grasps: part '" + part.name + "' has no triangles");

  const grasp_detail::SurfaceSampler surface(mesh);
  if (!(surface.area() > 0)) throw Error("grasps: part '" + part.name + "' has no area");
  const grasp_detail::MeshRays rays(mesh);
  // The part and the open gripper for FCL.
  const fcl::CollisionObjectd part_object(grasp_detail::FclMesh(mesh),
                                          fcl::Transform3d::Identity());
  const auto collides = [&](const Eigen::Isometry3d& model_from_gripper, double opening) {
    for (const grasp_detail::ToolShape& shape : grasp_detail::GripperShapes(gripper, opening)) {
      const fcl::CollisionObjectd object(shape.shape, model_from_gripper * shape.pose);
      fcl::CollisionRequestd request;
      fcl::CollisionResultd result;
      fcl::collide(&part_object, &object, request, result);
      if (result.isCollision()) return true;
    }
    return false;
  };

  std::vector<double> depths = o.depths_mm;
  if (depths.empty()) depths.push_back(gripper.pad_mm);
  for (const double depth : depths) {
    if (!(depth >= 0 && depth <= gripper.finger_length_mm))
      throw Error("grasps: a depth of " + std::to_string(depth) + " mm is off the " + gripper.name +
                  "'s fingers (0 to " + std::to_string(gripper.finger_length_mm) + " mm)");
  }
  const double cone = std::atan(o.friction);
  std::vector<ParallelJawGrasp> grasps;
  const size_t cap = o.max_grasps > 0 ? static_cast<size_t>(o.max_grasps) : SIZE_MAX;
  for (int s = 0; s < o.samples && grasps.size() < cap; ++s) {
    const uint64_t i = static_cast<uint64_t>(s);
    size_t tri = 0;
    const Eigen::Vector3d p1 =
        surface.Point(UniformDraw(o.seed, streams::kGraspPoint, (i << 2) + 0),
                      UniformDraw(o.seed, streams::kGraspPoint, (i << 2) + 1),
                      UniformDraw(o.seed, streams::kGraspPoint, (i << 2) + 2), &tri);
    const Eigen::Vector3d n1 = surface.Normal(tri);
    // Closing along the inward normal; the far contact where the axis leaves the part.
    const Eigen::Vector3d x = -n1;
    size_t far = 0;
    double width = 0;
    if (!rays.First(p1, x, 1e-6, &width, &far) || far == tri || !(width > 0)) continue;
    if (width + 2 * o.clearance_mm > gripper.max_opening_mm) continue;
    const double opening = width + 2 * o.clearance_mm;
    const Eigen::Vector3d n2 = surface.Normal(far);
    // The far jaw pushes along -x: its contact holds when its outward normal n2 lies within
    // `cone` of +x (the axis leaves the part through it).
    const double angle = std::acos(std::clamp(n2.dot(x), -1.0, 1.0));
    if (angle > cone) continue;
    const Eigen::Vector3d p2 = p1 + width * x;
    const Eigen::Vector3d centre = 0.5 * (p1 + p2);
    // Approaches about the axis, evenly spaced from a drawn start.
    const Eigen::Vector3d helper =
        std::abs(x.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    const Eigen::Vector3d e1 = x.cross(helper).normalized(), e2 = x.cross(e1);
    const double start = 2 * M_PI * UniformDraw(o.seed, streams::kGraspApproach, i);
    for (int k = 0; k < o.approaches; ++k) {
      const double phi = start + 2 * M_PI * k / o.approaches;
      const Eigen::Vector3d z = std::cos(phi) * e1 + std::sin(phi) * e2;
      const Eigen::Vector3d y = z.cross(x);
      for (const double depth : depths) {
        ParallelJawGrasp g;
        g.model_from_gripper.linear().col(0) = x;
        g.model_from_gripper.linear().col(1) = y;
        g.model_from_gripper.linear().col(2) = z;
        g.model_from_gripper.translation() = centre - (gripper.tip_mm() - depth) * z;
        if (collides(g.model_from_gripper, opening)) continue;
        g.free_when_open = opening >= gripper.max_opening_mm ||
                           !collides(g.model_from_gripper, gripper.max_opening_mm);
        g.width_mm = width;
        g.opening_mm = opening;
        g.depth_mm = depth;
        g.contacts[0] = p1;
        g.contacts[1] = p2;
        g.normals[0] = n1;
        g.normals[1] = n2;
        g.quality = 1.0 - angle / cone;
        grasps.push_back(g);
        if (grasps.size() >= cap) return grasps;
      }
    }
  }
  return grasps;
}

}  // namespace cadsynth
