// Stage 1 of a run, prepare: the recipe's parts read and built, repeated shapes merged, classes
// assigned, each scene arranged on the floor. Everything later stages need, as plain data.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "cad/part_cache.h"
#include "dataset/bop.h"
#include "recipes/recipe.h"
#include "render/scene.h"
#include "tools/pipeline/guarded_import.h"

namespace cadsynth {

// Everything a run renders, before rendering: the objects (all scenes share them), their classes,
// each scene arranged on the floor with the obj_id of each instance, and variants.json's text.
// A recipe's scene is one scene here, or 1 + picks scenes when it is a pile with a pick sequence
// (its steps follow it).
struct PreparedRun {
  std::vector<Part> parts;
  std::vector<ObjectClass> classes;
  std::vector<Scene> scenes;
  std::vector<std::vector<int>> obj_ids;
  // Per scene, its domain randomisation with instance_rule and instance_part resolved.
  std::vector<Randomization> randomization;
  std::string variants_json;
  // Per scene: its name (the recipe's; a pick sequence's steps add _pick_01, _pick_02, ...), and
  // for the steps of a pick sequence (the pile as it fell is step 0) where it stands in it.
  std::vector<std::string> scene_names;
  std::vector<std::optional<SequenceStep>> sequence;
  // Per scene: how its pile or dropped parts came to rest (none for other layouts and for the
  // steps after a pick, whose scene_sequence.json says it).
  std::vector<std::optional<SceneRest>> rest;
};

// Progress of a long preparation stage: a pile's simulation ("pile": `scene`, simulated seconds
// `done` of settle_time `total`, "37 of 60 bodies moving"), or the collision shapes of concave
// parts ("collision_shapes": parts `done` of `total`, "'bracket': 12 convex pieces in 1.3 s").
struct StageReport {
  std::string stage;  // "pile" or "collision_shapes"
  std::string scene;  // a pile's scene (empty for collision shapes)
  double done = 0, total = 0;
  std::string detail;
};
// Called from the stage's threads, at most every progress_interval_s per pile.
using StageProgress = std::function<void(const StageReport&)>;

// What Prepare does beyond its info lines.
struct PrepareControls {
  // Warnings that describe a broken dataset (parts kept outside their container, parts still
  // moving at the end of settle_time) are errors, "(an error under --strict)".
  bool strict = false;
  StageProgress progress;            // may be empty
  double progress_interval_s = 2.0;  // of wall time between two calls for one scene
};

// Reads the files and builds the family variants of every scene (in parallel), merges repeated
// shapes, computes each part's convex hull, assigns classes and arranges each scene. With a
// cache, imported files, built variants, hulls and repeated-shape checks are read from it where
// it has them, and stored where it has not (the result is the same bytes either way). Warnings
// come in recipe order. Throws Error naming the recipe entry.
// With `reader`, files are read in a child process (tools/pipeline/guarded_import.h).
PreparedRun Prepare(const RunSpec& spec, const std::function<void(const std::string&)>& info = {},
                    const PartCache* cache = nullptr, const ReaderProcess* reader = nullptr,
                    const PrepareControls& controls = {});

// How the placement warning of a camera closer to the target than the scene's reach ends (an
// error under --strict).
inline constexpr const char* kCameraInsideScene = "the camera will be inside or touching it";

// What a user should hear about a scene before rendering it: whether its objects fit the view at
// the nearest camera radius, and whether the smallest is still a few pixels at the farthest.
std::vector<std::string> PlacementWarnings(const std::vector<Part>& parts,
                                           const std::vector<Instance>& instances,
                                           const Intrinsics& intrinsics, const SweepOptions& sweep);

}  // namespace cadsynth
