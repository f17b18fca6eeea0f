#include "tools/pipeline/export.h"

#include <gtest/gtest.h>

#include "cad/core/error.h"
#include "cad/import.h"
#include "tests/test_support.h"
#include "tests/tools/pipeline/small_job.h"
#include "variants/families.h"

namespace cadsynth {
namespace {

using testing::Family;

TEST(ExportVariants, EveryVariantReimportsWithTheSameVolume) {
  testing::ScratchDir dir;
  RunSpec spec = DefaultRunSpec();
  spec.scenes = {
      SceneSpec{"kit",
                {Family("spur_gear", {{{"teeth", 13.0}}, {{"teeth", 27.0}, {"helix_angle", 0.3}}}),
                 Family("gear_pair", {{}}), Family("hex_nut", {{{"size", std::string("M6")}}})},
                {}}};
  const std::vector<VariantListing> listed = ListVariants(spec);
  ASSERT_EQ(listed.size(), 4u);
  EXPECT_EQ(listed[1].id, "kit/0/spur_gear/1");
  const std::vector<VariantListing> written = ExportVariants(spec, dir / "step", false);
  ASSERT_EQ(written.size(), 4u);
  for (size_t i = 0; i < written.size(); ++i) {
    const ParamValues& params =
        i < 2 ? spec.scenes[0].sources[0].variants[i] : spec.scenes[0].sources[i - 1].variants[0];
    const std::string family = i < 2 ? "spur_gear" : (i == 2 ? "gear_pair" : "hex_nut");
    const Assembly built = BuildVariant(*FindFamily(family), params, ImportOptions{});
    const Assembly again = ImportCad(written[i].step, ImportOptions{});
    ASSERT_EQ(again.instances.size(), built.instances.size()) << written[i].step;
    double v_built = 0, v_again = 0;
    for (const Instance& inst : built.instances) v_built += built.parts[inst.part].mass.volume_mm3;
    for (const Instance& inst : again.instances) v_again += again.parts[inst.part].mass.volume_mm3;
    EXPECT_NEAR(v_again, v_built, 1e-6 * v_built) << written[i].step;
  }
  EXPECT_THROW(ExportVariants(spec, dir / "step", false), Error);  // exists
  EXPECT_NO_THROW(ExportVariants(spec, dir / "step", true));
}

TEST(ExportVariants, ImpossibleVariantLeavesNoFolder) {
  testing::ScratchDir dir;
  RunSpec spec = DefaultRunSpec();
  spec.scenes = {SceneSpec{
      "s", {Family("spur_gear", {{{"teeth", 20.0}}, {{"teeth", 20.0}, {"bore", 60.0}}})}, {}}};
  try {
    ExportVariants(spec, dir / "step", false);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("s/0/spur_gear/1"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(
                  "bore diameter 60 mm must be smaller than the root diameter 35 mm"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), {}), 0);
}

}  // namespace
}  // namespace cadsynth
