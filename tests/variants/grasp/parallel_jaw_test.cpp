// Antipodal grasps against answers worked out by hand (a cube, a cylinder), the friction cone,
// and a collision check that does not use the sampler's (points of the part inside the open
// gripper's boxes).
#include "variants/grasp/parallel_jaw.h"

#include <cmath>

#include <gtest/gtest.h>

#include "cad/core/error.h"
#include "cad/shape.h"

namespace cadsynth {
namespace {

// Whether any of `points` (model frame) lies inside the open gripper's palm or fingers at
// `model_from_gripper` (shrunk by `slack` mm, for points on a box's face).
bool InsideGripper(const std::vector<Eigen::Vector3d>& points, const ParallelJawGripper& g,
                   const Eigen::Isometry3d& model_from_gripper, double slack) {
  const Eigen::Isometry3d gripper_from_model = model_from_gripper.inverse();
  const double half = 0.5 * g.max_opening_mm;
  struct Box {
    Eigen::Vector3d lo, hi;
  };
  const double z0 = g.palm_height_mm, z1 = g.tip_mm();
  const Box boxes[] = {{{half, -0.5 * g.finger_width_mm, z0},
                        {half + g.finger_thickness_mm, 0.5 * g.finger_width_mm, z1}},
                       {{-half - g.finger_thickness_mm, -0.5 * g.finger_width_mm, z0},
                        {-half, 0.5 * g.finger_width_mm, z1}},
                       {{-0.5 * g.palm_width_mm, -0.5 * g.palm_depth_mm, 0},
                        {0.5 * g.palm_width_mm, 0.5 * g.palm_depth_mm, g.palm_height_mm}}};
  for (const Eigen::Vector3d& p : points) {
    const Eigen::Vector3d q = gripper_from_model * p;
    for (const Box& b : boxes) {
      if ((q.array() > b.lo.array() + slack).all() && (q.array() < b.hi.array() - slack).all())
        return true;
    }
  }
  return false;
}

// The mesh's vertices and a dense grid of points on each triangle.
std::vector<Eigen::Vector3d> SurfacePoints(const Mesh& mesh) {
  std::vector<Eigen::Vector3d> out;
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.positions[t[0]].cast<double>(),
                          b = mesh.positions[t[1]].cast<double>(),
                          c = mesh.positions[t[2]].cast<double>();
    const int n = 12;
    for (int i = 0; i <= n; ++i) {
      for (int j = 0; i + j <= n; ++j) out.push_back(a + (b - a) * i / n + (c - a) * j / n);
    }
  }
  return out;
}

TEST(AntipodalGrasps, CubeGraspsAre40mmWideAlongAFaceNormal) {
  const Part cube = MakePart("cube", MakeBox(40, 40, 40), TessellationOptions{});
  const ParallelJawGripper franka = ParallelJawGripper::Franka();
  AntipodalOptions o;
  o.samples = 300;
  o.approaches = 4;
  const std::vector<ParallelJawGrasp> grasps = SampleAntipodalGrasps(cube, franka, o);
  ASSERT_GT(grasps.size(), 100u);
  const std::vector<Eigen::Vector3d> points = SurfacePoints(cube.mesh);
  for (const ParallelJawGrasp& g : grasps) {
    EXPECT_NEAR(g.width_mm, 40.0, 1e-4);
    const Eigen::Vector3d x = g.model_from_gripper.linear().col(0);
    EXPECT_NEAR(x.cwiseAbs().maxCoeff(), 1.0, 1e-9) << x.transpose();  // a face normal
    EXPECT_NEAR(g.quality, 1.0, 1e-6);
    EXPECT_NEAR(g.model_from_gripper.linear().determinant(), 1.0, 1e-9);
    // The contacts on the fingers' pads: pad_mm below the tips, on the x axis.
    const Eigen::Vector3d c =
        g.model_from_gripper.inverse() * (0.5 * (g.contacts[0] + g.contacts[1]));
    EXPECT_NEAR(c.z(), franka.tip_mm() - franka.pad_mm, 1e-6);
    EXPECT_NEAR(c.head<2>().norm(), 0.0, 1e-6);
    EXPECT_FALSE(InsideGripper(points, franka, g.model_from_gripper, 1e-6));
    EXPECT_TRUE(g.free_when_open);  // the fully open hand: InsideGripper's
  }
  // Same seed, same grasps.
  const auto again = SampleAntipodalGrasps(cube, franka, o);
  ASSERT_EQ(again.size(), grasps.size());
  for (size_t i = 0; i < grasps.size(); ++i)
    EXPECT_EQ(again[i].model_from_gripper.matrix(), grasps[i].model_from_gripper.matrix());
  // At most 25: the first 25 of the same list.
  AntipodalOptions capped = o;
  capped.max_grasps = 25;
  const auto first = SampleAntipodalGrasps(cube, franka, capped);
  ASSERT_EQ(first.size(), 25u);
  for (size_t i = 0; i < first.size(); ++i)
    EXPECT_EQ(first[i].model_from_gripper.matrix(), grasps[i].model_from_gripper.matrix());
  // Too wide for the opening: none.
  const Part big = MakePart("big", MakeBox(100, 100, 100), TessellationOptions{});
  EXPECT_TRUE(SampleAntipodalGrasps(big, franka, o).empty());
}

TEST(AntipodalGrasps, CylinderAcrossItsAxisIsItsDiameterAndCollisionsAreRejected) {
  // A rod of diameter 30 mm, 120 mm long (axis z, from -60 to 60): across the axis the width is
  // the diameter (less the facets' sag); along it, 120 mm exceeds the 80 mm opening. A hand
  // approaching along the axis has its palm 103.4 - 66 = 37.4 mm behind the contact: only
  // contacts that near the end it comes from can be kept (FCL); every grasp kept also passes a
  // point test that does not use FCL.
  const TessellationOptions fine{0.02, 0.1};
  const Part rod = MakePart("rod", MakeCylinder(15, 120), fine);
  const ParallelJawGripper franka = ParallelJawGripper::Franka();
  AntipodalOptions o;
  o.samples = 400;
  o.friction = 0.3;
  const std::vector<ParallelJawGrasp> grasps = SampleAntipodalGrasps(rod, franka, o);
  ASSERT_GT(grasps.size(), 100u);
  const std::vector<Eigen::Vector3d> points = SurfacePoints(rod.mesh);
  const double cone = std::atan(o.friction);
  for (const ParallelJawGrasp& g : grasps) {
    const Eigen::Vector3d x = g.model_from_gripper.linear().col(0);
    EXPECT_LT(std::abs(x.z()), 1e-6) << "only across the axis fits";
    EXPECT_NEAR(g.width_mm, 30.0, 0.05);
    // The friction cone at both contacts.
    EXPECT_NEAR((-g.normals[0]).dot(x), 1.0, 1e-9);
    EXPECT_LE(std::acos(std::min(1.0, g.normals[1].dot(x))), cone + 1e-9);
    EXPECT_FALSE(InsideGripper(points, franka, g.model_from_gripper, 1e-6));
  }
  int along = 0;
  for (const ParallelJawGrasp& g : grasps) {
    const Eigen::Vector3d z = g.model_from_gripper.linear().col(2);
    if (std::abs(z.z()) < 0.999) continue;  // within 2.6 degrees of the axis
    ++along;
    const double c = g.contacts[0].z();
    const double reach = z.z() > 0 ? c + 60 : 60 - c;  // from the end the hand comes from
    EXPECT_LE(reach, franka.finger_length_mm - franka.pad_mm + 1.0) << c;  // 15 tan(2.6 deg)
  }
  EXPECT_GT(along, 0);
}

TEST(AntipodalGrasps, FreeWhenOpenIsWhatTheFullyOpenHandClears) {
  // Two plates 10 x 40 x 40 mm, x in [0, 10] and [40, 50] (one part). Across a plate (closing
  // along x, 10 mm wide) the hand is checked at 20 mm open, its fingers' inner faces 10 mm from the
  // plate's middle and 25 mm short of the other plate: kept. Fully open (80 mm) a finger reaches
  // 45 mm from that middle, into the other plate: not free when open, as ACRONYM would try it.
  // Across the 40 mm of a plate (closing along y or z) the fingers stay 10 mm either side of the
  // plate along x, and fully open they are 40 mm off its middle: free either way.
  Mesh plates = Tessellate(MakeBox(10, 40, 40), TessellationOptions{});
  const Mesh other = Tessellate(
      Transformed(MakeBox(10, 40, 40), Eigen::Isometry3d(Eigen::Translation3d(40, 0, 0))),
      TessellationOptions{});
  const auto base = static_cast<uint32_t>(plates.positions.size());
  plates.positions.insert(plates.positions.end(), other.positions.begin(), other.positions.end());
  for (const auto& t : other.triangles)
    plates.triangles.emplace_back(t[0] + base, t[1] + base, t[2] + base);
  Part part;
  part.name = "plates";
  part.mesh = plates;
  const ParallelJawGripper franka = ParallelJawGripper::Franka();
  AntipodalOptions o;
  o.samples = 400;
  const std::vector<ParallelJawGrasp> grasps = SampleAntipodalGrasps(part, franka, o);
  const std::vector<Eigen::Vector3d> points = SurfacePoints(plates);
  int across = 0, along = 0;
  for (const ParallelJawGrasp& g : grasps) {
    const Eigen::Vector3d x = g.model_from_gripper.linear().col(0);
    if (std::abs(x.x()) > 0.999) {
      ++across;
      EXPECT_NEAR(g.width_mm, 10.0, 1e-4);
      EXPECT_FALSE(g.free_when_open);
      EXPECT_TRUE(InsideGripper(points, franka, g.model_from_gripper, 0.5));  // point test
    } else {
      ++along;
      EXPECT_NEAR(g.width_mm, 40.0, 1e-4);
      EXPECT_TRUE(g.free_when_open);
      EXPECT_FALSE(InsideGripper(points, franka, g.model_from_gripper, 1e-6));
    }
  }
  EXPECT_GT(across, 10);
  EXPECT_GT(along, 10);
}

TEST(AntipodalGrasps, ImpossibleOptionsAreRefused) {
  const Part cube = MakePart("cube", MakeBox(40, 40, 40), TessellationOptions{});
  AntipodalOptions o;
  o.friction = 0;
  EXPECT_THROW(SampleAntipodalGrasps(cube, ParallelJawGripper::Franka(), o), Error);
  ParallelJawGripper g;
  g.pad_mm = 100;
  EXPECT_THROW(SampleAntipodalGrasps(cube, g, AntipodalOptions{}), Error);
  EXPECT_THROW(SampleAntipodalGrasps(Part{}, ParallelJawGripper::Franka(), AntipodalOptions{}),
               Error);
}

}  // namespace
}  // namespace cadsynth
