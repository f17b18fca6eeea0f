// A corpus of hostile CAD and mesh files, built here in code from files our own code writes (no
// third-party bytes): each must be read or refused cleanly by `cadsynth inspect` and by a one-view
// `cadsynth generate`: exit 0, or exit 1 with one error line naming the file; never a signal, a
// hang, a library's wording, or a half-written output folder.
#include <sys/wait.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <BRepTools.hxx>
#include <IGESControl_Writer.hxx>

#include "cad/occt_shape.h"
#include "cad/shape.h"
#include "cad/step.h"
#include "tests/test_support.h"

namespace cadsynth {
namespace {

using testing::ScratchDir;

// What must happen to a file: refused (exit 1, one error line naming it), or read (exit 0). A
// damaged file is read only where what survives is a usable part, and then with a warning that
// says what was dropped: reading one silently, as if it were good, fails the test.
struct Hostile {
  std::string name;
  std::string bytes;
  int expected;         // exit code: 1 refused, 0 read
  std::string message;  // a part of the error (refused) or of a warning (read), when one is due
  bool damaged = true;  // false: a sound file of an awkward shape, read without a word
};

std::string Binary(const void* data, size_t size) {
  return std::string(static_cast<const char*>(data), size);
}

std::string BinaryStl(uint32_t declared, const std::vector<std::array<float, 9>>& facets) {
  std::string out(80, ' ');
  out += Binary(&declared, 4);
  for (const auto& f : facets) {
    out += std::string(12, '\0') + Binary(f.data(), 36) + std::string(2, '\0');
  }
  return out;
}

std::string Noise(size_t size, unsigned seed) {
  std::mt19937 random(seed);
  std::string out(size, '\0');
  for (char& c : out) c = static_cast<char>(random() & 0xff);
  return out;
}

std::string Head(const std::string& text, double share) {
  return text.substr(0, static_cast<size_t>(static_cast<double>(text.size()) * share));
}

std::vector<Hostile> MakeCorpus(const ScratchDir& dir) {
  std::vector<Hostile> corpus;
  const std::string ply_head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  corpus.push_back(
      {"index.ply", ply_head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", 1, "refers to vertex"});
  {
    std::string binary =
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
        "property float y\nproperty float z\nelement face 1\n"
        "property list uchar int vertex_indices\nend_header\n";
    const float v[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    binary += Binary(v, sizeof v);
    corpus.push_back({"cut_binary.ply", binary + "\x03", 1, "truncated"});
  }
  corpus.push_back({"no_properties.ply",
                    "ply\nformat ascii 1.0\nelement vertex 1000000000\nelement face 1\n"
                    "property list uchar int vertex_indices\nend_header\n3 0 1 2\n",
                    1, "but no properties"});
  corpus.push_back({"huge_count.ply",
                    "ply\nformat binary_big_endian 1.0\nelement vertex 4294967295\n"
                    "property double x\nproperty double y\nproperty double z\nend_header\n",
                    1, "bytes left in the file"});
  corpus.push_back({"cut.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 1\n", 1,
                    "ends in its face list"});
  corpus.push_back(
      {"inf.off", "OFF\n3 1 0\ninf 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", 1, "is not a finite number"});
  corpus.push_back({"no_faces.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n", 1, "holds no triangles"});
  const float nan = std::numeric_limits<float>::quiet_NaN();
  corpus.push_back({"nan.stl",
                    BinaryStl(2, {{0, 0, 0, 10, 0, 0, 0, 10, 0}, {0, 0, 0, 0, 10, 0, 0, 0, nan}}),
                    1, "is not a finite number"});
  corpus.push_back(
      {"cut.stl", BinaryStl(1000, {{0, 0, 0, 10, 0, 0, 0, 10, 0}}), 1, "truncated binary STL"});
  corpus.push_back({"zero.stl", BinaryStl(0, {}), 1, "holds no triangles"});
  // A tetrahedron at absurd scales, and one whose corners all coincide.
  corpus.push_back(
      {"huge.stl",
       BinaryStl(2, {{0, 0, 0, 1e30f, 0, 0, 0, 1e30f, 0}, {0, 0, 0, 0, 1e30f, 0, 0, 0, 1e30f}}), 1,
       "more than the 1 km cadsynth takes"});
  corpus.push_back(
      {"tiny.stl",
       BinaryStl(2, {{0, 0, 0, 1e-30f, 0, 0, 0, 1e-30f, 0}, {0, 0, 0, 0, 1e-30f, 0, 0, 0, 1e-30f}}),
       0, ""});  // read, with warnings: not closed, an implausible size
  corpus.push_back({"point.stl",
                    BinaryStl(2, {{1, 1, 1, 1, 1, 1, 1, 1, 1}, {1, 1, 1, 1, 1, 1, 1, 1, 1}}), 1,
                    "the mesh has no area"});
  {
    // A flat octagon (crashed the stable poses): read, and rests on either side.
    std::ostringstream stl;
    stl << "solid octagon\n";
    for (int i = 0; i < 8; ++i) {
      const double a = i * M_PI / 4, b = (i + 1) * M_PI / 4;
      stl << "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex " << 20 * std::cos(a) << " "
          << 20 * std::sin(a) << " 0\nvertex " << 20 * std::cos(b) << " " << 20 * std::sin(b)
          << " 0\nendloop\nendfacet\n";
    }
    stl << "endsolid octagon\n";
    corpus.push_back({"octagon.stl", stl.str(), 0, "", false});
  }
  corpus.push_back({"index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99\n", 1, "out of range"});
  corpus.push_back({"nan.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", 1, "not a finite number"});
  corpus.push_back({"lines.obj", "v 0 0 0\nv 1 0 0\nl 1 2\n", 1, ""});
  corpus.push_back(
      {"bad.gltf",
       R"({"asset":{"version":"2.0"},"buffers":[{"byteLength":12,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAA"}],)"
       R"("bufferViews":[{"buffer":0,"byteLength":12}],"accessors":[{"bufferView":0,"componentType":5126,"count":1000,"type":"VEC3"}],)"
       R"("meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],"nodes":[{"mesh":0}],"scenes":[{"nodes":[0]}]})",
       1, "out of range"});
  corpus.push_back({"noise.3mf", "PK\x03\x04" + Noise(3000, 1), 1, ""});
  // 3 kB of noise named .3mf kept assimp busy for more than 10 minutes.
  corpus.push_back({"noise_nozip.3mf", Noise(3000, 6), 1, "not a 3MF file"});
  corpus.push_back({"noise.dae", Noise(3000, 7), 1, "not a COLLADA file"});
  corpus.push_back({"noise.gltf", Noise(3000, 8), 1, "not a glTF file"});
  corpus.push_back({"cut.dae",
                    "<?xml version=\"1.0\"?>\n<COLLADA xmlns=\"http://www.collada.org/2005/11/"
                    "COLLADASchema\" version=\"1.4.1\"><asset><unit meter=\"0.001\"/></asset>"
                    "<library_geometries><geometry id=\"g\"><mesh><source id=\"p\"><float_array "
                    "id=\"a\" count=\"9000\">0 0 0 1 0",
                    1, ""});
  corpus.push_back({"noise.glb", "glTF" + Noise(2000, 2), 1, ""});

  // STEP, IGES and BREP written by OpenCASCADE (through our own writers), then damaged.
  WriteStep(dir / "box.step", "box", {StepComponent{"box", MakeBox(30, 20, 10)}});
  const std::string step = testing::ReadFile(dir / "box.step");
  {
    std::string toint = step;
    for (size_t at = toint.find("CARTESIAN_POINT"); at != std::string::npos;
         at = toint.find("CARTESIAN_POINT", at))
      toint.replace(at, 15, "CARTESIAN_TOINT");
    corpus.push_back({"toint.step", toint, 1, ""});
  }
  {
    // The first AXIS2_PLACEMENT_3D made to name itself as its origin.
    std::string self = step;
    const size_t entity = self.find("AXIS2_PLACEMENT_3D(");
    const size_t hash = self.rfind('#', entity);
    const std::string id = self.substr(hash, self.find_first_of(" =", hash) - hash);
    const size_t first_ref = self.find('#', entity);
    const size_t end_ref = self.find_first_of(",)", first_ref);
    self.replace(first_ref, end_ref - first_ref, id);
    corpus.push_back({"self_axis.step", self, 1, ""});
  }
  corpus.push_back({"deep.step",
                    "ISO-10303-21;\nHEADER;\nENDSEC;\nDATA;\n#1=A(" + std::string(200000, '(') +
                        std::string(200000, ')') + ");\nENDSEC;\nEND-ISO-10303-21;\n",
                    1, ""});
  corpus.push_back({"cut.step", Head(step, 0.5), 1, "not a readable STEP file"});
  corpus.push_back({"noise.step", "ISO-10303-21;\nHEADER;\n" + Noise(4000, 3), 1, ""});
  {
    IGESControl_Writer writer("MM", 0);
    writer.AddShape(OcctShape(MakeBox(30, 20, 10)));
    writer.ComputeModel();
    writer.Write((dir / "box.igs").string().c_str());
    corpus.push_back({"cut.igs", Head(testing::ReadFile(dir / "box.igs"), 0.5), 1, ""});
  }
  corpus.push_back({"noise.igs", Noise(4000, 4), 1, ""});
  BRepTools::Write(OcctShape(MakeBox(30, 20, 10)), (dir / "box.brep").string().c_str());
  const std::string brep = testing::ReadFile(dir / "box.brep");
  corpus.push_back({"cut.brep", Head(brep, 0.5), 1, "truncated"});
  // Cut inside the shape list: OpenCASCADE's reader looped for ever.
  corpus.push_back({"cut_shapes.brep", brep.substr(0, brep.rfind('*')), 1, "truncated"});
  corpus.push_back(
      {"noise.brep", "CASCADE Topology V1, (c) Matra-Datavision\n" + Noise(3000, 5), 1, ""});
  for (const Hostile& h : corpus) {
    std::ofstream(dir / h.name, std::ios::binary) << h.bytes;
  }
  return corpus;
}

struct Outcome {
  int code = -1;
  std::string err;
};

// `cadsynth ARGS` in DIR, stopped (exit 137) if it runs for more than 5 minutes.
Outcome RunCadsynth(const std::string& args, const ScratchDir& dir) {
  const std::string command = "cd '" + dir.path().string() +
                              "' && timeout -s KILL 300 '" CADSYNTH_EXE "' " + args +
                              " > /dev/null 2> stderr.txt";
  const int status = std::system(command.c_str());
  Outcome outcome;
  outcome.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  outcome.err = testing::ReadFile(dir / "stderr.txt");
  return outcome;
}

// The expected exit: 1 with exactly one error line that names the file (warnings may precede it),
// or 0, with a warning naming the file where it is damaged. Returns whether it was refused.
bool ExpectClean(const Hostile& h, const Outcome& run, const std::string& what) {
  const std::string where = what + " " + h.name + ": " + run.err;
  EXPECT_TRUE(run.code == 0 || run.code == 1) << "exit " << run.code << " of " << where;
  EXPECT_EQ(run.code, h.expected) << where;
  std::istringstream lines(run.err);
  int errors = 0, warnings = 0;
  for (std::string line; std::getline(lines, line);) {
    EXPECT_LE(line.size(), 2100u) << where;
    if (line.rfind("warning: ", 0) == 0 && line.find(h.name) != std::string::npos &&
        (h.message.empty() || line.find(h.message) != std::string::npos))
      ++warnings;
    if (line.rfind("error: ", 0) != 0) continue;
    ++errors;
    EXPECT_NE(line.find(h.name), std::string::npos) << where;
    EXPECT_EQ(line.find("internal"), std::string::npos) << where;
    EXPECT_EQ(line.find("exception"), std::string::npos) << where;
    if (!h.message.empty()) {
      EXPECT_NE(line.find(h.message), std::string::npos) << where;
    }
  }
  if (run.code == 1) {
    EXPECT_EQ(errors, 1) << where;
  } else if (h.damaged) {
    EXPECT_GE(warnings, 1) << "a damaged file read as if it were good: " << where;
  }
  return run.code == 1;
}

// How many of the corpus must be refused: the test counts its refusals against this, so a
// change that silently reads damaged files cannot pass by returning early.
size_t Refusals(const std::vector<Hostile>& corpus) {
  return static_cast<size_t>(std::count_if(corpus.begin(), corpus.end(),
                                           [](const Hostile& h) { return h.expected == 1; }));
}

TEST(HostileFiles, InspectReadsOrRefusesEachCleanly) {
  ScratchDir dir;
  const std::vector<Hostile> corpus = MakeCorpus(dir);
  size_t refused = 0;
  for (const Hostile& h : corpus)
    refused += ExpectClean(h, RunCadsynth("inspect " + h.name, dir), "inspect");
  EXPECT_EQ(refused, Refusals(corpus));
  EXPECT_GE(refused, 20u);  // the corpus is mostly damaged beyond use
}

TEST(HostileFiles, OneViewGenerateReadsOrRefusesEachCleanly) {
  ScratchDir dir;
  const std::vector<Hostile> corpus = MakeCorpus(dir);
  size_t refused = 0;
  for (const Hostile& h : corpus) {
    std::ofstream(dir / "r.yaml") << "parts: [{file: " << h.name
                                  << "}]\nsweep: {yaw: 0, pitch: 45, radius: 0.5 m}\n";
    const Outcome run = RunCadsynth("generate r.yaml -o out --no-cache --quiet", dir);
    refused += ExpectClean(h, run, "generate");
    if (run.code == 0) {
      EXPECT_TRUE(std::filesystem::exists(dir / "out" / "camera.json")) << h.name;
    } else {
      EXPECT_FALSE(std::filesystem::exists(dir / "out")) << h.name;
    }
    EXPECT_FALSE(std::filesystem::exists(dir / ".out.partial")) << h.name;
    std::filesystem::remove_all(dir / "out");
  }
  EXPECT_EQ(refused, Refusals(corpus));
}

}  // namespace
}  // namespace cadsynth
