// Named depth sensors: a camera preset (render/camera.h) with the depth model and operating range
// that make it behave as the maker says, and the published figures it is meant to reproduce on a
// flat target (the plane test of tools/pipeline/sensor_test.h, `cadsynth sensor-test`). The
// sources are named per figure and in docs/sensors.md; where a figure cannot be matched by the
// model, `unmatched` says why.
#pragma once

#include <string>
#include <vector>

#include "render/sensor.h"

namespace cadsynth {

// One figure from a datasheet or a paper, as the plane test measures it: at a distance (mm along
// the optical axis to a fronto-parallel target of the given albedo).
struct PublishedFigure {
  enum class Quantity {
    kTemporalNoise,  // sigma over repeated frames at a pixel (mm)
    kPlaneFitRms,    // RMS of the depth about the plane fitted to one frame (mm)
    kBias,           // |mean depth error| against the true distance (mm)
    kFillRate,       // share of the region of interest with a depth value (0-1)
  };
  enum class Bound { kAbout, kAtMost, kAtLeast };
  Quantity quantity = Quantity::kTemporalNoise;
  Bound bound = Bound::kAbout;
  double distance_mm = 1000.0;
  double value = 0.0;
  double tolerance = 0.15;  // kAbout: relative
  std::string source;

  // Whether `measured` meets the figure.
  bool Met(double measured) const;
};
const char* QuantityName(PublishedFigure::Quantity quantity);

struct SensorPreset {
  std::string name;
  std::string camera;  // the camera preset (intrinsics, grey or colour)
  std::string what;
  DepthModel depth;
  double albedo = 0.8;  // the target the figures were measured on
  std::vector<PublishedFigure> figures;
  std::string unmatched;  // published figures the model does not reproduce, and why
};
const std::vector<SensorPreset>& SensorPresets();
// The preset called `name`, or null.
const SensorPreset* FindSensorPreset(const std::string& name);

}  // namespace cadsynth
