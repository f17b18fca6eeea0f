#include "cad/step.h"

#include <fstream>

#include <gtest/gtest.h>

#include "cad/core/error.h"
#include "tests/test_support.h"

namespace cadsynth {
namespace {

using testing::ScratchDir;

std::string MessageOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(Step, WrittenAssemblyReadsBackWithInstancesNamesAndPlacements) {
  ScratchDir dir;
  const auto file = dir / "pair.step";
  const Eigen::Isometry3d left = Eigen::Translation3d(-100, 0, 0) * Eigen::Isometry3d::Identity();
  const Eigen::Isometry3d right =
      Eigen::Translation3d(100, 0, 0) * Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ());
  WriteStep(file, "fixture",
            {StepComponent{
                 "brick", MakeBox(40, 30, 20), {left, right}, Eigen::Vector3f(0.8f, 0.2f, 0.1f)},
             StepComponent{"pin", MakeCylinder(5, 60)}});
  ASSERT_TRUE(std::filesystem::exists(file));
  EXPECT_FALSE(std::filesystem::exists(file.string() + ".partial"));

  const Assembly a = ReadStep(file, TessellationOptions{});
  EXPECT_EQ(a.name, "fixture");
  ASSERT_EQ(a.parts.size(), 2u);  // the brick is one part used twice
  ASSERT_EQ(a.instances.size(), 3u);
  EXPECT_EQ(a.length_unit, "millimetre");
  const int brick = a.parts[0].name == "brick" ? 0 : 1;
  EXPECT_EQ(a.parts[brick].name, "brick");
  EXPECT_EQ(a.parts[1 - brick].name, "pin");
  EXPECT_NEAR(a.parts[brick].mass.volume_mm3, 24000.0, 1e-3);
  ASSERT_TRUE(a.parts[brick].color.has_value());
  EXPECT_TRUE(a.parts[brick].color->isApprox(Eigen::Vector3f(0.8f, 0.2f, 0.1f), 1e-3f));
  EXPECT_FALSE(a.parts[1 - brick].color.has_value());
  for (const Instance& i : a.instances) {
    EXPECT_EQ(i.path, "fixture/" + i.name);  // one level below the root
  }
  EXPECT_NEAR(a.parts[1 - brick].mass.volume_mm3, M_PI * 25 * 60, 1e-3);

  // The world bounds of each brick instance follow its placement.
  std::vector<Eigen::AlignedBox3d> bricks;
  for (const Instance& i : a.instances) {
    if (i.part == brick) bricks.push_back(a.parts[brick].mesh.Bounds(i.world_from_model));
  }
  ASSERT_EQ(bricks.size(), 2u);
  std::sort(bricks.begin(), bricks.end(),
            [](const auto& x, const auto& y) { return x.min().x() < y.min().x(); });
  EXPECT_TRUE(bricks[0].min().isApprox(Eigen::Vector3d(-100, 0, 0), 1e-4));
  EXPECT_TRUE(bricks[0].max().isApprox(Eigen::Vector3d(-60, 30, 20), 1e-4));
  // Rotated 90 degrees about z: x in [100 - 30, 100], y in [0, 40].
  EXPECT_TRUE(bricks[1].min().isApprox(Eigen::Vector3d(70, 0, 0), 1e-4));
  EXPECT_TRUE(bricks[1].max().isApprox(Eigen::Vector3d(100, 40, 20), 1e-4));
}

TEST(Step, BadFilesGiveOneClearError) {
  ScratchDir dir;
  const TessellationOptions o;
  EXPECT_EQ(MessageOf([&] { ReadStep(dir / "missing.stp", o); }),
            (dir / "missing.stp").string() + ": no such file");
  EXPECT_EQ(MessageOf([&] { ReadStep(dir.path(), o); }),
            dir.path().string() + ": is a folder, not a file");
  std::ofstream(dir / "empty.stp").close();
  EXPECT_EQ(MessageOf([&] { ReadStep(dir / "empty.stp", o); }),
            (dir / "empty.stp").string() + ": file is empty");
  std::ofstream(dir / "notes.stp") << "these are not the droids\n";
  EXPECT_NE(MessageOf([&] { ReadStep(dir / "notes.stp", o); }).find("not a readable STEP file"),
            std::string::npos);
  std::ofstream(dir / "truncated.stp") << "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((''),'2;1');\n";
  const std::string truncated = MessageOf([&] { ReadStep(dir / "truncated.stp", o); });
  EXPECT_EQ(truncated.rfind((dir / "truncated.stp").string() + ": ", 0), 0u) << truncated;
}

// 200,000 nested parentheses exhausted the stack inside OpenCASCADE's parser (SIGSEGV); they are
// refused before it runs. Parentheses inside a string or a comment do not count.
TEST(Step, AbsurdNestingIsRefusedBeforeParsing) {
  ScratchDir dir;
  {
    std::ofstream out(dir / "deep.stp");
    out << "ISO-10303-21;\nHEADER;\nENDSEC;\nDATA;\n#1=CARTESIAN_POINT('',"
        << std::string(200000, '(') << std::string(200000, ')') << ");\nENDSEC;\n";
  }
  EXPECT_EQ(MessageOf([&] { ReadStep(dir / "deep.stp", TessellationOptions{}); }),
            (dir / "deep.stp").string() +
                ":5: parentheses nested more than 1000 deep: not a STEP file cadsynth can read");
  {
    std::ofstream out(dir / "quoted.stp");
    out << "ISO-10303-21;\nHEADER;\nENDSEC;\nDATA;\n/* " << std::string(5000, '(')
        << " */\n#1=PRODUCT('" << std::string(5000, '(') << "','it''s','',());\nENDSEC;\n";
  }
  const std::string quoted =
      MessageOf([&] { ReadStep(dir / "quoted.stp", TessellationOptions{}); });
  EXPECT_EQ(quoted.find("nested"), std::string::npos) << quoted;
}

TEST(Step, CorruptedSharedFileIsAnErrorNotACrash) {
  CADSYNTH_REQUIRE_DATA(file, "step/awkward/bug32314_corrupted.stp");
  const std::string message = MessageOf([&] { ReadStep(file, TessellationOptions{}); });
  EXPECT_EQ(message.rfind(file.string() + ": corrupted STEP file: Line 13: ", 0), 0u) << message;
}

TEST(Step, As1AssemblyHasItsFivePartsInMillimetres) {
  CADSYNTH_REQUIRE_DATA(file, "step/assemblies/as1-oc-214.stp");
  const Assembly a = ReadStep(file, TessellationOptions{});
  ASSERT_EQ(a.parts.size(), 5u);
  std::map<std::string, Eigen::Vector3d> size;
  for (const Part& p : a.parts) size[p.name] = p.mesh.Bounds().sizes();
  ASSERT_TRUE(size.count("plate") && size.count("l-bracket") && size.count("rod") &&
              size.count("bolt") && size.count("nut"));
  EXPECT_TRUE(size["plate"].isApprox(Eigen::Vector3d(180, 150, 20), 1e-3))
      << size["plate"].transpose();
  EXPECT_NEAR(size["rod"].maxCoeff(), 200.0, 0.01);
  // Two L-brackets, each holding three bolt-nut pairs; the rod carries two more nuts.
  std::map<std::string, int> count;
  for (const Instance& i : a.instances) ++count[a.parts[i.part].name];
  EXPECT_EQ(count["plate"], 1);
  EXPECT_EQ(count["l-bracket"], 2);
  EXPECT_EQ(count["rod"], 1);
  EXPECT_EQ(count["bolt"], 6);
  EXPECT_EQ(count["nut"], 8);
}

}  // namespace
}  // namespace cadsynth
