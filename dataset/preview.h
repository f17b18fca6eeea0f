// A contact sheet of dataset frames for checking a dataset by eye: colour with each object's
// projected 3D bounding box and axes, coloured depth (exact and sensor's when the dataset has
// depth_gt/), coloured visible masks.
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

namespace cadsynth {

struct PreviewOptions {
  int count = 4;  // frames spread evenly over all scenes' images, when `frames` is empty
  std::vector<std::pair<int, int>> frames;  // (scene_id, im_id) to show, in order
  int panel_width = 320;  // each of the three panels per frame is scaled to this width
  std::string split;      // the folder of scenes; empty: the dataset's only one (train/ by default)
  // Another dataset of the same views (e.g. the same recipe with render.mode: pbr): each row then
  // shows the two colour images side by side, without overlays, instead of the three panels.
  std::filesystem::path versus;
  // A multi-sensor dataset's sensor (rgb_NAME/, scene_gt_NAME.json); empty: a single camera's.
  std::string sensor;
  // Grasp labels (graspnet/, suctionnet/ beside the scenes): this many of each frame's grasps
  // whose way in is free (spread over the instances, each one's best first), drawn on the colour
  // image in a last panel (parallel jaws as a U of
  // the fingers and the hand's axis, suction cups as their rim's circle and axis); 0: none.
  int grasps = 10;
  // 1-100: the sheet as a JPEG of this quality (a report's gallery); 0: PNG.
  int jpeg_quality = 0;
};

// The 8 corners of `box` (model frame, mm) projected with `k` at pose `cam_from_model`, in pixel
// coordinates (x right, y down, pixel (u, v) covering [u, u+1) x [v, v+1)).
std::vector<Eigen::Vector2d> ProjectBox(const Eigen::Matrix3d& k,
                                        const Eigen::Isometry3d& cam_from_model,
                                        const Eigen::AlignedBox3d& box);

// Reads DATASET (BOP layout) and returns the contact sheet as PNG (or JPEG) bytes: one row per
// frame.
// With `versus`, that dataset must have the same scene folder and images.
// Sets *shown to the frames it shows. Throws Error naming the file on missing or bad input.
std::string RenderPreview(const std::filesystem::path& dataset, const PreviewOptions& options,
                          std::vector<std::pair<int, int>>* shown = nullptr);

// OpenCV's own warnings off (its errors still print): what cadsynth reports it names once, without
// raw "[ WARN:0@0.1] global ..." lines from OpenCV's core before it. Images no longer go through
// OpenCV (render/image_codec.h), whose readers were the usual source. The command line calls it
// at start.
void SilenceOpenCvWarnings();

}  // namespace cadsynth
