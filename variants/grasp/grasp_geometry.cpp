#include "variants/grasp/grasp_geometry.h"

#include <algorithm>
#include <cmath>

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>
#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/cylinder.h>

namespace cadsynth::grasp_detail {

namespace {
using K = CGAL::Simple_cartesian<double>;
using Triangles = std::vector<K::Triangle_3>;
using Primitive = CGAL::AABB_triangle_primitive<K, Triangles::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;
}  // namespace

struct MeshRays::Impl {
  Triangles triangles;
  Tree tree;
};

MeshRays::MeshRays(const Mesh& mesh) : impl_(std::make_unique<Impl>()) {
  const auto point = [&](uint32_t i) {
    const Eigen::Vector3f& p = mesh.positions[i];
    return K::Point_3(p.x(), p.y(), p.z());
  };
  impl_->triangles.reserve(mesh.triangles.size());
  for (const auto& t : mesh.triangles)
    impl_->triangles.emplace_back(point(t[0]), point(t[1]), point(t[2]));
  impl_->tree.insert(impl_->triangles.cbegin(), impl_->triangles.cend());
  impl_->tree.build();
}

MeshRays::~MeshRays() = default;

bool MeshRays::First(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min, double* t,
                     size_t* triangle) const {
  if (impl_->triangles.empty()) return false;
  const Eigen::Vector3d s = o + t_min * d;
  const K::Ray_3 ray(K::Point_3(s.x(), s.y(), s.z()), K::Vector_3(d.x(), d.y(), d.z()));
  const auto hit = impl_->tree.first_intersection(ray);
  if (!hit) return false;
  const auto along = [&](const K::Point_3& p) {
    return (p.x() - o.x()) * d.x() + (p.y() - o.y()) * d.y() + (p.z() - o.z()) * d.z();
  };
  if (const K::Point_3* p = boost::get<K::Point_3>(&hit->first)) {
    *t = along(*p);
  } else if (const K::Segment_3* seg = boost::get<K::Segment_3>(&hit->first)) {
    *t = std::min(along(seg->source()), along(seg->target()));  // a ray in the triangle's plane
  } else {
    return false;
  }
  *triangle = static_cast<size_t>(hit->second - impl_->triangles.cbegin());
  return true;
}

SurfaceSampler::SurfaceSampler(const Mesh& mesh) : mesh_(mesh) {
  double total = 0;
  cumulative_.reserve(mesh.triangles.size());
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.positions[t[0]].cast<double>();
    total += 0.5 * (mesh.positions[t[1]].cast<double>() - a)
                       .cross(mesh.positions[t[2]].cast<double>() - a)
                       .norm();
    cumulative_.push_back(total);
  }
}

Eigen::Vector3d SurfaceSampler::Point(double r0, double r1, double r2, size_t* triangle) const {
  const size_t tri = std::min<size_t>(
      cumulative_.size() - 1,
      std::upper_bound(cumulative_.begin(), cumulative_.end(), r0 * area()) - cumulative_.begin());
  if (r1 + r2 > 1) r1 = 1 - r1, r2 = 1 - r2;
  const auto& t = mesh_.triangles[tri];
  const Eigen::Vector3d a = mesh_.positions[t[0]].cast<double>();
  *triangle = tri;
  return a + r1 * (mesh_.positions[t[1]].cast<double>() - a) +
         r2 * (mesh_.positions[t[2]].cast<double>() - a);
}

Eigen::Vector3d SurfaceSampler::Normal(size_t i) const {
  const auto& t = mesh_.triangles[i];
  const Eigen::Vector3d a = mesh_.positions[t[0]].cast<double>();
  return (mesh_.positions[t[1]].cast<double>() - a)
      .cross(mesh_.positions[t[2]].cast<double>() - a)
      .normalized();
}

std::shared_ptr<fcl::BVHModel<fcl::OBBd>> FclMesh(const Mesh& mesh) {
  auto model = std::make_shared<fcl::BVHModel<fcl::OBBd>>();
  std::vector<fcl::Vector3d> points;
  points.reserve(mesh.positions.size());
  for (const Eigen::Vector3f& p : mesh.positions) points.push_back(p.cast<double>());
  std::vector<fcl::Triangle> triangles;
  triangles.reserve(mesh.triangles.size());
  for (const auto& t : mesh.triangles) triangles.emplace_back(t[0], t[1], t[2]);
  model->beginModel();
  model->addSubModel(points, triangles);
  model->endModel();
  return model;
}

namespace {
// A box from z0 to z1 (z0 < z1) of sides sx, sy centred at (cx, 0) in x, y.
ToolShape SlabBox(double sx, double sy, double z0, double z1, double cx) {
  ToolShape s;
  s.shape = std::make_shared<fcl::Boxd>(sx, sy, z1 - z0);
  s.pose.translation() = Eigen::Vector3d(cx, 0.0, 0.5 * (z0 + z1));
  return s;
}
ToolShape Rod(double diameter, double z0, double z1) {
  ToolShape s;
  s.shape = std::make_shared<fcl::Cylinderd>(0.5 * diameter, z1 - z0);  // fcl: along z, centred
  s.pose.translation() = Eigen::Vector3d(0.0, 0.0, 0.5 * (z0 + z1));
  return s;
}
}  // namespace

std::vector<ToolShape> GripperShapes(const ParallelJawGripper& g, double opening_mm,
                                     double back_mm) {
  std::vector<ToolShape> shapes;
  // The palm first: checks stop at the first shape that hits, and the palm, the largest, is the
  // one that hits most often in a pile (placing a 60-bolt pile's grasps: 2.1 s fingers first,
  // 0.6 s palm first; the same grasps either way).
  if (g.palm_width_mm > 0 && g.palm_depth_mm > 0 && g.palm_height_mm + back_mm > 0) {
    shapes.push_back(SlabBox(g.palm_width_mm, g.palm_depth_mm, -back_mm, g.palm_height_mm, 0.0));
  }
  const double half = 0.5 * opening_mm;
  for (const double side : {-1.0, 1.0}) {
    shapes.push_back(SlabBox(g.finger_thickness_mm, g.finger_width_mm, g.palm_height_mm - back_mm,
                             g.tip_mm(), side * (half + 0.5 * g.finger_thickness_mm)));
  }
  return shapes;
}

std::vector<ToolShape> SuctionShapes(const SuctionCup& cup, double lift_mm, double back_mm) {
  std::vector<ToolShape> shapes;
  if (cup.cup_length_mm > lift_mm)
    shapes.push_back(Rod(cup.diameter_mm, -cup.cup_length_mm - back_mm, -lift_mm));
  if (cup.shaft_length_mm > 0) {
    shapes.push_back(Rod(cup.shaft_diameter_mm, -cup.cup_length_mm - cup.shaft_length_mm - back_mm,
                         -cup.cup_length_mm));
  }
  return shapes;
}

Eigen::Matrix3d FrameFromZ(const Eigen::Vector3d& z) {
  const Eigen::Vector3d hint =
      std::abs(z.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d x = (hint - hint.dot(z) * z).normalized();
  Eigen::Matrix3d r;
  r.col(0) = x;
  r.col(1) = z.cross(x);
  r.col(2) = z;
  return r;
}

}  // namespace cadsynth::grasp_detail
