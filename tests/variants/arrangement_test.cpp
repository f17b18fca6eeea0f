#include "variants/arrangement.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/intersection.h>
#include <CGAL/Surface_mesh.h>

#include <gtest/gtest.h>

#include "cad/error.h"
#include "cad/shape.h"

namespace cadsynth {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;

struct Fixture {
  std::vector<Part> parts;
  std::vector<Instance> instances;
  std::vector<int> group;
};

// A plate, a cylinder and a cube, each its own group, in arbitrary CAD poses.
Fixture Kit() {
  Fixture f;
  f.parts.push_back(MakePart("plate", MakeBox(100, 60, 10), TessellationOptions{}));
  f.parts.push_back(MakePart("cylinder", MakeCylinder(10, 40), TessellationOptions{0.05, 0.2}));
  f.parts.push_back(MakePart("cube", MakeBox(30, 30, 30), TessellationOptions{}));
  const Eigen::Isometry3d tilted = Eigen::Translation3d(300, -200, 50) *
                                   Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 1, 0).normalized());
  for (int i = 0; i < 3; ++i) {
    f.instances.push_back({i, f.parts[i].name, tilted * f.parts[i].cad_from_model});
    f.group.push_back(i);
  }
  return f;
}

SurfaceMesh Placed(const Part& part, const Instance& instance) {
  SurfaceMesh mesh;
  std::vector<SurfaceMesh::Vertex_index> v;
  for (const auto& p : part.mesh.positions) {
    const Eigen::Vector3d q = instance.world_from_model * p.cast<double>();
    v.push_back(mesh.add_vertex(Kernel::Point_3(q.x(), q.y(), q.z())));
  }
  for (const auto& t : part.mesh.triangles) mesh.add_face(v[t[0]], v[t[1]], v[t[2]]);
  return mesh;
}

// The checks every arrangement must pass.
void ExpectResting(const Fixture& f, const Arrangement& a) {
  ASSERT_EQ(a.instances.size(), a.group.size());
  for (size_t i = 0; i < a.instances.size(); ++i) {
    const Part& part = f.parts[a.instances[i].part];
    const Eigen::Isometry3d& pose = a.instances[i].world_from_model;
    // Touches the floor.
    EXPECT_NEAR(part.mesh.Bounds(pose).min().z(), 0.0, 0.01) << i;
    // Centre of mass over the support polygon: inside the box of the contact points (these bodies'
    // contact patches are rectangles or segments, so the box is the polygon).
    Eigen::AlignedBox2d contact;
    for (const auto& p : part.mesh.positions) {
      const Eigen::Vector3d q = pose * p.cast<double>();
      if (q.z() < 0.01) contact.extend(q.head<2>());
    }
    const Eigen::Vector2d com = (pose * part.mass.center_of_mass).head<2>();
    EXPECT_TRUE(contact.exteriorDistance(com) < 0.05) << i << ": " << com.transpose();
    // Nothing intersects anything else.
    for (size_t j = i + 1; j < a.instances.size(); ++j) {
      const SurfaceMesh mi = Placed(part, a.instances[i]),
                        mj = Placed(f.parts[a.instances[j].part], a.instances[j]);
      EXPECT_FALSE(CGAL::Polygon_mesh_processing::do_intersect(mi, mj)) << i << " and " << j;
    }
  }
}

TEST(Arrange, StablePosesInARow) {
  const Fixture f = Kit();
  ArrangementOptions o;
  o.layout = Layout::kRow;
  o.gap_mm = 25;
  const Arrangement a = Arrange(f.parts, f.instances, o, f.group);
  ExpectResting(f, a);
  // Each body on its most stable face: the plate flat (10 mm tall), the cylinder on its side.
  EXPECT_NEAR(f.parts[0].mesh.Bounds(a.instances[0].world_from_model).sizes().z(), 10.0, 1e-6);
  // Lying on a flat of its tessellated side, within the 0.05 mm deflection of 20 mm tall.
  EXPECT_NEAR(f.parts[1].mesh.Bounds(a.instances[1].world_from_model).sizes().z(), 20.0, 0.05);
  std::vector<Eigen::AlignedBox3d> boxes;
  for (const Instance& i : a.instances)
    boxes.push_back(f.parts[i.part].mesh.Bounds(i.world_from_model));
  for (size_t i = 1; i < boxes.size(); ++i)
    EXPECT_NEAR(boxes[i].min().x() - boxes[i - 1].max().x(), 25.0, 1e-4);
}

TEST(Arrange, AssembledRestsTheWholeAsOneBody) {
  const Fixture f = Kit();
  ArrangementOptions o;
  o.pose = PoseMode::kAsDesigned;
  const Arrangement as_designed = Arrange(f.parts, f.instances, o, f.group);
  // As designed: the instances keep their relative poses.
  const Eigen::Isometry3d shift =
      as_designed.instances[0].world_from_model * f.instances[0].world_from_model.inverse();
  EXPECT_TRUE(shift.linear().isIdentity(1e-12));
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_TRUE((shift * f.instances[i].world_from_model)
                    .isApprox(as_designed.instances[i].world_from_model, 1e-9));
  }
  o.pose = PoseMode::kStable;
  const Arrangement stable = Arrange(f.parts, f.instances, o, f.group);
  Eigen::AlignedBox3d all;
  for (const Instance& i : stable.instances)
    all.extend(f.parts[i.part].mesh.Bounds(i.world_from_model));
  EXPECT_NEAR(all.min().z(), 0.0, 1e-6);
  EXPECT_NEAR(all.center().x(), 0.0, 1e-6);
}

TEST(Arrange, ClutterIsSeededAndNeverOverlaps) {
  const Fixture f = Kit();
  ArrangementOptions o;
  o.layout = Layout::kClutter;
  o.pose = PoseMode::kRandom;
  o.copies = 3;
  o.clutter_radius_mm = 220;
  o.gap_mm = 2;
  o.seed = 5;
  const Arrangement a = Arrange(f.parts, f.instances, o, f.group);
  ASSERT_EQ(a.instances.size(), 9u);
  ExpectResting(f, a);
  for (const Instance& i : a.instances) {
    for (const auto& p : f.parts[i.part].mesh.positions) {
      EXPECT_LE((i.world_from_model * p.cast<double>()).head<2>().norm(), 220.0 + 1e-6);
    }
  }
  const Arrangement again = Arrange(f.parts, f.instances, o, f.group);
  for (size_t i = 0; i < a.instances.size(); ++i) {
    EXPECT_TRUE(again.instances[i].world_from_model.isApprox(a.instances[i].world_from_model, 0.0));
  }
  o.seed = 6;
  const Arrangement other = Arrange(f.parts, f.instances, o, f.group);
  EXPECT_FALSE(other.instances[0].world_from_model.isApprox(a.instances[0].world_from_model, 1e-6));
}

TEST(Arrange, TooDenseAClutterSaysHowManyFit) {
  const Fixture f = Kit();
  ArrangementOptions o;
  o.layout = Layout::kClutter;
  o.copies = 20;
  o.clutter_radius_mm = 120;
  try {
    Arrange(f.parts, f.instances, o, f.group);
    FAIL() << "no error";
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("clutter: only "), std::string::npos) << m;
    EXPECT_NE(m.find(" of 60 parts fit in a disc of radius 120 mm"), std::string::npos) << m;
  }
}

TEST(Arrange, AllPosesAndSingle) {
  Fixture f = Kit();
  ArrangementOptions o;
  o.layout = Layout::kGrid;
  o.pose = PoseMode::kAll;
  o.gap_mm = 10;
  f.instances.resize(1);  // the plate: six stable faces
  f.group.resize(1);
  const Arrangement a = Arrange(f.parts, f.instances, o, f.group);
  EXPECT_EQ(a.instances.size(), 6u);
  ExpectResting(f, a);
  o.layout = Layout::kSingle;
  o.pose = PoseMode::kStable;
  EXPECT_EQ(Arrange(f.parts, f.instances, o, f.group).instances.size(), 1u);
  EXPECT_THROW(Arrange(Kit().parts, Kit().instances, o, Kit().group), Error);  // three groups
}

TEST(Arrange, RejectsBadInput) {
  Fixture f = Kit();
  ArrangementOptions o;
  o.gap_mm = -1;
  EXPECT_THROW(Arrange(f.parts, f.instances, o), Error);
  o = ArrangementOptions{};
  o.copies = 2;  // assembled is one body
  EXPECT_THROW(Arrange(f.parts, f.instances, o), Error);
  f.instances[0].part = 7;
  EXPECT_THROW(Arrange(f.parts, f.instances, ArrangementOptions{}), Error);
  EXPECT_TRUE(Arrange(f.parts, {}, ArrangementOptions{}).instances.empty());
}

// A "T" drawn standing: a 10 x 10 x 100 post with a 100 x 100 x 5 plate on top. Dropped at
// random it most often lands with the plate down (its wide face or its edge); assembled, it stands
// on its post as it
// was drawn (pose auto = upright), which is stable: the centre of mass is above the foot.
TEST(Arrange, AssembledStandsAsDrawnUnlessAskedForTheLikeliestFace) {
  std::vector<Part> parts;
  parts.push_back(MakePart("post", MakeBox(10, 10, 100), TessellationOptions{}));
  parts.push_back(MakePart("plate", MakeBox(100, 100, 5), TessellationOptions{}));
  const std::vector<Instance> instances = {
      {0, "post", Eigen::Translation3d(-5, -5, 0) * parts[0].cad_from_model},
      {1, "plate", Eigen::Translation3d(-50, -50, 100) * parts[1].cad_from_model}};
  const auto lowest = [&](const Arrangement& a, int i) {
    double z = 1e300;
    for (const Eigen::Vector3f& p : parts[i].mesh.positions)
      z = std::min(z, (a.instances[i].world_from_model * p.cast<double>()).z());
    return z;
  };
  ArrangementOptions options;  // layout assembled, pose auto
  const Arrangement upright = Arrange(parts, instances, options);
  EXPECT_NEAR(lowest(upright, 0), 0.0, 1e-9);    // the post's foot on the floor
  EXPECT_NEAR(lowest(upright, 1), 100.0, 1e-9);  // the plate on top
  options.pose = PoseMode::kStable;
  const Arrangement likeliest = Arrange(parts, instances, options);
  EXPECT_NEAR(lowest(likeliest, 1), 0.0, 1e-9);  // the plate touches the floor: not standing
  // Each part on its own (row): auto means the likeliest face, so the post lies down.
  options.layout = Layout::kRow;
  options.pose = PoseMode::kAuto;
  const Arrangement row = Arrange(parts, instances, options, {0, 1});
  const Eigen::AlignedBox3d post = parts[0].mesh.Bounds(row.instances[0].world_from_model);
  EXPECT_NEAR(post.sizes().z(), 10.0, 1e-6);
}

}  // namespace
}  // namespace cadsynth
