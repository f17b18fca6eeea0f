#include "dataset/output_formats.h"

namespace cadsynth {

// The writers' factories, each defined beside its writer.
std::unique_ptr<FrameWriter> MakePaperLayoutWriter(const FormatScene& scene);  // paper_layout.cpp
std::unique_ptr<FrameWriter> MakePvn3dWriter(const FormatScene& scene);        // paper_layout.cpp
std::unique_ptr<FrameWriter> MakeGraspPointsWriter(const FormatScene& scene);  // grasp.cpp

const std::vector<OutputFormat>& OutputFormats() {
  static const std::vector<OutputFormat> formats = {
      // name, flag, implies, needs_rgb, writer (docs/formats.md describes each)
      {"bop"},  // images, masks, poses, camera files: always, the others derive from it
      {"coco", &BopOptions::coco},  // written by BopSceneWriter (scene_gt_coco.json, coco/)
      {"paper", &BopOptions::paper_layout, nullptr, true, MakePaperLayoutWriter},
      {"pvn3d", &BopOptions::pvn3d_meta, "paper", true, MakePvn3dWriter},
      {"grasp", &BopOptions::grasp_points, nullptr, false, MakeGraspPointsWriter},
      // packed from every format's files once a run or shard has rendered its frames
      // (dataset/webdataset.h; the generate pipeline calls it)
      {"webdataset", &BopOptions::webdataset},
  };
  return formats;
}

const OutputFormat* FindOutputFormat(std::string_view name) {
  for (const OutputFormat& format : OutputFormats()) {
    if (name == format.name) return &format;
  }
  return nullptr;
}

std::vector<std::string> OutputFormatNames() {
  std::vector<std::string> names;
  for (const OutputFormat& format : OutputFormats()) names.push_back(format.name);
  return names;
}

std::vector<std::unique_ptr<FrameWriter>> MakeFrameWriters(const FormatScene& scene) {
  std::vector<std::unique_ptr<FrameWriter>> writers;
  const auto on = [&](const OutputFormat& format) {
    return format.enabled == nullptr || scene.options.*format.enabled;
  };
  for (const OutputFormat& format : OutputFormats()) {
    if (format.make_writer == nullptr) continue;
    bool wanted = on(format);
    for (const OutputFormat& other : OutputFormats()) {
      if (other.implies != nullptr && other.implies == std::string_view(format.name) && on(other))
        wanted = true;
    }
    if (wanted) writers.push_back(format.make_writer(scene));
  }
  return writers;
}

}  // namespace cadsynth
