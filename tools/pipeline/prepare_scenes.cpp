// Prepare's scene stages (prepare_stages.h): the collision shapes of what piles and drops, every
// scene arranged at once with its distractors, then, in scene order, each scene's messages,
// materials and randomisation, and variants.json.
#include <fnmatch.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <filesystem>
#include <iomanip>
#include <optional>
#include <set>
#include <sstream>

#include <tbb/parallel_for.h>

#include "cad/core/error.h"
#include "cad/core/util.h"
#include "cad/part_cache.h"
#include "cad/shape.h"
#include "render/image.h"
#include "render/randomize.h"
#include "tools/pipeline/prepare_stages.h"
#include "variants/arrangement.h"

namespace cadsynth::prepare_stages {
namespace {

// A part's collision shape for piles, read from the cache or computed (and stored): a concave
// part's decomposition takes up to seconds, once per part for a whole farm. A decomposition
// stopped at its time limit is stored too, so that every shard sharing the cache simulates the
// same shape.
CollisionShape PartCollisionShape(const Part& part, const CollisionOptions& options,
                                  const PartCache* cache) {
  std::optional<CacheKey> key;
  if (cache) {
    KeyHasher hasher;
    cache->Start(&hasher, "collision 4");
    hasher.Geometry(part.mesh).Value(part.watertight).Value(part.mass.volume_mm3).Fields(options);
    key = hasher.Key();
    if (const std::optional<std::string> bytes = cache->Load("collision", *key)) {
      try {
        CollisionShape shape = DecodeCollisionShape(*bytes);
        if (shape.timed_out) {
          std::ostringstream text;
          text << "part '" << part.name << "': its convex decomposition did not finish within "
               << options.time_limit_s
               << " s (collision.time_limit) when the part cache's copy was made; it is "
                  "simulated as its convex hull";
          Warn(text.str());
        }
        return shape;
      } catch (const Error&) {  // damaged: computed again below
      }
    }
  }
  CollisionShape shape = MakeCollisionShape(part, options);
  if (key) cache->Store("collision", *key, EncodeCollisionShape(shape));
  return shape;
}

// Whether a rule's name, family and file patterns (shell globs, case-insensitive; empty matches
// anything) all match a part of `source` called `name`. File patterns without a '/' match the
// file's name wherever it lies.
template <typename Rule>
bool RuleMatches(const Rule& rule, const std::string& name, const PartSource& source) {
  const bool from_file = source.kind == PartSource::Kind::kFile;
  const std::string family = from_file ? "" : source.family;
  const std::string file = from_file ? source.path.string() : "";
  const auto matches = [](const std::string& pattern, const std::string& text) {
    if (pattern.empty()) return true;
    if (text.empty()) return false;
    const std::string subject = pattern.find('/') == std::string::npos
                                    ? std::filesystem::path(text).filename().string()
                                    : text;
    return fnmatch(pattern.c_str(), subject.c_str(), FNM_CASEFOLD) == 0;
  };
  return matches(rule.name, name) && matches(rule.family, family) && matches(rule.file, file);
}

// A scene's messages in the order they arise: its own (Say) and the warnings of what it calls
// (Warn on this thread), captured and kept in order with its own.
class SceneLog {
 public:
  explicit SceneLog(std::vector<std::pair<bool, std::string>>* messages) : messages_(messages) {}
  // The warnings captured so far.
  void Flush() {
    for (std::string& w : capture_.Take()) messages_->emplace_back(true, std::move(w));
  }
  void Say(bool warning, std::string text) {
    Flush();
    messages_->emplace_back(warning, std::move(text));
  }
  // A warning that describes a broken dataset (parts outside the container kept, parts still
  // moving): with --strict an error (the scene's error, prefixed with its name by PlaceScene).
  void Broken(bool strict, const std::string& scene, const std::string& text) {
    if (strict) throw Error(text + " (an error under --strict)");
    Say(true, "scene '" + scene + "': " + text);
  }

 private:
  WarningCapture capture_;
  std::vector<std::pair<bool, std::string>>* messages_;
};

// Warnings of the items of an inner parallel loop (captured per item, on whichever thread
// ran it), in item order.
void Replay(const std::vector<std::vector<std::string>>& warnings) {
  for (const auto& item : warnings) {
    for (const std::string& w : item) Warn(w);
  }
}

// Collision shapes of the parts that fall, made once per part before the scenes (from the cache
// where it can); per part, empty for those the scene does not use.
std::vector<CollisionShape> FallingShapes(const PileShapes& pile, size_t s,
                                          const std::vector<Instance>& instances) {
  std::vector<CollisionShape> shapes(pile.shapes.size());
  std::vector<size_t> used;
  for (const Instance& instance : instances) used.push_back(static_cast<size_t>(instance.part));
  std::sort(used.begin(), used.end());
  used.erase(std::unique(used.begin(), used.end()), used.end());
  for (size_t p : used) {
    if (pile.first_dropping[p] == static_cast<int>(s)) {
      for (const std::string& w : pile.warnings[p]) Warn(w);
    }
    if (pile.failures[p]) std::rethrow_exception(pile.failures[p]);
    shapes[p] = pile.shapes[p];
  }
  return shapes;
}

// The scene's distractors drawn (none unless the scene draws them), their draws recorded.
std::vector<DistractorPick> DrawSceneDistractors(const Randomization& draws, size_t s,
                                                 const std::vector<DistractorCandidate>& candidates,
                                                 std::vector<Drawn>* record) {
  if (!draws.distractors) return {};
  std::string why;
  if (!draws.Check(&why)) throw Error("randomize: " + why);
  std::vector<std::string> names;
  std::vector<int> sizes;
  for (const DistractorCandidate& c : candidates) {
    names.push_back(c.name);
    sizes.push_back(c.kind == DistractorObject::Kind::kBox        ? 3
                    : c.kind == DistractorObject::Kind::kCylinder ? 2
                    : c.kind == DistractorObject::Kind::kSphere   ? 1
                                                                  : 0);
  }
  return DrawDistractors(draws, s, names, sizes, record);
}

// The drawn distractors as parts, made in parallel: primitives of the drawn size, or copies of
// file and family parts.
std::vector<Part> MakeDistractorParts(const RunSpec& spec,
                                      const std::vector<DistractorCandidate>& candidates,
                                      const std::vector<DistractorPick>& picks) {
  std::vector<Part> made(picks.size());
  std::vector<std::vector<std::string>> made_warnings(picks.size());
  tbb::parallel_for(size_t{0}, picks.size(), [&](size_t k) {
    WarningCapture made_capture;
    const DistractorCandidate& c = candidates[picks[k].object];
    const Eigen::Vector3d& size = picks[k].size_mm;
    const std::string name = "distractor " + std::to_string(k) + " (" + c.name + ")";
    switch (c.kind) {
      case DistractorObject::Kind::kBox:
        made[k] = MakePart(name, MakeBox(size.x(), size.y(), size.z()), spec.tessellation);
        break;
      case DistractorObject::Kind::kCylinder:
        made[k] = MakePart(name, MakeCylinder(0.5 * size.x(), size.y()), spec.tessellation);
        break;
      case DistractorObject::Kind::kSphere:
        made[k] = MakePart(name, MakeSphere(0.5 * size.x()), spec.tessellation);
        break;
      case DistractorObject::Kind::kSource:
        made[k] = c.part;
        made[k].name = name;
        break;
    }
    made_warnings[k] = made_capture.Take();
  });
  Replay(made_warnings);
  return made;
}

// Collision shapes of every part that falls or is fallen on (cached where they can be), for
// those `shapes` does not have yet.
void CompleteCollisionShapes(const PartCache* cache, const CollisionOptions& collision,
                             const std::vector<Part>& with_distractors, size_t num_parts,
                             const std::vector<Instance>& instances,
                             const std::vector<int>& distractors,
                             std::vector<CollisionShape>* shapes) {
  std::vector<size_t> need;
  for (const Instance& instance : instances) need.push_back(static_cast<size_t>(instance.part));
  for (int d : distractors) need.push_back(static_cast<size_t>(d));
  std::sort(need.begin(), need.end());
  need.erase(std::unique(need.begin(), need.end()), need.end());
  // A flat part (no volume) has no shape: distractors do not land on it.
  std::vector<std::string> errors(need.size());
  std::vector<std::vector<std::string>> need_warnings(need.size());
  tbb::parallel_for(size_t{0}, need.size(), [&](size_t k) {
    if (!(*shapes)[need[k]].pieces.empty()) return;
    WarningCapture need_capture;
    try {
      (*shapes)[need[k]] = PartCollisionShape(with_distractors[need[k]], collision, cache);
    } catch (const Error& e) {
      errors[k] = e.what();
    }
    need_warnings[k] = need_capture.Take();
  });
  Replay(need_warnings);
  for (size_t k = 0; k < need.size(); ++k) {
    if (!errors[k].empty() && need[k] >= num_parts) throw Error(errors[k]);
  }
}

// The drawn distractors made and added after the parts (the returned list: the parts, then the
// distractors), listed in `arrangement` and given collision shapes in `shapes`.
std::vector<Part> AddDistractors(const Context& context, const std::vector<Part>& parts,
                                 const std::vector<DistractorCandidate>& candidates,
                                 const std::vector<DistractorPick>& picks,
                                 const std::vector<Instance>& instances,
                                 ArrangementOptions* arrangement,
                                 std::vector<CollisionShape>* shapes) {
  std::vector<Part> with_distractors = parts;
  std::vector<Part> made = MakeDistractorParts(context.spec, candidates, picks);
  shapes->resize(parts.size() + picks.size());
  for (size_t k = 0; k < picks.size(); ++k) {
    arrangement->distractors.push_back(static_cast<int>(with_distractors.size()));
    with_distractors.push_back(std::move(made[k]));
    // Primitives: their hulls; a ball needs more corners than the default 32 to stay within
    // 0.5 mm of its surface (a 24 mm ball sank 1.4 mm into the floor with 32). Every
    // contact scans them all, so cylinders take 64 and boxes have their 8.
    const DistractorObject::Kind kind = candidates[picks[k].object].kind;
    if (kind != DistractorObject::Kind::kSource) {
      CollisionOptions round = context.spec.collision;
      round.max_corners = kind == DistractorObject::Kind::kSphere ? 128 : 64;
      (*shapes)[parts.size() + k] = MakeCollisionShape(with_distractors.back(), round);
    }
  }
  CompleteCollisionShapes(context.cache, context.spec.collision, with_distractors, parts.size(),
                          instances, arrangement->distractors, shapes);
  return with_distractors;
}

// Each part's physics: the first rule matching it (by the source of its first instance);
// distractors take the scene's.
void AssignPhysics(const SceneSpec& scene_spec, const PrepareState& state,
                   const std::vector<Instance>& instances, const std::vector<int>& groups,
                   size_t num_arranged_parts, ArrangementOptions* arrangement) {
  const std::vector<Part>& parts = state.all.parts;
  arrangement->part_physics.assign(num_arranged_parts, arrangement->physics);
  std::vector<bool> done(parts.size(), false);
  for (size_t i = 0; i < instances.size(); ++i) {
    const auto p = static_cast<size_t>(instances[i].part);
    if (done[p]) continue;
    done[p] = true;
    for (const PhysicsRule& rule : scene_spec.physics_rules) {
      if (RuleMatches(rule, parts[p].name, *state.jobs[groups[i]].source)) {
        arrangement->part_physics[p] = rule.physics;
        break;
      }
    }
  }
}

// "#4 'bracket', #17 'bracket' and 3 more": instances of a pile (their drop order) for a message.
std::string NameInstances(const std::vector<Part>& parts, const std::vector<Instance>& instances,
                          const std::vector<int>& which) {
  constexpr size_t kNamed = 8;
  std::vector<std::string> names;
  for (size_t k = 0; k < which.size() && k < kNamed; ++k)
    names.push_back("#" + std::to_string(which[k]) + " '" + parts[instances[which[k]].part].name +
                    "'");
  std::string text = JoinNames(names);
  if (which.size() > kNamed) text += " and " + std::to_string(which.size() - kNamed) + " more";
  return text;
}

// The container as a message names it.
std::string ContainerName(const Container& container) {
  return container.kind == Container::Kind::kTote ? "the tote" : "the container";
}

// What a pile did: at rest or still moving.
void ReportPile(const SceneSpec& scene_spec, const std::vector<Part>& parts,
                const Arrangement& arranged, bool strict, SceneLog* log) {
  std::ostringstream m;
  m << "scene '" << scene_spec.name << "': " << Count(arranged.instances.size(), "part")
    << " in the pile; ";
  if (arranged.restless.empty()) {
    m << "at rest after " << arranged.settle_seconds << " s (simulated)";
    log->Say(false, m.str());
  } else {
    std::ostringstream broken;
    broken << Count(arranged.restless.size(), "part") << " ("
           << NameInstances(parts, arranged.instances, arranged.restless)
           << ") still moving after settle_time (" << scene_spec.arrangement.settle_time_s
           << " s, simulated): raise settle_time, or drop fewer parts";
    log->Broken(strict, scene_spec.name, broken.str());
  }
}

// The parts that ended outside a pile's container (arranged->escaped), as the scene's
// out_of_container says: named, then dropped again (redrop), taken out (remove, and what a redrop
// left outside) or kept where they lie (keep: a broken dataset, an error under --strict).
void SortOutEscaped(const SceneSpec& scene_spec, const std::vector<Part>& parts,
                    const ArrangementOptions& arrangement,
                    const std::vector<CollisionShape>& shapes, bool strict, SceneLog* log,
                    Arrangement* arranged) {
  if (arranged->escaped.empty()) return;
  const std::string container = ContainerName(arrangement.container);
  const size_t dropped = arranged->instances.size();
  std::ostringstream m;
  m << Count(arranged->escaped.size(), "part") << " of " << dropped << " ended outside "
    << container << " (" << NameInstances(parts, arranged->instances, arranged->escaped) << ")";
  switch (arrangement.out_of_container) {
    case OutOfContainer::kKeep:
      m << "; kept where they lie, drawn and labelled as parts of the scene (out_of_container: "
           "keep; remove takes them out, redrop drops them again)";
      log->Broken(strict, scene_spec.name, m.str());
      return;
    case OutOfContainer::kRedrop: {
      const size_t before = arranged->escaped.size();
      RedropEscaped(parts, arrangement, shapes, arranged);
      m << "; dropped again (out_of_container: redrop): " << before - arranged->escaped.size()
        << " landed inside";
      if (arranged->escaped.empty()) {
        log->Say(true, "scene '" + scene_spec.name + "': " + m.str());
        return;
      }
      m << ", " << arranged->escaped.size() << " still outside after three drops ("
        << NameInstances(parts, arranged->instances, arranged->escaped)
        << ") taken out of the scene";
      break;
    }
    case OutOfContainer::kRemove:
      m << "; taken out of the scene, neither drawn nor labelled (out_of_container: remove; keep "
           "labels them where they lie, redrop drops them again)";
      break;
  }
  RemoveEscaped(arranged);
  if (arranged->instances.empty())
    throw Error("every one of its " + Count(dropped, "part") + " ended outside " + container +
                ": the container is too small for them, or they bounce too much");
  log->Say(true, "scene '" + scene_spec.name + "': " + m.str());
}

// A pile's tote (or container file) as a fixture of the scene, unless it has no walls or floor.
void AddTote(const SceneSpec& scene_spec, const Container& container, Scene* scene) {
  const Mesh tote = MakeContainerMesh(container);
  if (tote.empty()) return;
  Scene::Fixture fixture;
  fixture.name =
      scene_spec.container_file ? scene_spec.container_file->path.filename().string() : "tote";
  fixture.mesh = tote;
  fixture.color = scene_spec.container_color;
  Eigen::Vector3f linear;
  for (int c = 0; c < 3; ++c) linear[c] = SrgbToLinear(fixture.color[c]);
  fixture.material = scene_spec.container_material
                         ? *scene_spec.container_material
                         : Scene::DefaultMaterial(scene_spec.container_color);
  if (fixture.material.base_from_part) fixture.material.surface.base_color = linear;
  scene->fixtures.push_back(std::move(fixture));
}

// The distractors as fixtures: drawn and traced, occluding, never labelled.
void AddDistractorFixtures(const std::vector<Part>& arranged_parts,
                           const std::vector<DistractorPick>& picks, Placement* placement) {
  const Arrangement& arranged = placement->arranged;
  placement->first_distractor = placement->scene.fixtures.size();
  for (size_t k = 0; k < arranged.distractors.size(); ++k) {
    const Instance& d = arranged.distractors[k];
    Scene::Fixture fixture;
    fixture.name = arranged_parts[d.part].name;
    fixture.mesh = arranged_parts[d.part].mesh;
    fixture.mesh.Transform(d.world_from_model);
    fixture.color = picks[k].color;
    fixture.material = Scene::DefaultMaterial(fixture.color);
    fixture.object = true;  // sampled as the parts are (render.background_samples)
    placement->scene.fixtures.push_back(std::move(fixture));
    const Eigen::Quaterniond q(d.world_from_model.linear());
    const Eigen::Vector3d t = d.world_from_model.translation();
    placement->distractor_record.push_back({"distractor." + std::to_string(k) + ".pose",
                                            {t.x(), t.y(), t.z(), q.w(), q.x(), q.y(), q.z()},
                                            ""});
  }
}

// Where the distractors came to rest (a pile reports its own drop), and those that did not.
void ReportDistractors(const SceneSpec& scene_spec, const Arrangement& arranged, bool pile,
                       SceneLog* log) {
  if (!arranged.distractors.empty() && !pile) {
    std::ostringstream m;
    m << "scene '" << scene_spec.name << "': " << Count(arranged.distractors.size(), "distractor")
      << " dropped among the parts in " << arranged.distractor_seconds << " s (simulated)";
    log->Say(false, m.str());
  }
  if (!arranged.escaped_distractors.empty()) {
    log->Say(true, "scene '" + scene_spec.name +
                       "': " + Count(arranged.escaped_distractors.size(), "distractor") +
                       " ended outside the container (kept where they lie: distractors are "
                       "drawn, never labelled)");
  }
  if (!arranged.restless_distractors.empty()) {
    log->Say(true, "scene '" + scene_spec.name +
                       "': " + Count(arranged.restless_distractors.size(), "distractor") +
                       " still moving after settle_time (" +
                       std::to_string(scene_spec.arrangement.settle_time_s) +
                       " s, simulated): they are kept where they were");
  }
}

// A pile's pick sequence (ArrangementOptions::sequence): each pick from the pile as the last one
// left it, one after the other, with the instance ids of what is left.
void RunPickSequence(const SceneSpec& scene_spec, const std::vector<Part>& parts,
                     const ArrangementOptions& arrangement,
                     const std::vector<CollisionShape>& shapes, bool strict, SceneLog* log,
                     Placement* placement) {
  const PickSequence& sequence = arrangement.sequence;
  if (sequence.picks <= 0) return;
  const Arrangement* pile = &placement->arranged;
  if (static_cast<size_t>(sequence.picks) >= pile->instances.size()) {
    throw Error("sequence.picks is " + std::to_string(sequence.picks) + " but the pile has " +
                std::to_string(pile->instances.size()) + " parts: at most " +
                std::to_string(pile->instances.size() - 1) + " picks");
  }
  std::vector<int> ids(pile->instances.size());
  for (size_t i = 0; i < ids.size(); ++i) ids[i] = static_cast<int>(i);
  placement->picks.reserve(static_cast<size_t>(sequence.picks));
  for (int k = 1; k <= sequence.picks; ++k) {
    const int picked = ChoosePick(parts, *pile, sequence.rule, arrangement.seed, k);
    placement->picks.push_back(PickFromPile(parts, *pile, arrangement, picked, shapes));
    const PickStep& step = placement->picks.back();
    std::ostringstream m;
    m << "scene '" << scene_spec.name << "': pick " << k << " took instance " << ids[picked] << "; "
      << Count(static_cast<size_t>(std::count(step.freed.begin(), step.freed.end(), true)), "part")
      << " free to settle again (" << step.arranged.settle_seconds << " s, simulated)";
    log->Say(false, m.str());
    if (!step.arranged.restless.empty()) {
      log->Broken(strict, scene_spec.name,
                  "after pick " + std::to_string(k) + ", " +
                      Count(step.arranged.restless.size(), "part") +
                      " still moving after settle_time");
    }
    ids.erase(ids.begin() + picked);
    placement->pick_ids.push_back(ids);
    pile = &step.arranged;
  }
}

// A pile's progress (ArrangementOptions::pile_progress) as the stage's reports, at most one every
// progress_interval_s of wall time (2 s: a pile of 60 bolts takes 1-5 s). `arrangement` (its
// copies, and the distractors added after this) outlives every call.
std::function<void(double, int, int)> PileProgress(const Context& context,
                                                   const SceneSpec& scene_spec,
                                                   const std::vector<Instance>& instances,
                                                   const ArrangementOptions* arrangement) {
  return [&context, &scene_spec, &instances, arrangement, last = std::chrono::steady_clock::now()](
             double seconds, int moving, int outside) mutable {
    const auto now = std::chrono::steady_clock::now();
    if (std::chrono::duration<double>(now - last).count() < context.progress_interval_s) return;
    last = now;
    const size_t bodies = instances.size() * static_cast<size_t>(arrangement->copies) +
                          arrangement->distractors.size();
    std::string detail =
        std::to_string(moving) + " of " + std::to_string(bodies) + " bodies moving";
    if (outside > 0) detail += ", " + std::to_string(outside) + " beside the container";
    context.progress(
        {"pile", scene_spec.name, seconds, scene_spec.arrangement.settle_time_s, detail});
  };
}

// A pile dropped and settled into placement->arranged, what left the container sorted out, its
// pick sequence run; or all of it, with its messages, read from the part cache where an earlier
// process (a shard, a worker) simulated it (and stored there when not).
void SettlePile(const Context& context, const SceneSpec& scene_spec, const std::vector<Part>& parts,
                const std::vector<Instance>& instances, const std::vector<int>& groups,
                const ArrangementOptions& arrangement, const std::vector<CollisionShape>& shapes,
                SceneLog* log, Placement* placement) {
  std::optional<CacheKey> key;
  if (context.cache) {
    key = PileKey(*context.cache, scene_spec, parts, instances, groups, arrangement,
                  context.spec.collision, context.strict);
    if (const std::optional<std::string> bytes = context.cache->Load("pile", *key)) {
      try {
        std::vector<std::pair<bool, std::string>> messages;
        DecodePile(*bytes, placement, &messages);
        for (auto& [warning, text] : messages) log->Say(warning, std::move(text));
        return;
      } catch (const Error&) {  // damaged: simulated again below
        placement->picks.clear();
        placement->pick_ids.clear();
      }
    }
  }
  log->Flush();
  const size_t first_message = placement->messages.size();
  Arrangement& arranged = placement->arranged;
  arranged = Arrange(parts, instances, arrangement, groups, &shapes);
  SortOutEscaped(scene_spec, parts, arrangement, shapes, context.strict, log, &arranged);
  ReportPile(scene_spec, parts, arranged, context.strict, log);
  RunPickSequence(scene_spec, parts, arrangement, shapes, context.strict, log, placement);
  log->Flush();
  if (key) {
    const std::vector<std::pair<bool, std::string>> messages(
        placement->messages.begin() + static_cast<std::ptrdiff_t>(first_message),
        placement->messages.end());
    context.cache->Store("pile", *key, EncodePile(*placement, messages));
  }
}

// Scene `s` arranged into `placement`: its parts dropped, piled or laid out, and its
// distractors among them. Throws what fails.
void ArrangeScene(const Context& context, const PrepareState& state, size_t s,
                  const std::vector<Instance>& instances, const std::vector<int>& groups,
                  SceneLog* log, Placement* placement) {
  const RunSpec& spec = context.spec;
  const SceneSpec& scene_spec = spec.scenes[s];
  const std::vector<Part>& parts = state.all.parts;
  const bool pile = scene_spec.arrangement.layout == Layout::kPile;
  const bool dropped = !pile && scene_spec.arrangement.pose == PoseMode::kDropped;
  std::vector<CollisionShape> shapes;
  if (pile || dropped) shapes = FallingShapes(state.pile_shapes, s, instances);
  ArrangementOptions arrangement = scene_spec.arrangement;
  if (scene_spec.container_file) arrangement.container.mesh = state.container_mesh[s];
  if (pile && context.progress)
    arrangement.pile_progress = PileProgress(context, scene_spec, instances, &arrangement);
  // Distractors: drawn for the scene, made (primitives) or taken (file and family parts),
  // given collision shapes, and dropped with (a pile) or onto (other layouts) the parts.
  const RandomizeSpec& randomize_spec =
      scene_spec.randomize ? *scene_spec.randomize : spec.randomize;
  const std::vector<DistractorCandidate>& candidates = state.distractor_candidates[s];
  const std::vector<DistractorPick> picks =
      DrawSceneDistractors(randomize_spec.draws, s, candidates, &placement->distractor_record);
  std::vector<Part> with_distractors;
  if (!picks.empty()) {
    with_distractors =
        AddDistractors(context, parts, candidates, picks, instances, &arrangement, &shapes);
    arrangement.distractor_seed = DistractorDropSeed(randomize_spec.draws, s);
  }
  const std::vector<Part>& arranged_parts = picks.empty() ? parts : with_distractors;
  if (!scene_spec.physics_rules.empty()) {
    AssignPhysics(scene_spec, state, instances, groups, arranged_parts.size(), &arrangement);
  }
  Arrangement& arranged = placement->arranged;
  placement->dropped = instances.size() * static_cast<size_t>(std::max(1, arrangement.copies));
  placement->distractors = picks.size();
  if (dropped) {
    arranged = Arrange(arranged_parts, instances, arrangement, groups, &shapes);
    if (!arranged.restless.empty()) {
      std::ostringstream m;
      m << Count(arranged.restless.size(), "dropped part") << " still moving after settle_time ("
        << scene_spec.arrangement.settle_time_s
        << " s, simulated): raise settle_time; each is put on the stable face nearest its "
           "last pose (or left as it was, tilted more than 5 degrees from any)";
      log->Broken(context.strict, scene_spec.name, m.str());
    }
  } else if (pile) {
    SettlePile(context, scene_spec, arranged_parts, instances, groups, arrangement, shapes, log,
               placement);
    AddTote(scene_spec, arrangement.container, &placement->scene);
  } else {
    arranged =
        Arrange(arranged_parts, instances, arrangement, groups, picks.empty() ? nullptr : &shapes);
  }
  AddDistractorFixtures(arranged_parts, picks, placement);
  ReportDistractors(scene_spec, arranged, pile, log);
}

// Scene `s` placed on this thread: its errors and messages kept in `placement` for later.
void PlaceScene(const Context& context, const PrepareState& state, size_t s, Placement* placement) {
  std::vector<Instance> instances;
  std::vector<int> groups;
  for (size_t i = 0; i < state.all.instances.size(); ++i) {
    if (state.jobs[state.job_of_instance[i]].scene != static_cast<int>(s)) continue;
    instances.push_back(state.all.instances[i]);
    groups.push_back(state.job_of_instance[i]);
  }
  placement->scene = context.spec.look;
  SceneLog log(&placement->messages);
  try {
    ArrangeScene(context, state, s, instances, groups, &log, placement);
  } catch (const Error& e) {
    placement->error = "scene '" + context.spec.scenes[s].name + "': " + e.what();
  } catch (...) {
    placement->exception = std::current_exception();
  }
  log.Flush();
}

// The pbr mode's materials: the first rule matching the part's name, family and file.
void AssignMaterials(const RunSpec& spec, const PrepareState& state, const std::vector<int>& group,
                     Scene* scene, std::vector<bool>* used_rules) {
  const std::vector<Part>& parts = state.all.parts;
  scene->materials.clear();
  scene->instance_material.assign(scene->instances.size(), -1);
  for (const MaterialRule& rule : spec.material_rules) scene->materials.push_back(rule.material);
  if (spec.default_material) scene->materials.push_back(*spec.default_material);
  for (size_t i = 0; i < scene->instances.size(); ++i) {
    const PartSource& source = *state.jobs[group[i]].source;
    const std::string& name = parts[scene->instances[i].part].name;
    for (size_t r = 0; r < spec.material_rules.size(); ++r) {
      const MaterialRule& rule = spec.material_rules[r];
      if (RuleMatches(rule, name, source)) {
        scene->instance_material[i] = static_cast<int>(r);
        (*used_rules)[r] = true;
        break;
      }
    }
    if (scene->instance_material[i] < 0 && spec.default_material)
      scene->instance_material[i] = static_cast<int>(spec.material_rules.size());
    const int m = scene->instance_material[i];
    if (m >= 0 && scene->materials[m].texture.projection == Texture::Projection::kUv &&
        !parts[scene->instances[i].part].mesh.has_uvs()) {
      const size_t r = static_cast<size_t>(m);
      const std::string at =
          r < spec.material_rules.size()
              ? (spec.material_rules[r].where.empty() ? "" : spec.material_rules[r].where + ": ") +
                    "materials.assign[" + std::to_string(r) + "]"
              : "materials.default";
      throw Error(at + ": texture projection 'uv', but part '" + name +
                  "' has no texture coordinates (only meshes such as OBJ or glTF files carry "
                  "them): use 'auto' or 'triplanar'");
    }
  }
}

// Domain randomisation: the scene's own (or the recipe's), each instance's first matching
// part rule. The recipe's rules a scene uses are marked in `used_recipe_rules`.
Randomization ResolveRandomization(const RunSpec& spec, const SceneSpec& scene_spec,
                                   const PrepareState& state, Placement* placement,
                                   std::vector<bool>* used_recipe_rules) {
  const std::vector<Instance>& instances = placement->scene.instances;
  const RandomizeSpec& randomize = scene_spec.randomize ? *scene_spec.randomize : spec.randomize;
  Randomization randomization = randomize.draws;
  {
    std::string why;
    if (!randomization.Check(&why))
      throw Error("scene '" + scene_spec.name + "': randomize: " + why);
  }
  randomization.first_distractor = placement->first_distractor;
  randomization.scene_record = std::move(placement->distractor_record);
  randomization.instance_rule.assign(instances.size(), -1);
  randomization.instance_part.clear();
  for (size_t i = 0; i < instances.size(); ++i) {
    const PartSource& source = *state.jobs[placement->arranged.group[i]].source;
    const int part = instances[i].part;
    randomization.instance_part.push_back(part);
    for (size_t r = 0; r < randomize.part_rules.size(); ++r) {
      if (RuleMatches(randomize.part_rules[r], state.all.parts[part].name, source)) {
        randomization.instance_rule[i] = static_cast<int>(r);
        break;
      }
    }
  }
  // Rules matching no part: a scene's own are reported for it; the recipe's once, below.
  for (size_t r = 0; r < randomize.part_rules.size(); ++r) {
    const std::vector<int>& rules = randomization.instance_rule;
    const bool used = std::find(rules.begin(), rules.end(), static_cast<int>(r)) != rules.end();
    if (!scene_spec.randomize) {
      (*used_recipe_rules)[r] = (*used_recipe_rules)[r] || used;
    } else if (!used) {
      const std::string& where = randomize.part_rules[r].where;
      Warn((where.empty() ? "" : where + ": ") + "scene '" + scene_spec.name +
           "': randomize.parts[" + std::to_string(r) + "] matches no part");
    }
  }
  return randomization;
}

// "the parts are 'a', 'b' (family gear) and 'c' (file c.step)": what a rule could have matched.
std::string PartNames(const PrepareState& state) {
  constexpr size_t kNamed = 12;
  std::vector<std::string> names;
  std::set<int> seen;
  for (size_t i = 0; i < state.all.instances.size() && names.size() < kNamed; ++i) {
    const int p = state.all.instances[i].part;
    if (!seen.insert(p).second) continue;
    const PartSource& source = *state.jobs[state.job_of_instance[i]].source;
    names.push_back("'" + state.all.parts[p].name + "' (" +
                    (source.kind == PartSource::Kind::kFile
                         ? "file " + source.path.filename().string()
                         : "family " + source.family) +
                    ")");
  }
  std::string text = "the parts are " + JoinNames(names);
  if (state.all.parts.size() > kNamed)
    text += " and " + std::to_string(state.all.parts.size() - kNamed) + " more";
  return text;
}

// The recipe's material rules and (when a scene uses them) part rules that matched no part.
void WarnUnusedRules(const RunSpec& spec, const PrepareState& state,
                     const std::vector<bool>& used_rules, bool recipe_randomize_used,
                     const std::vector<bool>& used_randomize_rules) {
  for (size_t r = 0; r < used_rules.size(); ++r) {
    if (used_rules[r]) continue;
    const MaterialRule& rule = spec.material_rules[r];
    std::vector<std::string> patterns;
    if (!rule.name.empty()) patterns.push_back("name '" + rule.name + "'");
    if (!rule.family.empty()) patterns.push_back("family '" + rule.family + "'");
    if (!rule.file.empty()) patterns.push_back("file '" + rule.file + "'");
    Warn((rule.where.empty() ? "" : rule.where + ": ") + "materials.assign[" + std::to_string(r) +
         "] (" + JoinNames(patterns) + ") matches no part, so no part takes its material; " +
         PartNames(state) + " (patterns are shell globs, case-insensitive)");
  }
  for (size_t r = 0; recipe_randomize_used && r < used_randomize_rules.size(); ++r) {
    if (!used_randomize_rules[r]) {
      const std::string& where = spec.randomize.part_rules[r].where;
      Warn((where.empty() ? "" : where + ": ") + "randomize.parts[" + std::to_string(r) +
           "] matches no part");
    }
  }
}

// Step k of a pile's pick sequence (0: the pile as it fell) as scene_sequence.json records it;
// `first` is the prepared scene index of step 0.
SequenceStep StepRecord(const SceneSpec& scene_spec, const Placement& placement, int first, int k) {
  SequenceStep step;
  step.first_scene = first;
  step.step = k;
  step.picks = static_cast<int>(placement.picks.size());
  step.rule = scene_spec.arrangement.sequence.rule == PickRule::kRandom ? "random" : "highest";
  if (k == 0) {
    const Arrangement& pile = placement.arranged;
    for (size_t i = 0; i < pile.instances.size(); ++i)
      step.instance_ids.push_back(static_cast<int>(i));
    step.freed.assign(pile.instances.size(), false);
    step.moved_mm.assign(pile.instances.size(), 0.0);
    step.settle_seconds = pile.settle_seconds;
    return step;
  }
  const PickStep& pick = placement.picks[k - 1];
  const Arrangement& was = k == 1 ? placement.arranged : placement.picks[k - 2].arranged;
  step.instance_ids = placement.pick_ids[k - 1];
  step.picked_id = k == 1 ? pick.picked : placement.pick_ids[k - 2][pick.picked];
  step.picked_obj_id = was.instances[pick.picked].part + 1;
  step.picked_world_from_model = was.instances[pick.picked].world_from_model;
  step.freed = pick.freed;
  step.moved_mm = pick.moved_mm;
  step.settle_seconds = pick.arranged.settle_seconds;
  for (int i : pick.arranged.restless) step.restless.push_back(step.instance_ids[i]);
  return step;
}

}  // namespace

PileShapes MakePileShapes(const Context& context, const PrepareState& state) {
  const RunSpec& spec = context.spec;
  const std::vector<Part>& parts = state.all.parts;
  PileShapes pile;
  pile.shapes.resize(parts.size());
  pile.failures.resize(parts.size());
  pile.warnings.resize(parts.size());
  pile.first_dropping.assign(parts.size(), -1);
  for (size_t i = 0; i < state.all.instances.size(); ++i) {
    const int s = state.jobs[state.job_of_instance[i]].scene;
    const ArrangementOptions& a = spec.scenes[s].arrangement;
    if (a.layout != Layout::kPile && a.pose != PoseMode::kDropped) continue;
    int& first = pile.first_dropping[state.all.instances[i].part];
    if (first < 0 || s < first) first = s;
  }
  // Progress as each part's shape is made (a concave part's decomposition takes up to seconds).
  const auto needed =
      static_cast<size_t>(std::count_if(pile.first_dropping.begin(), pile.first_dropping.end(),
                                        [](int first) { return first >= 0; }));
  std::atomic<size_t> made{0};
  tbb::parallel_for(size_t{0}, parts.size(), [&](size_t p) {
    if (pile.first_dropping[p] < 0) return;
    WarningCapture capture;
    const auto start = std::chrono::steady_clock::now();
    try {
      pile.shapes[p] = PartCollisionShape(parts[p], context.spec.collision, context.cache);
    } catch (...) {
      pile.failures[p] = std::current_exception();
    }
    pile.warnings[p] = capture.Take();
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const size_t done = ++made;
    if (context.progress && seconds >= context.progress_interval_s) {
      std::ostringstream detail;
      const CollisionShape& shape = pile.shapes[p];
      detail << "'" << parts[p].name << "': ";
      if (pile.failures[p]) {
        detail << "no collision shape";  // (the error comes with the scenes that drop it)
      } else if (shape.decomposed) {
        detail << Count(shape.pieces.size(), "convex piece");
      } else {
        detail << (shape.timed_out ? "its hull (out of time)" : "its hull");
      }
      if (shape.volume_ratio > 0)
        detail << ", " << std::setprecision(3) << shape.volume_ratio << "x its volume";
      detail << " in " << std::round(seconds * 10) / 10 << " s";
      context.progress({"collision_shapes", "", static_cast<double>(done),
                        static_cast<double>(needed), detail.str()});
    }
  });
  return pile;
}

// Each scene's placement, every scene at once: a pile or a drop simulates one Bullet world on
// one thread, so two piles take the time of one on two cores. Messages (the scene's own and the
// warnings of what it calls, captured), errors and other exceptions follow in scene order
// (RecordScenes).
std::vector<Placement> ArrangeScenes(const Context& context, const PrepareState& state) {
  std::vector<Placement> placements(context.spec.scenes.size());
  tbb::parallel_for(size_t{0}, context.spec.scenes.size(),
                    [&](size_t s) { PlaceScene(context, state, s, &placements[s]); });
  return placements;
}

// How scene_spec's pile or dropped parts came to rest (scene_physics.json); none for the other
// layouts.
std::optional<SceneRest> RestRecord(const SceneSpec& scene_spec, const Placement& placement,
                                    const PileShapes& pile_shapes) {
  const ArrangementOptions& a = scene_spec.arrangement;
  const bool pile = a.layout == Layout::kPile;
  if (!pile && a.pose != PoseMode::kDropped) return std::nullopt;
  const Arrangement& arranged = placement.arranged;
  SceneRest rest;
  rest.kind = pile ? "pile" : "dropped";
  rest.dropped = static_cast<int>(placement.dropped);
  rest.removed_outside = static_cast<int>(placement.dropped - arranged.instances.size());
  rest.outside = arranged.escaped;
  rest.settle_seconds = arranged.settle_seconds;
  rest.settle_time = a.settle_time_s;
  rest.restless = arranged.restless;
  rest.distractors = static_cast<int>(placement.distractors);
  rest.restless_distractors = static_cast<int>(arranged.restless_distractors.size());
  std::vector<int> used;
  for (const Instance& instance : arranged.instances) used.push_back(instance.part);
  std::sort(used.begin(), used.end());
  used.erase(std::unique(used.begin(), used.end()), used.end());
  for (int p : used) {
    const CollisionShape& shape = pile_shapes.shapes[static_cast<size_t>(p)];
    if (shape.pieces.empty()) continue;
    rest.shapes.push_back({p + 1, static_cast<int>(shape.pieces.size()), shape.decomposed,
                           shape.volume_ratio, shape.timed_out});
  }
  return rest;
}

PreparedRun RecordScenes(const Context& context, const PrepareState& state,
                         std::vector<Placement>* placements) {
  const RunSpec& spec = context.spec;
  const std::vector<Part>& parts = state.all.parts;
  PreparedRun prepared;
  std::vector<bool> used_rules(spec.material_rules.size(), false);
  std::vector<bool> used_randomize_rules(spec.randomize.part_rules.size(), false);
  bool recipe_randomize_used = false;
  // One placement as a scene of the run.
  const auto record = [&](const SceneSpec& scene_spec, Placement& placement) {
    Scene& scene = placement.scene;
    scene.instances = placement.arranged.instances;
    AssignMaterials(spec, state, placement.arranged.group, &scene, &used_rules);
    Randomization randomization =
        ResolveRandomization(spec, scene_spec, state, &placement, &used_randomize_rules);
    recipe_randomize_used = recipe_randomize_used || !scene_spec.randomize;
    scene.part_colors.clear();
    for (size_t i = 0; i < parts.size(); ++i) {
      const Eigen::Vector3f palette = PaletteColor(static_cast<int>(i));
      scene.part_colors.push_back(spec.cad_colors ? parts[i].color.value_or(palette) : palette);
    }
    if (!spec.cad_colors) {
      for (Instance& instance : scene.instances) instance.color.reset();
    }
    std::vector<int> obj_ids;
    for (const Instance& instance : scene.instances) obj_ids.push_back(instance.part + 1);
    prepared.scenes.push_back(std::move(scene));
    prepared.obj_ids.push_back(std::move(obj_ids));
    prepared.randomization.push_back(std::move(randomization));
  };
  for (size_t s = 0; s < spec.scenes.size(); ++s) {
    Placement& placement = (*placements)[s];
    for (const auto& [warning, text] : placement.messages)
      warning ? Warn(text) : context.info(text);
    if (!placement.error.empty()) throw Error(placement.error);
    if (placement.exception) std::rethrow_exception(placement.exception);
    const SceneSpec& scene_spec = spec.scenes[s];
    // A pick sequence's steps: the scene as placed (the look, the tote, the distractors) with
    // each step's instances.
    std::vector<Placement> steps(placement.picks.size());
    for (size_t k = 0; k < steps.size(); ++k) {
      steps[k].scene = placement.scene;
      steps[k].arranged = placement.picks[k].arranged;
      steps[k].distractor_record = placement.distractor_record;
      steps[k].first_distractor = placement.first_distractor;
    }
    const int first = static_cast<int>(prepared.scenes.size());
    record(scene_spec, placement);
    prepared.rest.push_back(RestRecord(scene_spec, placement, state.pile_shapes));
    prepared.scene_names.push_back(scene_spec.name);
    prepared.sequence.push_back(
        steps.empty() ? std::nullopt
                      : std::optional<SequenceStep>(StepRecord(scene_spec, placement, first, 0)));
    for (size_t k = 0; k < steps.size(); ++k) {
      record(scene_spec, steps[k]);
      prepared.rest.push_back(std::nullopt);
      char suffix[32];
      std::snprintf(suffix, sizeof(suffix), "_pick_%02zu", k + 1);
      prepared.scene_names.push_back(scene_spec.name + suffix);
      prepared.sequence.push_back(
          StepRecord(scene_spec, placement, first, static_cast<int>(k) + 1));
    }
  }
  WarnUnusedRules(spec, state, used_rules, recipe_randomize_used, used_randomize_rules);
  return prepared;
}

std::string VariantsRecord(const RunSpec& spec, const PrepareState& state) {
  Json variants = Json::array();
  for (size_t j = 0; j < state.jobs.size(); ++j) {
    std::set<int> obj_ids, class_ids;
    for (size_t i = 0; i < state.all.instances.size(); ++i) {
      if (state.job_of_instance[i] != static_cast<int>(j)) continue;
      obj_ids.insert(state.all.instances[i].part + 1);
      class_ids.insert(state.classes[state.all.instances[i].part].id);
    }
    const Job& job = state.jobs[j];
    const PartSource& source = *job.source;
    Json entry = {{"id", job.id}, {"scene_id", job.scene}, {"scene", spec.scenes[job.scene].name}};
    if (source.kind == PartSource::Kind::kFile) {
      entry["file"] = source.path.string();
    } else {
      entry["family"] = source.family;
      entry["params"] = ParamsJson(source.variants[job.variant]);
    }
    entry["obj_ids"] = obj_ids;
    entry["class_ids"] = class_ids;
    variants.push_back(entry);
  }
  return Json{{"variants", variants}}.dump(2) + "\n";
}

}  // namespace cadsynth::prepare_stages
