#include "cad/hull.h"

#include <algorithm>
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "cad/core/error.h"

namespace cadsynth {
namespace {

std::vector<Eigen::Vector3d> CubeWithInside(std::mt19937* rng) {
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 8; ++i)
    points.emplace_back(i & 1 ? 10 : -10, i & 2 ? 20 : -20, i & 4 ? 5 : 0);
  std::uniform_real_distribution<double> u(-0.99, 0.99);
  for (int i = 0; i < 500; ++i)
    points.emplace_back(10 * u(*rng), 20 * u(*rng), 2.5 + 2.5 * u(*rng));
  // Points on the faces and edges are not corners either.
  points.emplace_back(0, 0, 5);
  points.emplace_back(10, 0, 0);
  points.emplace_back(10, 20, 2.5);
  points.push_back(points[3]);  // a repeated corner
  return points;
}

// A box's hull: its 8 corners (points inside, on faces and on edges dropped), 12 triangles,
// each wound outward (the centre lies behind every triangle's plane), every edge shared by
// exactly two triangles in opposite directions (closed).
TEST(ConvexHull, BoxCornersOutwardClosed) {
  std::mt19937 rng(7);
  const ConvexHull hull = ComputeConvexHull(CubeWithInside(&rng));
  ASSERT_EQ(hull.vertices.size(), 8u);
  ASSERT_EQ(hull.triangles.size(), 12u);
  EXPECT_TRUE(std::is_sorted(hull.vertices.begin(), hull.vertices.end(),
                             [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
                               return std::lexicographical_compare(a.data(), a.data() + 3, b.data(),
                                                                   b.data() + 3);
                             }));
  EXPECT_TRUE(std::is_sorted(hull.triangles.begin(), hull.triangles.end()));
  const Eigen::Vector3d centre(0, 0, 2.5);
  std::map<std::pair<int, int>, int> edges;
  for (const auto& t : hull.triangles) {
    EXPECT_LT(t[0], t[1]);
    EXPECT_LT(t[0], t[2]);
    const Eigen::Vector3d& a = hull.vertices[t[0]];
    const Eigen::Vector3d n = (hull.vertices[t[1]] - a).cross(hull.vertices[t[2]] - a);
    EXPECT_LT(n.dot(centre - a), 0.0);
    for (int k = 0; k < 3; ++k) ++edges[{t[k], t[(k + 1) % 3]}];
  }
  EXPECT_EQ(edges.size(), 36u);
  for (const auto& [edge, count] : edges) {
    EXPECT_EQ(count, 1);
    EXPECT_EQ(edges.count({edge.second, edge.first}), 1u);
  }
}

// A moved hull is the hull of the moved points: same corners (in the new order) and triangles.
TEST(ConvexHull, TransformedHullIsTheHullOfTheMovedPoints) {
  std::mt19937 rng(5);
  std::vector<Eigen::Vector3d> points;
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 400; ++i) points.emplace_back(20 * u(rng), 8 * u(rng), 3 * u(rng));
  const Eigen::Isometry3d motion = Eigen::Translation3d(5, -2, 7) *
                                   Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized());
  const ConvexHull moved = TransformedHull(ComputeConvexHull(points), motion);
  for (Eigen::Vector3d& p : points) p = motion * p;
  const ConvexHull direct = ComputeConvexHull(points);
  ASSERT_EQ(moved.vertices.size(), direct.vertices.size());
  for (size_t i = 0; i < direct.vertices.size(); ++i)
    EXPECT_EQ(moved.vertices[i], direct.vertices[i]);  // the same doubles: p moved once
  EXPECT_EQ(moved.triangles, direct.triangles);        // random points: every facet a triangle
  EXPECT_NEAR(moved.diameter, direct.diameter, 1e-12 * direct.diameter);
  Eigen::Isometry3d mirror = Eigen::Isometry3d::Identity();
  mirror(0, 0) = -1;
  EXPECT_THROW(TransformedHull(direct, mirror), Error);
}

// The result is a function of the point set: shuffled input gives the same bits.
TEST(ConvexHull, SameBitsWhateverTheInputOrder) {
  std::mt19937 rng(3);
  std::vector<Eigen::Vector3d> points;
  std::normal_distribution<double> g;
  for (int i = 0; i < 3000; ++i) points.push_back(Eigen::Vector3d(g(rng), g(rng), g(rng)) * 7.0);
  const ConvexHull first = ComputeConvexHull(points);
  for (int round = 0; round < 5; ++round) {
    std::shuffle(points.begin(), points.end(), rng);
    const ConvexHull again = ComputeConvexHull(points);
    ASSERT_EQ(again.vertices.size(), first.vertices.size());
    for (size_t i = 0; i < first.vertices.size(); ++i)
      EXPECT_EQ(again.vertices[i], first.vertices[i]);
    EXPECT_EQ(again.triangles, first.triangles);
  }
}

TEST(ConvexHull, FlatTooFewOrNotFiniteIsAnError) {
  std::vector<Eigen::Vector3d> octagon;
  for (int i = 0; i < 8; ++i)
    octagon.emplace_back(std::cos(i * M_PI / 4), std::sin(i * M_PI / 4), 3.0);
  EXPECT_THROW(ComputeConvexHull(octagon), Error);
  EXPECT_THROW(ComputeConvexHull({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}), Error);
  EXPECT_THROW(ComputeConvexHull({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}, {4, 0, 0}}), Error);
  std::vector<Eigen::Vector3d> tetra = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  EXPECT_EQ(ComputeConvexHull(tetra).triangles.size(), 4u);
  tetra.emplace_back(std::nan(""), 0, 0);
  EXPECT_THROW(ComputeConvexHull(tetra), Error);
}

// The diameter is the largest pairwise distance: checked against every pair.
TEST(PointSetDiameter, MatchesEveryPair) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 700; ++i) points.emplace_back(30 * u(rng), 12 * u(rng), 5 * u(rng));
  double brute = 0;
  for (const auto& a : points) {
    for (const auto& b : points) brute = std::max(brute, (a - b).norm());
  }
  EXPECT_EQ(PointSetDiameter(points), brute);
  EXPECT_EQ(ComputeConvexHull(points).diameter, brute);
  EXPECT_EQ(PointSetDiameter({{1, 2, 3}}), 0.0);
}

}  // namespace
}  // namespace cadsynth
