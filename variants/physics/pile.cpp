#include "variants/physics/pile.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <sstream>

#include <LinearMath/btConvexHullComputer.h>
#include <btBulletDynamicsCommon.h>
#include <Eigen/Eigenvalues>

#include "cad/core/error.h"
#include "cad/core/random.h"
#include "cad/core/util.h"
#include "cad/mesh_analysis.h"

namespace cadsynth {

namespace {

// Bullet works in centimetres here: parts of 5-200 mm are 0.5-20 units, the range its tolerances
// are made for (collision margins, contact thresholds, sleeping speeds are absolute lengths).
constexpr double kUnitsPerMm = 0.1;
constexpr double kGravity = 9810.0 * kUnitsPerMm;  // 9.81 m/s^2
constexpr double kMargin = 0.1 * kUnitsPerMm;      // 0.1 mm: the tote's corner prisms
constexpr double kMaxMarginMm = 0.5;               // parts: up to 0.5 mm,
constexpr double kMarginPerWidth = 0.06;           // or 6 % of a collision piece's width
constexpr int kCornerSegments = 8;
constexpr double kMinColliderMm = 10.0;  // a tote's walls and floor collide at least this thick
constexpr double kLinearDamping = 0.1, kAngularDamping = 0.3;  // fractions of speed lost per s
constexpr double kCalmDamping = 0.9, kCalmRampS = 1.0;
constexpr double kSpinningFrictionMm = 0.5;
constexpr double kRollingFrictionMm = 0.05;
constexpr double kConfirmSliceS = 0.05;  // a confirmation checks the drift this often

btVector3 ToBt(const Eigen::Vector3d& p) { return btVector3(p.x(), p.y(), p.z()); }

// The inner outline of a tote (or the outer one, with `grow`): a rounded rectangle, counter-
// clockwise from the +x+y corner, kCornerSegments per corner (one point when the radius is 0).
std::vector<Eigen::Vector2d> Outline(const Container& c, double grow) {
  const double a = 0.5 * c.inner_mm.x() + grow, b = 0.5 * c.inner_mm.y() + grow;
  const double r = c.corner_radius_mm > 0 ? c.corner_radius_mm + grow : 0.0;
  std::vector<Eigen::Vector2d> points;
  const double sx[4] = {1, -1, -1, 1}, sy[4] = {1, 1, -1, -1};
  for (int corner = 0; corner < 4; ++corner) {
    const Eigen::Vector2d centre(sx[corner] * (a - r), sy[corner] * (b - r));
    const int n = r > 0 ? kCornerSegments : 0;
    for (int k = 0; k <= n; ++k) {
      const double angle = M_PI / 2 * (corner + (n > 0 ? static_cast<double>(k) / n : 0.5));
      points.push_back(centre + r * Eigen::Vector2d(std::cos(angle), std::sin(angle)));
    }
  }
  return points;
}

struct World {
  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher{&configuration};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &configuration};
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  std::vector<std::unique_ptr<btMotionState>> states;
  std::vector<std::unique_ptr<btRigidBody>> bodies;     // statics first, then the dropped bodies
  std::vector<std::unique_ptr<btTriangleMesh>> meshes;  // the triangles of mesh shapes

  ~World() {
    for (auto& body : bodies) world.removeRigidBody(body.get());
  }

  btRigidBody* AddStatic(std::unique_ptr<btCollisionShape> shape, const PhysicsMaterial& m) {
    btRigidBody::btRigidBodyConstructionInfo info(0.0, nullptr, shape.get());
    info.m_friction = m.friction;
    info.m_restitution = m.restitution;
    // Bullet combines rolling (and spinning) friction as r0 f1 + f0 r1 (each body's rolling
    // friction times the other's friction): the parts' own decide, the container adds none.
    info.m_spinningFriction = 0.0;
    info.m_rollingFriction = 0.0;
    auto body = std::make_unique<btRigidBody>(info);
    world.addRigidBody(body.get());
    shapes.push_back(std::move(shape));
    bodies.push_back(std::move(body));
    return bodies.back().get();
  }
};

void AddContainer(const Container& c, World* w) {
  // The floor everywhere (parts that bounce out land on it).
  // (A large thin box rather than btStaticPlaneShape: Bullet's convex-plane contacts keep one
  // point per step and let a part lying flat sink and spin.)
  {
    auto floor = std::make_unique<btBoxShape>(btVector3(1e4, 1e4, 10.0) * kUnitsPerMm);
    btRigidBody* body = w->AddStatic(std::move(floor), c.material);
    btTransform at = btTransform::getIdentity();
    at.setOrigin(btVector3(0, 0, -10.0 * kUnitsPerMm));
    body->setWorldTransform(at);
  }
  if (c.kind == Container::Kind::kMesh) {
    // Bullet's static concave mesh (a bounding-volume tree of the triangles); it keeps pointers
    // into the triangle store, which the world owns with the shape.
    auto triangles = std::make_unique<btTriangleMesh>(/*use32bitIndices=*/true,
                                                      /*use4componentVertices=*/false);
    for (const auto& t : c.mesh.triangles) {
      btVector3 v[3];
      for (int k = 0; k < 3; ++k) v[k] = ToBt(c.mesh.positions[t[k]].cast<double>() * kUnitsPerMm);
      triangles->addTriangle(v[0], v[1], v[2], /*removeDuplicateVertices=*/false);
    }
    auto shape = std::make_unique<btBvhTriangleMeshShape>(triangles.get(), true);
    shape->setMargin(kMargin);
    w->AddStatic(std::move(shape), c.material);
    w->meshes.push_back(std::move(triangles));
    return;
  }
  if (c.kind != Container::Kind::kTote) return;
  auto compound = std::make_unique<btCompoundShape>();
  std::vector<std::unique_ptr<btCollisionShape>> children;
  // The walls and the floor collide as if at least kMinColliderMm thick, the extra thickness
  // outside (under the floor, beyond the walls) where the images show none: a thin part that
  // reaches past the middle of a thin slab in one step is pushed out of its far side (M3 and M4
  // washers dropped from 400 mm fell through a 1 mm floor despite continuous collision detection,
  // whose swept sphere must fit inside a 0.8 mm washer).
  const double a = 0.5 * c.inner_mm.x(), b = 0.5 * c.inner_mm.y();
  const double t = std::max(c.wall_mm, kMinColliderMm);
  const double top = c.floor_mm + c.height_mm;
  const double bottom = c.floor_mm - std::max(c.floor_mm, kMinColliderMm);
  const auto box = [&](const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
    auto shape = std::make_unique<btBoxShape>(ToBt(0.5 * (hi - lo) * kUnitsPerMm));
    btTransform at = btTransform::getIdentity();
    at.setOrigin(ToBt(0.5 * (hi + lo) * kUnitsPerMm));
    compound->addChildShape(at, shape.get());
    children.push_back(std::move(shape));
  };
  box({-a, -b, bottom}, {a, b, c.floor_mm});        // floor
  box({-a - t, b, bottom}, {a + t, b + t, top});    // +y wall
  box({-a - t, -b - t, bottom}, {a + t, -b, top});  // -y wall
  box({a, -b, bottom}, {a + t, b, top});            // +x wall
  box({-a - t, -b, bottom}, {-a, b, top});          // -x wall
  // Rounded inner corners: the space between each square corner and the arc, as a fan of prisms
  // from the corner (the same polygon as the tote's mesh).
  if (c.corner_radius_mm > 0) {
    const std::vector<Eigen::Vector2d> inner = Outline(c, 0.0);
    const double sx[4] = {1, -1, -1, 1}, sy[4] = {1, 1, -1, -1};
    for (int corner = 0; corner < 4; ++corner) {
      const Eigen::Vector2d square(sx[corner] * a, sy[corner] * b);
      for (int k = 0; k < kCornerSegments; ++k) {
        const Eigen::Vector2d p = inner[corner * (kCornerSegments + 1) + k];
        const Eigen::Vector2d q = inner[corner * (kCornerSegments + 1) + k + 1];
        auto prism = std::make_unique<btConvexHullShape>();
        for (const Eigen::Vector2d& xy : {square, p, q}) {
          for (double z : {c.floor_mm, top})
            prism->addPoint(ToBt(Eigen::Vector3d(xy.x(), xy.y(), z) * kUnitsPerMm), false);
        }
        prism->recalcLocalAabb();
        prism->setMargin(kMargin);
        compound->addChildShape(btTransform::getIdentity(), prism.get());
        children.push_back(std::move(prism));
      }
    }
  }
  w->AddStatic(std::move(compound), c.material);
  for (auto& child : children) w->shapes.push_back(std::move(child));
}

// A part as a rigid body: its frame at the centre of mass along the principal axes of inertia.
struct BodyModel {
  std::shared_ptr<btCollisionShape> shape;
  std::vector<std::unique_ptr<btCollisionShape>> children;
  Eigen::Isometry3d model_from_body = Eigen::Isometry3d::Identity();
  double mass_kg = 0;
  Eigen::Vector3d inertia = Eigen::Vector3d::Zero();  // principal moments, kg * unit^2
  double radius_mm = 0;                               // bounding sphere about the centre of mass
  double thickness_mm = 0;  // the smallest extent along a principal axis (for CCD)
  std::vector<Eigen::Vector3d> corners_in_model;  // every piece's corners (drift checks)
};

// The collision margin of one convex piece: 0.5 mm, or 6 % of the piece's width (its smallest
// extent along its own principal axes) where that is less. Bullet rounds a piece's corners by its
// margin: a cube corner ends 0.73 margins inside the true one and an edge 0.41, so two parts
// meeting corner to corner overlap by up to 1.46 margins where Bullet sees them touch. With one
// margin per part (a tenth of the part's thickness, so 0.5 mm for an L bracket of 4 mm plate),
// 60 brackets overlapped by up to 0.75 mm; with 0.25 mm per piece, 0.27-0.38 mm (seeds 1-8).
// Thick pieces keep 0.5 mm: a margin that is not thin keeps fast landings in GJK's robust
// shallow regime, and bolts' piles stay what they were (their pieces are 10 and 16 mm wide).
double PieceMarginMm(const std::vector<Eigen::Vector3d>& corners) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : corners) mean += p;
  mean /= static_cast<double>(corners.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& p : corners) scatter += (p - mean) * (p - mean).transpose();
  const Eigen::Matrix3d axes =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(scatter).eigenvectors();
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  for (const Eigen::Vector3d& p : corners) {
    const Eigen::Vector3d q = axes.transpose() * p;
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  return std::min(kMaxMarginMm, kMarginPerWidth * (hi - lo).minCoeff());
}

BodyModel MakeBodyModel(const Part& part, const CollisionShape& collision,
                        const PhysicsMaterial& material) {
  BodyModel m;
  MassProperties mass = part.mass;
  if (!part.watertight || !(mass.volume_mm3 > 0)) {
    // An open mesh: the hull's mass properties stand in.
    Mesh hull_mesh;
    const ConvexHull hull = part.hull ? *part.hull : ComputeConvexHull(part.mesh);
    for (const Eigen::Vector3d& v : hull.vertices) hull_mesh.positions.push_back(v.cast<float>());
    for (const auto& t : hull.triangles) hull_mesh.triangles.emplace_back(t[0], t[1], t[2]);
    mass = ComputeMeshMassProperties(hull_mesh);
  }
  if (!(mass.volume_mm3 > 0)) throw Error("part '" + part.name + "' has no volume to drop");
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(mass.inertia);
  Eigen::Matrix3d axes = eigen.eigenvectors();
  if (axes.determinant() < 0) axes.col(2) = -axes.col(2);
  m.model_from_body.linear() = axes;
  m.model_from_body.translation() = mass.center_of_mass;
  const double density_kg_mm3 = material.density_kg_m3 * 1e-9;
  m.mass_kg = density_kg_mm3 * mass.volume_mm3;
  m.inertia = eigen.eigenvalues().cwiseMax(0.0) * density_kg_mm3 * kUnitsPerMm * kUnitsPerMm;

  const Eigen::Isometry3d body_from_model = m.model_from_body.inverse();
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  // Each piece shrunk by the collision margin, which Bullet adds back around it: the piece's own
  // shape with edges rounded by the margin. A margin that is not thin keeps contacts in GJK's
  // robust shallow regime when parts land fast (with 0.1 mm, a cube landing on a corner at 1 m/s
  // sank 4 mm into the floor and spun there).
  std::vector<Eigen::Vector3d> all;
  for (const auto& piece : collision.pieces) {
    for (const Eigen::Vector3d& p : piece) {
      all.push_back(body_from_model * p);
      m.corners_in_model.push_back(p);
    }
  }
  for (const Eigen::Vector3d& q : all) {
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
    m.radius_mm = std::max(m.radius_mm, q.norm());
  }
  m.thickness_mm = (hi - lo).minCoeff();
  const auto piece_shape = [&](const std::vector<Eigen::Vector3d>& corners) {
    std::vector<double> coords;
    for (const Eigen::Vector3d& p : corners) {
      const Eigen::Vector3d q = body_from_model * p * kUnitsPerMm;
      coords.insert(coords.end(), {q.x(), q.y(), q.z()});
    }
    btConvexHullComputer computer;
    // Thin pieces shrink less (at most a quarter of their inner radius) and keep a smaller margin.
    const btScalar shrunk =
        computer.compute(coords.data(), 3 * sizeof(double), static_cast<int>(corners.size()),
                         PieceMarginMm(corners) * kUnitsPerMm, 0.25);
    auto hull = std::make_unique<btConvexHullShape>();
    for (int v = 0; v < computer.vertices.size(); ++v) hull->addPoint(computer.vertices[v], false);
    hull->recalcLocalAabb();
    hull->setMargin(shrunk > 0 ? shrunk : kMargin);
    return hull;
  };
  if (collision.pieces.size() == 1) {
    m.shape = piece_shape(collision.pieces[0]);
  } else {
    auto compound = std::make_shared<btCompoundShape>();
    for (const auto& piece : collision.pieces) {
      m.children.push_back(piece_shape(piece));
      compound->addChildShape(btTransform::getIdentity(), m.children.back().get());
    }
    m.shape = compound;
  }
  return m;
}

btTransform ToBtTransform(const Eigen::Isometry3d& world_from_body) {
  const Eigen::Quaterniond q(world_from_body.linear());
  btTransform t;
  t.setRotation(btQuaternion(q.x(), q.y(), q.z(), q.w()));
  t.setOrigin(ToBt(world_from_body.translation() * kUnitsPerMm));
  return t;
}

Eigen::Isometry3d FromBtTransform(const btTransform& t) {
  const btQuaternion r = t.getRotation();
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = Eigen::Quaterniond(r.w(), r.x(), r.y(), r.z()).normalized().toRotationMatrix();
  const btVector3& o = t.getOrigin();
  out.translation() = Eigen::Vector3d(o.x(), o.y(), o.z()) / kUnitsPerMm;
  return out;
}

// A world with the container and a body per entry of options.bodies at `world_from_model`.
struct Simulation {
  std::vector<BodyModel> models;  // per part (declared first: the world goes before its shapes)
  World world;
  std::vector<btRigidBody*> bodies;
  std::vector<int> part_of;

  Simulation(const std::vector<Part>& parts, const std::vector<CollisionShape>& shapes,
             const PileOptions& o) {
    world.world.setGravity(btVector3(0, 0, -kGravity));
    btContactSolverInfo& info = world.world.getSolverInfo();
    info.m_numIterations = o.solver_iterations;
    info.m_splitImpulse = 1;
    // Two friction directions per contact, cached between steps: without them parts resting on
    // several convex pieces creep a few mm/s.
    info.m_solverMode |=
        SOLVER_USE_2_FRICTION_DIRECTIONS | SOLVER_ENABLE_FRICTION_DIRECTION_CACHING;
    AddContainer(o.container, &world);
    models.resize(parts.size());
    std::vector<bool> made(parts.size(), false);
    std::vector<int> used = o.bodies;
    for (const PileOptions::Fixed& f : o.fixed) used.push_back(f.part);
    for (int p : used) {
      if (made[p]) continue;
      const PhysicsMaterial m = o.materials.empty() ? PhysicsMaterial{} : o.materials[p];
      models[p] = MakeBodyModel(parts[p], shapes[p], m);
      made[p] = true;
    }
    for (const PileOptions::Fixed& f : o.fixed) AddFixed(f.part, f.world_from_model, o);
  }

  // A part that does not move (its shape is the model's, which outlives the world).
  void AddFixed(int part, const Eigen::Isometry3d& world_from_model, const PileOptions& o) {
    const BodyModel& m = models[part];
    const PhysicsMaterial mat = o.materials.empty() ? PhysicsMaterial{} : o.materials[part];
    btRigidBody::btRigidBodyConstructionInfo info(0.0, nullptr, m.shape.get());
    info.m_friction = mat.friction;
    info.m_restitution = mat.restitution;
    info.m_spinningFriction = 0.0;  // as the container's (World::AddStatic)
    info.m_rollingFriction = 0.0;
    auto body = std::make_unique<btRigidBody>(info);
    body->setWorldTransform(ToBtTransform(world_from_model * m.model_from_body));
    world.world.addRigidBody(body.get());
    world.bodies.push_back(std::move(body));
  }

  void AddBody(int part, const Eigen::Isometry3d& world_from_model, const PileOptions& o) {
    const BodyModel& m = models[part];
    const PhysicsMaterial mat = o.materials.empty() ? PhysicsMaterial{} : o.materials[part];
    world.states.push_back(std::make_unique<btDefaultMotionState>(
        ToBtTransform(world_from_model * m.model_from_body)));
    btRigidBody::btRigidBodyConstructionInfo info(m.mass_kg, world.states.back().get(),
                                                  m.shape.get(), ToBt(m.inertia));
    info.m_friction = mat.friction;
    info.m_restitution = mat.restitution;
    // Air drag of a sort (Bullet's damping: a fraction of the speed lost per second), enough to
    // take the last energy out of a pile in a second or two, far too little to change a fall.
    info.m_linearDamping = kLinearDamping;
    info.m_angularDamping = kAngularDamping;
    // Torsional and rolling resistance at contacts (a torque of this length times the normal
    // force): the solver's friction at a patch's few contact points lets a part lying flat
    // turn and drift slowly for seconds without it.
    info.m_spinningFriction = kSpinningFrictionMm * kUnitsPerMm;
    info.m_rollingFriction = kRollingFrictionMm * kUnitsPerMm;
    auto body = std::make_unique<btRigidBody>(info);
    // Static friction that holds: each contact point stays where it first touched (Bullet's
    // friction anchor) as long as its friction force lies inside the Coulomb cone, and the solver
    // pulls it back there, where plain sequential impulses only damp the sliding speed and let a
    // part resting on a slope creep. In 60-bolt piles this took a second's resimulated drift from a
    // median 1.06 mm (19 of 24 piles over 0.5 mm) to 0.24 mm (docs/benchmarks.md, piles).
    body->setCollisionFlags(body->getCollisionFlags() | btCollisionObject::CF_HAS_FRICTION_ANCHOR);
    // Continuous collision detection for fast thin parts: a swept sphere inside the part.
    body->setCcdMotionThreshold(0.05 * m.thickness_mm * kUnitsPerMm);
    body->setCcdSweptSphereRadius(0.2 * m.thickness_mm * kUnitsPerMm);
    // Asleep (frozen until touched) once its whole group of touching bodies stayed below 5 mm/s
    // and 0.05 rad/s for 2 s (gDeactivationTime, Bullet's process-wide default, left as it is:
    // 0.5 s froze cubes tipping over an edge): contact jitter stays below that, real motion not.
    body->setSleepingThresholds(5.0 * kUnitsPerMm, 0.05);
    world.world.addRigidBody(body.get());
    bodies.push_back(body.get());
    part_of.push_back(part);
    world.bodies.push_back(std::move(body));
  }

  // Bodies whose mean speed over the last window (since `before`) exceeded the thresholds: a
  // window's displacement rather than the instant's velocity, so that the solver's contact
  // jitter (velocities that flip every step around a fixed pose) does not count as motion.
  std::vector<int> Moving(const PileOptions& o, const std::vector<btTransform>& before,
                          double window_s) const {
    std::vector<int> moving;
    for (size_t i = 0; i < bodies.size(); ++i) {
      if (!bodies[i]->isActive()) continue;  // asleep: at rest by Bullet's own test
      const btTransform& now = bodies[i]->getWorldTransform();
      const double moved_mm = (now.getOrigin() - before[i].getOrigin()).length() / kUnitsPerMm;
      const btQuaternion turn = now.getRotation() * before[i].getRotation().inverse();
      const double turned =
          2 * std::atan2(btVector3(turn.x(), turn.y(), turn.z()).length(), std::abs(turn.w()));
      // The fastest point: the centre's move plus the turn at the bounding sphere.
      const double point_mm = moved_mm + turned * models[part_of[i]].radius_mm;
      if (point_mm > o.rest_speed_mm_s * window_s || turned > o.rest_angular_rad_s * window_s)
        moving.push_back(static_cast<int>(i));
    }
    return moving;
  }

  Eigen::Isometry3d Pose(size_t i) const {
    return FromBtTransform(bodies[i]->getWorldTransform()) *
           models[part_of[i]].model_from_body.inverse();
  }

  // Steps until rest or max_seconds; `start_s` is the simulated time already behind the pile
  // (a failed confirmation's world goes on from there), for progress and messages.
  void Run(const PileOptions& o, PileResult* out, double start_s = 0) {
    const int window = std::max(1, static_cast<int>(std::lround(o.rest_seconds / o.time_step_s)));
    const int max_steps = static_cast<int>(std::ceil(o.max_seconds / o.time_step_s));
    std::vector<btTransform> before;
    for (const btRigidBody* b : bodies) before.push_back(b->getWorldTransform());
    std::vector<int> moving;
    bool rest = false;
    int step = 0;
    const int calm_from = static_cast<int>(std::lround(o.calm_after_s / o.time_step_s));
    const int calm_steps = std::max(1, static_cast<int>(std::lround(kCalmRampS / o.time_step_s)));
    while (step < max_steps && !rest) {
      world.world.stepSimulation(o.time_step_s, 1, o.time_step_s);
      ++step;
      if (step > calm_from && step <= calm_from + calm_steps) {
        // Calming: damping rises to kCalmDamping over kCalmRampS, which ends the slow rolling and
        // creeping of the last few parts without adding any force (a pile at rest feels none).
        const double f = static_cast<double>(step - calm_from) / calm_steps;
        for (btRigidBody* b : bodies) {
          b->setDamping(kLinearDamping + f * (kCalmDamping - kLinearDamping),
                        kAngularDamping + f * (kCalmDamping - kAngularDamping));
        }
      }
      if (step % window != 0) continue;
      moving = Moving(o, before, window * o.time_step_s);
      rest = moving.empty();
      for (size_t i = 0; i < bodies.size(); ++i) before[i] = bodies[i]->getWorldTransform();
      const int outside = Outside(o);
      if (o.progress)
        o.progress(start_s + step * o.time_step_s, static_cast<int>(moving.size()), outside);
      if (o.give_up_outside < 1.0 && outside > o.give_up_outside * bodies.size()) {
        std::ostringstream m;
        m << outside << " of " << Count(bodies.size(), "part") << " lie beside the "
          << (o.container.kind == Container::Kind::kTote ? "tote" : "container") << " after "
          << start_s + step * o.time_step_s
          << " s (simulated): stopped. The container is too small for "
          << "them, or they bounce out: use a larger one or fewer copies";
        throw Error(m.str());
      }
    }
    out->steps = step;
    out->seconds = step * o.time_step_s;
    if (!rest) {
      out->restless = moving;
      // The time ran out inside a window: judge the part of it that passed.
      const int partial = step % window;
      if (moving.empty() && partial > 0) out->restless = Moving(o, before, partial * o.time_step_s);
    }
    out->world_from_model.clear();
    for (size_t i = 0; i < bodies.size(); ++i) out->world_from_model.push_back(Pose(i));
  }

  // The bodies lying beside the container now: centre of mass below its rim and outside its
  // walls (a tote's outer size, a mesh container's bounding box). None on the bare floor.
  int Outside(const PileOptions& o) const {
    if (o.container.kind == Container::Kind::kFloor) return 0;
    Eigen::AlignedBox2d box;
    if (o.container.kind == Container::Kind::kTote) {
      const Eigen::Vector2d half =
          0.5 * o.container.inner_mm + Eigen::Vector2d::Constant(o.container.wall_mm);
      box = Eigen::AlignedBox2d(-half, half);
    } else {
      const Eigen::AlignedBox3d b = o.container.mesh.Bounds();
      box = Eigen::AlignedBox2d(b.min().head<2>(), b.max().head<2>());
    }
    const double rim = o.container.RimZ();
    int outside = 0;
    for (const btRigidBody* b : bodies) {
      const btVector3 c = b->getCenterOfMassPosition();
      const Eigen::Vector3d mm(c.x() / kUnitsPerMm, c.y() / kUnitsPerMm, c.z() / kUnitsPerMm);
      if (mm.z() < rim && !box.contains(mm.head<2>())) ++outside;
    }
    return outside;
  }

  // The bodies at `poses` whose centre of mass lies outside the tote (or beside a mesh container's
  // bounding box).
  std::vector<int> Escaped(const PileOptions& o,
                           const std::vector<Eigen::Isometry3d>& poses) const {
    std::vector<int> escaped;
    const Eigen::AlignedBox3d box = o.container.kind == Container::Kind::kMesh
                                        ? o.container.mesh.Bounds()
                                        : Eigen::AlignedBox3d();
    for (size_t i = 0; i < poses.size(); ++i) {
      const Eigen::Vector3d c = poses[i] * models[part_of[i]].model_from_body.translation();
      if (o.container.kind == Container::Kind::kTote) {
        const double a = 0.5 * o.container.inner_mm.x(), b = 0.5 * o.container.inner_mm.y();
        if (std::abs(c.x()) > a || std::abs(c.y()) > b || c.z() < o.container.floor_mm - 1)
          escaped.push_back(static_cast<int>(i));
      } else if (o.container.kind == Container::Kind::kMesh) {
        if (c.x() < box.min().x() || c.x() > box.max().x() || c.y() < box.min().y() ||
            c.y() > box.max().y())
          escaped.push_back(static_cast<int>(i));
      }
    }
    return escaped;
  }
};

// A new world with the bodies of `o` at `poses`, awake and never put to sleep, under the pile's
// own physics: how a settled pile is checked (ContinuePile, the confirmation, which are therefore
// the same simulation step for step), and where it goes on when the confirmation finds it still
// moving.
struct Restart {
  PileOptions options;
  Simulation sim;
  std::vector<Eigen::Isometry3d> start;

  Restart(const std::vector<Part>& parts, const std::vector<CollisionShape>& shapes,
          const PileOptions& o, const std::vector<Eigen::Isometry3d>& poses)
      : options(o), sim(parts, shapes, options), start(poses) {
    for (size_t i = 0; i < poses.size(); ++i) {
      sim.AddBody(o.bodies[i], poses[i], options);
      sim.bodies.back()->setActivationState(DISABLE_DEACTIVATION);
    }
  }
  // Steps for `seconds`; returns the steps taken.
  int Step(double seconds) {
    const int steps = static_cast<int>(std::ceil(seconds / options.time_step_s - 1e-9));
    Steps(steps);
    return steps;
  }
  void Steps(int steps) {
    for (int k = 0; k < steps; ++k)
      sim.world.world.stepSimulation(options.time_step_s, 1, options.time_step_s);
  }
  std::vector<Eigen::Isometry3d> Poses() const {
    std::vector<Eigen::Isometry3d> poses;
    for (size_t i = 0; i < start.size(); ++i) poses.push_back(sim.Pose(i));
    return poses;
  }
  // How far each body moved from its start: the largest displacement of a corner of its
  // collision pieces (mm).
  std::vector<double> Drift() const {
    std::vector<double> drift;
    for (size_t i = 0; i < start.size(); ++i) {
      const Eigen::Isometry3d now = sim.Pose(i);
      double d = 0;
      for (const Eigen::Vector3d& corner : sim.models[sim.part_of[i]].corners_in_model)
        d = std::max(d, (now * corner - start[i] * corner).norm());
      drift.push_back(d);
    }
    return drift;
  }
};

void CheckInputs(const std::vector<Part>& parts, const std::vector<CollisionShape>& shapes,
                 const PileOptions& o) {
  std::string why;
  if (!o.Check(&why)) throw Error("pile: " + why);
  if (shapes.size() != parts.size()) throw Error("pile: one collision shape per part needed");
  if (!o.materials.empty() && o.materials.size() != parts.size())
    throw Error("pile: one physics material per part needed");
  std::vector<int> used = o.bodies;
  for (const PileOptions::Fixed& f : o.fixed) used.push_back(f.part);
  for (int b : used) {
    if (b < 0 || static_cast<size_t>(b) >= parts.size())
      throw Error("pile: a body refers to part " + std::to_string(b) + ", which does not exist");
    if (shapes[b].pieces.empty()) throw Error("pile: part '" + parts[b].name + "' has no shape");
  }
}

// Confirms a rest `result` found (see PileOptions::confirm_seconds; nothing without a
// confirmation or a rest). Where it fails, that world goes on until it rests again (its bodies
// keep their motion), then a new confirmation; result's poses, time and restless bodies follow.
void Confirm(const std::vector<Part>& parts, const std::vector<CollisionShape>& shapes,
             const PileOptions& o, PileResult* result) {
  if (!result->restless.empty() || !(o.confirm_seconds > 0)) return;
  std::vector<Eigen::Isometry3d> poses = result->world_from_model;
  while (true) {
    Restart check(parts, shapes, o, poses);
    // In slices, so that a confirmation that fails ends as soon as a point has moved too far (the
    // rest of the second could not bring it back within the tolerance of where it started).
    const int total = static_cast<int>(std::ceil(o.confirm_seconds / o.time_step_s - 1e-9));
    const int slice = std::max(1, static_cast<int>(std::lround(kConfirmSliceS / o.time_step_s)));
    std::vector<double> drift;
    for (int done = 0; done < total;) {
      const int steps = std::min(slice, total - done);
      check.Steps(steps);
      done += steps;
      result->steps += steps;
      result->seconds += steps * o.time_step_s;
      drift = check.Drift();
      result->drift_mm = *std::max_element(drift.begin(), drift.end());
      if (result->drift_mm > o.confirm_drift_mm) break;
    }
    if (result->drift_mm <= o.confirm_drift_mm) break;  // `poses` held: they are the pile
    PileOptions more = check.options;
    more.calm_after_s = 0;  // late already: the calming damping rises at once
    more.max_seconds = o.max_seconds - result->seconds;
    if (!(more.max_seconds > 0)) {
      for (size_t i = 0; i < drift.size(); ++i) {
        if (drift[i] > o.confirm_drift_mm) result->restless.push_back(static_cast<int>(i));
      }
      poses = check.Poses();
      break;
    }
    PileResult settled;
    check.sim.Run(more, &settled, result->seconds);
    result->steps += settled.steps;
    result->seconds += settled.seconds;
    poses = settled.world_from_model;
    if (!settled.restless.empty()) {
      result->restless = settled.restless;
      break;
    }
  }
  result->world_from_model = poses;
}

}  // namespace

bool PhysicsMaterial::Check(std::string* why) const {
  if (!(density_kg_m3 > 0) || !std::isfinite(density_kg_m3)) {
    *why = "density must be positive (kg/m3)";
  } else if (!(friction >= 0 && friction <= 10)) {
    *why = "friction must lie in [0, 10]";
  } else if (!(restitution >= 0 && restitution <= 1)) {
    *why = "restitution must lie in [0, 1]";
  } else {
    return true;
  }
  return false;
}

double Container::RimZ() const {
  if (kind == Kind::kTote) return floor_mm + height_mm;
  if (kind == Kind::kMesh && !mesh.empty()) return mesh.Bounds().max().z();
  return 0.0;
}

bool Container::Check(std::string* why) const {
  if (kind == Kind::kFloor) return material.Check(why);
  if (kind == Kind::kMesh) {
    // (Empty until the file it comes from is read; PileOptions::Check wants triangles.)
    const Eigen::AlignedBox3d box =
        mesh.empty() ? Eigen::AlignedBox3d(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones())
                     : mesh.Bounds();
    if (!box.sizes().allFinite() || !(box.sizes().head<2>().minCoeff() > 0)) {
      *why = "a mesh container must have a floor plan (its x and y extents must be positive)";
      return false;
    }
    return material.Check(why);
  }
  if (!(inner_mm.minCoeff() > 0) || !inner_mm.allFinite()) {
    *why = "inner: a tote's inner size must be positive";
  } else if (!(height_mm > 0)) {
    *why = "height of a tote must be positive";
  } else if (!(wall_mm > 0)) {
    *why = "wall of a tote must be positive";
  } else if (!(floor_mm > 0)) {
    *why = "floor of a tote must be positive";
  } else if (!(corner_radius_mm >= 0) || 2 * corner_radius_mm > inner_mm.minCoeff()) {
    std::ostringstream m;
    m << "corner_radius must lie between 0 and half the tote's inner width ("
      << 0.5 * inner_mm.minCoeff() << " mm)";
    *why = m.str();
  } else {
    return material.Check(why);
  }
  return false;
}

bool PileOptions::Check(std::string* why) const {
  if (bodies.empty()) {
    *why = "a pile needs at least one body";
  } else if (bodies.size() > 1000) {
    *why = "at most 1000 bodies per pile";
  } else if (!container.Check(why)) {
    return false;
  } else if (container.kind == Container::Kind::kMesh && container.mesh.empty()) {
    *why = "a mesh container needs triangles";
  } else if (!(drop_size_mm.minCoeff() >= 0)) {
    *why = "the drop region's size must not be negative";
  } else if (!(drop_height_mm >= 0)) {
    *why = "the drop height must not be negative";
  } else if (!(time_step_s > 0 && time_step_s <= 0.02)) {
    *why = "the time step must lie in (0, 0.02] s";
  } else if (solver_iterations < 1 || solver_iterations > 1000) {
    *why = "solver iterations must be 1 to 1000";
  } else if (!(max_seconds > 0 && max_seconds <= 600)) {
    *why = "the simulated time limit must lie in (0, 600] s";
  } else if (!(calm_after_s >= 0)) {
    *why = "calm_after must not be negative";
  } else if (!(rest_speed_mm_s > 0) || !(rest_angular_rad_s > 0) || !(rest_seconds > 0)) {
    *why = "rest thresholds must be positive";
  } else if (!(confirm_seconds >= 0 && confirm_seconds <= 60) || !(confirm_drift_mm > 0)) {
    *why = "the rest's confirmation needs 0 to 60 s and a positive drift";
  } else {
    for (const PhysicsMaterial& m : materials) {
      if (!m.Check(why)) return false;
    }
    return true;
  }
  return false;
}

Eigen::Quaterniond UniformRotation(double u1, double u2, double u3) {
  const double a = std::sqrt(1 - u1), b = std::sqrt(u1);
  const double t1 = 2 * M_PI * u2, t2 = 2 * M_PI * u3;
  return Eigen::Quaterniond(b * std::cos(t2), a * std::sin(t1), a * std::cos(t1), b * std::sin(t2));
}

Mesh MakeContainerMesh(const Container& c) {
  if (c.kind == Container::Kind::kMesh) return c.mesh;
  Mesh mesh;
  if (c.kind != Container::Kind::kTote) return mesh;
  const std::vector<Eigen::Vector2d> inner = Outline(c, 0.0), outer = Outline(c, c.wall_mm);
  const size_t n = inner.size();
  const double top = c.floor_mm + c.height_mm;
  const auto ring = [&](const std::vector<Eigen::Vector2d>& outline, double z) {
    const auto base = static_cast<uint32_t>(mesh.positions.size());
    for (const Eigen::Vector2d& p : outline)
      mesh.positions.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()),
                                  static_cast<float>(z));
    return base;
  };
  const uint32_t outer_bottom = ring(outer, 0.0), outer_top = ring(outer, top);
  const uint32_t inner_top = ring(inner, top), inner_bottom = ring(inner, c.floor_mm);
  const auto quad = [&](uint32_t a, uint32_t b, uint32_t cc, uint32_t d) {  // counter-clockwise
    mesh.triangles.emplace_back(a, b, cc);
    mesh.triangles.emplace_back(a, cc, d);
  };
  for (size_t k = 0; k < n; ++k) {
    const auto i = static_cast<uint32_t>(k), j = static_cast<uint32_t>((k + 1) % n);
    quad(outer_bottom + i, outer_bottom + j, outer_top + j, outer_top + i);  // outside, facing out
    quad(outer_top + i, outer_top + j, inner_top + j, inner_top + i);        // rim, facing up
    quad(inner_top + i, inner_top + j, inner_bottom + j, inner_bottom + i);  // inside, facing in
  }
  for (uint32_t k = 1; k + 1 < n; ++k) {
    mesh.triangles.emplace_back(inner_bottom, inner_bottom + k, inner_bottom + k + 1);  // up
    mesh.triangles.emplace_back(outer_bottom, outer_bottom + k + 1, outer_bottom + k);  // down
  }
  // Flat faces stay flat; the rounded corners' facets (11.25 degrees apart) are smoothed.
  ComputeCreaseNormals(&mesh, 30.0 * M_PI / 180.0);
  return mesh;
}

PileResult DropPile(const std::vector<Part>& parts, const std::vector<CollisionShape>& shapes,
                    const PileOptions& o) {
  CheckInputs(parts, shapes, o);
  Simulation sim(parts, shapes, o);
  Eigen::Vector2d region = o.drop_size_mm;
  if (!(region.minCoeff() > 0)) {
    if (o.container.kind == Container::Kind::kTote) {
      region = o.container.inner_mm - Eigen::Vector2d::Constant(20.0);
    } else if (o.container.kind == Container::Kind::kMesh) {
      region = (o.container.mesh.Bounds().sizes().head<2>() - Eigen::Vector2d::Constant(20.0))
                   .cwiseMax(1.0);
    } else {
      region = Eigen::Vector2d(300.0, 300.0);
    }
  }
  // Over the middle of a mesh container's floor plan, else over the origin.
  const Eigen::Vector2d centre = o.container.kind == Container::Kind::kMesh
                                     ? Eigen::Vector2d(o.container.mesh.Bounds().center().head<2>())
                                     : Eigen::Vector2d::Zero();
  // Start positions: for each body in turn, a few random spots in the region; the one where its
  // bounding sphere clears every earlier body's at the lowest height wins.
  double top = o.container.RimZ();
  for (const PileOptions::Fixed& f : o.fixed) {
    for (const Eigen::Vector3d& corner : sim.models[f.part].corners_in_model)
      top = std::max(top, (f.world_from_model * corner).z());
  }
  const double base = top + o.drop_height_mm;
  struct Sphere {
    Eigen::Vector3d centre;
    double radius;
  };
  std::vector<Sphere> placed;
  const double gap = 2.0;
  for (size_t i = 0; i < o.bodies.size(); ++i) {
    const int part = o.bodies[i];
    const BodyModel& m = sim.models[part];
    const auto draw = [&](const RandomStream& s, uint64_t index) {
      return UniformDraw(o.seed, s, (static_cast<uint64_t>(i) << 8) + index);
    };
    const Eigen::Quaterniond q =
        UniformRotation(UniformDraw(o.seed, streams::kDropRotation, (uint64_t{i} << 2) + 0),
                        UniformDraw(o.seed, streams::kDropRotation, (uint64_t{i} << 2) + 1),
                        UniformDraw(o.seed, streams::kDropRotation, (uint64_t{i} << 2) + 2));
    const double r = m.radius_mm;
    const Eigen::Vector2d half = (0.5 * region - Eigen::Vector2d::Constant(r)).cwiseMax(0.0);
    Eigen::Vector3d best(0, 0, 1e300);
    for (uint64_t attempt = 0; attempt < 8; ++attempt) {
      const Eigen::Vector2d xy =
          centre +
          Eigen::Vector2d((2 * draw(streams::kDropPosition, attempt << 1) - 1) * half.x(),
                          (2 * draw(streams::kDropPosition, (attempt << 1) + 1) - 1) * half.y());
      double z = base + r;
      for (const Sphere& s : placed) {
        const double reach = r + s.radius + gap;
        const double d2 = (xy - s.centre.head<2>()).squaredNorm();
        if (d2 < reach * reach) z = std::max(z, s.centre.z() + std::sqrt(reach * reach - d2));
      }
      if (z < best.z()) best = Eigen::Vector3d(xy.x(), xy.y(), z);
    }
    placed.push_back({best, r});
    // The body's centre of mass at the sphere's centre, turned by q.
    Eigen::Isometry3d world_from_body = Eigen::Isometry3d::Identity();
    world_from_body.linear() = q.toRotationMatrix();
    world_from_body.translation() = best;
    sim.AddBody(part, world_from_body * m.model_from_body.inverse(), o);
  }
  PileResult result;
  sim.Run(o, &result);
  Confirm(parts, shapes, o, &result);
  result.escaped = sim.Escaped(o, result.world_from_model);
  return result;
}

PileResult ContinuePile(const std::vector<Part>& parts, const std::vector<CollisionShape>& shapes,
                        const PileOptions& o, const std::vector<Eigen::Isometry3d>& poses,
                        double seconds) {
  CheckInputs(parts, shapes, o);
  if (poses.size() != o.bodies.size()) throw Error("pile: one pose per body needed");
  if (!(seconds > 0 && seconds <= 600)) throw Error("pile: simulate 0 to 600 s");
  Restart again(parts, shapes, o, poses);
  PileResult result;
  result.steps = again.Step(seconds);
  result.seconds = result.steps * o.time_step_s;
  result.world_from_model = again.Poses();
  const std::vector<double> drift = again.Drift();
  result.drift_mm = *std::max_element(drift.begin(), drift.end());
  return result;
}

std::vector<PileContact> PileContacts(const std::vector<Part>& parts,
                                      const std::vector<CollisionShape>& shapes,
                                      const PileOptions& o,
                                      const std::vector<Eigen::Isometry3d>& poses) {
  CheckInputs(parts, shapes, o);
  if (poses.size() != o.bodies.size()) throw Error("pile: one pose per body needed");
  Simulation sim(parts, shapes, o);
  for (size_t i = 0; i < poses.size(); ++i) sim.AddBody(o.bodies[i], poses[i], o);
  sim.world.world.performDiscreteCollisionDetection();
  std::map<const btCollisionObject*, int> index;
  for (size_t i = 0; i < sim.bodies.size(); ++i) index[sim.bodies[i]] = static_cast<int>(i);
  constexpr double kWithinMm = 0.5, kCarries = 0.1;
  // Per pair (a < b): -1 side by side, 0 a rests on b, 1 b rests on a (a pair touching at
  // several points with normals of both kinds: the first kind found that carries weight).
  std::map<std::pair<int, int>, int> pairs;
  btCollisionDispatcher& dispatcher = sim.world.dispatcher;
  for (int m = 0; m < dispatcher.getNumManifolds(); ++m) {
    const btPersistentManifold* manifold = dispatcher.getManifoldByIndexInternal(m);
    const auto a = index.find(manifold->getBody0()), b = index.find(manifold->getBody1());
    if (a == index.end() || b == index.end()) continue;  // the container or a fixed part
    for (int k = 0; k < manifold->getNumContacts(); ++k) {
      const btManifoldPoint& point = manifold->getContactPoint(k);
      if (point.getDistance() > kWithinMm * kUnitsPerMm) continue;
      // m_normalWorldOnB points from body 1 towards body 0.
      const double up = point.m_normalWorldOnB.z();
      int kind = -1;
      if (up > kCarries) kind = 0;   // body 0 rests on body 1
      if (up < -kCarries) kind = 1;  // body 1 rests on body 0
      int lo = a->second, hi = b->second;
      if (lo > hi) {
        std::swap(lo, hi);
        if (kind >= 0) kind = 1 - kind;
      }
      auto [at, added] = pairs.emplace(std::make_pair(lo, hi), kind);
      if (!added && at->second < 0) at->second = kind;
    }
  }
  std::vector<PileContact> contacts;
  for (const auto& [pair, kind] : pairs) {
    const auto [a, b] = pair;
    if (kind < 0) {
      contacts.push_back({a, -1, b});
    } else if (kind == 0) {
      contacts.push_back({b, a, -1});
    } else {
      contacts.push_back({a, b, -1});
    }
  }
  return contacts;
}

PileResult SettleAfterPick(const std::vector<Part>& parts,
                           const std::vector<CollisionShape>& shapes, const PileOptions& o,
                           const std::vector<Eigen::Isometry3d>& poses, int picked,
                           std::vector<bool>* freed_out) {
  if (picked < 0 || static_cast<size_t>(picked) >= o.bodies.size())
    throw Error("pile: pick of body " + std::to_string(picked) + ", which does not exist");
  // Free: what touched the picked body, then whatever rests on something free.
  const std::vector<PileContact> contacts = PileContacts(parts, shapes, o, poses);
  std::vector<bool> free(o.bodies.size(), false);
  for (const PileContact& c : contacts) {
    const int a = c.lower, b = c.upper >= 0 ? c.upper : c.other;
    if (a == picked) free[b] = true;
    if (b == picked) free[a] = true;
  }
  for (bool grew = true; grew;) {
    grew = false;
    for (const PileContact& c : contacts) {
      if (c.upper >= 0 && c.upper != picked && !free[c.upper] &&
          (free[c.lower] || c.lower == picked)) {
        free[c.upper] = true;
        grew = true;
      }
    }
  }
  free[picked] = false;
  // The remaining bodies, the free ones simulated, the held ones fixed where they are.
  std::vector<int> remaining;
  PileOptions settle = o;
  settle.bodies.clear();
  std::vector<Eigen::Isometry3d> start;
  std::vector<int> free_index;  // per free body: its index in `remaining`
  for (size_t i = 0; i < o.bodies.size(); ++i) {
    if (static_cast<int>(i) == picked) continue;
    remaining.push_back(static_cast<int>(i));
    if (free[i]) {
      free_index.push_back(static_cast<int>(remaining.size()) - 1);
      settle.bodies.push_back(o.bodies[i]);
      start.push_back(poses[i]);
    } else {
      settle.fixed.push_back({o.bodies[i], poses[i]});
    }
  }
  PileResult result;
  for (int i : remaining) result.world_from_model.push_back(poses[i]);
  freed_out->assign(remaining.size(), false);
  for (int k : free_index) (*freed_out)[k] = true;
  if (settle.bodies.empty()) return result;  // nothing leaned on it
  CheckInputs(parts, shapes, settle);
  Simulation sim(parts, shapes, settle);
  for (size_t k = 0; k < start.size(); ++k) sim.AddBody(settle.bodies[k], start[k], settle);
  PileResult moved;
  sim.Run(settle, &moved);
  Confirm(parts, shapes, settle, &moved);
  moved.escaped = sim.Escaped(settle, moved.world_from_model);
  for (size_t k = 0; k < free_index.size(); ++k) {
    const int i = free_index[k];
    result.world_from_model[i] = moved.world_from_model[k];
    double d = 0;
    for (const Eigen::Vector3d& corner : sim.models[settle.bodies[k]].corners_in_model)
      d = std::max(d, (moved.world_from_model[k] * corner - start[k] * corner).norm());
    result.drift_mm = std::max(result.drift_mm, d);
  }
  for (int k : moved.restless) result.restless.push_back(free_index[k]);
  for (int k : moved.escaped) result.escaped.push_back(free_index[k]);
  result.seconds = moved.seconds;
  result.steps = moved.steps;
  return result;
}

}  // namespace cadsynth
