// Placing parts as they would rest in a work cell: on the floor z = 0, centred on the origin.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "cad/core/schema.h"
#include "cad/part.h"
#include "variants/physics/pile.h"

namespace cadsynth {

// Instances come in rigid groups (a file's assembly, one variant of a family): a layout moves
// whole groups and never takes one apart.
enum class Layout {
  kAssembled,  // all groups as designed, in their own frames, resting together as one rigid body
  kSingle,     // one group at the origin
  kRow,        // each group resting on its own, side by side along +x
  kGrid,       // each group resting on its own, in rows of about sqrt(N)
  kClutter,    // each group dropped at a random yaw and position in a disc, none overlapping
  kPile,       // every copy dropped at a random orientation into a tote or onto the floor, and
               // simulated until it rests (variants/physics/pile.h): touching, stacked
};

// Which way up a group rests (see StablePoses).
enum class PoseMode {
  kStable,      // on its most probable face
  kRandom,      // on a face drawn by probability, at a random yaw
  kAll,         // one copy on every distinct stable pose (faces a symmetry relates are one)
  kAsDesigned,  // as the CAD has it, lowered onto the floor
  kUpright,     // on the stable face nearest the design's down (-z): the way it was drawn standing
  kAuto,        // upright for an assembled layout, stable for the others
  kDropped,     // dropped alone onto the floor at a random orientation and simulated until it
                // rests (variants/physics/pile.h): the face physics picks, at the yaw it lands
};

// A part's physics material for a pile or a drop, each value drawn per scene uniformly from
// [low, high] (stream pile.physics; equal bounds: that value, no draw).
struct PhysicsDraw {
  PhysicsMaterial low, high;

  PhysicsDraw() = default;
  PhysicsDraw(const PhysicsMaterial& m) : low(m), high(m) {}  // NOLINT: a fixed material is one
  bool Check(std::string* why) const;
  // The values for `seed` and `part` (the part's index in the scene).
  PhysicsMaterial Draw(uint64_t seed, uint64_t part) const;
};

// A pick sequence (issue 45): after a pile rests, parts are taken out one at a time, the pile
// settling again after each (SettleAfterPick), by a rule: the part whose highest point is highest
// (what a bin picker sees first and reaches most easily), or one drawn at random (stream
// sequence.pick, from the pile's seed).
enum class PickRule { kHighest, kRandom };

// What becomes of a pile's parts that end outside its container (on the floor beside a tote):
// taken out of the scene (not drawn, not labelled), kept where they lie (drawn and labelled as
// instances of the scene), or dropped again onto the pile, up to three times, the rest then taken
// out. Remove is the default: a part on the floor is no part of the bin, and a dataset should not
// teach that it is.
enum class OutOfContainer { kRemove, kKeep, kRedrop };

struct PickSequence {
  int picks = 0;  // 0: no sequence
  PickRule rule = PickRule::kHighest;

  bool Check(std::string* why) const;
  // A scene's `sequence` keys (cad/core/schema.h).
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.picks, Field{"picks", "integer",
                         "parts taken out one at a time after the pile rests, the pile settling "
                         "again after each (fewer than the pile's parts)"});
    visit(o.rule, Field{"pick",
                        "choice",
                        "which part each pick takes: the one reaching highest, or one at random",
                        {"highest", "random"}});
  }
};

struct ArrangementOptions {
  Layout layout = Layout::kAssembled;
  PoseMode pose = PoseMode::kAuto;
  double gap_mm = 40.0;              // row, grid, clutter: least free space between groups
  int copies = 1;                    // each group placed this many times (not with kAssembled)
  double clutter_radius_mm = 150.0;  // clutter: the disc the groups land in
  uint64_t seed = 0;                 // random poses, yaws and clutter positions
  // Pile (and pose: dropped, which falls onto the floor): what the parts fall into, how they
  // behave (one material for all parts), from how high, and the simulation's limits. The drop
  // region is the container's inner size (or the clutter disc's square on the floor).
  Container container;
  PhysicsDraw physics;
  std::vector<PhysicsDraw> part_physics;  // per part where parts differ; empty: `physics` for all
  double drop_height_mm = 30.0;
  double settle_time_s = 10.0;  // simulated; parts still moving then are reported
  double time_step_s = PileOptions{}.time_step_s;
  bool confirm_rest = true;  // PileOptions::confirm_seconds: true 1 s, false 0 (none)
  // Distractors (domain randomisation): parts that are dropped among the arranged ones but are
  // not instances of the arrangement (indices into `parts`, each falling alone). A pile drops
  // them with its copies, each at a place in the drop order drawn from `distractor_seed` (stream
  // arrange.distractor_order); the other layouts arrange first and then drop them from
  // `distractor_seed` onto the floor over the arranged parts, which stay where they are (static
  // bodies). Their physics is `physics` (or part_physics) like the parts'.
  std::vector<int> distractors;
  uint64_t distractor_seed = 0;
  PickSequence sequence;  // a pile's pick sequence (its own recipe section, `sequence`)
  OutOfContainer out_of_container = OutOfContainer::kRemove;  // a pile's
  // A pile's (and a drop's) progress: PileOptions::progress. Not a recipe key; changes nothing.
  std::function<void(double seconds, int moving, int outside)> pile_progress;

  bool Check(std::string* why) const;

  // The recipe keys of a scene (the root `scene:` section or an entry of `scenes:`);
  // cad/core/schema.h.
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.layout, Field{"layout",
                          "choice",
                          "how the part groups lie: together as designed, one group alone, side "
                          "by side, on a grid, or dropped apart in a disc",
                          {"assembled", "single", "row", "grid", "clutter", "pile"}});
    visit(o.pose, Field{"pose",
                        "choice",
                        "which way up a group rests: most probable stable face, a face drawn by "
                        "probability at a random yaw, one copy on every face, as designed, on the "
                        "stable face nearest the design's down, auto (upright when assembled, "
                        "else stable), or dropped (simulated fall onto the floor)",
                        {"stable", "random", "all", "as_designed", "upright", "auto", "dropped"}});
    visit(o.gap_mm, Field{"gap", "length", "least free space between groups (row, grid, clutter)"});
    visit(o.copies,
          Field{"copies", "integer", "each group placed this many times (not with assembled)"});
    visit(o.clutter_radius_mm, Field{"radius", "length", "clutter: the disc the groups land in"});
    visit(o.seed, RunSeed("seed", "random poses, yaws, clutter positions and piles"));
    visit(o.drop_height_mm, Field{"drop_height", "length",
                                  "pile: the lowest part's start above the container's rim"});
    visit(o.settle_time_s, Field{"settle_time", "number",
                                 "pile: simulated seconds before parts still moving are "
                                 "reported"});
    visit(o.time_step_s, Field{"time_step", "number", "pile: the physics step in seconds"});
    visit(o.confirm_rest,
          Field{"confirm_rest", "bool",
                "pile: a rest counts once a new world started from it moves no "
                "part by more than 0.4 mm in a second (false: the rest test alone)"});
    visit(o.out_of_container,
          Field{"out_of_container",
                "choice",
                "pile: parts that end outside the container are taken out of the scene, kept "
                "(drawn and labelled where they lie), or dropped again onto the pile (up to three "
                "times, then taken out)",
                {"remove", "keep", "redrop"}});
  }
};

struct Arrangement {
  std::vector<Instance> instances;  // world poses: resting on z = 0, centred on the z axis
  std::vector<int> group;           // the input group of each instance (copies share it)
  // Pile: instances still moving when settle_time ran out, or outside the tote; the simulated
  // time it took (pose: dropped: instances of bodies still moving, the longest fall).
  std::vector<int> restless, escaped;
  double settle_seconds = 0;
  // Where ArrangementOptions::distractors came to rest (their `part` as given), which of them
  // were still moving when settle_time ran out, and (a pile) which ended outside the tote.
  std::vector<Instance> distractors;
  std::vector<int> restless_distractors, escaped_distractors;
  double distractor_seconds = 0;  // the simulated time of their drop (a pile's: settle_seconds)
};

// One pick of a sequence: which instance of the pile was taken (its index there), and the pile
// after it settled again (the other instances in their order, distractors where they were).
struct PickStep {
  int picked = -1;
  Arrangement arranged;
  std::vector<bool> freed;       // per instance left: free to move after the pick (the others held)
  std::vector<double> moved_mm;  // per instance left: the largest move of a point of it
};

// The instance of `pile` the rule takes at step `step` (1 for the first pick); `seed` the pile's.
int ChoosePick(const std::vector<Part>& parts, const Arrangement& pile, PickRule rule,
               uint64_t seed, int step);

// `pile` (arranged from `options`, a pile) with instance `picked` taken out and settled again
// (SettleAfterPick; its distractors held where they are). `parts` and `shapes` as Arrange's (with
// the distractors' parts).
PickStep PickFromPile(const std::vector<Part>& parts, const Arrangement& pile,
                      const ArrangementOptions& options, int picked,
                      const std::vector<CollisionShape>& shapes);

// A pile's parts that ended outside its container (pile->escaped) dropped again from above onto
// the pile as it lies, its other parts and distractors held where they are (static bodies, as a
// pick's untouched parts), up to `rounds` times, each round's seed drawn from stream
// arrange.redrop_seed; those still outside stay in pile->escaped, those still moving join
// pile->restless. `parts` and `shapes` as Arrange's.
void RedropEscaped(const std::vector<Part>& parts, const ArrangementOptions& options,
                   const std::vector<CollisionShape>& shapes, Arrangement* pile, int rounds = 3);

// The instances in pile->escaped taken out of the pile (restless renumbered, escaped emptied).
// Returns the instances taken out, in order.
std::vector<Instance> RemoveEscaped(Arrangement* pile);

// Arranges `instances` (`group[i]` is the group of instance i; empty: one group per instance).
// Throws Error when a clutter does not fit, saying how many groups did. A pile drops single parts
// (a group of several instances is an error); pose: dropped drops each group alone as one rigid
// body. Both need each part's collision shape: `shapes` (per part), or computed here when null.
Arrangement Arrange(const std::vector<Part>& parts, const std::vector<Instance>& instances,
                    const ArrangementOptions& options, const std::vector<int>& group = {},
                    const std::vector<CollisionShape>* shapes = nullptr);

}  // namespace cadsynth
