// The rendered images and per-instance ground truth of one camera view.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "render/camera.h"

namespace cadsynth {

// Images are row-major, width x height, pixel (u, v) at index v * width + u.
struct Frame {
  Camera camera;

  std::vector<uint8_t> rgb;        // 3 bytes per pixel: R, G, B
  std::vector<float> depth;        // z in the camera frame, mm; 0 = no return
  std::vector<uint16_t> instance;  // visible instance: index in Scene::instances + 1; 0 = none
  std::vector<Eigen::Vector3f> normals;  // RenderOptions::normals: unit, camera frame; 0 = none
  // RenderOptions::hdr: 3 floats per pixel; pbr mode: linear radiance, W/(m^2 sr), before
  // exposure; fast mode: the colour before rounding. Empty otherwise.
  std::vector<float> radiance;
  // SensorOptions::image gray or gray16: the grey camera's image, the display value of the
  // luminance (0.2126 R + 0.7152 G + 0.0722 B of the linear colour) in [0, 1]. Empty for colour
  // cameras.
  std::vector<float> gray;
  // A depth model other than ideal (render/sensor.h): what the sensor returns (mm, 0 = none).
  // `depth` stays exact, and every label comes from it. Empty for the ideal model.
  std::vector<float> sensor_depth;
  // pbr mode: the paths each pixel's colour averages (render.samples, or fewer where adaptive
  // sampling stopped early; render.noise_threshold). Empty in the fast mode.
  std::vector<uint32_t> samples;
  // RenderOptions::denoiser_inputs (pbr): what the denoiser reads, per pixel (the depth is
  // `depth`): the radiance before denoising (3), the first surface's albedo (3, mean over the
  // pixel's paths) and shading normal (3, world frame, mean), and the variance of the pixel's mean
  // luminance (1). Empty otherwise.
  struct DenoiserInputs {
    std::vector<float> radiance, albedo, normal, variance;
  };
  DenoiserInputs denoiser_inputs;
  // active_stereo: the left IR image the matcher read (8 bit, the dots and the ambient light).
  std::vector<uint8_t> infrared;

  // Domain randomisation: what was drawn for this frame, as a JSON object of named draws
  // (written to scene_randomization.json); empty when nothing is randomised.
  std::string randomization;

  struct InstanceTruth {
    Eigen::Isometry3d cam_from_model = Eigen::Isometry3d::Identity();
    // Full silhouette, also where other instances hide it: 1 = covered, 0 outside the pixel
    // rectangle [roi[0], roi[2]) x [roi[1], roi[3]) (clamped to the image; the default is the whole
    // image). Stored for that rectangle only, row-major like amodal_depth (Covers reads it): a
    // whole image per instance was 93 MB per frame for 60 instances at 1440 x 1080.
    std::vector<uint8_t> amodal_mask;
    int roi[4] = {0, 0, 1 << 30, 1 << 30};
    // roi clamped to a width x height image.
    std::array<int, 4> Roi(int width, int height) const {
      return {std::clamp(roi[0], 0, width), std::clamp(roi[1], 0, height),
              std::clamp(roi[2], 0, width), std::clamp(roi[3], 0, height)};
    }
    // Whether the full silhouette covers pixel (u, v) of a width x height image.
    bool Covers(int u, int v, int width, int height) const {
      const std::array<int, 4> r = Roi(width, height);
      if (amodal_mask.empty() || u < r[0] || v < r[1] || u >= r[2] || v >= r[3]) return false;
      return amodal_mask[static_cast<size_t>(v - r[1]) * (r[2] - r[0]) + (u - r[0])] != 0;
    }
    // RenderOptions::amodal_depth: the depth (mm) of the instance rendered alone, 0 where it is
    // not hit, inside the rectangle roi (clamped to the image), row-major: pixel (u, v) at
    // (v - roi[1]) * (roi[2] - roi[0]) + (u - roi[0]). Empty otherwise.
    std::vector<float> amodal_depth;
    int px_count_all = 0;  // pixels of the amodal mask inside the image
    // The silhouette on the canvas of three times the image size, [-w, 2w) x [-h, 2h) (as
    // bop_toolkit renders it), so that truncated parts count: its pixel count and its bounding
    // box (u_min, v_min, u_max, v_max, inclusive, image coordinates; all -1 when empty).
    int px_count_canvas = 0;
    int bbox_canvas[4] = {-1, -1, -1, -1};
    int px_count_visib = 0;  // pixels where this instance is the front-most surface
  };
  std::vector<InstanceTruth> instances;  // one per Scene::instances entry, same order

  int width() const { return camera.intrinsics.width; }
  int height() const { return camera.intrinsics.height; }
};

}  // namespace cadsynth
