// BOP datasets (bop_toolkit's docs/bop_datasets_format.md is the contract).
//
//   ROOT/camera.json                         intrinsics and depth_scale
//   ROOT/models/obj_OBJID.ply                one mesh per object, mm, model frame
//   ROOT/models/models_info.json             diameter and 3D bounding box per object
//   ROOT/models/models_cad.json              (cadsynth) name, cad_from_model, volume per object
//   ROOT/SPLIT/SCENEID/rgb/IMID.png          colour
//   ROOT/SPLIT/SCENEID/depth/IMID.png        uint16, depth_mm = value * depth_scale, 0 = none
//   ROOT/SPLIT/SCENEID/mask/IMID_GTID.png    full silhouette of ground-truth entry GTID (0/255)
//   ROOT/SPLIT/SCENEID/mask_visib/IMID_GTID.png  its visible part (0/255)
//   ROOT/SPLIT/SCENEID/scene_camera.json     cam_K, depth_scale, cam_R_w2c, cam_t_w2c per image
//   ROOT/SPLIT/SCENEID/scene_gt.json         cam_R_m2c, cam_t_m2c, obj_id per instance
//   ROOT/SPLIT/SCENEID/scene_gt_info.json    bboxes, pixel counts, visib_fract per instance
//   ROOT/SPLIT/SCENEID/scene_randomization.json  (cadsynth, domain randomisation) per image, what
//                                            was drawn for it (Frame::randomization)
//
// A camera rig (several sensors moved together) writes BOP's multi-sensor layout instead: every
// folder and scene file of a sensor NAME carries its name (bop_toolkit's dataset_params.py,
// BOP 2025's industrial datasets), and the sensors share image ids, one per rig pose:
//
//   ROOT/camera_NAME.json                    per sensor (camera.json: the first sensor's)
//   ROOT/SPLIT/SCENEID/rgb_NAME/IMID.png     or gray_NAME/; depth_NAME/, mask_NAME/,
//                                            mask_visib_NAME/ (and depth_gt_NAME/, ...)
//   ROOT/SPLIT/SCENEID/scene_camera_NAME.json, scene_gt_NAME.json, scene_gt_info_NAME.json,
//                      scene_gt_coco_NAME.json
//   ROOT/test_targets_multiview_bop25.json   per test image: scene_id and [[NAME, im_id], ...]
//
// All ids are written with 6 digits. Rotations are row-major; translations in mm.
// cam_R_m2c / cam_t_m2c is cam_from_model; cam_R_w2c / cam_t_w2c is cam_from_world (the
// inverse of the camera pose world_from_cam), so world_from_model = inverse(w2c) * m2c.
#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "cad/core/schema.h"
#include "cad/part.h"
#include "dataset/file_io.h"
#include "dataset/frame_writer.h"
#include "render/camera.h"
#include "render/frame.h"
#include "render/image_codec.h"

namespace cadsynth {

struct BopOptions {
  double depth_scale = 0.1;     // mm per depth unit: 0.1 mm steps, up to 6.5535 m
  std::string split = "train";  // folder holding the scenes
  // Train/test split of each scene's images, in image order: every `test_every`-th image is a test
  // image (the reference paper: every 4th, 75/25), or, when test_every is 0, each image is a test
  // image with probability `test_fraction` (seeded). Test images also go to
  // test_targets_bop19.json.
  int test_every = 4;
  double test_fraction = 0.25;
  uint64_t split_seed = 0;
  // Test targets count instances at least this visible (bop_toolkit: 0.1).
  double target_min_visib_fract = 0.1;
  // Which pixels of an instance are visible: in mask_visib/, scene_gt_info.json (px_count_visib,
  // visib_fract, bbox_visib), COCO and the test targets.
  //   kExact: where the instance is the front-most surface (the default);
  //   kBop19: bop_toolkit's rule (calc_gt_masks.py, calc_gt_info.py, visib_mode "bop19"): where
  //     the instance rendered alone lies at most `visib_delta_mm` behind the exact depth
  //     (compared as distances from the camera centre), or the exact depth has no value. Two
  //     touching instances can then both be visible in one pixel.
  enum class Visibility { kExact, kBop19 };
  Visibility visibility = Visibility::kExact;
  double visib_delta_mm = 15.0;  // bop_toolkit: 15 (5 for ITODD)
  // Box of each COCO annotation (scene_gt_coco.json and the merged coco/ files): the full
  // silhouette's box inside the image (amodal, as bop_toolkit's calc_gt_coco.py writes by
  // default) or the visible mask's box (modal). Annotations with visib_fract < 0.1 carry
  // "ignore": true either way, as bop_toolkit's.
  bool coco_amodal_bbox = true;
  // Cameras with an IR image (active_stereo's left IR camera, the camera itself): also write it,
  // 8 bits with the projector's dots, to ir[_CAMTYPE]/IMID.png.
  bool infrared = false;
  // Model point clouds (models/points/obj_*.ply): points per part (the paper: 3,000; 0: none),
  // spread uniformly by area or evenly spaced, seeded.
  int model_points = 3000;
  // COCO instance annotations of the visible masks (compressed RLE): SCENE/scene_gt_coco.json as
  // BOP writes it, and coco/{train,test}.json merged over the scenes by split.
  bool coco = true;
  // Colour images as lossless PNG (default) or as JPEG of this quality (1-100; 0: PNG).
  int jpeg_quality = 0;
  std::string RgbExtension() const { return jpeg_quality > 0 ? ".jpg" : ".png"; }
  // A grey camera (recipes' camera.image): 8 or 16 bits per pixel in gray/ instead of rgb/ (as
  // BOP's ITODD); 0: colour.
  int gray_bits = 0;
  std::string ImageFolder() const { return gray_bits > 0 ? "gray" : "rgb"; }
  // Formats derived from the same frames (dataset/paper_layout.h): the reference paper's layout
  // under paper/, PVN3D's YCB-style -meta.mat files beside it, grasp-detector point arrays.
  bool paper_layout = false;
  bool pvn3d_meta = false;
  bool grasp_points = false;
  // Webdataset archive shards (formats: webdataset; dataset/webdataset.h): a new archive starts
  // before one would hold more than archive_samples samples or archive_megabytes MiB.
  bool webdataset = false;
  int archive_samples = 1000;
  int archive_megabytes = 1024;
  bool even_points = false;
  uint64_t point_seed = 0;

  bool Check(std::string* why) const;
  bool IsTest(int index, int count) const;  // index-th of `count` images of a scene

  // Every field, once (cad/core/schema.h): the recipe's `output:` section, the run key, the shard
  // file.
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.depth_scale, Field{"depth_scale", "number",
                               "mm per depth PNG unit (0.1: 0.1 mm steps, up to 6.5535 m)"});
    visit(o.split, Field{"split", "text", "folder of the scenes (train, test, ...)"});
    visit(
        o.test_every,
        Field{"test_every",
              "integer",
              "every Nth image of each scene is a test image (the paper: 4); 0: use test_fraction",
              {},
              true});
    visit(o.test_fraction,
          Field{"test_fraction",
                "number",
                "or: each image a test image with this probability (seeded by split_seed)",
                {},
                true});
    visit(o.split_seed, Field{"split_seed", "integer", "seed of the test_fraction draws"});
    visit(o.target_min_visib_fract,
          Field{"target_min_visib_fract", "number",
                "test targets count instances at least this visible (0..1)"});
    visit(o.model_points,
          Field{"model_points", "integer", "points per model cloud in models/points/ (0: none)"});
    visit(o.even_points,
          Field{"point_sampling",
                "choice",
                "area: uniform by surface area; even: farthest-point thinning of 10x as many",
                {"area", "even"}});
    visit(o.point_seed, Field{"point_seed", "integer", "seed of the model clouds"});
    visit(o.coco, Field{"", "bool", "COCO files (formats: coco)", {}, true, "coco"});
    visit(
        o.paper_layout,
        Field{
            "", "bool", "the reference paper's layout (formats: paper)", {}, true, "paper_layout"});
    visit(o.pvn3d_meta,
          Field{"", "bool", "PVN3D meta files (formats: pvn3d)", {}, true, "pvn3d_meta"});
    visit(
        o.grasp_points,
        Field{
            "", "bool", "grasp-detector point arrays (formats: grasp)", {}, true, "grasp_points"});
    visit(
        o.webdataset,
        Field{
            "", "bool", "webdataset archive shards (formats: webdataset)", {}, true, "webdataset"});
    visit(o.archive_samples,
          Field{"archive_samples", "integer",
                "with formats: webdataset, the most samples (views) per archive (1-1,000,000)"});
    visit(o.archive_megabytes,
          Field{"archive_megabytes", "integer",
                "with formats: webdataset, the most MiB per archive (1-1,048,576; a larger view "
                "gets an archive of its own)"});
    visit(
        o.jpeg_quality,
        Field{
            "jpeg_quality", "integer", "with rgb: jpg, the JPEG quality 1-100 (0: PNG)", {}, true});
    visit(o.gray_bits, Field{"", "integer", "set by camera.image", {}, true, "gray_bits"});
    visit(o.visibility,
          Field{"visibility",
                "choice",
                "exact: the front-most surface; bop19: bop_toolkit's rule with visibility_delta",
                {"exact", "bop19"}});
    visit(o.visib_delta_mm,
          Field{"visibility_delta",
                "length",
                "with visibility: bop19, bop_toolkit's delta (15 mm; 5 mm for ITODD)",
                {},
                true});
    visit(o.coco_amodal_bbox,
          Field{"coco_bbox",
                "choice",
                "COCO boxes: amodal (full silhouette, as bop_toolkit) or modal (visible part)",
                {"modal", "amodal"}});
    visit(o.infrared,
          Field{"infrared", "bool",
                "active_stereo cameras: also write the left IR image (ir/IMID.png, 8 bits)"});
  }
};

// One scene's split, as BopSceneWriter::Finish sees it.
struct SceneSplit {
  std::vector<int> train, test;  // image ids
  // BOP test targets: (image id, obj_id, number of instances at least target_min_visib_fract
  // visible).
  struct Target {
    int im_id, obj_id, inst_count;
  };
  std::vector<Target> targets;
};

// The folder of DATASET holding the scene folders (e.g. DATASET/train): the one whose
// subfolders have scene_gt.json (a multi-sensor dataset's sensor: scene_gt_SENSOR.json). Throws
// Error when there is none (naming the sensors of a multi-sensor dataset) or more than one.
std::filesystem::path FindSceneFolder(const std::filesystem::path& dataset,
                                      const std::string& sensor = "");

// Writes ROOT/splits/{train,test}.txt ("scene_id image_id" per line) and
// ROOT/test_targets_bop19.json for the given scenes' splits.
void WriteSplits(const std::filesystem::path& root, const std::vector<SceneSplit>& scenes);

// The semantic class of an object: several objects (distinct shapes) may share one, e.g. every
// bolt size is a 'bolt'. Ids start at 1.
struct ObjectClass {
  int id = 0;
  std::string name;
};

// Classes for parts named `part_names`: group g (in order) is class g + 1 and takes every part
// whose name matches one of its shell globs (case-insensitive; the first matching group wins).
// Parts with a non-empty `labels[i]` (e.g. a family that is one class) share one class per label
// instead, numbered after the groups in order of first appearance; the remaining parts get
// classes of their own, named after the part. Sets *empty_groups to the names of groups that
// matched no part. `labels` may be empty.
std::vector<ObjectClass> AssignClasses(
    const std::vector<std::string>& part_names, const std::vector<std::string>& labels,
    const std::vector<std::pair<std::string, std::vector<std::string>>>& groups,
    std::vector<std::string>* empty_groups);

// Writes ROOT/models/ for `parts`; part i becomes obj_id i + 1. `classes[i]` is the class of part
// i (written to models_cad.json); empty: each object is its own class, named after the part.
void WriteBopModels(const std::filesystem::path& root, const std::vector<Part>& parts,
                    const std::vector<ObjectClass>& classes = {});

// Writes ROOT/models/points/obj_OBJID.ply (options.model_points surface points per part) and
// ROOT/models/keypoints.json: per obj_id, 8 and 16 farthest-point keypoints on the surface, the
// centre and the 8 bounding-box corners (model frame, mm), as PVN3D uses.
void WriteModelPoints(const std::filesystem::path& root, const std::vector<Part>& parts,
                      const BopOptions& options);

// Writes ROOT/camera.json, or ROOT/camera_SENSOR.json for a rig's sensor.
void WriteBopCamera(const std::filesystem::path& root, const Intrinsics& intrinsics,
                    const BopOptions& options, const std::string& sensor = "");

// A rig's sensor as the writers see it: BOP's CAMTYPE name (empty: a single-camera dataset, with
// rgb/ and scene_gt.json) and its image (BopOptions::gray_bits).
struct BopSensor {
  std::string name;
  int gray_bits = 0;
  // "_NAME", or nothing for the unnamed sensor: what BOP appends to folder and file names.
  std::string Suffix() const { return name.empty() ? std::string() : "_" + name; }
};

// Ground-truth statistics of one instance in one frame, as scene_gt_info.json holds them, computed
// as bop_toolkit's calc_gt_info.py computes them. Boxes are x, y, width, height with width =
// x_max - x_min (bop_toolkit's misc.calc_2d_bbox: a one-pixel box has width 0), and
// [-1, -1, -1, -1] for both boxes of an instance with no visible pixel.
struct GtInfo {
  // The full silhouette on the 3x canvas: not clipped to the image.
  int bbox_obj[4] = {-1, -1, -1, -1};
  int bbox_visib[4] = {-1, -1, -1, -1};  // the visible pixels
  int px_count_all = 0;                  // full silhouette on the 3x canvas (truncated parts count)
  int px_count_valid = 0;  // silhouette pixels with a depth value in the written depth image
  int px_count_visib = 0;
  double visib_fract = 0.0;
};
// `instance` is the index in frame.instances; options.depth_scale decides which depths are
// writable and options.visibility which pixels are visible (kBop19 needs the frame's amodal
// depth: RenderOptions::amodal_depth).
GtInfo ComputeGtInfo(const Frame& frame, int instance, const BopOptions& options);
// All instances at once: one pass over the visible ids, and one over each amodal mask's rectangle.
std::vector<GtInfo> ComputeGtInfos(const Frame& frame, const BopOptions& options);

// The pixels where each instance of a frame counts as visible, by options.visibility.
class VisibleMasks {
 public:
  VisibleMasks(const Frame& frame, const BopOptions& options);
  // Whether pixel (u, v) of the image is a visible pixel of instance i (index in frame.instances).
  bool operator()(size_t i, int u, int v) const;
  // The same for the pixel at row-major index `pixel`.
  bool AtPixel(size_t i, size_t pixel) const {
    if (exact_) return frame_.instance[pixel] == i + 1;
    const size_t w = static_cast<size_t>(frame_.width());
    return (*this)(i, static_cast<int>(pixel % w), static_cast<int>(pixel / w));
  }

 private:
  const Frame& frame_;
  bool exact_;
  std::vector<std::vector<uint8_t>> masks_;  // kBop19: per instance, inside its roi
};

// Depth in mm to BOP's uint16 units; 0 where there is no return or the value does not fit.
uint16_t EncodeDepth(float depth_mm, double depth_scale);

// A grey camera's value (Frame::gray, in [0, 1]; clamped) as its 8- or 16-bit image holds it.
inline uint16_t EncodeGray(float value, int bits) {
  const float scale = bits == 16 ? 65535.0f : 255.0f;
  const float clamped = value < 0.0f ? 0.0f : (value > 1.0f ? 1.0f : value);
  return static_cast<uint16_t>(clamped * scale + 0.5f);  // round half up
}

// PNG bytes of an image, encoded as the dataset writers encode theirs: `channels` 1 or 3 (R, G, B
// order), `bits` 8 or 16 per value, rows packed. Throws Error.
std::string EncodeImagePng(const void* pixels, int width, int height, int channels, int bits);

// An image file (PNG, JPEG, EXR; render/image_codec.h) as the writers' images read back: 8 or 16
// bits per value, or 32 for float EXR (rgb_hdr/; native-endian floats), 1 or 3 channels (R, G, B
// order; an alpha channel is dropped), rows packed. Throws Error naming the file.
DecodedImage ReadImageFile(const std::filesystem::path& path);
// The same from an image file's bytes (a webdataset member); `origin` names it in errors.
DecodedImage DecodeImage(std::string_view bytes, const std::string& origin);

// One scene of a pick sequence (issue 45): a pile that rested, then had parts taken out one at a
// time, settling again after each; every step is a scene of its own (scene_sequence.json).
struct SequenceStep {
  int first_scene = 0;  // the scene id of step 0 (the pile as it fell)
  int step = 0;         // 0, 1, ... picks
  int picks = 0;        // the sequence's number of picks
  std::string rule;     // how each pick chose its part
  // Per instance of this scene (scene_gt order): its instance id, which is its index in step 0's
  // scene_gt and stays the same in every step.
  std::vector<int> instance_ids;
  // The pick that led to this step (none at step 0): the instance id taken, its obj_id and its
  // world pose in the step before.
  int picked_id = -1;
  int picked_obj_id = 0;
  Eigen::Isometry3d picked_world_from_model = Eigen::Isometry3d::Identity();
  // The picked instance's grasp in the step before (grasp labels only, where it had a free one):
  // the kind ("parallel_jaw" or "suction"), its index in the object's grasp list and the tool's
  // world pose (the gripper's frame; the suction cup's contact frame, +z the approach).
  struct Grasp {
    std::string kind;
    int index = -1;
    double quality = 0;
    Eigen::Isometry3d world_from_tool = Eigen::Isometry3d::Identity();
  };
  std::vector<Grasp> grasps;
  // Per instance of this scene: whether the pick left it free to settle again (it touched the
  // picked part, or rested on one that did), and the largest move of a point of it (mm).
  std::vector<bool> freed;
  std::vector<double> moved_mm;
  double settle_seconds = 0;  // simulated, to rest after the pick
  std::vector<int> restless;  // instance ids still moving when settle_time ran out
};

// How a pile (layout: pile) or a scene's dropped parts (pose: dropped) came to rest, as
// scene_physics.json (cadsynth) records it. Instance ids are scene_gt indices.
struct SceneRest {
  std::string kind;              // "pile" or "dropped"
  int dropped = 0;               // parts dropped
  int removed_outside = 0;       // taken out of the scene: they ended outside the container
  std::vector<int> outside;      // kept where they lie outside it (out_of_container: keep)
  double settle_seconds = 0;     // simulated, until rest or settle_time
  double settle_time = 0;        // the limit
  std::vector<int> restless;     // still moving when settle_time ran out
  int distractors = 0;           // dropped with the parts
  int restless_distractors = 0;  // of them, still moving
  // The collision shape each object was simulated as, by obj_id: its convex pieces, whether they
  // are a decomposition (else the part's hull), the pieces' volume over the part's (the shape's
  // quality: 1 is exact, more fills concavities; 0 when the part has no known volume, an open
  // mesh), and whether the decomposition was stopped at collision.time_limit.
  struct Shape {
    int obj_id = 0;
    int pieces = 0;
    bool decomposed = false;
    double volume_ratio = 0;
    bool timed_out = false;
  };
  std::vector<Shape> shapes;
};

// Writes the images of one scene as frames arrive (from any thread) and its JSON files at the end.
class BopSceneWriter {
 public:
  // obj_id_of_instance[i] is the BOP obj_id of Scene::instances[i]. A named `sensor` writes its
  // folders and scene files with its suffix (rgb_NAME/, scene_gt_NAME.json) and keeps its frame
  // fragments apart (.fragments_NAME/); its gray_bits replaces options.gray_bits.
  BopSceneWriter(const std::filesystem::path& root, int scene_id, const BopOptions& options,
                 std::vector<int> obj_id_of_instance, const BopSensor& sensor = {});

  // Encodes and writes rgb, depth, mask and mask_visib of `frame` as image `image_id`, then each
  // of `formats` (the other formats of the same frame, dataset/frame_writer.h), and last the
  // frame's fragment: its JSON entries (so memory does not grow with the number of frames) and
  // its manifest entry, every file it wrote with size and CRC-32. A frame whose fragment exists
  // is complete: a writer opened on a folder with fragments (an interrupted run, other shards)
  // takes those frames as written.
  void WriteFrame(int image_id, const Frame& frame,
                  const std::vector<const FrameWriter*>& formats = {});
  bool HasFrame(int image_id) const;
  // Image ids whose fragment exists (this writer's and those found when it was opened), sorted.
  std::vector<int> WrittenFrames() const;
  // Empty when every file of the frame's manifest entry is on disk with its recorded size and
  // CRC-32; otherwise the first problem, naming the file.
  std::string CheckFrame(int image_id) const;
  // Drops a written frame's record, so that it counts as not written (e.g. a damaged file).
  void ForgetFrame(int image_id);

  // Writes scene_camera.json, scene_gt.json and scene_gt_info.json (and scene_gt_coco.json, and
  // scene_randomization.json when frames carry a randomisation record) from
  // the fragments, ordered by image id, streaming one frame at a time, and returns the scene's
  // split. The fragments stay (a resumed run finishes the scene again) until RemoveFragments().
  SceneSplit Finish();
  void RemoveFragments();

  // Writes scene_gt_world.json (cadsynth): the world pose of every instance of this static scene,
  // in scene_gt order: obj_id, world_R_m2w (row-major) and world_t_m2w (mm), so that
  // world_from_model = [world_R_m2w, world_t_m2w]; and the instance's name.
  void WriteWorldPoses(const std::vector<Instance>& instances);

  // Writes scene_sequence.json (cadsynth): this scene's place in a pick sequence (SequenceStep).
  void WriteSequence(const SequenceStep& step);

  // Writes scene_physics.json (cadsynth): how the scene's pile or dropped parts came to rest.
  void WriteRest(const SceneRest& rest);

  // Names of the COCO categories of scene_gt_coco.json (category id = obj_id, as BOP); by default
  // each is named after its obj_id.
  struct CocoCategory {
    int id = 0;
    std::string name, supercategory;
  };
  void SetCocoCategories(std::vector<CocoCategory> categories) {
    categories_ = std::move(categories);
  }

  const std::filesystem::path& scene_dir() const { return scene_dir_; }
  const BopSensor& sensor() const { return sensor_; }

 private:
  std::filesystem::path Folder(const std::string& name) const {
    return scene_dir_ / (name + sensor_.Suffix());
  }
  std::filesystem::path FragmentPath(int image_id) const;

  std::filesystem::path root_, scene_dir_;
  BopOptions options_;
  BopSensor sensor_;
  std::vector<int> obj_ids_;
  mutable std::mutex mutex_;
  std::vector<int> image_ids_;  // written so far
  std::vector<CocoCategory> categories_;
};

// One scene's writers, one per sensor of a rig (one unnamed sensor without a rig): the sensors
// share image ids, and a frame is written when every sensor's frame is (each sensor's fragment
// is written last for that sensor, the sensors in order).
class RigSceneWriter {
 public:
  RigSceneWriter(const std::filesystem::path& root, int scene_id, const BopOptions& options,
                 const std::vector<int>& obj_id_of_instance, const std::vector<BopSensor>& sensors);

  // frames[k] is sensor k's frame of the rig pose `image_id`; `formats` (the paper layout, ...)
  // are written for the first sensor only.
  void WriteFrame(int image_id, const std::vector<const Frame*>& frames,
                  const std::vector<const FrameWriter*>& formats = {});
  bool HasFrame(int image_id) const;
  std::vector<int> WrittenFrames() const;  // written by every sensor, sorted
  std::string CheckFrame(int image_id) const;
  void ForgetFrame(int image_id);
  // Each sensor's split (the same image ids for all; test targets counted per sensor).
  std::vector<SceneSplit> Finish();
  void RemoveFragments();
  void WriteWorldPoses(const std::vector<Instance>& instances);
  void WriteSequence(const SequenceStep& step);
  void WriteRest(const SceneRest& rest);
  void SetCocoCategories(const std::vector<BopSceneWriter::CocoCategory>& categories);

  size_t size() const { return sensors_.size(); }
  BopSceneWriter& sensor(size_t k) { return *sensors_[k]; }
  const BopSceneWriter& sensor(size_t k) const { return *sensors_[k]; }

 private:
  std::vector<std::unique_ptr<BopSceneWriter>> sensors_;
};

// Writes ROOT/test_targets_multiview_bop25.json: per scene (in order) and test image, one target
// {"scene_id", "im_id": [[SENSOR, im_id] for every sensor]}: the images of one rig pose taken
// together, as BOP 2025's multi-view task groups them.
void WriteMultiviewTargets(const std::filesystem::path& root, const std::vector<SceneSplit>& scenes,
                           const std::vector<BopSensor>& sensors);

// Throws Error (naming `origin` and the line) unless `text` is a frame fragment as
// BopSceneWriter writes it (.fragments/NNNNNN.json): what Finish and merge read back is checked
// first. For tests and the fuzz harness; the writer checks its own fragments the same way.
void CheckFragmentText(const std::string& text, const std::string& origin);

// Writes ROOT/coco/train.json and ROOT/coco/test.json: the scenes' scene_gt_coco.json merged by
// the split, images numbered from 1 with file names relative to ROOT, and categories the object
// classes: `classes[obj_id - 1]` (each annotation also keeps obj_id, scene_id, im_id, inst_id).
// A rig's sensor (named) merges its scene_gt_coco_NAME.json files into coco/{train,test}_NAME.json.
void WriteMergedCoco(const std::filesystem::path& root, const BopOptions& options,
                     const std::vector<SceneSplit>& scenes, const std::vector<ObjectClass>& classes,
                     const BopSensor& sensor = {});

}  // namespace cadsynth
