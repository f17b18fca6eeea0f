#include "variants/arrangement.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

#include "cad/core/error.h"
#include "cad/core/random.h"
#include "cad/mesh_analysis.h"
#include "variants/families.h"
#include "variants/stable_pose.h"

namespace cadsynth {

bool ArrangementOptions::Check(std::string* why) const {
  if (!(gap_mm >= 0.0)) {
    *why = "gap must not be negative";
  } else if (copies < 1 || copies > 10000) {
    *why = "copies must be 1 to 10000";
  } else if (!(clutter_radius_mm > 0.0)) {
    *why = "clutter radius must be positive";
  } else if (layout == Layout::kAssembled && (copies != 1 || pose == PoseMode::kAll)) {
    *why = "an assembled layout is one body: no copies, and one pose";
  } else if (!(drop_height_mm >= 0.0)) {
    *why = "drop_height must not be negative";
  } else if (!(settle_time_s > 0.0 && settle_time_s <= 600.0)) {
    *why = "settle_time must lie in (0, 600] s";
  } else if (!(time_step_s > 0.0 && time_step_s <= 0.02)) {
    *why = "time_step must lie in (0, 0.02] s";
  } else if (!container.Check(why) || !physics.Check(why) || !sequence.Check(why)) {
    return false;
  } else if (sequence.picks > 0 && layout != Layout::kPile) {
    *why = "only a pile (layout: pile) has a pick sequence";
  } else {
    for (const PhysicsDraw& p : part_physics) {
      if (!p.Check(why)) return false;
    }
    return true;
  }
  return false;
}

bool PickSequence::Check(std::string* why) const {
  if (picks < 0 || picks > 1000) {
    *why = "sequence.picks must be 0 to 1000";
    return false;
  }
  return true;
}

bool PhysicsDraw::Check(std::string* why) const {
  if (!low.Check(why) || !high.Check(why)) return false;
  if (low.density_kg_m3 > high.density_kg_m3 || low.friction > high.friction ||
      low.restitution > high.restitution) {
    *why = "a range's low end must not exceed its high end";
    return false;
  }
  return true;
}

PhysicsMaterial PhysicsDraw::Draw(uint64_t seed, uint64_t part) const {
  const auto draw = [&](double lo, double hi, uint64_t k) {
    return lo == hi ? lo
                    : lo + (hi - lo) * UniformDraw(seed, streams::kPilePhysics, (part << 2) + k);
  };
  PhysicsMaterial m;
  m.density_kg_m3 = draw(low.density_kg_m3, high.density_kg_m3, 0);
  m.friction = draw(low.friction, high.friction, 1);
  m.restitution = draw(low.restitution, high.restitution, 2);
  return m;
}

namespace {

using Polygon = std::vector<Eigen::Vector2d>;

// Convex hull of 2D points, counter-clockwise (monotone chain).
Polygon ConvexHull2D(std::vector<Eigen::Vector2d> p) {
  std::sort(p.begin(), p.end(), [](const auto& a, const auto& b) {
    return a.x() != b.x() ? a.x() < b.x() : a.y() < b.y();
  });
  if (p.size() < 3) return p;
  Polygon hull(2 * p.size());
  size_t k = 0;
  const auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a,
                        const Eigen::Vector2d& b) {
    return (a - o).x() * (b - o).y() - (a - o).y() * (b - o).x();
  };
  for (size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], p[i]) <= 0) --k;
    hull[k++] = p[i];
  }
  for (size_t i = p.size() - 1, t = k + 1; i > 0; --i) {
    while (k >= t && cross(hull[k - 2], hull[k - 1], p[i - 1]) <= 0) --k;
    hull[k++] = p[i - 1];
  }
  hull.resize(k - 1);
  return hull;
}

// Separation of two convex polygons along the best axis (negative: they overlap).
double Separation(const Polygon& a, const Polygon& b) {
  double best = -1e300;
  for (const Polygon* poly : {&a, &b}) {
    for (size_t i = 0; i < poly->size(); ++i) {
      const Eigen::Vector2d e = (*poly)[(i + 1) % poly->size()] - (*poly)[i];
      const Eigen::Vector2d n = Eigen::Vector2d(e.y(), -e.x()).normalized();
      double a_min = 1e300, a_max = -1e300, b_min = 1e300, b_max = -1e300;
      for (const auto& p : a) a_min = std::min(a_min, n.dot(p)), a_max = std::max(a_max, n.dot(p));
      for (const auto& p : b) b_min = std::min(b_min, n.dot(p)), b_max = std::max(b_max, n.dot(p));
      best = std::max(best, std::max(b_min - a_max, a_min - b_max));
    }
  }
  return best;
}

double Area(const Polygon& p) {
  double area = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    const auto& a = p[i];
    const auto& b = p[(i + 1) % p.size()];
    area += a.x() * b.y() - b.x() * a.y();
  }
  return 0.5 * area;
}

struct Body {
  int group = 0;
  std::vector<Instance> instances;
  bool restless = false;  // pose: dropped, still moving at settle_time
};

Eigen::AlignedBox3d Bounds(const std::vector<Part>& parts, const Body& body) {
  Eigen::AlignedBox3d box;
  for (const Instance& i : body.instances)
    box.extend(parts[i.part].mesh.Bounds(i.world_from_model));
  return box;
}

void Apply(const Eigen::Isometry3d& motion, Body* body) {
  for (Instance& i : body->instances) i.world_from_model = motion * i.world_from_model;
}

// The stable pose whose resting face points most nearly down in the body's own (design) frame;
// ties go to the more probable pose (the list's order).
size_t UprightPose(const std::vector<StablePose>& poses) {
  size_t best = 0;
  for (size_t i = 1; i < poses.size(); ++i) {
    if (-poses[i].normal.z() > -poses[best].normal.z() + 1e-9) best = i;
  }
  return best;
}

// Centres a body over the origin and lowers it onto the floor.
void Lower(const std::vector<Part>& parts, Body* body) {
  const Eigen::AlignedBox3d box = Bounds(parts, *body);
  Apply(
      Eigen::Isometry3d(Eigen::Translation3d(-box.center().x(), -box.center().y(), -box.min().z())),
      body);
}

// Rests a body on `poses[pose_index]` (the caller's pick: its most stable face, a drawn one, or
// the upright one; as designed: unturned); then yaw about z and lower onto the floor.
void Rest(const std::vector<Part>& parts, const ArrangementOptions& o,
          const std::vector<StablePose>& poses, size_t pose_index, double yaw, Body* body) {
  if (o.pose != PoseMode::kAsDesigned) Apply(poses[pose_index].floor_from_body, body);
  Apply(Eigen::Isometry3d(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ())), body);
  Lower(parts, body);
}

// pose: dropped. Drops `body` alone onto the floor at a random orientation (its own pile of one,
// seeded from the scene's seed and `index`) and rests it where it came to rest: on the stable
// pose whose face physics put down, exactly flat (the simulation leaves it within a fraction of
// a degree, its collision margin), at the yaw it landed with. A body of several parts falls as
// one rigid body (their meshes, mass and collision pieces together). Returns false when it was
// still moving at settle_time.
bool Drop(const std::vector<Part>& parts, const std::vector<CollisionShape>& shapes,
          const ArrangementOptions& o, uint64_t index, const std::vector<StablePose>& poses,
          Body* body) {
  PileOptions pile;
  pile.container.kind = Container::Kind::kFloor;
  pile.container.material = o.container.material;
  pile.drop_height_mm = o.drop_height_mm;
  pile.max_seconds = o.settle_time_s;
  pile.time_step_s = o.time_step_s;
  pile.confirm_seconds = o.confirm_rest ? 1.0 : 0.0;
  pile.seed = static_cast<uint64_t>(UniformDraw(o.seed, streams::kDropSeed, index) * 0x1p53);
  pile.bodies = {0};
  // A group's parts fall with its first part's material.
  const int first = body->instances[0].part;
  pile.materials = {(o.part_physics.empty() ? o.physics : o.part_physics[first])
                        .Draw(o.seed, static_cast<uint64_t>(first))};
  std::vector<Part> one(1);
  std::vector<CollisionShape> shape(1);
  Eigen::Isometry3d model_from_design = Eigen::Isometry3d::Identity();
  if (body->instances.size() == 1) {
    const Instance& i = body->instances[0];
    one[0] = parts[i.part];
    shape[0] = shapes[i.part];
    model_from_design = i.world_from_model.inverse();
  } else {
    // The group in its design frame as one part (mass from the meshes together).
    Part& all = one[0];
    all.name = "a group of " + std::to_string(body->instances.size()) + " parts";
    all.watertight = true;
    for (const Instance& i : body->instances) {
      Mesh mesh = parts[i.part].mesh;
      mesh.Transform(i.world_from_model);
      all.mesh.Append(mesh);
      all.watertight = all.watertight && parts[i.part].watertight;
      for (const auto& piece : shapes[i.part].pieces) {
        shape[0].pieces.emplace_back();
        for (const Eigen::Vector3d& p : piece)
          shape[0].pieces.back().push_back(i.world_from_model * p);
      }
    }
    if (all.watertight) all.mass = ComputeMeshMassProperties(all.mesh);
  }
  const PileResult r = DropPile(one, shape, pile);
  const Eigen::Isometry3d landed = r.world_from_model[0] * model_from_design;  // world_from_design
  // The stable pose whose resting face points most nearly down.
  const Eigen::Vector3d down = landed.linear().transpose() * -Eigen::Vector3d::UnitZ();
  size_t pick = 0;
  for (size_t p = 1; p < poses.size(); ++p) {
    if (poses[p].normal.dot(down) > poses[pick].normal.dot(down)) pick = p;
  }
  if (!poses.empty() && poses[pick].normal.dot(down) > std::cos(5.0 * M_PI / 180.0)) {
    const Eigen::Matrix3d turn = landed.linear() * poses[pick].floor_from_body.linear().transpose();
    Apply(poses[pick].floor_from_body, body);
    Apply(Eigen::Isometry3d(
              Eigen::AngleAxisd(std::atan2(turn(1, 0), turn(0, 0)), Eigen::Vector3d::UnitZ())),
          body);
  } else {
    // More than 5 degrees from every stable face: only a body still moving at settle_time (one
    // at rest on a flat floor stands on a face of its hull); kept as the simulation left it.
    Apply(landed, body);
  }
  Lower(parts, body);
  return r.restless.empty();
}

// The collision shapes of the parts marked `needed` (the others left empty).
std::vector<CollisionShape> NeededShapes(const std::vector<Part>& parts,
                                         const std::vector<bool>& needed) {
  std::vector<CollisionShape> own;
  own.resize(parts.size());
  for (size_t p = 0; p < parts.size(); ++p) {
    if (needed[p]) own[p] = MakeCollisionShape(parts[p]);
  }
  return own;
}

void CheckInputs(const std::vector<Part>& parts, const std::vector<Instance>& instances,
                 const ArrangementOptions& o, const std::vector<int>& group) {
  std::string why;
  if (!o.Check(&why)) throw Error("arrangement: " + why);
  if (!group.empty() && group.size() != instances.size())
    throw Error("arrangement: one group per instance");
  if (!o.part_physics.empty() && o.part_physics.size() != parts.size())
    throw Error("arrangement: one physics material per part");
  for (const Instance& instance : instances) {
    if (instance.part < 0 || static_cast<size_t>(instance.part) >= parts.size()) {
      throw Error("arrangement: instance '" + instance.name + "' refers to a missing part");
    }
  }
}

// Rigid bodies: the groups, or everything for an assembled layout.
std::vector<Body> GroupBodies(const std::vector<Instance>& instances,
                              const std::vector<int>& group) {
  std::vector<Body> groups;
  std::map<int, size_t> index_of;
  for (size_t i = 0; i < instances.size(); ++i) {
    const int g = group.empty() ? static_cast<int>(i) : group[i];
    auto [it, inserted] = index_of.emplace(g, groups.size());
    if (inserted) groups.push_back(Body{g, {}});
    groups[it->second].instances.push_back(instances[i]);
  }
  return groups;
}

// Distractors join the drop: distractor k falls just before copy `slot` (after the last
// copy for slot = copies), drawn uniformly; `body_of[b]` says what body b is (>= 0: a copy,
// -1 - k: distractor k). Sets the pile's bodies in that order and returns `body_of`.
std::vector<int> DropOrder(const ArrangementOptions& o, const std::vector<Instance>& copies,
                           PileOptions* pile) {
  std::vector<std::pair<double, int>> order;
  for (size_t c = 0; c < copies.size(); ++c) order.emplace_back(c + 0.5, static_cast<int>(c));
  for (size_t k = 0; k < o.distractors.size(); ++k) {
    const double slot = std::floor(UniformDraw(o.distractor_seed, streams::kDistractorOrder, k) *
                                   (copies.size() + 1));
    order.emplace_back(slot, -1 - static_cast<int>(k));
  }
  std::stable_sort(order.begin(), order.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<int> body_of;
  pile->bodies.clear();
  for (const auto& [slot, what] : order) {
    body_of.push_back(what);
    pile->bodies.push_back(what >= 0 ? copies[what].part : o.distractors[-1 - what]);
  }
  return body_of;
}

// Where the pile's bodies came to rest: into the copies, or `out`'s distractors; and which of
// them were restless or escaped.
void SortOutPile(const ArrangementOptions& o, const PileResult& r, const std::vector<int>& body_of,
                 std::vector<Instance>* copies, Arrangement* out) {
  std::vector<int> index_of_body(body_of.size());
  out->distractors.resize(o.distractors.size());
  for (size_t b = 0; b < body_of.size(); ++b) {
    const int what = body_of[b];
    if (what >= 0) {
      (*copies)[what].world_from_model = r.world_from_model[b];
      index_of_body[b] = what;
    } else {
      Instance& d = out->distractors[-1 - what];
      d.part = o.distractors[-1 - what];
      d.name = "distractor " + std::to_string(-1 - what);
      d.world_from_model = r.world_from_model[b];
      index_of_body[b] = what;
    }
  }
  for (const std::vector<int>* from : {&r.restless, &r.escaped}) {
    std::vector<int>& to = from == &r.restless ? out->restless : out->escaped;
    for (int b : *from) {
      const int what = index_of_body[b];
      if (what >= 0) {
        to.push_back(what);
      } else {
        (from == &r.restless ? out->restless_distractors : out->escaped_distractors)
            .push_back(-1 - what);
      }
    }
    std::sort(to.begin(), to.end());
  }
  std::sort(out->restless_distractors.begin(), out->restless_distractors.end());
  std::sort(out->escaped_distractors.begin(), out->escaped_distractors.end());
}

// layout: pile. Every copy of every (single-part) group and the distractors fall together into
// the container.
// A pile's physics from its arrangement options (no bodies yet).
PileOptions PileSettings(const std::vector<Part>& parts, const ArrangementOptions& o) {
  PileOptions pile;
  pile.container = o.container;
  for (size_t p = 0; p < parts.size(); ++p)
    pile.materials.push_back(
        (o.part_physics.empty() ? o.physics : o.part_physics[p]).Draw(o.seed, p));
  pile.drop_height_mm = o.drop_height_mm;
  pile.max_seconds = o.settle_time_s;
  pile.time_step_s = o.time_step_s;
  pile.confirm_seconds = o.confirm_rest ? 1.0 : 0.0;
  pile.seed = o.seed;
  pile.progress = o.pile_progress;
  if (o.container.kind == Container::Kind::kFloor) {
    const double side = std::sqrt(M_PI) * o.clutter_radius_mm;  // the clutter disc's area
    pile.drop_size_mm = Eigen::Vector2d(side, side);
  }
  return pile;
}

Arrangement ArrangePile(const std::vector<Part>& parts, const ArrangementOptions& o,
                        const std::vector<Body>& groups,
                        const std::vector<CollisionShape>* shapes) {
  Arrangement out;
  PileOptions pile = PileSettings(parts, o);
  for (const Body& g : groups) {
    if (g.instances.size() != 1) {
      throw Error("arrangement: a pile drops single parts, but one group is an assembly of " +
                  std::to_string(g.instances.size()) +
                  " parts (give its parts as separate entries, or use another layout)");
    }
  }
  std::vector<Instance> copies;
  for (const Body& g : groups) {
    for (int c = 0; c < o.copies; ++c) {
      pile.bodies.push_back(g.instances[0].part);
      copies.push_back(g.instances[0]);
      out.group.push_back(g.group);
    }
  }
  const std::vector<int> body_of = DropOrder(o, copies, &pile);
  std::vector<CollisionShape> own;
  if (shapes == nullptr) {
    std::vector<bool> needed(parts.size(), false);
    for (int b : pile.bodies) needed[static_cast<size_t>(b)] = true;
    own = NeededShapes(parts, needed);
    shapes = &own;
  }
  const PileResult r = DropPile(parts, *shapes, pile);
  SortOutPile(o, r, body_of, &copies, &out);
  out.instances = std::move(copies);
  out.settle_seconds = r.seconds;
  return out;
}

// layout: assembled. Every group together as one body, rested on the chosen pose.
Arrangement ArrangeAssembled(const std::vector<Part>& parts, const ArrangementOptions& o,
                             const std::vector<Body>& groups) {
  Arrangement out;
  Body all{groups[0].group, {}};
  for (const Body& b : groups)
    all.instances.insert(all.instances.end(), b.instances.begin(), b.instances.end());
  const std::vector<StablePose> poses = o.pose == PoseMode::kAsDesigned
                                            ? std::vector<StablePose>{}
                                            : StablePoses(parts, all.instances);
  size_t pick = 0;
  if (o.pose == PoseMode::kRandom) {
    double u = UniformDraw(o.seed, streams::kAssembledPose, 0), acc = 0;
    while (pick + 1 < poses.size() && (acc += poses[pick].probability) < u) ++pick;
  } else if (o.pose == PoseMode::kUpright) {
    pick = UprightPose(poses);
  }
  Rest(parts, o, poses, pick, 0.0, &all);
  // Keep each instance's group for the caller.
  std::vector<int> owner;
  for (const Body& b : groups) owner.insert(owner.end(), b.instances.size(), b.group);
  out.instances = all.instances;
  out.group = owner;
  return out;
}

// Copies of each group, each resting on its own: on the chosen face, at yaw 0 (or random), or
// where it fell.
std::vector<Body> RestCopies(const std::vector<Part>& parts, const ArrangementOptions& o,
                             const std::vector<Body>& groups,
                             const std::vector<CollisionShape>* shapes) {
  const bool clutter = o.layout == Layout::kClutter;
  std::vector<Body> bodies;
  for (size_t g = 0; g < groups.size(); ++g) {
    const std::vector<StablePose> poses = o.pose == PoseMode::kAsDesigned
                                              ? std::vector<StablePose>{}
                                              : StablePoses(parts, groups[g].instances);
    // `all`: a copy on each distinct pose (its first face): faces the part's symmetry maps onto
    // each other would give copies that look the same.
    std::vector<size_t> pose_starts;
    for (size_t i = 0; i < poses.size(); ++i) {
      if (i == 0 || poses[i].pose != poses[i - 1].pose) pose_starts.push_back(i);
    }
    const size_t faces = o.pose == PoseMode::kAll ? pose_starts.size() : 1;
    for (int c = 0; c < o.copies; ++c) {
      for (size_t f = 0; f < faces; ++f) {
        const uint64_t index =
            (static_cast<uint64_t>(g) << 32) + static_cast<uint64_t>(c) * faces + f;
        if (o.pose == PoseMode::kDropped) {
          Body body = groups[g];
          body.restless = !Drop(parts, *shapes, o, index, poses, &body);
          bodies.push_back(std::move(body));
          continue;
        }
        size_t pick = o.pose == PoseMode::kAll ? pose_starts[f] : 0;
        if (o.pose == PoseMode::kUpright) pick = UprightPose(poses);
        if (o.pose == PoseMode::kRandom) {
          const double u = UniformDraw(o.seed, streams::kCopyPose, index);
          double acc = 0;
          while (pick + 1 < poses.size() && (acc += poses[pick].probability) < u) ++pick;
        }
        const double yaw = (clutter || o.pose == PoseMode::kRandom)
                               ? 2 * M_PI * UniformDraw(o.seed, streams::kCopyYaw, index)
                               : 0.0;
        Body body = groups[g];
        Rest(parts, o, poses, pick, yaw, &body);
        bodies.push_back(std::move(body));
      }
    }
  }
  return bodies;
}

// Cells: a row, or rows of about sqrt(N); each body centred in its cell.
void PlaceInCells(const std::vector<Part>& parts, const ArrangementOptions& o,
                  std::vector<Body>* bodies) {
  const size_t n = bodies->size();
  const size_t columns = (o.layout == Layout::kRow || o.layout == Layout::kSingle)
                             ? n
                             : static_cast<size_t>(std::ceil(std::sqrt(double(n))));
  std::vector<double> column_width(columns, 0.0), row_depth((n + columns - 1) / columns, 0.0);
  std::vector<Eigen::AlignedBox3d> bounds;
  for (size_t b = 0; b < n; ++b) {
    bounds.push_back(Bounds(parts, (*bodies)[b]));
    column_width[b % columns] = std::max(column_width[b % columns], bounds[b].sizes().x());
    row_depth[b / columns] = std::max(row_depth[b / columns], bounds[b].sizes().y());
  }
  for (size_t b = 0; b < n; ++b) {
    double x = 0, y = 0;
    for (size_t c = 0; c < b % columns; ++c) x += column_width[c] + o.gap_mm;
    for (size_t r = 0; r < b / columns; ++r) y -= row_depth[r] + o.gap_mm;
    const Eigen::Vector3d shift(x + 0.5 * column_width[b % columns] - bounds[b].center().x(),
                                y - 0.5 * row_depth[b / columns] - bounds[b].center().y(), 0.0);
    Apply(Eigen::Isometry3d(Eigen::Translation3d(shift)), &(*bodies)[b]);
  }
}

// Each body's footprint: the convex hull of its floor shadow.
std::vector<Polygon> Footprints(const std::vector<Part>& parts, const std::vector<Body>& bodies) {
  std::vector<Polygon> footprint(bodies.size());
  for (size_t b = 0; b < bodies.size(); ++b) {
    std::vector<Eigen::Vector2d> shadow;
    for (const Instance& i : bodies[b].instances) {
      for (const Eigen::Vector3f& p : parts[i.part].mesh.positions)
        shadow.push_back((i.world_from_model * p.cast<double>()).head<2>());
    }
    footprint[b] = ConvexHull2D(shadow);
  }
  return footprint;
}

// Clutter: largest footprints first, each at up to 500 random spots in the disc, kept `gap`
// from every body already down (footprints are the convex hulls of the bodies' floor shadows,
// so disjoint footprints mean disjoint bodies).
std::vector<Body> PlaceInClutter(const std::vector<Part>& parts, const ArrangementOptions& o,
                                 const std::vector<Body>& bodies) {
  const std::vector<Polygon> footprint = Footprints(parts, bodies);
  std::vector<size_t> order(bodies.size());
  for (size_t b = 0; b < order.size(); ++b) order[b] = b;
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return Area(footprint[a]) > Area(footprint[b]); });
  std::vector<Polygon> placed;
  std::vector<Body> kept;
  for (size_t b : order) {
    bool done = false;
    for (int attempt = 0; attempt < 500 && !done; ++attempt) {
      const uint64_t index = (static_cast<uint64_t>(b) << 20) + static_cast<uint64_t>(attempt);
      const double r =
          o.clutter_radius_mm * std::sqrt(UniformDraw(o.seed, streams::kClutterRadius, index));
      const double phi = 2 * M_PI * UniformDraw(o.seed, streams::kClutterAngle, index);
      const Eigen::Vector2d at(r * std::cos(phi), r * std::sin(phi));
      Polygon moved = footprint[b];
      bool inside = true;
      for (auto& p : moved) {
        p += at;
        inside = inside && p.norm() <= o.clutter_radius_mm;
      }
      if (!inside) continue;
      bool free = true;
      for (const Polygon& other : placed) free = free && Separation(moved, other) >= o.gap_mm;
      if (!free) continue;
      placed.push_back(moved);
      Body body = bodies[b];
      Apply(Eigen::Isometry3d(Eigen::Translation3d(at.x(), at.y(), 0.0)), &body);
      kept.push_back(std::move(body));
      done = true;
    }
  }
  if (kept.size() < bodies.size()) {
    std::ostringstream message;
    message << "clutter: only " << kept.size() << " of " << bodies.size()
            << " parts fit in a disc of radius " << o.clutter_radius_mm << " mm with " << o.gap_mm
            << " mm between them; give a larger radius or fewer copies";
    throw Error(message.str());
  }
  // Back in input order, for stable output.
  std::sort(kept.begin(), kept.end(),
            [&](const Body& a, const Body& b) { return a.group < b.group; });
  return kept;
}

// The placed bodies' instances in order, each with its group (and restless ones marked).
Arrangement Collect(const std::vector<Part>& parts, const std::vector<Body>& bodies, bool clutter) {
  Arrangement out;
  for (const Body& body : bodies) {
    for (const Instance& i : body.instances) {
      if (body.restless) out.restless.push_back(static_cast<int>(out.instances.size()));
      out.instances.push_back(i);
      out.group.push_back(body.group);
    }
  }
  // Centre everything on the z axis (clutter is centred on the disc already).
  if (!clutter) {
    Eigen::AlignedBox3d all;
    for (const Instance& i : out.instances)
      all.extend(parts[i.part].mesh.Bounds(i.world_from_model));
    for (Instance& i : out.instances) {
      i.world_from_model =
          Eigen::Translation3d(-all.center().x(), -all.center().y(), 0.0) * i.world_from_model;
    }
  }
  return out;
}

// The arrangement of `instances`; a pile's distractors fall with it (the other layouts' fall in
// Arrange, after it).
Arrangement ArrangeParts(const std::vector<Part>& parts, const std::vector<Instance>& instances,
                         const ArrangementOptions& options, const std::vector<int>& group,
                         const std::vector<CollisionShape>* shapes) {
  ArrangementOptions o = options;
  if (o.pose == PoseMode::kAuto)
    o.pose = o.layout == Layout::kAssembled ? PoseMode::kUpright : PoseMode::kStable;
  CheckInputs(parts, instances, o, group);
  if (instances.empty()) return Arrangement{};

  const std::vector<Body> groups = GroupBodies(instances, group);
  if (o.layout == Layout::kPile) return ArrangePile(parts, o, groups, shapes);
  if (o.layout == Layout::kSingle && groups.size() != 1) {
    throw Error("arrangement: the single layout takes one part or assembly (got " +
                std::to_string(groups.size()) + ")");
  }
  if (o.layout == Layout::kAssembled) return ArrangeAssembled(parts, o, groups);

  const bool clutter = o.layout == Layout::kClutter;
  std::vector<CollisionShape> own;
  if (o.pose == PoseMode::kDropped && shapes == nullptr) {
    std::vector<bool> needed(parts.size(), false);
    for (const Instance& i : instances) needed[static_cast<size_t>(i.part)] = true;
    own = NeededShapes(parts, needed);
    shapes = &own;
  }
  std::vector<Body> bodies = RestCopies(parts, o, groups, shapes);
  if (!clutter) {
    PlaceInCells(parts, o, &bodies);
  } else {
    bodies = PlaceInClutter(parts, o, bodies);
  }
  return Collect(parts, bodies, clutter);
}

// The points that bound a part: its hull's corners (all of its mesh without a hull).
std::vector<Eigen::Vector3d> HullPoints(const Part& part) {
  if (part.hull) return part.hull->vertices;
  std::vector<Eigen::Vector3d> points;
  for (const Eigen::Vector3f& v : part.mesh.positions) points.push_back(v.cast<double>());
  return points;
}

}  // namespace

Arrangement Arrange(const std::vector<Part>& parts, const std::vector<Instance>& instances,
                    const ArrangementOptions& o, const std::vector<int>& group,
                    const std::vector<CollisionShape>* shapes) {
  for (int d : o.distractors) {
    if (d < 0 || static_cast<size_t>(d) >= parts.size())
      throw Error("arrangement: a distractor refers to a missing part");
  }
  Arrangement out = ArrangeParts(parts, instances, o, group, shapes);
  if (o.layout == Layout::kPile || o.distractors.empty() || out.instances.empty()) return out;
  // The other layouts: the distractors fall onto the floor over the arranged parts, which stay
  // (static bodies of their collision shapes: a part's triangles would cost a contact test each
  // under a distractor larger than the part, 20 ms per step under a 67 mm cylinder on gears).
  PileOptions pile;
  pile.container.kind = Container::Kind::kFloor;
  pile.container.material = o.container.material;
  pile.drop_height_mm = o.drop_height_mm;
  pile.max_seconds = o.settle_time_s;
  pile.time_step_s = o.time_step_s;
  pile.confirm_seconds = o.confirm_rest ? 1.0 : 0.0;
  pile.seed = o.distractor_seed;
  pile.bodies = o.distractors;
  for (size_t p = 0; p < parts.size(); ++p)
    pile.materials.push_back(
        (o.part_physics.empty() ? o.physics : o.part_physics[p]).Draw(o.seed, p));
  // Over the parts' floor plan (they are centred on the z axis), 20 mm wider each side.
  Eigen::AlignedBox3d all;
  for (const Instance& i : out.instances) all.extend(parts[i.part].mesh.Bounds(i.world_from_model));
  const Eigen::Vector2d reach =
      all.min().head<2>().cwiseAbs().cwiseMax(all.max().head<2>().cwiseAbs());
  pile.drop_size_mm = 2.0 * reach + Eigen::Vector2d::Constant(40.0);
  std::vector<CollisionShape> own;
  if (shapes == nullptr) {
    std::vector<bool> falls(parts.size(), false), stays(parts.size(), false);
    for (int b : pile.bodies) falls[static_cast<size_t>(b)] = true;
    for (const Instance& i : out.instances) stays[static_cast<size_t>(i.part)] = true;
    own.resize(parts.size());
    for (size_t p = 0; p < parts.size(); ++p) {
      if (falls[p]) {
        own[p] = MakeCollisionShape(parts[p]);
      } else if (stays[p]) {
        try {
          own[p] = MakeCollisionShape(parts[p]);
        } catch (const Error&) {  // flat: distractors do not land on it
        }
      }
    }
    shapes = &own;
  }
  // The arranged parts stay (static bodies of their collision shapes; a flat part has none).
  for (const Instance& i : out.instances) {
    if (static_cast<size_t>(i.part) < shapes->size() && !(*shapes)[i.part].pieces.empty())
      pile.fixed.push_back({i.part, i.world_from_model});
  }
  const PileResult r = DropPile(parts, *shapes, pile);
  for (size_t k = 0; k < o.distractors.size(); ++k) {
    Instance d;
    d.part = o.distractors[k];
    d.name = "distractor " + std::to_string(k);
    d.world_from_model = r.world_from_model[k];
    out.distractors.push_back(std::move(d));
  }
  out.restless_distractors = r.restless;
  out.distractor_seconds = r.seconds;
  return out;
}

int ChoosePick(const std::vector<Part>& parts, const Arrangement& pile, PickRule rule,
               uint64_t seed, int step) {
  const size_t n = pile.instances.size();
  if (n == 0) throw Error("arrangement: nothing left to pick");
  if (rule == PickRule::kRandom) {
    const double u = UniformDraw(seed, streams::kPickRandom, static_cast<uint64_t>(step));
    return static_cast<int>(std::min(n - 1, static_cast<size_t>(u * static_cast<double>(n))));
  }
  int best = 0;
  double best_z = -1e300;
  for (size_t i = 0; i < n; ++i) {
    const Instance& instance = pile.instances[i];
    double top = -1e300;
    for (const Eigen::Vector3d& v : HullPoints(parts[static_cast<size_t>(instance.part)]))
      top = std::max(top, (instance.world_from_model * v).z());
    if (top > best_z) best_z = top, best = static_cast<int>(i);
  }
  return best;
}

PickStep PickFromPile(const std::vector<Part>& parts, const Arrangement& pile,
                      const ArrangementOptions& o, int picked,
                      const std::vector<CollisionShape>& shapes) {
  if (picked < 0 || static_cast<size_t>(picked) >= pile.instances.size())
    throw Error("arrangement: pick of instance " + std::to_string(picked) +
                ", which does not exist");
  PileOptions settings = PileSettings(parts, o);
  std::vector<Eigen::Isometry3d> poses;
  for (const Instance& instance : pile.instances) {
    settings.bodies.push_back(instance.part);
    poses.push_back(instance.world_from_model);
  }
  for (const Instance& d : pile.distractors) settings.fixed.push_back({d.part, d.world_from_model});
  PickStep step;
  step.picked = picked;
  const PileResult r = SettleAfterPick(parts, shapes, settings, poses, picked, &step.freed);
  Arrangement& out = step.arranged;
  out.distractors = pile.distractors;
  out.settle_seconds = r.seconds;
  out.restless = r.restless;
  out.escaped = r.escaped;
  size_t k = 0;
  for (size_t i = 0; i < pile.instances.size(); ++i) {
    if (static_cast<int>(i) == picked) continue;
    Instance instance = pile.instances[i];
    double moved = 0;
    const Eigen::Isometry3d& now = r.world_from_model[k];
    for (const Eigen::Vector3d& v : HullPoints(parts[static_cast<size_t>(instance.part)]))
      moved = std::max(moved, (now * v - instance.world_from_model * v).norm());
    instance.world_from_model = now;
    out.instances.push_back(instance);
    if (!pile.group.empty()) out.group.push_back(pile.group[i]);
    step.moved_mm.push_back(moved);
    ++k;
  }
  return step;
}

void RedropEscaped(const std::vector<Part>& parts, const ArrangementOptions& o,
                   const std::vector<CollisionShape>& shapes, Arrangement* pile, int rounds) {
  for (int round = 0; round < rounds && !pile->escaped.empty(); ++round) {
    PileOptions settings = PileSettings(parts, o);
    settings.seed =
        static_cast<uint64_t>(UniformDraw(o.seed, streams::kRedropSeed, round) * 0x1p53);
    settings.give_up_outside = 1.0;  // a few parts falling again: what lands outside is reported
    const std::vector<int> falling = pile->escaped;  // sorted
    for (size_t i = 0, f = 0; i < pile->instances.size(); ++i) {
      const Instance& instance = pile->instances[i];
      if (f < falling.size() && falling[f] == static_cast<int>(i)) {
        settings.bodies.push_back(instance.part);
        ++f;
      } else {
        settings.fixed.push_back({instance.part, instance.world_from_model});
      }
    }
    for (const Instance& d : pile->distractors)
      settings.fixed.push_back({d.part, d.world_from_model});
    const PileResult r = DropPile(parts, shapes, settings);
    for (size_t f = 0; f < falling.size(); ++f)
      pile->instances[falling[f]].world_from_model = r.world_from_model[f];
    pile->escaped.clear();
    for (int f : r.escaped) pile->escaped.push_back(falling[f]);
    for (int f : r.restless) pile->restless.push_back(falling[f]);
    std::sort(pile->restless.begin(), pile->restless.end());
    pile->restless.erase(std::unique(pile->restless.begin(), pile->restless.end()),
                         pile->restless.end());
    pile->settle_seconds += r.seconds;
  }
}

std::vector<Instance> RemoveEscaped(Arrangement* pile) {
  std::vector<Instance> removed;
  if (pile->escaped.empty()) return removed;
  std::vector<int> new_index(pile->instances.size(), -1);
  Arrangement kept = *pile;
  kept.instances.clear();
  kept.group.clear();
  kept.restless.clear();
  kept.escaped.clear();
  for (size_t i = 0, e = 0; i < pile->instances.size(); ++i) {
    if (e < pile->escaped.size() && pile->escaped[e] == static_cast<int>(i)) {
      removed.push_back(pile->instances[i]);
      ++e;
      continue;
    }
    new_index[i] = static_cast<int>(kept.instances.size());
    kept.instances.push_back(pile->instances[i]);
    if (!pile->group.empty()) kept.group.push_back(pile->group[i]);
  }
  for (int i : pile->restless) {
    if (new_index[i] >= 0) kept.restless.push_back(new_index[i]);
  }
  *pile = std::move(kept);
  return removed;
}

}  // namespace cadsynth
