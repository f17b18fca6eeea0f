// Physically dropped piles of parts (issue 16): copies of parts fall at random orientations into a
// tote or onto the floor and come to rest, simulated by Bullet (rigid bodies, Debian's
// libbullet-dev, double precision). One world per pile, built from scratch from the seed, bodies
// added in a fixed order, one fixed time step, stepped on one thread: the same options give the
// same poses bit for bit for any thread count, on any machine and in any shard.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "cad/core/schema.h"
#include "cad/mesh.h"
#include "cad/part.h"
#include "variants/physics/collision.h"

namespace cadsynth {

// How a part's material behaves in contact. Friction is Coulomb's coefficient (Bullet combines
// two bodies' by multiplying them), restitution the fraction of the normal speed kept in a bounce.
struct PhysicsMaterial {
  double density_kg_m3 = 7850.0;  // steel; aluminium 2700, ABS 1050, nylon 1150, brass 8500
  double friction = 0.7;
  double restitution = 0.1;

  bool Check(std::string* why) const;

  // A pile's `physics` (where each may also be a range [low, high], read by hand) and a
  // container's keys.
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.density_kg_m3, Field{"density", "number", "kg/m3"});
    visit(o.friction, Field{"friction", "number", "Coulomb's mu"});
    visit(o.restitution, Field{"restitution", "number", "bounciness (0-1)"});
  }
};

// What the parts fall into. A tote stands on the floor centred on the origin: its inner floor is
// at z = floor_mm, its rim at floor_mm + height_mm; inner corners are rounded with
// corner_radius_mm (as a polygon of 8 segments per corner, the same for the collision and the
// images), outer corners with corner_radius_mm + wall_mm. Its walls and floor collide as if at
// least 10 mm thick (the extra outside, where nothing is drawn) so that nothing tunnels through
// thin ones. A mesh container (a bin, a tray, a
// fixture from a CAD or mesh file) is its triangles in the world frame, exactly as they are for
// the collision (Bullet's static triangle mesh: no convexity needed, no thickness either, so thin
// walls rely on the parts' continuous collision detection).
struct Container {
  enum class Kind { kTote, kFloor, kMesh };  // in the recipe's order (Fields' choices)
  Kind kind = Kind::kFloor;
  Mesh mesh;  // kMesh: in the world frame (mm), standing on the floor z = 0
  Eigen::Vector2d inner_mm{355.0, 265.0};  // inner length (x) and width (y)
  double height_mm = 150.0;                // inner depth: from the inner floor to the rim
  double wall_mm = 6.0;
  double floor_mm = 6.0;
  double corner_radius_mm = 15.0;
  PhysicsMaterial material{1050.0, 0.8, 0.1};  // a plastic tote (the floor's too)

  bool Check(std::string* why) const;
  // The z of the surface parts land on (the inner floor or the floor).
  double BottomZ() const { return kind == Kind::kTote ? floor_mm : 0.0; }
  // The tote's rim, the mesh's top, or the floor.
  double RimZ() const;

  // A pile's `container` keys but its physics (`material`: PhysicsMaterial::Fields) and its mesh
  // (read from its file with the parts). Read by hand: `type` (the tag the other keys go with)
  // and `inner` (its own message).
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.kind, Field{.key = "type",
                        .kind = "choice",
                        .doc = "a tote made here, the bare floor, or a CAD or mesh file",
                        .choices = {"tote", "floor", "file"},
                        .by_hand = true});
    visit(o.inner_mm, Field{.key = "inner",
                            .kind = "lengths",
                            .doc = "inner size [length, width]",
                            .by_hand = true,
                            .only_with = {"tote"}});
    visit(o.height_mm,
          Field{.key = "height", .kind = "length", .doc = "wall height", .only_with = {"tote"}});
    visit(o.wall_mm,
          Field{.key = "wall", .kind = "length", .doc = "wall thickness", .only_with = {"tote"}});
    visit(o.floor_mm,
          Field{.key = "floor", .kind = "length", .doc = "floor thickness", .only_with = {"tote"}});
    visit(o.corner_radius_mm, Field{.key = "corner_radius",
                                    .kind = "length",
                                    .doc = "inner corner radius",
                                    .only_with = {"tote"}});
  }
};

// The container as a triangle mesh in its own frame (= the world's), outward normals, for the
// images and the depth: the tote as a closed mesh, a mesh container as it is, nothing for the
// floor.
Mesh MakeContainerMesh(const Container& container);

struct PileOptions {
  std::vector<int> bodies;  // the part of each dropped copy, in drop order
  // Parts that stay where they are (static bodies, added before the drop): what a drop of
  // distractors among an arranged scene's parts lands on. The drop starts above the highest of
  // them (or the rim, whichever is higher).
  struct Fixed {
    int part = 0;
    Eigen::Isometry3d world_from_model = Eigen::Isometry3d::Identity();
  };
  std::vector<Fixed> fixed;
  std::vector<PhysicsMaterial> materials;  // per part; empty: PhysicsMaterial{} for all
  Container container;
  // The drop region: a rectangle centred over the origin, or over the middle of a mesh
  // container's bounding box (size 0: the tote's inner size, or the mesh's bounding box, less 10 mm
  // each side; 300 x 300 mm on the floor); and the height of the lowest body's lowest point above
  // the rim (the mesh's top, the floor). Bodies start apart (their bounding spheres do not meet),
  // stacked as low as the region lets them.
  Eigen::Vector2d drop_size_mm = Eigen::Vector2d::Zero();
  double drop_height_mm = 30.0;
  double time_step_s = 1.0 / 480.0;  // 240 Hz let compound parts creep mm after rest
  // 20 left stacked parts creeping 0.5 mm/s and 30 took longer to rest; 40 rests 60-bolt piles
  // that pass the one-second resimulation as 50 does, in 0.87x its wall time (docs/benchmarks.md).
  int solver_iterations = 40;
  double max_seconds = 10.0;  // simulated; bodies still moving then are reported
  // From this simulated time on, damping rises over a second to 0.9 (Bullet's fraction of speed
  // lost per second) so that the last rolling or creeping parts stop; a rest it finds is still an
  // equilibrium (damping adds no force to a part at rest, and the confirmation below runs
  // without it).
  double calm_after_s = 1.0;
  // At rest: over the last rest_seconds, no point of any body moved faster than rest_speed on
  // average, nor did a body turn faster than rest_angular (a window's displacement, not the
  // instant's velocity, which contact jitter flips every step); or every body is asleep (Bullet's
  // deactivation: its whole group of touching bodies below 5 mm/s and 0.05 rad/s for 2 s).
  double rest_speed_mm_s = 2.0;
  double rest_angular_rad_s = 0.05;
  double rest_seconds = 0.25;
  // The rest is then confirmed the way a pile is checked: a new world with every body awake at its
  // resting pose, under the same physics, nothing holding it but its contacts (ContinuePile),
  // simulated for confirm_seconds, must move no point of any part by more than confirm_drift_mm.
  // The check stops as soon as a point has moved further; the pile then goes on in that world (a
  // part balanced on an edge has toppled there, a creeping one moved on) until it rests again and
  // a new confirmation holds, or max_seconds run out (its moving parts reported restless). A pile
  // declared at rest has therefore passed ContinuePile for confirm_seconds, step for step. The
  // default second costs a simulated second at the end of every pile (1.5x the median wall time
  // of the unconfirmed rest for 60 bolts, 1.34x in total over 24 piles; docs/benchmarks.md). 0: no
  // confirmation (the rest test alone lets piles through that move 0.5-16 mm in a second).
  double confirm_seconds = 1.0;
  double confirm_drift_mm = 0.4;
  uint64_t seed = 0;
  // Called after every rest window (rest_seconds simulated) with the simulated time, the bodies
  // still moving and those lying beside the container (below its rim, outside its walls); may be
  // empty. It only reports: the pile is the same with or without it.
  std::function<void(double seconds, int moving, int outside)> progress;
  // More than this fraction of the bodies lying beside the container stops the drop at once with
  // an Error saying how many (the container is too small for them, or they bounce out); 1: never.
  double give_up_outside = 0.5;

  bool Check(std::string* why) const;
};

struct PileResult {
  std::vector<Eigen::Isometry3d> world_from_model;  // per body
  std::vector<int> restless;                        // bodies still moving when max_seconds ran out
  std::vector<int> escaped;  // bodies that ended outside the tote (bounced out; for a mesh
                             // container: beside its bounding box)
  // Simulated time until rest (or max_seconds), confirmations included: a rest found just before
  // max_seconds is still confirmed, so this may pass it by up to confirm_seconds.
  double seconds = 0;
  int steps = 0;
  // ContinuePile: the largest displacement of a point of a part; DropPile: that of its last
  // confirmation (0 without one).
  double drift_mm = 0;
};

// Drops options.bodies (parts[b] with collision shapes shapes[b]) and simulates until rest or
// max_seconds. Throws Error for impossible options (naming the option) or a part without volume.
PileResult DropPile(const std::vector<Part>& parts, const std::vector<CollisionShape>& shapes,
                    const PileOptions& options);

// A new world with the bodies in `poses`, at rest and awake (never put to sleep), simulated for
// `seconds` under the physics the pile rested under: how far a settled pile moves when nothing
// holds it still but its contacts, which is what a pile at rest must survive
// (PileResult::drift_mm says the largest move of a point).
PileResult ContinuePile(const std::vector<Part>& parts, const std::vector<CollisionShape>& shapes,
                        const PileOptions& options, const std::vector<Eigen::Isometry3d>& poses,
                        double seconds);

// Bodies in contact in a pile at `poses` (options.bodies' order): `upper` rests on `lower` where
// their contact can carry its weight (the contact normal from lower to upper rises more than
// 5.7 degrees above the horizontal, z > 0.1); `upper` = -1 for a contact that carries none
// (side by side), then `lower` and `other` are the two bodies. Contacts within 0.5 mm count.
struct PileContact {
  int lower = 0, upper = 0;  // upper == -1: side by side, `lower` touches `other`
  int other = -1;
};
std::vector<PileContact> PileContacts(const std::vector<Part>& parts,
                                      const std::vector<CollisionShape>& shapes,
                                      const PileOptions& options,
                                      const std::vector<Eigen::Isometry3d>& poses);

// A pick (issue 45): body `picked` taken out of a pile at rest at `poses`, and the pile let settle
// again. The bodies that touched it, and every body resting on those (transitively), are free:
// they fall and settle in a new world until rest (confirmed as DropPile's when
// options.confirm_seconds > 0), under options' solver and limits. The other bodies are held where
// they are (static bodies): nothing they leaned on has gone, and a real pile's static friction
// holds them, where the solver would only add its creep (docs/scenes.md). Returns the remaining
// bodies (options.bodies without `picked`, in order): poses, restless and escaped ones, the
// simulated time; `freed` says which of them were free, drift_mm the largest move of a point.
PileResult SettleAfterPick(const std::vector<Part>& parts,
                           const std::vector<CollisionShape>& shapes, const PileOptions& options,
                           const std::vector<Eigen::Isometry3d>& poses, int picked,
                           std::vector<bool>* freed);

// A rotation drawn uniformly on SO(3) from three uniform numbers in [0, 1) (Shoemake 1992).
Eigen::Quaterniond UniformRotation(double u1, double u2, double u3);

}  // namespace cadsynth
