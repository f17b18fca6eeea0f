// Readers of BOP files that other tools wrote or people edited: pose estimates (the BOP results
// CSV), scene_gt.json and models_info.json. `eval` scores with them. Every value is checked (whole
// numbers where ids are expected, finite numbers, rotations that are rotations), and anything else
// is one Error naming the origin and, where there is one, the line.
#pragma once

#include <exception>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

namespace cadsynth {

// What is wrong with the JSON text `text` read from `origin`, for an exception nlohmann::json threw
// on it, in plain words: "FILE:LINE:COLUMN: not valid JSON (unexpected end of input)" for a
// syntax error, "FILE: KEY: ..." wording for type errors.
std::string JsonErrorMessage(const std::string& origin, const std::string& text,
                             const std::exception& error);

// A BOP id written as text (a JSON key, a folder name "000012"): a whole number in [0, 2^31), or
// nothing.
std::optional<int> ParseBopId(std::string_view text);

struct BopEstimate {
  int scene_id = 0, im_id = 0, obj_id = 0;
  double score = 0;
  Eigen::Isometry3d cam_from_model = Eigen::Isometry3d::Identity();  // t in mm
};

// scene_id,im_id,obj_id,score,R,t[,time] per line (R row-major, 9 numbers, and t, 3 numbers, each
// space-separated), an optional header line starting with "scene_id". R must be a rotation
// (determinant within 1e-3 of 1).
std::vector<BopEstimate> ParseBopResults(const std::string& text, const std::string& origin);

struct BopGroundTruth {
  int obj_id = 0;
  Eigen::Isometry3d cam_from_model = Eigen::Isometry3d::Identity();
};

// scene_gt.json: {"im_id": [{"obj_id", "cam_R_m2c", "cam_t_m2c"}, ...], ...}: per image (in file
// order, images without instances included) its instances.
using BopSceneGt = std::vector<std::pair<int, std::vector<BopGroundTruth>>>;
BopSceneGt ParseSceneGt(const std::string& text, const std::string& origin);

struct BopModelInfo {
  int obj_id = 0;
  double diameter = 0;     // mm, > 0
  bool symmetric = false;  // any discrete or continuous symmetry listed
  // The poses the object cannot be told apart in, as bop_toolkit's
  // misc.get_symmetry_transformations expands them for MSSD (max_sym_disc_step 0.01): the
  // identity and each discrete symmetry, each combined with every step of 2 pi / 315 about each
  // continuous axis (the step of 0 included: older bop_toolkit versions leave it out, which
  // scores a perfect estimate of a cylinder 0.02 radians off).
  std::vector<Eigen::Isometry3d> symmetry_poses;
};

// models_info.json: {"obj_id": {"diameter", ["symmetries_discrete"], ["symmetries_continuous"]}}.
std::vector<BopModelInfo> ParseModelsInfo(const std::string& text, const std::string& origin);

// One scene folder of a BOP dataset and one of its sensors.
struct BopSceneFolder {
  std::string split;  // the folder under the dataset root (train, test, ...)
  int scene_id = 0;
  std::string suffix;         // "" for the only camera, "_NAME" for a rig's sensor
  std::filesystem::path dir;  // ROOT/SPLIT/NNNNNN
  // SPLIT/NNNNNN/NAME: a path relative to the dataset root.
  std::string Relative(const std::string& name) const;
};

// Every scene folder (ROOT/SPLIT/NNNNNN holding a scene_camera[_NAME].json) with each sensor, by
// split, scene id and sensor. Hidden folders are skipped.
std::vector<BopSceneFolder> FindBopScenes(const std::filesystem::path& root);

}  // namespace cadsynth
