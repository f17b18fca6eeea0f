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
//
// Their writers are the `paper` and `pvn3d` rows of dataset/output_formats.cpp (pvn3d turns the
// paper layout on: its meta files belong beside those images).
#pragma once

#include <filesystem>
#include <vector>

#include "render/frame.h"

namespace cadsynth {

// Writes a MATLAB v5 .mat file of PVN3D / YCB-Video meta data (through libmatio): cls_indexes
// (N x 1), poses (3 x 4 x N, [R | t] model to camera, t in metres), intrinsic_matrix (3 x 3),
// factor_depth (depth PNG units per metre), center (N x 2, projected model origins, pixels) and
// rotation_translation_matrix (3 x 4, world to camera, metres). Lists the instances with visible
// pixels, in instance order; cls_of_instance[i] is the label of instance i (its grey value in the
// mask image).
void WritePvn3dMeta(const std::filesystem::path& path, const Frame& frame,
                    const std::vector<int>& cls_of_instance, double depth_scale);

}  // namespace cadsynth
