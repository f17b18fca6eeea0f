#include "dataset/models.h"

#include <cstring>

#include <gtest/gtest.h>

#include "cad/shape.h"

namespace cadsynth {
namespace {

TEST(MeshDiameter, BoxDiameterIsItsSpaceDiagonal) {
  const Mesh box = Tessellate(MakeBox(30, 40, 120), TessellationOptions{});
  EXPECT_NEAR(MeshDiameter(box), std::sqrt(30.0 * 30 + 40 * 40 + 120 * 120), 1e-4);  // 130
}

TEST(MeshDiameter, MatchesBruteForceOnACurvedPart) {
  const Mesh cyl = Tessellate(MakeCylinder(15, 40), TessellationOptions{0.05, 0.2});
  double brute = 0;
  for (const auto& a : cyl.positions) {
    for (const auto& b : cyl.positions)
      brute = std::max(brute, (a.cast<double>() - b.cast<double>()).norm());
  }
  EXPECT_NEAR(MeshDiameter(cyl), brute, 1e-9);
  // Chords of the tessellated rim fall short of the exact 50 mm by at most twice the deflection.
  EXPECT_NEAR(brute, std::sqrt(30.0 * 30 + 40 * 40), 0.1);
  EXPECT_LE(brute, 50.0 + 1e-4);
}

TEST(EncodePly, HeaderAndBinaryBodyMatchTheMesh) {
  const Mesh box = Tessellate(MakeBox(1, 2, 3), TessellationOptions{});
  const std::string ply = EncodePly(box);
  const size_t end = ply.find("end_header\n");
  ASSERT_NE(end, std::string::npos);
  const std::string header = ply.substr(0, end);
  EXPECT_NE(header.find("format binary_little_endian 1.0"), std::string::npos);
  EXPECT_NE(header.find("element vertex " + std::to_string(box.num_vertices())), std::string::npos);
  EXPECT_NE(header.find("element face 12"), std::string::npos);
  EXPECT_NE(header.find("property float nx"), std::string::npos);
  const size_t body = end + std::strlen("end_header\n");
  EXPECT_EQ(ply.size() - body, box.num_vertices() * 24 + 12 * 13);
  float x;
  std::memcpy(&x, ply.data() + body + 24 * 5, sizeof(float));  // x of vertex 5
  EXPECT_EQ(x, box.positions[5].x());
}

}  // namespace
}  // namespace cadsynth
