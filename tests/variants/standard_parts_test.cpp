#include "variants/standard_parts.h"

#include <gtest/gtest.h>

#include "cad/assembly.h"
#include "cad/core/error.h"

namespace cadsynth {
namespace {

const TessellationOptions kFineStandard{0.02, 0.2};

double Volume(const Component& c) { return ComputeMassProperties(c.shape).volume_mm3; }

// Every declared symmetry maps the tessellated part onto itself (within the mesh's own error).
void ExpectSymmetriesHold(const Component& c, double tolerance = 0.05) {
  const Mesh mesh =
      Tessellate(c.shape, kFineStandard);  // CAD frame, where the symmetries are declared
  for (size_t i = 0; i < c.symmetries.discrete.size(); ++i) {
    EXPECT_LT(MaxSurfaceDistance(mesh, mesh, c.symmetries.discrete[i]), tolerance)
        << c.name << " discrete " << i;
  }
  for (const auto& axis : c.symmetries.continuous) {
    for (double angle : {0.3, 1.7, 4.0}) {
      const Eigen::Isometry3d turn = Eigen::Translation3d(axis.offset) *
                                     Eigen::AngleAxisd(angle, axis.direction) *
                                     Eigen::Translation3d(-axis.offset);
      EXPECT_LT(MaxSurfaceDistance(mesh, mesh, turn), tolerance)
          << c.name << " continuous " << angle;
    }
  }
  // And something that is not a symmetry is caught: a small turn about a tilted axis.
  EXPECT_GT(MaxSurfaceDistance(
                mesh, mesh,
                Eigen::Isometry3d(Eigen::AngleAxisd(0.2, Eigen::Vector3d(1, 0, 1).normalized()))),
            tolerance)
      << c.name;
}

TEST(IsoParts, HexBoltHeadAndShankHaveTheTableDimensions) {
  EXPECT_EQ(IsoMetricSizes().size(), 11u);  // M3 ... M24
  for (const std::string name : {"M3", "M8", "M24"}) {
    const MetricSize& m = IsoMetric(name);
    const Component bolt = MakeHexBolt(name, 40);
    const Eigen::Vector3d size = Tessellate(bolt.shape, kFineStandard).Bounds().sizes();
    EXPECT_NEAR(size.y(), m.s, 1e-5) << name;  // across flats (mesh positions are floats)
    EXPECT_NEAR(size.x(), 2 * m.s / std::sqrt(3.0), 1e-5) << name;  // across corners
    EXPECT_NEAR(size.z(), m.k + 40, 1e-5) << name;
    const double hexagon = std::sqrt(3.0) / 2 * m.s * m.s;
    EXPECT_NEAR(Volume(bolt), hexagon * m.k + M_PI * m.d * m.d / 4 * 40, 1e-6 * Volume(bolt))
        << name;
    ExpectSymmetriesHold(bolt);
  }
  EXPECT_EQ(IsoMetric("M8").s, 13.0);
  EXPECT_EQ(IsoMetric("M16").k, 10.0);
  EXPECT_EQ(IsoMetric("M12").m, 10.8);
  try {
    IsoMetric("M7");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()),
              "unknown metric size 'M7' (known: M3, M4, M5, M6, M8, M10, M12, M14, M16, M20, M24)");
  }
}

TEST(IsoParts, NutAndWasherVolumes) {
  const MetricSize& m = IsoMetric("M10");
  const Component nut = MakeHexNut("M10");
  EXPECT_NEAR(Volume(nut), (std::sqrt(3.0) / 2 * 16 * 16 - M_PI * 25) * 8.4, 1e-6 * Volume(nut));
  const Component washer = MakeWasher("M10");
  EXPECT_NEAR(Volume(washer),
              M_PI / 4 * (m.washer_outer * m.washer_outer - m.washer_inner * m.washer_inner) *
                  m.washer_thickness,
              1e-6 * Volume(washer));
  ExpectSymmetriesHold(nut);
  ExpectSymmetriesHold(washer);
}

TEST(StandardParts, PegsPlateShaftShoulderBoltBearing) {
  const Component round = MakeRoundPeg(20, 50), square = MakeSquarePeg(20, 50);
  EXPECT_NEAR(Volume(round), M_PI * 100 * 50, 1e-6);
  EXPECT_NEAR(Volume(square), 20000, 1e-6);
  ExpectSymmetriesHold(round);
  ExpectSymmetriesHold(square);

  const Component plate = MakeFaceplate(120, 80, 8, 2, 3, 10, 15);
  EXPECT_NEAR(Volume(plate), (120 * 80 - 6 * M_PI * 25) * 8, 1e-6 * Volume(plate));
  ExpectSymmetriesHold(plate);
  EXPECT_THROW(MakeFaceplate(50, 50, 5, 4, 4, 12, 8), Error);  // holes overlap

  const Component shaft = MakeSteppedShaft({{20, 10}, {30, 40}, {20, 10}});
  EXPECT_NEAR(Volume(shaft), M_PI * (100 * 20 + 225 * 40), 1e-6 * Volume(shaft));
  EXPECT_EQ(shaft.symmetries.discrete.size(), 1u);  // palindromic: flips
  EXPECT_TRUE(MakeSteppedShaft({{20, 10}, {30, 40}}).symmetries.discrete.empty());
  ExpectSymmetriesHold(shaft);

  const Component shoulder = MakeShoulderBolt(10, 30);
  const ShoulderSize& s = IsoShoulder(10);
  EXPECT_NEAR(Tessellate(shoulder.shape, kFineStandard).Bounds().sizes().z(),
              s.head_k + 30 + s.thread_length, 1e-6);
  ExpectSymmetriesHold(shoulder);

  const Component bearing = MakeBallBearing(20, 47, 14);  // a 6204's envelope
  const Eigen::Vector3d size = Tessellate(bearing.shape, kFineStandard).Bounds().sizes();
  EXPECT_NEAR(size.x(), 47, 0.01);
  EXPECT_NEAR(size.z(), 14, 1e-6);
  ExpectSymmetriesHold(bearing, 0.1);
  EXPECT_THROW(MakeBallBearing(20, 22, 5), Error);
}

}  // namespace
}  // namespace cadsynth
