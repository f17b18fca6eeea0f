// One dataset format derived from the frames beside BOP: the interface every per-frame writer
// other than BOP's own implements (dataset/paper_layout.h: the paper's layout, PVN3D meta, grasp
// points). BopSceneWriter::WriteFrame calls each after its own images and before the frame's
// manifest entry, so their files are checked on resume and merge like BOP's.
#pragma once

#include <filesystem>

#include "dataset/file_io.h"
#include "render/frame.h"

namespace cadsynth {

// Where BopSceneWriter wrote a frame's colour (or grey) image and its depth image.
struct BopFrameFiles {
  std::filesystem::path image, depth;
};

class FrameWriter {
 public:
  virtual ~FrameWriter() = default;
  // Writes image `image_id` of `frame`; BOP's files of the frame are already written (`bop`:
  // colour and depth may be linked from there). Every file goes through `files` (the frame's
  // manifest entry; null: not recorded). Called from several threads for different images.
  virtual void WriteFrame(int image_id, const Frame& frame, const BopFrameFiles& bop,
                          FileLog* files) const = 0;
};

}  // namespace cadsynth
