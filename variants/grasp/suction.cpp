#include "variants/grasp/suction.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/collision_object.h>

#include "cad/core/error.h"
#include "cad/core/random.h"
#include "variants/grasp/grasp_geometry.h"
#include "variants/grasp/scene_grasps.h"

namespace cadsynth {

namespace {

// The seal score of the cup at c approaching along a on the mesh behind `rays` (see
// SampleSuctionGrasps); `reach` is a distance from c that clears the part. *rim_height: the
// rim's highest hit above c towards the cup.
double Seal(const grasp_detail::MeshRays& rays, const SuctionCup& cup, const Eigen::Vector3d& c,
            const Eigen::Vector3d& a, double reach, double* rim_height) {
  double t = 0;
  size_t triangle = 0;
  // c must be the first surface the approach meets.
  if (!rays.First(c - reach * a, a, 0.0, &t, &triangle)) return -1;
  if (std::abs(t - reach) > 1e-6 * reach + 1e-4) return -1;
  const Eigen::Matrix3d frame = grasp_detail::FrameFromZ(a);
  const int n = cup.ring_points;
  const double r = cup.radius_mm();
  std::vector<Eigen::Vector3d> rim(static_cast<size_t>(n));
  std::vector<double> height(static_cast<size_t>(n));  // towards the cup, from c's tangent plane
  for (int i = 0; i < n; ++i) {
    const double theta = 2 * M_PI * i / n;
    const Eigen::Vector3d start =
        c + r * (std::cos(theta) * frame.col(0) + std::sin(theta) * frame.col(1)) - reach * a;
    if (!rays.First(start, a, 0.0, &t, &triangle)) return -1;  // off the part: a leak
    rim[static_cast<size_t>(i)] = start + t * a;
    height[static_cast<size_t>(i)] = reach - t;
  }
  // Least-squares plane h = h0 + hx cos + hy sin over the evenly spaced ring (closed form).
  double h0 = 0, hx = 0, hy = 0;
  for (int i = 0; i < n; ++i) {
    const double theta = 2 * M_PI * i / n;
    h0 += height[static_cast<size_t>(i)] / n;
    hx += 2.0 / n * height[static_cast<size_t>(i)] * std::cos(theta);
    hy += 2.0 / n * height[static_cast<size_t>(i)] * std::sin(theta);
  }
  *rim_height = std::max(0.0, *std::max_element(height.begin(), height.end()));
  double off_plane = 0;
  for (int i = 0; i < n; ++i) {
    const double theta = 2 * M_PI * i / n;
    off_plane = std::max(off_plane, std::abs(height[static_cast<size_t>(i)] - h0 -
                                             hx * std::cos(theta) - hy * std::sin(theta)));
  }
  const double rest = 2 * r * std::sin(M_PI / n);
  double stretch = 0;
  for (int i = 0; i < n; ++i) {
    const double length =
        (rim[static_cast<size_t>((i + 1) % n)] - rim[static_cast<size_t>(i)]).norm();
    stretch = std::max(stretch, std::abs(length / rest - 1));
  }
  return 1.0 - std::max(off_plane / cup.compliance_mm, stretch / cup.stretch);
}

// A distance from any point of the mesh that clears it: its bounding box's diagonal plus a margin.
double Reach(const Mesh& mesh) {
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3f& p : mesh.positions) box.extend(p.cast<double>());
  return box.diagonal().norm() + 10.0;
}

void CheckInputs(const Part& part, const SuctionCup& cup) {
  std::string why;
  if (!cup.Check(&why)) throw Error("suction cup '" + cup.name + "': " + why);
  if (part.mesh.triangles.empty())
    throw Error("suction: part '" + part.name + "' has no triangles");
}

}  // namespace

bool SuctionOptions::Check(std::string* why) const {
  if (samples < 1 || samples > 10000000) {
    *why = "samples must be 1 to 10,000,000";
  } else if (!(density_kg_m3 > 0 && density_kg_m3 <= 100000)) {
    *why = "density must lie in (0, 100000] kg/m^3";
  } else if (!(gravity_m_s2 >= 0 && gravity_m_s2 <= 1000)) {
    *why = "gravity must lie in [0, 1000] m/s^2";
  } else if (max_grasps < 0) {
    *why = "the number of grasps per part must not be negative";
  } else {
    return true;
  }
  return false;
}

double SuctionSeal(const Part& part, const SuctionCup& cup, const Eigen::Vector3d& c,
                   const Eigen::Vector3d& a) {
  CheckInputs(part, cup);
  const grasp_detail::MeshRays rays(part.mesh);
  double rim_height = 0;
  return Seal(rays, cup, c, a.normalized(), Reach(part.mesh), &rim_height);
}

std::vector<SuctionGrasp> SampleSuctionGrasps(const Part& part, const SuctionCup& cup,
                                              const SuctionOptions& o) {
  CheckInputs(part, cup);
  std::string why;
  if (!o.Check(&why)) throw Error("suction: " + why);
  const grasp_detail::SurfaceSampler surface(part.mesh);
  if (!(surface.area() > 0)) throw Error("suction: part '" + part.name + "' has no area");
  const grasp_detail::MeshRays rays(part.mesh);
  const fcl::CollisionObjectd part_object(grasp_detail::FclMesh(part.mesh),
                                          fcl::Transform3d::Identity());
  const double reach = Reach(part.mesh);
  const double weight = o.density_kg_m3 * part.mass.volume_mm3 * 1e-9 * o.gravity_m_s2;  // N
  const double vacuum = cup.vacuum_force_n();
  const double radius_m = 1e-3 * cup.radius_mm();
  std::vector<SuctionGrasp> grasps;
  const size_t cap = o.max_grasps > 0 ? static_cast<size_t>(o.max_grasps) : SIZE_MAX;
  for (int s = 0; s < o.samples && grasps.size() < cap; ++s) {
    const uint64_t i = static_cast<uint64_t>(s);
    size_t tri = 0;
    const Eigen::Vector3d c =
        surface.Point(UniformDraw(o.seed, streams::kSuctionPoint, (i << 2) + 0),
                      UniformDraw(o.seed, streams::kSuctionPoint, (i << 2) + 1),
                      UniformDraw(o.seed, streams::kSuctionPoint, (i << 2) + 2), &tri);
    const Eigen::Vector3d a = -surface.Normal(tri);
    double rim_height = 0;
    const double seal = Seal(rays, cup, c, a, reach, &rim_height);
    if (!(seal > 0)) continue;
    // The cup's body, from just above the rim up, and the shaft must be free of the part (a pin
    // or a wall inside or beside the rim).
    const Eigen::Isometry3d model_from_tool = ModelFromSuctionTool({c, a});
    bool hits = false;
    for (const grasp_detail::ToolShape& shape :
         grasp_detail::SuctionShapes(cup, rim_height + grasp_detail::kRimClearanceMm)) {
      const fcl::CollisionObjectd object(shape.shape, model_from_tool * shape.pose);
      fcl::CollisionRequestd request;
      fcl::CollisionResultd result;
      fcl::collide(&part_object, &object, request, result);
      hits = hits || result.isCollision();
    }
    if (hits) continue;
    const Eigen::Vector3d r = part.mass.center_of_mass - c;
    const double arm_m = 1e-3 * (r - r.dot(a) * a).norm();
    const double wrench = 1.0 - (weight + 2.0 * weight * arm_m / radius_m) / vacuum;
    if (!(wrench > 0)) continue;
    SuctionGrasp g;
    g.point = c;
    g.approach = a;
    g.seal = seal;
    g.wrench = wrench;
    g.rim_height_mm = rim_height;
    grasps.push_back(g);
  }
  return grasps;
}

}  // namespace cadsynth
