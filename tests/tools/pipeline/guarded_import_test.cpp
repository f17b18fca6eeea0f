// Reading files in a child process: the child's crash, hang or error becomes one clear Error.
#include "tools/pipeline/guarded_import.h"

#include <sys/stat.h>

#include <chrono>
#include <fstream>

#include <gtest/gtest.h>

#include "cad/core/error.h"
#include "cad/shape.h"
#include "cad/step.h"
#include "tests/test_support.h"
#include "tests/tools/cli_support.h"

namespace cadsynth {
namespace {

using testing::ScratchDir;

std::string MessageOf(const std::filesystem::path& file, const ReaderProcess& reader) {
  std::vector<std::string> warnings;
  try {
    ImportGuarded(file, ImportOptions{}, &reader, &warnings);
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

// A stand-in reader: a shell script doing what a reader does when things go wrong.
std::filesystem::path Script(const ScratchDir& dir, const std::string& name,
                             const std::string& body) {
  const std::filesystem::path path = dir / name;
  std::ofstream(path) << "#!/bin/sh\n" << body << "\n";
  ::chmod(path.c_str(), 0755);
  return path;
}

TEST(GuardedImport, CrashHangAndErrorOfTheReaderAreErrors) {
  ScratchDir dir;
  std::ofstream(dir / "part.obj") << "v 0 0 0\n";
  const std::filesystem::path file = dir / "part.obj";
  EXPECT_EQ(MessageOf(file, {Script(dir, "crash.sh", "kill -SEGV $$"), 60}),
            file.string() + ": cannot read: the reader crashed on this file (Segmentation fault)");
  EXPECT_EQ(MessageOf(file, {Script(dir, "abort.sh", "kill -ABRT $$"), 60}),
            file.string() + ": cannot read: the reader crashed on this file (Aborted)");
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(MessageOf(file, {Script(dir, "hang.sh", "exec sleep 60"), 0.5}),
            file.string() +
                ": the reader did not finish in 0.5 s (a damaged file? limits.read_timeout sets "
                "the time)");
  // Its pipes closed, the reader still runs: the same time limit stops it.
  EXPECT_EQ(MessageOf(file, {Script(dir, "quiet.sh", "exec >&- 2>&-; exec sleep 60"), 0.5}),
            file.string() +
                ": the reader did not finish in 0.5 s (a damaged file? limits.read_timeout sets "
                "the time)");
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 30);
  EXPECT_EQ(MessageOf(file, {Script(dir, "fail.sh", "echo 'part.obj: no faces' >&2; exit 3"), 60}),
            "part.obj: no faces");
  EXPECT_EQ(MessageOf(file, {Script(dir, "garbage.sh", "echo not an assembly"), 60})
                .find(file.string() + ": the reader's answer is damaged"),
            0u);
  EXPECT_NE(MessageOf(file, {dir / "missing-reader", 60}).find("cannot start a reader"),
            std::string::npos);
  EXPECT_FALSE(NeedsGuardedReader("big.STL"));  // read in-process by our checked readers
  EXPECT_FALSE(NeedsGuardedReader("scan.ply"));
  EXPECT_TRUE(NeedsGuardedReader("part.obj"));
  EXPECT_TRUE(NeedsGuardedReader("part.step"));
}

// Read by the real executable in a child, a file gives the assembly read in this process.
TEST(GuardedImport, ChildReadsWhatThisProcessReads) {
  ScratchDir dir;
  WriteStep(dir / "kit.step", "kit",
            {StepComponent{"brick", MakeBox(40, 30, 20), {Eigen::Isometry3d::Identity()}},
             StepComponent{"pin", MakeCylinder(4, 30), {Eigen::Isometry3d::Identity()}}});
  const ReaderProcess reader{CADSYNTH_EXE, 120};
  std::vector<std::string> guarded_warnings, local_warnings;
  const Assembly guarded =
      ImportGuarded(dir / "kit.step", ImportOptions{}, &reader, &guarded_warnings);
  const Assembly local = ImportGuarded(dir / "kit.step", ImportOptions{}, nullptr, &local_warnings);
  EXPECT_EQ(guarded_warnings, local_warnings);
  ASSERT_EQ(guarded.parts.size(), local.parts.size());
  for (size_t p = 0; p < local.parts.size(); ++p) {
    EXPECT_EQ(guarded.parts[p].name, local.parts[p].name);
    ASSERT_EQ(guarded.parts[p].mesh.positions.size(), local.parts[p].mesh.positions.size());
    EXPECT_TRUE(std::equal(local.parts[p].mesh.positions.begin(),
                           local.parts[p].mesh.positions.end(),
                           guarded.parts[p].mesh.positions.begin()));
    EXPECT_EQ(guarded.parts[p].mass.volume_mm3, local.parts[p].mass.volume_mm3);
    EXPECT_FALSE(guarded.parts[p].brep.IsNull());
  }
  EXPECT_EQ(guarded.instances.size(), local.instances.size());
}

// A real STEP file with one entity name misspelled everywhere crashes OpenCASCADE (SIGSEGV):
// inspect and generate now end with one error line and exit 1, and write nothing.
TEST(GuardedImport, CrashingStepFileEndsCleanly) {
  CADSYNTH_REQUIRE_DATA(real, "step/parts/sg1-c5-214.stp");
  ScratchDir dir;
  std::string text = testing::ReadFile(real);
  for (size_t at = text.find("CARTESIAN_POINT"); at != std::string::npos;
       at = text.find("CARTESIAN_POINT", at))
    text.replace(at, 15, "CARTESIAN_TOINT");
  std::ofstream(dir / "toint.stp") << text;
  const testing::CliRun inspect = testing::Cadsynth("inspect toint.stp", dir);
  EXPECT_EQ(inspect.code, 1) << inspect.err;
  EXPECT_NE(inspect.err.find("the reader crashed on this file"), std::string::npos) << inspect.err;
  std::ofstream(dir / "r.yaml") << "parts: [{file: toint.stp}]\nsweep: {yaw: 0, pitch: 45, "
                                   "radius: 0.5 m}\n";
  const testing::CliRun generate = testing::Cadsynth("generate r.yaml -o out --no-cache", dir);
  EXPECT_EQ(generate.code, 1) << generate.err;
  EXPECT_NE(generate.err.find("the reader crashed on this file"), std::string::npos)
      << generate.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out"));
  EXPECT_FALSE(std::filesystem::exists(dir / ".out.partial"));
}

// Files that crashed assimp (a PLY face naming vertex 7 of 3: SIGSEGV; an OFF face list cut short:
// an assert's abort) now end inspect with an error naming the file and line (our checked readers).
TEST(GuardedImport, MeshFilesThatCrashedAssimpEndCleanly) {
  ScratchDir dir;
  std::ofstream(dir / "index.ply")
      << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
         "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
         "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n";
  std::ofstream(dir / "cut.off") << "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 1\n";
  for (const char* name : {"index.ply", "cut.off"}) {
    const testing::CliRun inspect = testing::Cadsynth(std::string("inspect ") + name, dir);
    EXPECT_EQ(inspect.code, 1) << name << ": " << inspect.err;
    EXPECT_EQ(inspect.err.rfind("error: " + std::string(name) + ":", 0), 0u) << inspect.err;
    EXPECT_EQ(std::count(inspect.err.begin(), inspect.err.end(), '\n'), 1) << inspect.err;
  }
}

}  // namespace
}  // namespace cadsynth
