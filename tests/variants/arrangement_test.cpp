#include "variants/arrangement.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/intersection.h>
#include <CGAL/Surface_mesh.h>

#include <gtest/gtest.h>

#include "cad/core/error.h"
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
  f.instances.resize(1);  // the plate: six stable faces, pairs at three heights: three poses
  f.group.resize(1);
  const Arrangement a = Arrange(f.parts, f.instances, o, f.group);
  EXPECT_EQ(a.instances.size(), 3u);
  ExpectResting(f, a);
  o.layout = Layout::kSingle;
  o.pose = PoseMode::kStable;
  EXPECT_EQ(Arrange(f.parts, f.instances, o, f.group).instances.size(), 1u);
  EXPECT_THROW(Arrange(Kit().parts, Kit().instances, o, Kit().group), Error);  // three groups
}

// Distractors fall onto a laid-out scene without moving its parts: the grid is the grid without
// them, every distractor rests (on the floor or on a part, never below the floor), and the same
// seed drops them the same way. In a pile they fall with the copies, inside the tote.
TEST(Arrange, DistractorsFallAmongThePartsAndLeaveALayoutAsItWas) {
  Fixture f = Kit();
  f.parts.push_back(MakePart("ball", MakeSphere(12), TessellationOptions{}));
  f.parts.push_back(MakePart("brick", MakeBox(40, 20, 15), TessellationOptions{}));
  ArrangementOptions o;
  o.layout = Layout::kGrid;
  const Arrangement plain = Arrange(f.parts, f.instances, o, f.group);
  o.distractors = {3, 4, 4};
  o.distractor_seed = 9;
  // Round parts need more hull corners than the default 32 to stay within 0.5 mm of their
  // surface (the run gives primitives 128).
  CollisionOptions round;
  round.max_corners = 128;
  std::vector<CollisionShape> shapes;
  for (const Part& part : f.parts) shapes.push_back(MakeCollisionShape(part, round));
  const Arrangement with = Arrange(f.parts, f.instances, o, f.group, &shapes);
  ASSERT_EQ(with.instances.size(), plain.instances.size());
  for (size_t i = 0; i < plain.instances.size(); ++i) {
    EXPECT_EQ(with.instances[i].world_from_model.matrix(),
              plain.instances[i].world_from_model.matrix());
  }
  ASSERT_EQ(with.distractors.size(), 3u);
  EXPECT_TRUE(with.restless_distractors.empty());
  const Eigen::AlignedBox3d layout = [&] {
    Eigen::AlignedBox3d b;
    for (const Instance& i : plain.instances)
      b.extend(f.parts[i.part].mesh.Bounds(i.world_from_model));
    return b;
  }();
  for (size_t k = 0; k < 3; ++k) {
    const Instance& d = with.distractors[k];
    EXPECT_EQ(d.part, o.distractors[k]);
    const Eigen::AlignedBox3d box = f.parts[d.part].mesh.Bounds(d.world_from_model);
    EXPECT_GT(box.min().z(), -0.6) << k;
    EXPECT_LT(box.min().z(), layout.max().z() + 1) << k << ": resting, not in the air";
    // Where they were dropped: over the layout's floor plan (20 mm wider), give or take a roll.
    EXPECT_LT(std::abs(box.center().x()), layout.sizes().x() + 100) << k;
  }
  const Arrangement again = Arrange(f.parts, f.instances, o, f.group, &shapes);
  for (size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(again.distractors[k].world_from_model.matrix(),
              with.distractors[k].world_from_model.matrix());
  }
  // A pile: 8 cubes and 3 distractors in a tote, all inside it.
  ArrangementOptions pile;
  pile.layout = Layout::kPile;
  pile.copies = 8;
  pile.container.kind = Container::Kind::kTote;
  pile.container.inner_mm = {200, 150};
  pile.container.height_mm = 80;
  pile.distractors = {3, 4, 3};
  pile.distractor_seed = 4;
  const Arrangement tote = Arrange(f.parts, {f.instances[2]}, pile, {}, &shapes);
  ASSERT_EQ(tote.instances.size(), 8u);
  ASSERT_EQ(tote.distractors.size(), 3u);
  EXPECT_TRUE(tote.escaped.empty());
  for (const Instance& d : tote.distractors) {
    const Eigen::Vector3d c = d.world_from_model.translation();
    EXPECT_LT(std::abs(c.x()), 100.0);
    EXPECT_LT(std::abs(c.y()), 75.0);
    EXPECT_GT(f.parts[d.part].mesh.Bounds(d.world_from_model).min().z(),
              pile.container.floor_mm - 0.6);
  }
  // A flat part (no volume) among the parts: nothing to land on, but no error either.
  Fixture flat = f;
  Part sheet;
  sheet.name = "sheet";
  sheet.mesh.positions = {{-20, -20, 0}, {20, -20, 0}, {20, 20, 0}, {-20, 20, 0}};
  sheet.mesh.normals.assign(4, Eigen::Vector3f::UnitZ());
  sheet.mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  flat.parts.push_back(sheet);
  flat.instances.push_back({5, "sheet", Eigen::Isometry3d::Identity()});
  flat.group.push_back(5);
  ArrangementOptions row = o;
  row.layout = Layout::kRow;
  row.pose = PoseMode::kAsDesigned;
  row.distractors = {3};
  EXPECT_EQ(Arrange(flat.parts, flat.instances, row, flat.group).distractors.size(), 1u);
  o.distractors = {9};
  EXPECT_THROW(Arrange(f.parts, f.instances, o, f.group), Error);
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

// A "T" drawn standing, as one assembly: a 10 x 10 x 100 post with a 100 x 100 x 5 plate on top.
Fixture StandingT() {
  Fixture f;
  f.parts.push_back(MakePart("post", MakeBox(10, 10, 100), TessellationOptions{}));
  f.parts.push_back(MakePart("plate", MakeBox(100, 100, 5), TessellationOptions{}));
  f.instances = {{0, "post", Eigen::Translation3d(-5, -5, 0) * f.parts[0].cad_from_model},
                 {1, "plate", Eigen::Translation3d(-50, -50, 100) * f.parts[1].cad_from_model}};
  return f;
}

// The standing T: a 10 x 10 x 100 post with a 100 x 100 x 5 plate on top. Dropped at
// random it most often lands with the plate down (its wide face or its edge); assembled, it stands
// on its post as it
// was drawn (pose auto = upright), which is stable: the centre of mass is above the foot.
TEST(Arrange, AssembledStandsAsDrawnUnlessAskedForTheLikeliestFace) {
  const Fixture t = StandingT();
  const std::vector<Part>& parts = t.parts;
  const std::vector<Instance>& instances = t.instances;
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

// pose: dropped. A 20 x 40 x 60 mm block dropped 40 times rests exactly flat on one of its faces
// (the physics leaves it within its collision margin of flat; the arrangement puts it on the
// stable pose of that face), touching the floor, at the yaw it landed with; it lies on its largest
// face far more often than it stands on its smallest (the physics, not the quasi-static
// solid-angle estimate, decides which); the same seed gives the same poses, another seed others.
TEST(Arrange, DroppedBlocksRestFlatOnTheFaceTheyFellOn) {
  Fixture f;
  f.parts.push_back(MakePart("block", MakeBox(20, 40, 60), TessellationOptions{}));
  f.instances.push_back({0, "block", f.parts[0].cad_from_model});
  f.group.push_back(0);
  ArrangementOptions o;
  o.layout = Layout::kGrid;
  o.pose = PoseMode::kDropped;
  o.copies = 40;
  o.seed = 5;
  const Arrangement a = Arrange(f.parts, f.instances, o, f.group);
  ASSERT_EQ(a.instances.size(), 40u);
  EXPECT_TRUE(a.restless.empty());
  ExpectResting(f, a);
  int flat = 0, side = 0, end = 0, yawed = 0;
  for (const Instance& i : a.instances) {
    const Eigen::AlignedBox3d box = f.parts[0].mesh.Bounds(i.world_from_model);
    EXPECT_NEAR(box.min().z(), 0.0, 1e-9);
    // Exactly one model axis is vertical.
    const Eigen::Matrix3d r = i.world_from_model.linear() * f.parts[0].cad_from_model.linear();
    const double up = r.row(2).cwiseAbs().maxCoeff();
    EXPECT_NEAR(up, 1.0, 1e-9);
    const double height = box.sizes().z();
    flat += std::abs(height - 20) < 1e-6;
    side += std::abs(height - 40) < 1e-6;
    end += std::abs(height - 60) < 1e-6;
    // Not every copy at the same yaw (they land as they land).
    yawed += std::abs(r(0, 0)) < 0.99 && std::abs(r(0, 1)) < 0.99 && std::abs(r(0, 2)) < 0.99;
  }
  EXPECT_EQ(flat + side + end, 40);
  EXPECT_GT(flat, 2 * end);
  EXPECT_GT(flat, 10);
  EXPECT_GT(yawed, 10);
  const Arrangement again = Arrange(f.parts, f.instances, o, f.group);
  for (size_t i = 0; i < a.instances.size(); ++i) {
    EXPECT_TRUE(a.instances[i].world_from_model.isApprox(again.instances[i].world_from_model, 0.0));
  }
  o.seed = 6;
  const Arrangement other = Arrange(f.parts, f.instances, o, f.group);
  int differ = 0;
  for (size_t i = 0; i < a.instances.size(); ++i)
    differ += !a.instances[i].world_from_model.isApprox(other.instances[i].world_from_model, 1e-6);
  EXPECT_GT(differ, 30);
  // Stopped in mid-air (0.05 s simulated), every block is reported as still moving, and still
  // put down on the floor.
  o.settle_time_s = 0.05;
  const Arrangement early = Arrange(f.parts, f.instances, o, f.group);
  EXPECT_EQ(early.restless.size(), 40u);
  for (const Instance& i : early.instances)
    EXPECT_NEAR(f.parts[0].mesh.Bounds(i.world_from_model).min().z(), 0.0, 1e-9);
}

// A group of several parts falls as one rigid body: ten copies of the "T" of post and plate keep
// their shape, touch the floor and rest with their joint centre of mass over the points they
// stand on.
TEST(Arrange, DroppedAssemblyFallsAsOneBody) {
  const Fixture t = StandingT();
  const std::vector<Part>& parts = t.parts;
  const std::vector<Instance>& instances = t.instances;
  ArrangementOptions o;
  o.layout = Layout::kRow;
  o.pose = PoseMode::kDropped;
  o.copies = 10;
  o.seed = 2;
  const Arrangement a = Arrange(parts, instances, o, {0, 0});
  ASSERT_EQ(a.instances.size(), 20u);
  EXPECT_TRUE(a.restless.empty());
  for (size_t c = 0; c < 10; ++c) {
    const Instance& post = a.instances[2 * c];
    const Instance& plate = a.instances[2 * c + 1];
    const Eigen::Isometry3d moved = post.world_from_model * instances[0].world_from_model.inverse();
    EXPECT_TRUE((moved * instances[1].world_from_model).isApprox(plate.world_from_model, 1e-9));
    Eigen::AlignedBox3d all;
    Eigen::AlignedBox2d contact;
    Eigen::Vector3d com = Eigen::Vector3d::Zero();
    double mass = 0;
    for (const Instance* i : {&post, &plate}) {
      const Part& part = parts[i->part];
      all.extend(part.mesh.Bounds(i->world_from_model));
      com += part.mass.volume_mm3 * (i->world_from_model * part.mass.center_of_mass);
      mass += part.mass.volume_mm3;
    }
    for (const Instance* i : {&post, &plate}) {
      for (const auto& p : parts[i->part].mesh.positions) {
        const Eigen::Vector3d q = i->world_from_model * p.cast<double>();
        if (q.z() < 0.01) contact.extend(q.head<2>());
      }
    }
    EXPECT_NEAR(all.min().z(), 0.0, 1e-9) << c;
    EXPECT_LT(contact.exteriorDistance((com / mass).head<2>()), 0.05) << c;
  }
}

// A fixed physics material is used as it is; a range is drawn uniformly within its bounds, per
// seed and part.
TEST(Arrange, PhysicsRangesAreDrawnPerSeedAndPart) {
  PhysicsMaterial fixed{2700, 0.45, 0.2};
  const PhysicsMaterial same = PhysicsDraw(fixed).Draw(9, 3);
  EXPECT_EQ(same.density_kg_m3, 2700.0);
  EXPECT_EQ(same.friction, 0.45);
  EXPECT_EQ(same.restitution, 0.2);
  PhysicsDraw range(fixed);
  range.low.friction = 0.2;
  range.high.friction = 0.6;
  double sum = 0;
  for (uint64_t part = 0; part < 4000; ++part) {
    const PhysicsMaterial m = range.Draw(1, part);
    ASSERT_GE(m.friction, 0.2);
    ASSERT_LE(m.friction, 0.6);
    EXPECT_EQ(m.density_kg_m3, 2700.0);
    sum += m.friction;
  }
  EXPECT_NEAR(sum / 4000, 0.4, 0.01);  // the uniform's mean; its standard error is 0.0018
  EXPECT_EQ(range.Draw(1, 5).friction, range.Draw(1, 5).friction);
  EXPECT_NE(range.Draw(1, 5).friction, range.Draw(2, 5).friction);
  std::string why;
  std::swap(range.low.friction, range.high.friction);
  EXPECT_FALSE(range.Check(&why));
  EXPECT_EQ(why, "a range's low end must not exceed its high end");
}

}  // namespace
}  // namespace cadsynth
