// The dataset formats a recipe's `output.formats` lists: one registration each, in
// dataset/output_formats.cpp. BOP is always written (the others derive from its frames); COCO is
// written by BOP's own scene writer; every other format is a FrameWriter (dataset/frame_writer.h)
// made per scene by its factory and called by BopSceneWriter after BOP's files of each frame.
//
// Adding a format: its writer in a file of its own (a FrameWriter and a factory), a flag in
// BopOptions (with its Fields line: the run key and the shard file see it), and one row in
// OutputFormats(). The recipe reader, `--help-recipe`, the JSON Schema and the generate command
// take the name and the writer from the row.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Geometry>

#include "dataset/bop.h"
#include "dataset/frame_writer.h"

namespace cadsynth {

// One instance of a scene, as the derived formats name it.
struct FormatInstance {
  int obj_id = 0;
  ObjectClass object_class;
  std::string name;
  Eigen::Isometry3d world_from_model = Eigen::Isometry3d::Identity();
};

// What a format's per-scene writer is made from.
struct FormatScene {
  std::filesystem::path root;  // the dataset's root folder
  int scene_id = 0;
  BopOptions options;
  std::vector<FormatInstance> instances;  // in Scene::instances order
};

using FrameWriterFactory = std::unique_ptr<FrameWriter> (*)(const FormatScene& scene);

struct OutputFormat {
  const char* name;  // as `output.formats` lists it
  // The BopOptions flag that turns the format on; null: always written (bop).
  bool BopOptions::*enabled = nullptr;
  // A format this one's files belong to, turned on with it (pvn3d's meta files sit in the
  // paper layout beside its images); null: none.
  const char* implies = nullptr;
  // Its files need colour images (camera.image: rgb).
  bool needs_rgb = false;
  // The per-scene writer; null: BopSceneWriter writes the format itself.
  FrameWriterFactory make_writer = nullptr;
};

// Every format, in the order their writers run for a frame.
const std::vector<OutputFormat>& OutputFormats();
// The format called `name`, or null.
const OutputFormat* FindOutputFormat(std::string_view name);
// Their names, in order ("bop, coco, ..." for messages and the recipe reference).
std::vector<std::string> OutputFormatNames();

// The per-scene writers of the formats `scene.options` turns on, in OutputFormats() order.
std::vector<std::unique_ptr<FrameWriter>> MakeFrameWriters(const FormatScene& scene);

}  // namespace cadsynth
