#include "dataset/point_cloud.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "cad/assembly.h"
#include "cad/core/error.h"
#include "cad/shape.h"

namespace cadsynth {
namespace {

Mesh Bar() {
  return MakePart("bar", MakeBox(100, 10, 10), TessellationOptions{}).mesh;
}  // model frame

TEST(SampleSurface, PointsLieOnTheSurfaceSpreadByArea) {
  const Mesh bar = Bar();
  const auto points = SampleSurface(bar, 3000, 1);
  ASSERT_EQ(points.size(), 3000u);
  Mesh cloud;
  cloud.positions = points;
  EXPECT_LT(MaxSurfaceDistance(bar, cloud, Eigen::Isometry3d::Identity()), 1e-4);
  // The two 10 x 10 ends are 200 of 4,200 mm2: about 143 points.
  int on_ends = 0;
  for (const auto& p : points) on_ends += std::abs(std::abs(p.x()) - 50.0f) < 1e-4f;
  EXPECT_NEAR(on_ends, 3000.0 * 200 / 4200, 35);
  EXPECT_EQ(SampleSurface(bar, 10, 1), SampleSurface(bar, 10, 1));
  EXPECT_NE(SampleSurface(bar, 10, 1), SampleSurface(bar, 10, 2));
}

TEST(SampleEvenly, NoTwoPointsCrowdTogether) {
  const Mesh bar = Bar();
  const auto even = SampleEvenly(bar, 300, 1), random = SampleSurface(bar, 300, 1);
  const auto closest = [](const std::vector<Eigen::Vector3f>& p) {
    float best = 1e9f;
    for (size_t i = 0; i < p.size(); ++i) {
      for (size_t j = i + 1; j < p.size(); ++j) best = std::min(best, (p[i] - p[j]).norm());
    }
    return best;
  };
  // 300 points on 4,200 mm2: spacing about sqrt(4200 / 300) = 3.7 mm.
  EXPECT_GT(closest(even), 1.5f);
  EXPECT_LT(closest(random), closest(even));
}

TEST(Keypoints, FarthestPointsStartAtOppositeCornersAndSpread) {
  const Mesh box = MakePart("box", MakeBox(60, 40, 20), TessellationOptions{}).mesh;
  const Keypoints k = ComputeKeypoints(box, SampleSurface(box, 20000, 3));
  ASSERT_EQ(k.fps8.size(), 8u);
  ASSERT_EQ(k.fps16.size(), 16u);
  EXPECT_TRUE(k.center.isZero(1e-6f));
  // Greedy FPS starts at a corner (the point farthest from the centroid) and
  // then takes the diagonally opposite corner; the rest spread over the box.
  const auto near_corner = [&](const Eigen::Vector3f& p) {
    int hit = -1;
    for (int c = 0; c < 8; ++c) {
      if ((p - k.corners[c]).norm() < 3.0f) hit = c;
    }
    return hit;
  };
  const int first = near_corner(k.fps8[0]);
  const int second = near_corner(k.fps8[1]);
  ASSERT_GE(first, 0) << k.fps8[0].transpose();
  ASSERT_GE(second, 0) << k.fps8[1].transpose();
  EXPECT_EQ(first ^ second, 7);  // opposite corner: every coordinate flips
  float min_gap = std::numeric_limits<float>::infinity();
  for (size_t i = 0; i < k.fps8.size(); ++i) {
    for (size_t j = i + 1; j < k.fps8.size(); ++j)
      min_gap = std::min(min_gap, (k.fps8[i] - k.fps8[j]).norm());
  }
  EXPECT_GT(min_gap, 20.0f);  // 8 random surface points would typically be far closer
  // Every keypoint lies on the box's surface: one coordinate at its face.
  for (const Eigen::Vector3f& p : k.fps16) {
    const float face =
        std::max({std::abs(p.x()) / 30.0f, std::abs(p.y()) / 20.0f, std::abs(p.z()) / 10.0f});
    EXPECT_NEAR(face, 1.0f, 1e-4f) << p.transpose();
  }
  EXPECT_EQ(std::vector<Eigen::Vector3f>(k.fps16.begin(), k.fps16.begin() + 8),
            k.fps8);  // FPS is greedy
}

TEST(PointPly, DecodeReadsWhatEncodeWrites) {
  const std::vector<Eigen::Vector3f> points = {{1.5f, -2.25f, 3.0f}, {0.0f, 1e-3f, 1234.5f}};
  EXPECT_EQ(DecodePointPly(EncodePointPly(points), "x.ply"), points);
  try {
    DecodePointPly("ply\nformat ascii 1.0\nelement vertex 3\nend_header\n1 2 3\n4 5\n", "bad.ply");
    FAIL() << "a short vertex line must be refused";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.ply:6"), std::string::npos) << e.what();
  }
  // A damaged count (found by the fuzzer: reserve() of 5e30 points ended the process).
  EXPECT_THROW(DecodePointPly("ply\nformat ascii 1.0\nelement vertex 5555555555555555555555\n"
                              "end_header\n1 2 3\n",
                              "c.ply"),
               Error);
  EXPECT_THROW(DecodePointPly(
                   "ply\nformat ascii 1.0\nelement vertex 900000000\nend_header\n1 2 3\n", "c.ply"),
               Error);
  EXPECT_THROW(DecodePointPly("ply\nformat binary_little_endian 1.0\nend_header\n", "b.ply"),
               Error);
}

}  // namespace
}  // namespace cadsynth
