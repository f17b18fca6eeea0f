// The plane test (`cadsynth sensor-test`): a depth sensor measured the way its makers measure it.
// A flat target of a chosen albedo (or material) fills the view at a series of distances and
// tilts; the sensor's depth model renders it several times, and the test reports what datasheets
// report:
//
//   temporal noise   per pixel, the standard deviation over the repeated frames; the RMS of it over
//                    the region of interest (Photoneo's "temporal noise", Intel's, as a sigma)
//   plane-fit RMS    per frame, the points of the region fitted with a plane (least squares in 3D),
//                    the RMS of depth about it after trimming 0.5 % at each end (Intel's "RMS
//                    error"; Khoshelham's random error); the mean over frames
//   bias             the mean of measured minus true depth over the region and the frames
//   fill rate        the share of the region's pixels on the target with a depth value
//   edge             a step of `step_mm` towards the camera across the middle of the view (tilt 0
//                    only): per image row within 16 px of the step, the pixels without depth and
//                    the pixels whose depth is off the true one by more than max(4 x the plane-fit
//                    RMS, 1 mm) (flying pixels and edge fattening)
//
// The region of interest is the central `roi` of the image's width and height (Intel's 80 %). The
// target is the floor plane seen from `distance` along the optical axis; a tilt turns it about the
// camera's y axis, its normal towards the projector's side (+x) for positive angles. Frames are
// views 0, 1, ... of the sensor's noise: the same numbers on any thread count.
#pragma once

#include <string>
#include <vector>

#include "render/camera.h"
#include "render/material.h"
#include "render/sensor.h"
#include "render/sensor_presets.h"

namespace cadsynth {

struct PlaneTestOptions {
  std::string name;  // the sensor's name in the report
  Intrinsics intrinsics;
  SensorOptions sensor;
  double albedo = 0.8;   // the target's diffuse reflectance (fast mode)
  std::string material;  // a material preset instead (render/material.h; path-traced signal)
  std::vector<double> distances_mm = {500.0, 1000.0, 2000.0, 3000.0};
  std::vector<double> tilts_rad = {0.0};
  int frames = 10;                       // repeated frames for the temporal noise (2-1000)
  double roi = 0.8;                      // the central share of the image's width and height
  double step_mm = 100.0;                // the edge test's step (0: no edge test)
  std::vector<PublishedFigure> figures;  // published figures to check the results against

  bool Check(std::string* why) const;
};

struct PlaneTestRow {
  double distance_mm = 0.0, tilt_rad = 0.0;
  double temporal_mm = 0.0, plane_rms_mm = 0.0, bias_mm = 0.0, fill = 0.0;
  // tilt 0 with a step: per image row at the step, pixels without depth and with wrong depth
  double edge_holes_px = -1.0, edge_wrong_px = -1.0;
};

struct FigureCheck {
  PublishedFigure figure;
  double measured = 0.0;
  bool met = false;
};

struct PlaneTestResult {
  PlaneTestOptions options;
  std::vector<PlaneTestRow> rows;
  std::vector<FigureCheck> checks;  // one per figure, at its distance and tilt 0
  bool AllMet() const;
};

// The test's options for a sensor preset (render/sensor_presets.h): its camera, depth model,
// albedo and figures, and distances that include every figure's.
PlaneTestOptions PlaneTestFor(const SensorPreset& preset);

// Runs the test. Throws Error for options that fail Check.
PlaneTestResult RunPlaneTest(const PlaneTestOptions& options);

// The result as a table (text), as JSON, and as a picture (SVG: noise and bias against distance,
// fill rate, the published figures as marks).
std::string PlaneTestTable(const PlaneTestResult& result);
std::string PlaneTestJson(const PlaneTestResult& result);
std::string PlaneTestSvg(const PlaneTestResult& result);

}  // namespace cadsynth
