// A scene's journal (internal to dataset/): one fragment per written frame,
// SCENE/.fragments[_SENSOR]/IMID.json, written last by BopSceneWriter::WriteFrame. Its existence
// marks the frame complete (the resume half: HasFrame, WrittenFrames, CheckFrame, ForgetFrame, in
// bop_fragment.cpp), and Finish streams the scene files from the fragments. The text is composed
// and parsed here only, so writer and readers agree on it.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "dataset/bop_internal.h"
#include "dataset/file_io.h"

namespace cadsynth::bop_internal {

// A frame's fragment: five lines of JSON, the scene_camera, scene_gt and scene_gt_info entries,
// the COCO entry and the manifest, and a sixth with the frame's randomisation record when it has
// one. Every line's shape is checked on parsing, so Finish and CheckFrame never meet a value of
// the wrong type in a damaged or hand-edited fragment.
struct Fragment {
  Json camera, gt, gt_info, coco;
  std::vector<FileRecord> files;
  Json randomization;  // null when the frame has none
};

// Throws Error naming `origin` and the line.
Fragment ParseFragmentText(const std::string& text, const std::string& origin);
Fragment ReadFragment(const std::filesystem::path& path);

// The fragment's text: the entries as compact JSON lines, the COCO entry {width, height,
// annotations}, the manifest {files: [[path, size, crc32], ...]}, and the randomisation record
// (JSON text; empty: none) re-serialised compactly.
std::string FragmentText(const Json& camera, const Json& gt, const Json& gt_info, int width,
                         int height, const Json& coco_annotations,
                         const std::vector<FileRecord>& files, const std::string& randomization);

// The image ids of the fragments in `folder` (names NNNNNN.json), in directory order.
std::vector<int> FragmentIds(const std::filesystem::path& folder);

}  // namespace cadsynth::bop_internal
