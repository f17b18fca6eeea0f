// The checked STL, PLY and OFF readers: answers worked out by hand, and every damaged file that
// crashed, aborted or hung assimp refused with the file and line.
#include "cad/mesh_formats.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cad/core/error.h"

namespace cadsynth {
namespace {

using Triangle = Eigen::Matrix<uint32_t, 3, 1>;

std::string ErrorOf(const std::string& bytes, const std::string& ext) {
  try {
    ParseMeshBytes(bytes, ext, "f" + ext);
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

void Put(std::string* out, const void* data, size_t size, bool big_endian = false) {
  std::string bytes(static_cast<const char*>(data), size);
  if (big_endian) std::reverse(bytes.begin(), bytes.end());
  *out += bytes;
}

// A binary STL: 80-byte header, count, 50 bytes per facet.
std::string BinaryStl(const std::string& header, const std::vector<std::array<float, 9>>& facets,
                      uint32_t declared) {
  std::string out = header;
  out.resize(80, ' ');
  Put(&out, &declared, 4);
  for (const auto& f : facets) {
    const float normal[3] = {0, 0, 1};
    Put(&out, normal, 12);
    Put(&out, f.data(), 36);
    out += std::string(2, '\0');
  }
  return out;
}

TEST(ParseStl, AsciiFacetsKeepTheirCornersInFileOrder) {
  const Mesh m = ParseStl(
      "solid part name with spaces\n"
      "  facet normal 0 0 1\n    outer loop\n      vertex 0 0 0\n      vertex 1.5 0 0\n"
      "      vertex 0 2e1 0\n    endloop\n  endfacet\n"
      "  facet normal 0 0 -1\n outer loop\n vertex 0 0 0\n vertex 0 1 0\n vertex -1 0 +3\n"
      " endloop\n endfacet\nendsolid part name with spaces\n",
      "a.stl");
  ASSERT_EQ(m.positions.size(), 6u);
  ASSERT_EQ(m.triangles.size(), 2u);
  EXPECT_EQ(m.positions[1], Eigen::Vector3f(1.5f, 0, 0));
  EXPECT_EQ(m.positions[2], Eigen::Vector3f(0, 20, 0));
  EXPECT_EQ(m.positions[5], Eigen::Vector3f(-1, 0, 3));
  EXPECT_EQ(m.triangles[1], Triangle(3, 4, 5));
}

TEST(ParseStl, BinaryIsReadEvenWhenItsHeaderSaysSolid) {
  const std::string bytes =
      BinaryStl("solid exported by a CAD tool", {{0, 0, 0, 1, 0, 0, 0, 1, 0}}, 1);
  const Mesh m = ParseStl(bytes, "b.stl");
  ASSERT_EQ(m.triangles.size(), 1u);
  EXPECT_EQ(m.positions[2], Eigen::Vector3f(0, 1, 0));
  // Trailing bytes after the declared facets are ignored when the header is not text.
  const Mesh extra =
      ParseStl(BinaryStl("binary", {{0, 0, 0, 1, 0, 0, 0, 1, 0}}, 1) + "xyz", "c.stl");
  EXPECT_EQ(extra.triangles.size(), 1u);
}

TEST(ParseStl, DamagedFilesAreRefusedWithTheirLine) {
  // A binary file claiming more facets than it holds (a cut download).
  EXPECT_EQ(ErrorOf(BinaryStl("binary", {{0, 0, 0, 1, 0, 0, 0, 1, 0}}, 1000), ".stl"),
            "f.stl: truncated binary STL: its header says 1000 triangles, the file holds 1");
  EXPECT_EQ(ErrorOf("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
                    "endloop\nendfacet\n",
                    ".stl"),
            "f.stl:7: a facet with 2 vertices, not 3");
  EXPECT_EQ(ErrorOf("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 zero 0\n", ".stl"),
            "f.stl:4: expected a number, got 'zero'");
  EXPECT_EQ(ErrorOf("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n", ".stl"),
            "f.stl:4: the file ends inside a facet");
  EXPECT_EQ(ErrorOf("solid x\nbanana\n", ".stl"),
            "f.stl:2: expected facet, vertex or endfacet, got 'banana'");
  EXPECT_EQ(ErrorOf("hello", ".stl"),
            "f.stl: not an STL file (neither 'solid' text nor a binary header and count)");
}

// PLY: a unit square as a quad plus an unused vertex, in each of the three encodings.
std::string SquarePly(const std::string& format) {
  std::string out = "ply\nformat " + format +
                    " 1.0\ncomment made by hand\nelement vertex 5\nproperty float x\n"
                    "property float y\nproperty double z\nproperty uchar red\n"
                    "element face 1\nproperty list uchar int vertex_indices\n"
                    "property int flags\nelement edge 1\nproperty list uchar uint vertices\n"
                    "end_header\n";
  const float xy[5][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {9, 9}};
  if (format == "ascii") {
    out += "0 0 0 255\n1 0 0 255\n1 1 0 255\n0 1 0 255\n9 9 9 0\n4 0 1 2 3 7\n2 0 4\n";
    return out;
  }
  const bool big = format == "binary_big_endian";
  for (int v = 0; v < 5; ++v) {
    Put(&out, &xy[v][0], 4, big);
    Put(&out, &xy[v][1], 4, big);
    const double z = v == 4 ? 9 : 0;
    Put(&out, &z, 8, big);
    out += '\xff';
  }
  out += '\x04';
  for (const int32_t i : {0, 1, 2, 3, 7}) Put(&out, &i, 4, big);
  out += '\x02';
  for (const uint32_t i : {0u, 4u}) Put(&out, &i, 4, big);
  return out;
}

TEST(ParsePly, EveryEncodingGivesTheSameTrianglesAndDropsUnusedVertices) {
  for (const char* format : {"ascii", "binary_little_endian", "binary_big_endian"}) {
    const Mesh m = ParsePly(SquarePly(format), "sq.ply");
    ASSERT_EQ(m.positions.size(), 4u) << format;  // vertex 4 is only used by an edge
    EXPECT_EQ(m.positions[2], Eigen::Vector3f(1, 1, 0)) << format;
    ASSERT_EQ(m.triangles.size(), 2u) << format;
    EXPECT_EQ(m.triangles[0], Triangle(0, 1, 2)) << format;
    EXPECT_EQ(m.triangles[1], Triangle(0, 2, 3)) << format;
  }
}

TEST(ParsePly, AConcaveQuadIsSplitAlongItsInsideDiagonal) {
  // An arrowhead, concave at vertex 3 (0.5, 0.3): the diagonal 0-2 runs outside it.
  const Mesh m = ParsePly(
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_index\nend_header\n"
      "0 0 0\n0.5 1 0\n1 0 0\n0.5 0.3 0\n4 0 1 2 3\n",
      "arrow.ply");
  ASSERT_EQ(m.triangles.size(), 2u);
  EXPECT_EQ(m.triangles[0], Triangle(0, 1, 3));
  EXPECT_EQ(m.triangles[1], Triangle(1, 2, 3));
}

TEST(ParsePly, DamagedFilesAreRefusedWithTheirLine) {
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  // A face naming vertex 7 of 3 (assimp: SIGSEGV).
  EXPECT_EQ(ErrorOf(head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", ".ply"),
            "f.ply:13: face refers to vertex 7.000000, but the file has 3 vertices before it");
  // An element count with no properties (assimp: looped for ever).
  EXPECT_EQ(ErrorOf("ply\nformat ascii 1.0\nelement vertex 1000000000\nend_header\n", ".ply"),
            "f.ply:3: element 'vertex' has 1000000000 records but no properties");
  // More records than the file could hold: refused before anything is reserved.
  EXPECT_EQ(ErrorOf("ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\n"
                    "property float x\nproperty float y\nproperty float z\nend_header\n",
                    ".ply"),
            "f.ply:3: element 'vertex' has 4000000000 records, more than the 0 bytes left in the "
            "file can hold");
  // A binary body cut short (assimp: SIGSEGV).
  std::string cut = SquarePly("binary_little_endian");
  cut.resize(cut.size() - 15);
  EXPECT_EQ(ErrorOf(cut, ".ply"),
            "f.ply: truncated: the file ends in the list item of element 'face' 0 (of the count "
            "its header gives)");
  EXPECT_EQ(ErrorOf(head + "0 0 0\n1 0 0\n0 1\n", ".ply"),
            "f.ply:12: the file ends where value was expected");
  EXPECT_EQ(ErrorOf("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                    "property float z\nend_header\n0 0 zero\n",
                    ".ply"),
            "f.ply:8: expected a number (value), got 'zero'");
  EXPECT_EQ(
      ErrorOf("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n", ".ply"),
      "f.ply:3: element 'vertex' has no x, y and z properties");
  EXPECT_EQ(ErrorOf("ply\nformat ascii 1.0\nelement vertex 1\nproperty quaternion x\n", ".ply"),
            "f.ply:4: unknown property type 'quaternion'");
  EXPECT_EQ(ErrorOf("ply\nformat ascii 1.0\nelement vertex 1\n", ".ply"),
            "f.ply:3: the header has no 'end_header'");
  EXPECT_EQ(ErrorOf("ply\nelement vertex 0\nend_header\n", ".ply"),
            "f.ply: the PLY header has no 'format' line");
  EXPECT_EQ(ErrorOf("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                    "property float y\nproperty float z\nend_header\n0 0 0\n",
                    ".ply"),
            "f.ply: the PLY file has no faces (a point cloud?)");
  EXPECT_EQ(ErrorOf("PK\x03\x04", ".ply"),
            "f.ply:1: not a PLY file (it does not begin with 'ply')");
}

TEST(ParseOff, ColouredOffWithCommentsAndCountsOnTheKeywordLine) {
  const Mesh m = ParseOff(
      "COFF 4 2 0 # a square\n# comment line\n0 0 0 255 0 0 255\n1 0 0 255 0 0 255\n"
      "1 1 0 0 255 0 255\n\n0 1 0 0 0 255 255\n3 0 1 2 0.5 0.5 0.5\n3 0 2 3\n",
      "sq.off");
  ASSERT_EQ(m.positions.size(), 4u);
  EXPECT_EQ(m.positions[3], Eigen::Vector3f(0, 1, 0));
  ASSERT_EQ(m.triangles.size(), 2u);
  EXPECT_EQ(m.triangles[1], Triangle(0, 2, 3));
}

TEST(ParseOff, DamagedFilesAreRefusedWithTheirLine) {
  // A face list cut short (assimp: an assert's abort).
  EXPECT_EQ(ErrorOf("OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 1\n", ".off"),
            "f.off:8: the file ends in its face list (the header gives 4 vertices and 4 faces)");
  EXPECT_EQ(ErrorOf("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", ".off"),
            "f.off:6: face 0 refers to vertex 3.000000, but the file has 3");
  EXPECT_EQ(ErrorOf("OFF\n99999999 1 0\n0 0 0\n", ".off"),
            "f.off:3: the header's 99999999 vertices and 1 faces cannot fit in the 6 bytes that "
            "follow");
  EXPECT_EQ(ErrorOf("4OFF\n1 0 0\n0 0 0 0\n", ".off"),
            "f.off:1: only 3D OFF files are read, not '4OFF'");
  EXPECT_EQ(ErrorOf("OFF BINARY\n", ".off"),
            "f.off:1: binary OFF files are not read; write them as text");
  EXPECT_EQ(ErrorOf("ply\n", ".off"), "f.off:1: not an OFF file (it does not begin with 'OFF')");
}

}  // namespace
}  // namespace cadsynth
