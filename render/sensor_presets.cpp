#include "render/sensor_presets.h"

#include <cmath>

namespace cadsynth {

bool PublishedFigure::Met(double measured) const {
  if (!std::isfinite(measured)) return false;
  switch (bound) {
    case Bound::kAbout:
      return std::abs(measured - value) <= tolerance * std::abs(value);
    case Bound::kAtMost:
      return measured <= value;
    case Bound::kAtLeast:
      return measured >= value;
  }
  return false;
}

const char* QuantityName(PublishedFigure::Quantity quantity) {
  switch (quantity) {
    case PublishedFigure::Quantity::kTemporalNoise:
      return "temporal noise";
    case PublishedFigure::Quantity::kPlaneFitRms:
      return "plane-fit RMS";
    case PublishedFigure::Quantity::kBias:
      return "bias";
    case PublishedFigure::Quantity::kFillRate:
      return "fill rate";
  }
  return "";
}

namespace {

using Q = PublishedFigure::Quantity;
using B = PublishedFigure::Bound;

PublishedFigure Figure(Q quantity, B bound, double distance_mm, double value,
                       const std::string& source, double tolerance = 0.15) {
  PublishedFigure f;
  f.quantity = quantity, f.bound = bound, f.distance_mm = distance_mm, f.value = value;
  f.tolerance = tolerance, f.source = source;
  return f;
}

SensorPreset KinectV1() {
  SensorPreset p;
  p.name = "kinect_v1";
  p.camera = "kinect_v1";
  p.what = "Kinect v1 (structured light, disparity in 1/8 px)";
  p.depth = DepthModel::Defaults(DepthModel::Kind::kKinectV1);
  // Khoshelham and Elberink 2012 (Sensors 12:1437): sigma_Z = (m / f b) Z^2 sigma_d with m / f b =
  // 2.85e-5 / cm and sigma_d = 1/2 px, i.e. 1.425e-3 Z^2 m (Z in m), the random error of points
  // about a plane fitted to them; "up to about 4 cm at the maximum range of the sensor" (5 m).
  const std::string source = "Khoshelham and Elberink 2012, sigma_Z = 1.425e-3 Z^2 (m)";
  for (const double z : {2000.0, 3000.0, 4000.0}) {
    p.figures.push_back(Figure(Q::kPlaneFitRms, B::kAbout, z, 1.425e-6 * z * z, source));
  }
  p.figures.push_back(Figure(Q::kPlaneFitRms, B::kAbout, 5000.0, 40.0,
                             "Khoshelham and Elberink 2012: about 4 cm at 5 m"));
  p.unmatched =
      "At 1 m the model gives 1.9 mm where Khoshelham's quadratic gives 1.4 mm: the model is "
      "Nguyen et al.'s (1.2 mm + 1.9 mm (z - 0.4 m)^2), whose constant is the floor they measured "
      "near the camera; Khoshelham's curve is the quadratic term alone.";
  return p;
}

SensorPreset AzureKinect(bool wide) {
  SensorPreset p;
  p.name = wide ? "azure_kinect_wfov" : "azure_kinect_nfov";
  p.camera = p.name;
  p.what = wide ? "Azure Kinect, wide field of view unbinned (time of flight)"
                : "Azure Kinect, narrow field of view unbinned (time of flight)";
  p.depth = DepthModel::Defaults(DepthModel::Kind::kAzureKinect);
  // Microsoft's hardware specification: operating range 0.5-3.86 m (NFOV unbinned), 0.25-2.21 m
  // (WFOV unbinned) for 15-95 % reflectivity at 850 nm; random error sd <= 17 mm; systematic
  // error < 11 mm + 0.1 % of the distance without multipath. Tolgyessy et al. 2021 (Sensors
  // 21:413) confirm both bounds up to 3.5 m in all four modes.
  p.depth.min_range_mm = wide ? 250.0 : 500.0;
  p.depth.max_range_mm = wide ? 2210.0 : 3860.0;
  const std::string spec = "Azure Kinect DK hardware specification";
  const std::vector<double> distances = wide ? std::vector<double>{500.0, 1000.0, 2000.0}
                                             : std::vector<double>{1000.0, 2000.0, 3500.0};
  for (const double z : distances) {
    p.figures.push_back(
        Figure(Q::kTemporalNoise, B::kAtMost, z, 17.0, spec + ": random error sd <= 17 mm"));
    p.figures.push_back(Figure(Q::kBias, B::kAtMost, z, 11.0 + 0.001 * z,
                               spec + ": systematic error < 11 mm + 0.1 % of distance"));
    p.figures.push_back(
        Figure(Q::kFillRate, B::kAtLeast, z, 0.99, spec + ": inside the operating range"));
  }
  p.figures.push_back(Figure(Q::kFillRate, B::kAtMost, wide ? 2500.0 : 4000.0, 0.01,
                             spec + ": beyond the operating range"));
  p.unmatched =
      "Microsoft publishes bounds only. The model (BlenderProc's, after Tolgyessy et al.: 0.5 mm "
      "+ 1 mm per metre beyond 0.5 m, 3.5 mm at 3.5 m) lies well inside the 17 mm bound, and it "
      "has no systematic error (multipath, the temperature drift the paper warms up for): its "
      "bias is 0, inside the 11 mm bound. Its noise does not depend on the albedo, as a real "
      "time-of-flight camera's does (1 / sqrt of the returned amplitude).";
  return p;
}

SensorPreset RealSenseD435() {
  SensorPreset p;
  p.name = "realsense_d435";
  p.camera = "realsense_d435_depth";
  p.what = "RealSense D435 depth at 848 x 480 (active stereo, 50 mm baseline)";
  p.depth = DepthModel::Defaults(DepthModel::Kind::kActiveStereo);
  // Intel's datasheet gives min-Z 195 mm at 848 x 480.
  p.depth.min_depth_mm = 195.0;
  // Intel RealSense D400 datasheet, depth quality for the D43x at up to 2 m, 80 % ROI: Z accuracy
  // +-2 %, fill rate >= 99 %, RMS error <= 2 %, temporal noise <= 1 %.
  const std::string spec = "Intel RealSense D400 datasheet (D43x, 80 % ROI)";
  for (const double z : {500.0, 1000.0, 2000.0}) {
    p.figures.push_back(
        Figure(Q::kPlaneFitRms, B::kAtMost, z, 0.02 * z, spec + ": RMS error <= 2 %"));
    p.figures.push_back(Figure(Q::kBias, B::kAtMost, z, 0.02 * z, spec + ": Z accuracy +-2 %"));
    p.figures.push_back(
        Figure(Q::kTemporalNoise, B::kAtMost, z, 0.01 * z, spec + ": temporal noise <= 1 %"));
    p.figures.push_back(Figure(Q::kFillRate, B::kAtLeast, z, 0.99, spec + ": fill rate >= 99 %"));
  }
  // Intel's tuning white paper: RMS error = z^2 s / (f B) with a sub-pixel error s of 0.08 px
  // typical (f = 446.8 px, B = 50 mm: 0.90 mm at 0.5 m, 3.58 mm at 1 m).
  const double fb = 446.8 * 50.0;
  for (const double z : {500.0, 1000.0}) {
    p.figures.push_back(Figure(Q::kPlaneFitRms, B::kAbout, z, z * z * 0.08 / fb,
                               "Intel's depth tuning white paper: RMS = z^2 0.08 px / (f B)"));
  }
  p.unmatched =
      "The z^2 law with Intel's typical 0.08 px holds at 0.5 and 1 m; at 2 m the plane-fit RMS is "
      "about half of it (7.8 against 14.3 mm): there the true disparity is 11 px and OpenCV's SGBM "
      "errs mostly by a bias that is the same across a fronto-parallel plane (its parabola fit "
      "locks towards whole pixels), which the plane fit takes out and the bias figure shows "
      "(12 mm, 0.07 px, inside the 2 % the datasheet allows).";
  return p;
}

SensorPreset PhoXiL() {
  SensorPreset p;
  p.name = "photoneo_phoxi_l";
  p.camera = "photoneo_phoxi_l";
  p.what = "Photoneo PhoXi 3D Scanner L (structured light, 550 mm baseline)";
  p.depth = DepthModel::Defaults(DepthModel::Kind::kStructuredLight);
  // As quoted from Photoneo's PhoXi L datasheet (scanning range 870-2150 mm, sweet spot 1239 mm,
  // baseline 550 mm, temporal noise 0.190 mm, calibration accuracy 0.200 mm); Photoneo measures
  // temporal noise as one sigma on a diffuse plane of 80 % albedo.
  p.depth.baseline_mm = 550.0;
  p.depth.min_range_mm = 870.0;
  p.depth.max_range_mm = 2150.0;
  p.depth.noise_mm = 0.1048;  // 0.190 mm at the sweet spot on 80 % albedo (signal ~0.73)
  const std::string spec = "Photoneo PhoXi L datasheet (as quoted; 80 % albedo)";
  p.figures.push_back(
      Figure(Q::kTemporalNoise, B::kAbout, 1239.0, 0.190, spec + ": temporal noise 0.190 mm"));
  for (const double z : {900.0, 1239.0, 2000.0}) {
    p.figures.push_back(
        Figure(Q::kBias, B::kAtMost, z, 0.200, spec + ": calibration accuracy 0.200 mm"));
    p.figures.push_back(
        Figure(Q::kFillRate, B::kAtLeast, z, 0.99, spec + ": inside the scanning range"));
  }
  p.figures.push_back(
      Figure(Q::kFillRate, B::kAtMost, 2400.0, 0.01, spec + ": beyond the scanning range"));
  p.unmatched =
      "The model has no calibration error (its bias is 0, inside the 0.2 mm figure); the noise "
      "parameter is set so that the sweet spot's temporal noise is the datasheet's, and the other "
      "distances follow the z^2 law of triangulation.";
  return p;
}

}  // namespace

const std::vector<SensorPreset>& SensorPresets() {
  static const std::vector<SensorPreset> presets = {KinectV1(), AzureKinect(false),
                                                    AzureKinect(true), RealSenseD435(), PhoXiL()};
  return presets;
}

const SensorPreset* FindSensorPreset(const std::string& name) {
  for (const SensorPreset& p : SensorPresets()) {
    if (p.name == name) return &p;
  }
  return nullptr;
}

}  // namespace cadsynth
