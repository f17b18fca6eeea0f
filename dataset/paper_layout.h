// The reference paper's dataset layout and PVN3D's YCB-style meta files, derived from the same
// frames as the BOP dataset (the colour and depth images are hard links to BOP's).
//
//   ROOT/paper/SCENEID/rgb/IMID.png       = the BOP colour image
//   ROOT/paper/SCENEID/depth/IMID.png     = the BOP depth image (uint16, x depth_scale = mm)
//   ROOT/paper/SCENEID/mask/IMID.png      one grey value per object: its obj_id (0: background)
//   ROOT/paper/SCENEID/meta/IMID.json     K, depth_scale, T_C_W and per instance T_O_C, T_O_W
//                                         (4 x 4, row-major lists, mm), obj_id, class
//   ROOT/paper/SCENEID/meta/IMID-meta.mat (pvn3d) cls_indexes, poses, intrinsic_matrix,
//                                         factor_depth, center, rotation_translation_matrix
//   ROOT/grasp/SCENEID/IMID_INST.npy      (grasp) visible points of each instance, camera frame, m
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "dataset/bop.h"
#include "dataset/frame_writer.h"
#include "render/frame.h"

namespace cadsynth {

struct PaperInstance {
  int obj_id = 0;
  ObjectClass object_class;
  std::string name;
  Eigen::Isometry3d world_from_model = Eigen::Isometry3d::Identity();
};

class PaperSceneWriter : public FrameWriter {
 public:
  // `instances` in Scene::instances order. Writes the formats `options` asks for
  // (paper_layout, pvn3d_meta, grasp_points).
  PaperSceneWriter(const std::filesystem::path& root, int scene_id, const BopOptions& options,
                   std::vector<PaperInstance> instances);

  // Call after BopSceneWriter::WriteFrame of the same image: links its colour and depth images
  // (`bop`). Thread-safe for different images.
  // Every file goes through `files` (the frame's manifest entry; null: not recorded).
  void WriteFrame(int image_id, const Frame& frame, const BopFrameFiles& bop,
                  FileLog* files = nullptr) const override;

 private:
  std::filesystem::path root_, paper_dir_, grasp_dir_;
  BopOptions options_;
  std::vector<PaperInstance> instances_;
};

// Writes a MATLAB v5 .mat file of PVN3D / YCB-Video meta data (through libmatio): cls_indexes
// (N x 1), poses (3 x 4 x N, [R | t] model to camera, t in metres), intrinsic_matrix (3 x 3),
// factor_depth (depth PNG units per metre), center (N x 2, projected model origins, pixels) and
// rotation_translation_matrix (3 x 4, world to camera, metres). Lists the instances with visible
// pixels, in instance order; cls_of_instance[i] is the label of instance i (its grey value in the
// mask image).
void WritePvn3dMeta(const std::filesystem::path& path, const Frame& frame,
                    const std::vector<int>& cls_of_instance, double depth_scale);

}  // namespace cadsynth
