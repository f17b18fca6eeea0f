// `cadsynth inspect` reports what a run would work out about each part: its symmetries and, for
// gears, their parameters (issue 20).
#include "tools/pipeline/inspect.h"

#include <cmath>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cad/shape.h"
#include "cad/step.h"
#include "tests/test_support.h"
#include "variants/families.h"

namespace cadsynth {
namespace {

TEST(Inspect, ShowsSymmetriesAndRecognisedGears) {
  testing::ScratchDir dir;
  const FamilyInfo& spur = *FindFamily("spur_gear");
  const ShapeAssembly gear = BuildVariantShapes(
      spur, CompleteParams(spur, {{"teeth", 25.0}, {"module", 1.5}, {"bore", 10.0}}));
  WriteStep(dir / "parts.step", "parts",
            {StepComponent{"gear", gear.components.at(0).shape},
             StepComponent{"block", MakeBox(60, 40, 30), {Eigen::Isometry3d::Identity()}}});
  const std::string text = InspectText(dir / "parts.step", ImportOptions{}, nullptr);
  EXPECT_NE(text.find("25-fold about (0, 0, "), std::string::npos) << text;
  EXPECT_NE(text.find("1) and 25 flips"), std::string::npos) << text;
  EXPECT_NE(text.find("gears (recognised on the meshes):"), std::string::npos) << text;
  EXPECT_NE(text.find("spur, 25 teeth, module 1.5 mm, pressure angle 20"), std::string::npos)
      << text;

  const nlohmann::json j =
      nlohmann::json::parse(InspectJson(dir / "parts.step", ImportOptions{}, nullptr));
  ASSERT_EQ(j["parts"].size(), 2u);
  for (const nlohmann::json& part : j["parts"]) {
    if (part["name"] == "gear") {
      EXPECT_EQ(part["symmetry"]["axes"][0]["order"], 25);
      EXPECT_EQ(part["symmetry"]["discrete"], 49);  // 24 turns and 25 flips
      EXPECT_LE(part["symmetry"]["largest_deviation_mm"].get<double>(),
                part["symmetry"]["tolerance_mm"].get<double>());
      EXPECT_EQ(part["gear"]["teeth"], 25);
      EXPECT_NEAR(part["gear"]["module_mm"].get<double>(), 1.5, 0.015);
      EXPECT_NEAR(part["gear"]["pressure_angle_deg"].get<double>(), 20.0, 0.2);
      EXPECT_NEAR(part["gear"]["bore_diameter_mm"].get<double>(), 10.0, 0.1);
    } else {
      EXPECT_EQ(part["name"], "block");
      EXPECT_EQ(part["symmetry"]["discrete"], 3);
      EXPECT_TRUE(part["gear"].is_null());
    }
  }
}

}  // namespace
}  // namespace cadsynth
