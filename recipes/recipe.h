// Recipes: one YAML file describes a whole run. Only this module knows YAML; it fills the
// Options structs of the other modules and checks them, pointing at file:line:column.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "cad/import.h"
#include "cad/shape.h"
#include "dataset/bop.h"
#include "dataset/grasp_labels.h"
#include "render/camera.h"
#include "render/randomize.h"
#include "render/renderer.h"
#include "render/scene.h"
#include "render/sensor.h"
#include "variants/arrangement.h"
#include "variants/families.h"
#include "variants/grasp/parallel_jaw.h"
#include "variants/grasp/scene_grasps.h"
#include "variants/grasp/suction.h"

namespace cadsynth {

// Where a part list entry comes from: a file, or a parametric family with its variants.
struct PartSource {
  enum class Kind { kFile, kFamily };
  Kind kind = Kind::kFile;
  std::filesystem::path path;  // kFile: STEP, IGES, BREP or mesh
  std::string unit;  // kFile: the unit its numbers are in, overriding the file (see ImportOptions)
  std::string encoding;  // kFile, STEP: code page of raw-byte names (see ImportOptions)
  std::string family;    // kFamily: the family's name (see Families())
  // kFamily: every variant's complete parameters, in a stable order (grid: nested loops over the
  // family's parameters in their order, the last varying fastest; random: draw order).
  std::vector<ParamValues> variants;
  bool one_class = false;  // kFamily: all variants are one object class (class: family)
  // The axis its designer drew as up (recipe `up: y` for a file drawn Y-up): this rotation turns
  // it to +z before the scene is arranged. Identity for z.
  Eigen::Matrix3d z_from_up = Eigen::Matrix3d::Identity();
  // Parts that declare no symmetries (files; families declare theirs): `symmetry: auto` finds
  // them (cad/symmetry.h, within symmetry_tolerance_mm, 0: automatic), `none` leaves them empty.
  bool detect_symmetry = true;
  double symmetry_tolerance_mm = 0;
  // An explicit list (`symmetry: [{axis: [0, 0, 1], order: 6}, ...]`) instead of detection: each
  // an n-fold rotation (order 0: continuous) about `axis` through `through`, in the part's own
  // CAD frame (mm; default: the centroid of its surface). The run completes the list to its group
  // and measures every member; one beyond the tolerance stops the run. Files with one part only.
  struct GivenSymmetry {
    Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
    int order = 0;
    std::optional<Eigen::Vector3d> through;
    std::string where;  // "recipe.yaml:7:9"
  };
  std::vector<GivenSymmetry> given_symmetries;
  std::string where;  // "recipe.yaml:3:5" (empty when built in)
};

// Domain randomisation as the recipe gives it (`randomize:`): the draws, and for each of
// draws.parts the patterns of the parts it is for (by name, family or file, as MaterialRule; the
// first matching rule draws a part's material). The run resolves draws.instance_rule per scene.
struct RandomizeRule {
  std::string name, family, file;
  std::string where;  // "recipe.yaml:12:7"
};
// A distractor object (randomize.distractors.objects): a primitive whose size the scene draws,
// or a part source (a file, each file of a folder, a family's variants), every distinct part of
// which is an object to pick.
struct DistractorObject {
  enum class Kind { kBox, kCylinder, kSphere, kSource };
  Kind kind = Kind::kBox;
  PartSource source;  // kSource
  std::string where;  // "recipe.yaml:12:7"
};
struct RandomizeSpec {
  Randomization draws;
  std::vector<RandomizeRule> part_rules;  // one per draws.parts entry
  // With draws.distractors: what they are (default: a box, a cylinder and a sphere).
  std::vector<DistractorObject> distractor_objects;
};

// A pile's (or dropped parts') physics for the parts a rule matches: patterns as MaterialRule's.
struct PhysicsRule {
  std::string name, family, file;
  PhysicsDraw physics;  // keys the rule leaves out keep the defaults (PhysicsMaterial)
  std::string where;    // "recipe.yaml:12:7"
};

// One BOP scene: what lies on the floor together, and how.
struct SceneSpec {
  std::string name;
  std::vector<PartSource> sources;
  ArrangementOptions arrangement;
  // A pile's tote as the images show it: its colour (sRGB, the fast mode) and material (pbr).
  Eigen::Vector3f container_color{0.16f, 0.30f, 0.55f};
  std::optional<Material> container_material;
  // A pile's container from a CAD or mesh file (container type: file): read like a part file,
  // all its instances as one fixture, centred over the origin and standing on the floor.
  std::optional<PartSource> container_file;
  // Physics per part: the first rule matching a part; parts matching none (or no rules, when
  // `physics` is one map) take arrangement.physics.
  std::vector<PhysicsRule> physics_rules;
  // This scene's `randomize:` (the recipe's, with the groups the scene gives replaced); unset:
  // the recipe's.
  std::optional<RandomizeSpec> randomize;
  // Where the recipe gives the scene, its container and its copies ("recipe.yaml:12:7"; empty
  // when built in or not given): what the checks before a run point at.
  std::string where, container_where, copies_where;
};

// Grasp labels (`grasps:`): antipodal parallel-jaw grasps (and, with a cup, suction grasps)
// sampled per object in its model frame, written as ACRONYM's per-object HDF5 files
// (models/grasps/obj_OBJID.h5); placed on every instance of each scene, filtered for collisions
// and written per frame in GraspNet-1Billion's and SuctionNet-1Billion's layouts.
struct GraspSpec {
  bool enabled = false;
  ParallelJawGripper gripper = ParallelJawGripper::Franka();
  AntipodalOptions sampling;
  bool suction = false;  // `suction:` given
  SuctionCup cup;
  SuctionOptions suction_sampling;
  SceneGraspOptions scene;
  GraspLabelOptions labels;  // graspnet on by default, suctionnet with a cup (the reader)
  bool acronym = true;
};

// Bounds on how much work a recipe may ask for, so a typo (5,000 teeth, a grid of 100,000
// variants, a 0.0001 mm tessellation) is an error at once instead of minutes of silence. A recipe
// that means it raises them in its `limits:` section.
struct RunLimits {
  int max_variants = 2000;           // family variants and files, all scenes together
  int max_count = 1000;              // any count parameter of a family (teeth, planets, ...)
  double min_deflection_mm = 0.001;  // tessellation.linear_deflection
  double read_timeout_s = 600;       // a CAD or mesh reader still busy after this is stopped

  bool Check(std::string* why) const;
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.max_variants,
          Field{"max_variants", "integer", "most family variants and files in one run"});
    visit(o.max_count,
          Field{"max_count", "integer", "largest count parameter of a family (teeth, planets)"});
    visit(o.min_deflection_mm,
          Field{"min_deflection", "length", "finest tessellation.linear_deflection allowed"});
    visit(o.read_timeout_s,
          Field{"read_timeout", "number",
                "seconds a CAD or mesh file may take to read before its reader is stopped"});
  }
};

// The physically based mode's material for the parts a rule matches: by part name, by the family
// that built them or by the file they came from (shell globs, case-insensitive; an empty pattern
// matches anything). A part takes the material of the first rule that matches all given patterns.
struct MaterialRule {
  std::string name, family, file;
  Material material;
  std::string where;  // "recipe.yaml:12:7" (empty when built in)
};

// One sensor of a camera rig (the recipe's `cameras:` list): several sensors fixed to one
// another, moved together by the sweep, each with its own intrinsics, image and depth model.
struct RigSensor {
  std::string name;  // BOP's CAMTYPE: rgb_NAME/, scene_gt_NAME.json, camera_NAME.json
  Intrinsics intrinsics;
  SensorOptions sensor;
  // Where the sensor sits on the rig: the rig's frame is the first sensor's camera frame (x right,
  // y down, z forward, mm), which the sweep places; the first sensor's is the identity.
  Eigen::Isometry3d rig_from_cam = Eigen::Isometry3d::Identity();
  std::string where;  // "recipe.yaml:12:5" (empty when built in code)
};

// BopOptions::gray_bits of a camera's image: 0 (colour), 8 or 16.
int GrayBits(SensorOptions::Image image);

// Everything one run needs, each module's options filled in.
struct RunSpec {
  std::filesystem::path recipe;  // empty for the built-in default job
  std::string recipe_text;       // the recipe's bytes as read once (the run key holds them)
  std::vector<SceneSpec> scenes;
  TessellationOptions tessellation;
  double crease_angle_rad = ImportOptions{}.crease_angle_rad;  // meshes
  // What one object class is: each distinct part shape (kPart) or each file's whole assembly
  // (kAssembly, fused into one rigid object).
  enum class ClassBy { kPart, kAssembly };
  ClassBy class_by = ClassBy::kPart;
  // Named classes grouping parts by name (shell globs, case-insensitive), in recipe order;
  // parts matching none keep a class of their own.
  std::vector<std::pair<std::string, std::vector<std::string>>> class_groups;
  Intrinsics intrinsics;
  SensorOptions sensor;  // camera.image and camera.depth: grey images, depth sensor models
  // A camera rig (`cameras:`): every sensor, the first one's intrinsics and sensor repeated in
  // `intrinsics` and `sensor` above (camera.json, placement checks use them); empty: the one
  // camera above, written in BOP's single-sensor layout.
  std::vector<RigSensor> rig;
  SweepOptions sweep;
  ViewSampler sampler;         // kGrid: the sweep as listed
  int min_visible_pixels = 0;  // skip views where fewer object pixels are visible (0: keep all)
  // Floor, colours and lights of both modes, floor material, light sources and environment of the
  // pbr mode (its instances are filled in by the run).
  Scene look;
  std::vector<MaterialRule> material_rules;  // pbr: materials of parts, first match wins
  // pbr: parts no rule matches; unset: a dielectric of the part's colour (Scene::DefaultMaterial).
  std::optional<Material> default_material;
  bool cad_colors = true;  // colours from the CAD files where they have them, else the palette
  RenderOptions render;
  RandomizeSpec randomize;  // the recipe's `randomize:` (scenes may replace groups of it)
  GraspSpec grasps;
  CollisionOptions collision;  // the collision shapes of the parts that piles and drops simulate
  BopOptions bop;
  std::filesystem::path output;  // empty: the command line decides
  RunLimits limits;
  // Reseed(): the stream the seeds were moved to (0: the recipe's own seeds).
  uint64_t reseed = 0;

  // The run-wide options that are RunSpec's own rather than a section struct's, each a key of a
  // different section (tessellation, classes, sweep, render) and read there. Described here, not
  // moved into a struct of their own: four scalars of four sections would make no section's struct,
  // and described they still reach every visitor (the run key, the recipe tree, the tests). The
  // rest of the spec is its structs' (their own Fields) or the recipe's own syntax.
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.crease_angle_rad, Field{"crease_angle", "angle",
                                    "meshes: sharper edges keep their own normals (0: faceted)"});
    visit(
        o.class_by,
        Field{"by", "choice", "each distinct part, or each file's assembly", {"part", "assembly"}});
    visit(o.min_visible_pixels, Field{.key = "min_visible_pixels",
                                      .kind = "integer",
                                      .doc = "skip views with fewer object pixels",
                                      .range = Range::kNonNegative});
    visit(o.cad_colors, Field{"colors",
                              "choice",
                              "colours from the CAD files where they have them, or the palette",
                              {"palette", "cad"}});
  }
};

// The same run with every seed of what is drawn per run moved to stream `stream` (0: unchanged):
// each scene's arrangement (random poses, piles), domain randomisation, the view sampler, the
// path tracer's sampler and the sensors' noise. The parts and their grasps stay. For endless
// streams of new scenes (the Python module's torch dataset): stream k always gives the same run.
RunSpec Reseed(const RunSpec& spec, uint64_t stream);

// The sensors a run renders: `spec.rig`, or the one unnamed camera (intrinsics, sensor) without a
// rig.
std::vector<RigSensor> RunSensors(const RunSpec& spec);

// Throws Error, naming the recipe entry (or `recipe` for run-wide options), when `spec` asks for
// more than its limits allow.
void CheckLimits(const RunSpec& spec, const std::string& recipe = "");

// The built-in default job: the reference paper's three demo sets rebuilt parametrically, one BOP
// scene each (a planetary gearbox, a slider-crank mechanism, an assembly-benchmark set of pegs,
// faceplate, shaft and bolt), on a 144-view sweep (yaw every 30 degrees, pitch 15-75 by 20,
// radius 0.65, 1.05, 1.45 m), Kinect v1 camera.
RunSpec DefaultRunSpec();

// The three demo scenes of the default job (also what `scenes: default` means in a recipe).
std::vector<SceneSpec> DemoScenes();

// Reads a recipe. Throws Error "FILE:LINE:COL: what" for unknown keys (with the nearest known
// key), values of the wrong kind or unit, impossible values and missing files.
RunSpec LoadRecipe(const std::filesystem::path& path);

// Same, from text; `name` is used in messages and `base_dir` resolves relative paths.
RunSpec ParseRecipe(const std::string& text, const std::string& name,
                    const std::filesystem::path& base_dir);

}  // namespace cadsynth
