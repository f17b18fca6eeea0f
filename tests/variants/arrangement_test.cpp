#include "variants/arrangement.h"

#include <gtest/gtest.h>

#include "cad/error.h"
#include "cad/shape.h"

namespace cadsynth {
namespace {

struct Fixture {
  std::vector<Part> parts;
  std::vector<Instance> instances;
};

Fixture TwoBoxesAndACylinder() {
  Fixture f;
  f.parts.push_back(MakePart("box", MakeBox(40, 30, 20), TessellationOptions{}));
  f.parts.push_back(MakePart("cyl", MakeCylinder(10, 50), TessellationOptions{}));
  const auto place = [&](int part, const Eigen::Isometry3d& cad) {
    f.instances.push_back({part, std::string("i").append(std::to_string(f.instances.size())), cad * f.parts[part].cad_from_model});
  };
  place(0, Eigen::Translation3d(500, 200, 100) * Eigen::Isometry3d::Identity());
  place(0, Eigen::Translation3d(500, 260, 130) * Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()));
  place(1, Eigen::Translation3d(450, 200, 90) * Eigen::Isometry3d::Identity());
  return f;
}

Eigen::AlignedBox3d BoundsOf(const Fixture& f, const Instance& i) {
  return f.parts[i.part].mesh.Bounds(i.world_from_model);
}

TEST(Arrange, AssembledKeepsRelativePosesAndRestsOnTheFloor) {
  const Fixture f = TwoBoxesAndACylinder();
  const std::vector<Instance> placed = Arrange(f.parts, f.instances, {Layout::kAssembled, 40.0});
  ASSERT_EQ(placed.size(), 3u);
  Eigen::AlignedBox3d all;
  for (const Instance& i : placed) all.extend(BoundsOf(f, i));
  EXPECT_NEAR(all.min().z(), 0.0, 1e-4);
  EXPECT_NEAR(all.center().x(), 0.0, 1e-4);
  EXPECT_NEAR(all.center().y(), 0.0, 1e-4);
  // Every instance moved by the same translation, rotations untouched.
  const Eigen::Isometry3d shift = placed[0].world_from_model * f.instances[0].world_from_model.inverse();
  EXPECT_TRUE(shift.linear().isIdentity(1e-12));
  for (size_t i = 0; i < placed.size(); ++i) {
    EXPECT_TRUE((shift * f.instances[i].world_from_model).isApprox(placed[i].world_from_model, 1e-9));
    EXPECT_EQ(placed[i].name, f.instances[i].name);
  }
}

TEST(Arrange, RowPutsEveryInstanceOnTheFloorWithGaps) {
  const Fixture f = TwoBoxesAndACylinder();
  const std::vector<Instance> placed = Arrange(f.parts, f.instances, {Layout::kRow, 25.0});
  std::vector<Eigen::AlignedBox3d> boxes;
  for (const Instance& i : placed) boxes.push_back(BoundsOf(f, i));
  for (const auto& b : boxes) EXPECT_NEAR(b.min().z(), 0.0, 1e-4);
  for (size_t i = 1; i < boxes.size(); ++i) {
    EXPECT_NEAR(boxes[i].min().x() - boxes[i - 1].max().x(), 25.0, 1e-4);
  }
  EXPECT_NEAR(boxes.front().min().x(), -boxes.back().max().x(), 1e-4);  // centred
}

TEST(Arrange, RejectsBadInput) {
  Fixture f = TwoBoxesAndACylinder();
  EXPECT_THROW(Arrange(f.parts, f.instances, {Layout::kRow, -1.0}), Error);
  f.instances[0].part = 7;
  EXPECT_THROW(Arrange(f.parts, f.instances, {}), Error);
  EXPECT_TRUE(Arrange(f.parts, {}, {}).empty());
}

}  // namespace
}  // namespace cadsynth
