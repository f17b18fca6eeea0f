#include "variants/grasp/parallel_jaw.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/geometry/shape/box.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/collision_object.h>

#include "cad/error.h"
#include "cad/random.h"

namespace cadsynth {

namespace {

// The nearest hit beyond t > 0 of the ray o + t d with a triangle of `mesh` (Moller-Trumbore,
// both sides), or -1.
double NearestHit(const Mesh& mesh, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                  size_t* triangle) {
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < mesh.triangles.size(); ++i) {
    const auto& t = mesh.triangles[i];
    const Eigen::Vector3d a = mesh.positions[t[0]].cast<double>();
    const Eigen::Vector3d e1 = mesh.positions[t[1]].cast<double>() - a;
    const Eigen::Vector3d e2 = mesh.positions[t[2]].cast<double>() - a;
    const Eigen::Vector3d p = d.cross(e2);
    const double det = e1.dot(p);
    if (std::abs(det) < 1e-12) continue;
    const Eigen::Vector3d s = o - a;
    const double u = s.dot(p) / det;
    if (u < 0 || u > 1) continue;
    const Eigen::Vector3d q = s.cross(e1);
    const double v = d.dot(q) / det;
    if (v < 0 || u + v > 1) continue;
    const double dist = e2.dot(q) / det;
    if (dist > 1e-9 && dist < best) {
      best = dist;
      *triangle = i;
    }
  }
  return std::isfinite(best) ? best : -1.0;
}

Eigen::Vector3d FaceNormal(const Mesh& mesh, size_t i) {
  const auto& t = mesh.triangles[i];
  const Eigen::Vector3d a = mesh.positions[t[0]].cast<double>();
  return (mesh.positions[t[1]].cast<double>() - a)
      .cross(mesh.positions[t[2]].cast<double>() - a)
      .normalized();
}

}  // namespace

bool ParallelJawGripper::Check(std::string* why) const {
  if (!(max_opening_mm > 0 && max_opening_mm < 1000)) {
    *why = "max_opening must lie in (0, 1000) mm";
  } else if (!(finger_width_mm > 0) || !(finger_thickness_mm > 0) || !(finger_length_mm > 0)) {
    *why = "finger width, thickness and length must be positive";
  } else if (!(palm_height_mm >= 0) || !(palm_width_mm >= 0) || !(palm_depth_mm >= 0)) {
    *why = "palm sizes must not be negative";
  } else if (!(pad_mm >= 0 && pad_mm <= finger_length_mm)) {
    *why = "pad must lie on the finger (0 to finger_length below the tip)";
  } else {
    return true;
  }
  return false;
}

ParallelJawGripper ParallelJawGripper::Franka() { return ParallelJawGripper{}; }

bool AntipodalOptions::Check(std::string* why) const {
  if (!(friction > 0 && friction <= 10)) {
    *why = "friction (mu) must lie in (0, 10]";
  } else if (samples < 1 || samples > 10000000) {
    *why = "samples must be 1 to 10,000,000";
  } else if (approaches < 1 || approaches > 360) {
    *why = "approaches must be 1 to 360";
  } else if (!(clearance_mm >= 0)) {
    *why = "clearance must not be negative";
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

  // Triangles by area, for surface points drawn uniformly.
  std::vector<double> cumulative;
  double total = 0;
  for (size_t i = 0; i < mesh.triangles.size(); ++i) {
    const auto& t = mesh.triangles[i];
    const Eigen::Vector3d a = mesh.positions[t[0]].cast<double>();
    total += 0.5 * (mesh.positions[t[1]].cast<double>() - a)
                       .cross(mesh.positions[t[2]].cast<double>() - a)
                       .norm();
    cumulative.push_back(total);
  }
  if (!(total > 0)) throw Error("grasps: part '" + part.name + "' has no area");

  // The part for FCL: a bounding-volume hierarchy of its triangles.
  auto model = std::make_shared<fcl::BVHModel<fcl::OBBRSSd>>();
  {
    std::vector<fcl::Vector3d> points;
    for (const Eigen::Vector3f& p : mesh.positions) points.push_back(p.cast<double>());
    std::vector<fcl::Triangle> triangles;
    for (const auto& t : mesh.triangles) triangles.emplace_back(t[0], t[1], t[2]);
    model->beginModel();
    model->addSubModel(points, triangles);
    model->endModel();
  }
  const fcl::CollisionObjectd part_object(model, fcl::Transform3d::Identity());
  // The open gripper's boxes in its frame.
  struct Box {
    std::shared_ptr<fcl::Boxd> shape;
    Eigen::Vector3d centre;
  };
  const double half = 0.5 * gripper.max_opening_mm;
  const double finger_z = gripper.palm_height_mm + 0.5 * gripper.finger_length_mm;
  std::vector<Box> boxes;
  for (const double side : {-1.0, 1.0}) {
    boxes.push_back({std::make_shared<fcl::Boxd>(gripper.finger_thickness_mm,
                                                 gripper.finger_width_mm, gripper.finger_length_mm),
                     {side * (half + 0.5 * gripper.finger_thickness_mm), 0.0, finger_z}});
  }
  if (gripper.palm_height_mm > 0 && gripper.palm_width_mm > 0 && gripper.palm_depth_mm > 0) {
    boxes.push_back({std::make_shared<fcl::Boxd>(gripper.palm_width_mm, gripper.palm_depth_mm,
                                                 gripper.palm_height_mm),
                     {0.0, 0.0, 0.5 * gripper.palm_height_mm}});
  }
  const auto collides = [&](const Eigen::Isometry3d& model_from_gripper) {
    for (const Box& box : boxes) {
      fcl::Transform3d at = model_from_gripper * Eigen::Translation3d(box.centre);
      const fcl::CollisionObjectd object(box.shape, at);
      fcl::CollisionRequestd request;
      fcl::CollisionResultd result;
      fcl::collide(&part_object, &object, request, result);
      if (result.isCollision()) return true;
    }
    return false;
  };

  const double cone = std::atan(o.friction);
  std::vector<ParallelJawGrasp> grasps;
  for (int s = 0; s < o.samples; ++s) {
    const uint64_t i = static_cast<uint64_t>(s);
    const double pick = UniformDraw(o.seed, streams::kGraspPoint, (i << 2) + 0) * total;
    const size_t tri = std::min<size_t>(
        mesh.triangles.size() - 1,
        std::upper_bound(cumulative.begin(), cumulative.end(), pick) - cumulative.begin());
    double u = UniformDraw(o.seed, streams::kGraspPoint, (i << 2) + 1);
    double v = UniformDraw(o.seed, streams::kGraspPoint, (i << 2) + 2);
    if (u + v > 1) u = 1 - u, v = 1 - v;
    const auto& t = mesh.triangles[tri];
    const Eigen::Vector3d a = mesh.positions[t[0]].cast<double>();
    const Eigen::Vector3d p1 = a + u * (mesh.positions[t[1]].cast<double>() - a) +
                               v * (mesh.positions[t[2]].cast<double>() - a);
    const Eigen::Vector3d n1 = FaceNormal(mesh, tri);
    // Closing along the inward normal; the far contact where the axis leaves the part.
    const Eigen::Vector3d x = -n1;
    size_t far = 0;
    const double width = NearestHit(mesh, p1 + 1e-6 * x, x, &far);
    if (width <= 0 || far == tri) continue;
    if (width + 2 * o.clearance_mm > gripper.max_opening_mm) continue;
    const Eigen::Vector3d n2 = FaceNormal(mesh, far);
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
      ParallelJawGrasp g;
      g.model_from_gripper.linear().col(0) = x;
      g.model_from_gripper.linear().col(1) = y;
      g.model_from_gripper.linear().col(2) = z;
      g.model_from_gripper.translation() = centre - (gripper.tip_mm() - gripper.pad_mm) * z;
      if (collides(g.model_from_gripper)) continue;
      g.width_mm = width;
      g.contacts[0] = p1;
      g.contacts[1] = p2;
      g.normals[0] = n1;
      g.normals[1] = n2;
      g.quality = 1.0 - angle / cone;
      grasps.push_back(g);
    }
  }
  return grasps;
}

}  // namespace cadsynth
