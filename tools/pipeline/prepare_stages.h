// The stages of Prepare (prepare.h), in the order it runs them, and the plain data that flows
// between them. Internal to tools/pipeline/prepare*.cpp, not an API: the part stages
// (prepare_parts.cpp) read and build every source, find symmetries, merge repeated shapes, name
// the objects, compute their hulls and assign classes; the scene stages (prepare_scenes.cpp) make
// the collision shapes of what piles and drops, arrange every scene with its distractors, and
// record each scene's materials and randomisation and variants.json.
//
// Every stage keeps the order of its messages, random draws and parallel loops: a run's output
// does not depend on how Prepare is cut into stages.
#pragma once

#include <cstddef>
#include <exception>
#include <functional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "cad/part.h"
#include "cad/part_cache.h"
#include "dataset/bop.h"
#include "recipes/recipe.h"
#include "render/randomize.h"
#include "render/scene.h"
#include "tools/pipeline/guarded_import.h"
#include "tools/pipeline/prepare.h"
#include "variants/arrangement.h"
#include "variants/physics/collision.h"

namespace cadsynth::prepare_stages {

// What every stage reads: the recipe, where progress lines go, and how parts are read.
struct Context {
  const RunSpec& spec;
  std::function<void(const std::string&)> info;  // never empty (drops lines without a sink)
  const PartCache* cache = nullptr;
  const ReaderProcess* reader = nullptr;
  bool strict = false;     // PrepareControls' strict, progress and progress_interval_s
  StageProgress progress;  // (may be empty)
  double progress_interval_s = 2.0;
};

// One thing to build: a file, or one variant of a family; a rigid group in its scene.
struct Job {
  int scene = 0;
  const PartSource* source = nullptr;
  size_t variant = 0;
  std::string id;  // stable: scene/entry/family-or-file/variant
  Assembly assembly;
  std::vector<std::string> warnings;  // reading or building it gave (also from the cache)
  std::string error;
};

// A distractor a scene may draw: a primitive by name, or one part of a file or family variant.
struct DistractorCandidate {
  std::string name;
  DistractorObject::Kind kind = DistractorObject::Kind::kBox;
  Part part;  // kSource
};

// A part without declared symmetries, to look for them, or with a recipe's list, to measure it.
struct SymmetryCheck {
  size_t part;
  double tolerance_mm;
  const PartSource* given = nullptr;  // a recipe's explicit list, measured instead
};

// The collision shapes of the parts that piles and drops use, each made once (two piles of one
// part would otherwise both decompose it on a cold cache); a shape's warnings surface with the
// first scene that drops the part, its failure with every such scene. All per part.
struct PileShapes {
  std::vector<CollisionShape> shapes;
  std::vector<std::exception_ptr> failures;
  std::vector<std::vector<std::string>> warnings;
  std::vector<int> first_dropping;  // the first scene that drops the part, -1 for none
};

// What the part stages make, for the stages after them.
struct PrepareState {
  std::vector<Job> jobs;             // every file and variant of every scene, in recipe order
  std::vector<Mesh> container_mesh;  // per scene: its container file's mesh (or empty)
  std::vector<std::vector<DistractorCandidate>> distractor_candidates;  // per scene
  // One list of parts; instances remember their job (a rigid group) and scene.
  Assembly all;
  std::vector<int> job_of_instance;
  std::vector<std::string> label_of_part;  // a one-class source's family, else empty
  std::vector<ObjectClass> classes;        // per part
  PileShapes pile_shapes;
};

// One scene's placement, made on its own thread: messages (the scene's own and the warnings of
// what it calls, captured), errors and other exceptions are kept to follow in scene order.
struct Placement {
  Scene scene;  // the recipe's look, with the tote and the distractors as fixtures
  Arrangement arranged;
  std::vector<Drawn> distractor_record;
  size_t first_distractor = 0;
  std::vector<std::pair<bool, std::string>> messages;  // (a warning?, the text)
  std::string error;
  std::exception_ptr exception;  // anything else thrown
  // A pile's pick sequence: each pick, and per step the instance id (index in `arranged`) of
  // each instance left.
  std::vector<PickStep> picks;
  std::vector<std::vector<int>> pick_ids;
  // A pile's or dropped scene's parts before any was taken out, and its distractors.
  size_t dropped = 0, distractors = 0;
};

using Json = nlohmann::ordered_json;

// A variant's parameters as JSON (variants.json; also tells distractor sources apart).
Json ParamsJson(const ParamValues& values);

// The part stages (prepare_parts.cpp).

// Every file and variant of every scene, built in parallel; warnings and errors in recipe order.
std::vector<Job> BuildParts(const Context& context);
// Per scene, its container file's mesh (container type: file), empty without one.
std::vector<Mesh> BuildContainers(const Context& context);
// Per scene, the distractors it may draw (randomize.distractors.objects).
std::vector<std::vector<DistractorCandidate>> BuildDistractorObjects(const Context& context);
// Moves every job's parts and instances into state->all (filling job_of_instance and
// label_of_part) and returns the parts whose symmetries are to be looked for or measured.
std::vector<SymmetryCheck> GatherParts(const Context& context, PrepareState* state);
void FindSymmetries(const Context& context, const std::vector<SymmetryCheck>& detect,
                    std::vector<Part>* parts);
void ReportFamilies(const Context& context);
void MergeRepeatedShapes(const Context& context, PrepareState* state);
void RenameRepeatedNames(std::vector<Part>* parts);
void ComputeHulls(const Context& context, std::vector<Part>* parts);
std::vector<ObjectClass> AssignPartClasses(const Context& context, const PrepareState& state);

// A length in millimetres for a message: "0.8" below 10 mm (not "1"), whole millimetres above,
// three significant digits past 1e12 (preflight.cpp).
std::string Mm(double x);

// The checks before simulation and rendering (preflight.cpp): Errors naming the recipe line.

// Each pile in a tote: every part fits inside it (its thinnest width between the walls, its
// length within the inner diagonal), all of them together fit at the densest random packing (64 %
// of the inner volume), and no camera of the sweep sits inside the tote.
void CheckScenesCanBeMade(const Context& context, const PrepareState& state);
// No camera of the sweep inside the bounding box of an arranged part (for a part from a file
// whose unit the recipe overrides, the message asks about the unit).
void CheckCamerasOutsideParts(const Context& context, const PrepareState& state,
                              const std::vector<Placement>& placements);

// A pile in the part cache (pile_cache.cpp), kind "pile": its key holds everything that decides
// the pile (the arranged parts' geometry, mass and names, the instances and their groups, every
// pile option, the collision options, the distractors, --strict); its value the pile, its pick
// sequence (placement's arranged, picks and pick_ids) and the messages they gave, so that a second
// shard or a DataLoader worker reads the pile instead of simulating it again (the same bytes).
// Decode throws Error for a damaged entry.
CacheKey PileKey(const PartCache& cache, const SceneSpec& scene_spec,
                 const std::vector<Part>& parts, const std::vector<Instance>& instances,
                 const std::vector<int>& groups, const ArrangementOptions& arrangement,
                 const CollisionOptions& collision, bool strict);
std::string EncodePile(const Placement& placement,
                       const std::vector<std::pair<bool, std::string>>& messages);
void DecodePile(std::string_view bytes, Placement* placement,
                std::vector<std::pair<bool, std::string>>* messages);

// The scene stages (prepare_scenes.cpp).

PileShapes MakePileShapes(const Context& context, const PrepareState& state);
// Every scene arranged at once (piles, drops, distractors), one per thread.
std::vector<Placement> ArrangeScenes(const Context& context, const PrepareState& state);
// The placements' messages and errors in scene order, then each scene's materials, randomisation,
// colours and obj_ids (the run without its parts, classes and variants.json).
PreparedRun RecordScenes(const Context& context, const PrepareState& state,
                         std::vector<Placement>* placements);
// variants.json: what each file or variant is, and which objects it became.
std::string VariantsRecord(const RunSpec& spec, const PrepareState& state);

}  // namespace cadsynth::prepare_stages
