#include "tools/pipeline/frames.h"

#include <algorithm>
#include <chrono>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "cad/core/error.h"
#include "cad/part_cache.h"
#include "render/randomize.h"
#include "render/renderer.h"
#include "render/sampling.h"
#include "tools/pipeline/generate.h"
#include "tools/pipeline/journal.h"

namespace cadsynth {

// A scene ready to render: its renderer, and what domain randomisation draws around.
struct FrameSource::SceneState {
  std::unique_ptr<Renderer> renderer;
  FrameLook base_look;
  // The middle of its instances on the floor: randomised lights are placed about it.
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
};

// Built scenes, at most kKeep of them (the most recently asked for; a renderer in use stays
// alive through its shared_ptr). Each scene has its own slot and lock, so building one never
// holds up another.
struct FrameSource::Cache {
  static constexpr size_t kKeep = 2;
  struct Slot {
    std::mutex mutex;
    std::shared_ptr<const SceneState> state;
  };
  std::mutex mutex;  // guards `slots` and `recent`
  std::map<size_t, std::shared_ptr<Slot>> slots;
  std::vector<size_t> recent;  // scenes with a built state, most recent last
};

struct FrameSource::GraspState {
  std::once_flag sampled;
  std::vector<std::vector<ParallelJawGrasp>> jaw;  // per part
  std::vector<std::vector<SuctionGrasp>> suction;  // per part; empty without a cup
  std::vector<std::once_flag> placed_once;         // per scene
  std::vector<SceneGrasps> placed;                 // per scene
};

FrameSource::FrameSource(const RunSpec& spec, const FrameSourceOptions& options)
    : spec_(spec), options_(options), cache_(std::make_unique<Cache>()) {
  std::string why;
  if (!spec_.intrinsics.Check(&why)) throw Error("camera: " + why);
  sensors_ = RunSensors(spec_);
  for (const RigSensor& sensor : sensors_) {
    if (!sensor.intrinsics.Check(&why)) throw Error("camera '" + sensor.name + "': " + why);
  }
  if (!spec_.sweep.Check(&why)) throw Error("sweep: " + why);
  if (!spec_.bop.Check(&why)) throw Error("output: " + why);
  if (spec_.grasps.enabled && spec_.grasps.labels.suctionnet && !spec_.grasps.suction)
    throw Error("grasps: the suctionnet format needs a suction cup (grasps.suction)");
  CheckLimits(spec_);  // a RunSpec built in code has not been through the recipe reader

  std::optional<PartCache> cache;
  if (options_.cache) cache.emplace(*options_.cache, BuildId());
  std::optional<ReaderProcess> reader;
  if (!options_.reader.empty())
    reader = ReaderProcess{options_.reader, spec_.limits.read_timeout_s};
  PrepareControls controls;
  controls.strict = options_.strict;
  controls.progress = options_.stage_progress;
  prepared_ = Prepare(spec_, options_.info, cache ? &*cache : nullptr, reader ? &*reader : nullptr,
                      controls);
  if (!spec_.sampler.Check(&why)) throw Error("sweep: " + why);
  views_ = SampleViews(spec_.sampler, spec_.sweep);
  if (spec_.grasps.enabled) {
    grasps_ = std::make_unique<GraspState>();
    grasps_->placed_once = std::vector<std::once_flag>(prepared_.scenes.size());
    grasps_->placed.resize(prepared_.scenes.size());
  }
}

FrameSource::~FrameSource() = default;

std::shared_ptr<const FrameSource::SceneState> FrameSource::Scene(size_t s) const {
  std::shared_ptr<Cache::Slot> slot;
  {
    std::lock_guard<std::mutex> lock(cache_->mutex);
    auto& entry = cache_->slots[s];
    if (!entry) entry = std::make_shared<Cache::Slot>();
    slot = entry;
  }
  std::shared_ptr<const SceneState> state;
  {
    std::lock_guard<std::mutex> lock(slot->mutex);
    if (!slot->state) {
      // Isolated: Embree's BVH build waits on TBB tasks, and a thread waiting outside isolation
      // may pick up another frame of a pipeline, which would ask for this scene again and block
      // on the lock it holds itself.
      tbb::this_task_arena::isolate([&] {
        auto built = std::make_shared<SceneState>();
        RenderOptions render = spec_.render;
        render.amodal_depth = spec_.bop.visibility == BopOptions::Visibility::kBop19;
        const cadsynth::Scene& scene = prepared_.scenes[s];
        built->renderer = std::make_unique<Renderer>(prepared_.parts, scene, render);
        if (prepared_.randomization[s].changes_look())
          built->base_look = built->renderer->BaseLook();
        if (!scene.instances.empty()) {
          Eigen::AlignedBox3d box;
          for (const Instance& instance : scene.instances)
            box.extend(instance.world_from_model.translation());
          built->centre = box.center();
          built->centre.z() = 0.0;
        }
        slot->state = std::move(built);
      });
    }
    state = slot->state;
  }
  // The most recent scenes stay built; older ones are dropped (rebuilt if asked for again).
  std::vector<std::shared_ptr<const SceneState>> dropped;  // freed outside the lock
  {
    std::lock_guard<std::mutex> lock(cache_->mutex);
    auto& recent = cache_->recent;
    recent.erase(std::remove(recent.begin(), recent.end(), s), recent.end());
    recent.push_back(s);
    while (recent.size() > Cache::kKeep) {
      auto it = cache_->slots.find(recent.front());
      if (it != cache_->slots.end()) {
        std::lock_guard<std::mutex> slot_lock(it->second->mutex);
        dropped.push_back(std::move(it->second->state));
        it->second->state.reset();
      }
      recent.erase(recent.begin());
    }
  }
  return state;
}

void FrameSource::BuildScene(size_t scene) const { Scene(scene); }

void FrameSource::ReleaseScene(size_t scene) const {
  std::shared_ptr<const SceneState> dropped;
  std::lock_guard<std::mutex> lock(cache_->mutex);
  auto it = cache_->slots.find(scene);
  if (it == cache_->slots.end()) return;
  {
    std::lock_guard<std::mutex> slot_lock(it->second->mutex);
    dropped = std::move(it->second->state);
    it->second->state.reset();
  }
  auto& recent = cache_->recent;
  recent.erase(std::remove(recent.begin(), recent.end(), scene), recent.end());
}

RenderedView FrameSource::Render(size_t unit) const {
  if (views_.empty() || unit >= units())
    throw Error("frame " + std::to_string(unit) + " of a run of " + std::to_string(units()));
  RenderedView out;
  out.scene = unit / views_.size();
  out.view = unit % views_.size();
  const size_t s = out.scene, i = out.view;
  const std::shared_ptr<const SceneState> state = Scene(s);
  const Randomization& randomization = prepared_.randomization[s];
  // One unit renders every sensor of the rig at view i: sensor k sits at
  // world_from_rig * rig_from_cam and draws its noise from the key (view, k).
  for (size_t k = 0; k < sensors_.size(); ++k) {
    if (!randomization.active()) {
      const Camera camera{sensors_[k].intrinsics,
                          views_[i].world_from_cam * sensors_[k].rig_from_cam};
      out.frames.push_back(
          state->renderer->Render(camera, SensorFrameKey(i, k), sensors_[k].sensor));
      continue;
    }
    // Every sensor of the rig draws the same numbers (the keys name the scene, the view and the
    // quantity, not the sensor).
    const FrameDraw draw = DrawFrame(randomization, state->base_look, views_[i].world_from_cam,
                                     sensors_[k].sensor, state->centre, s, i);
    const Camera camera{sensors_[k].intrinsics, draw.world_from_cam * sensors_[k].rig_from_cam};
    Frame frame = state->renderer->Render(camera, SensorFrameKey(i, k), draw.sensor,
                                          randomization.changes_look() ? &draw.look : nullptr);
    frame.randomization = RandomizationRecord(draw.record);
    out.frames.push_back(std::move(frame));
  }
  // A rig pose is kept when any of its sensors sees enough.
  for (const Frame& frame : out.frames) {
    int seen = 0;
    for (const Frame::InstanceTruth& t : frame.instances) seen += t.px_count_visib;
    out.visible_pixels = std::max(out.visible_pixels, seen);
  }
  out.kept = spec_.min_visible_pixels <= 0 || out.visible_pixels >= spec_.min_visible_pixels;
  return out;
}

namespace {

// What a part's grasps depend on: its mesh, its volume and centre of mass (the suction cup's
// wrench), the gripper, the cup and the samplings' options with the part's own seeds.
CacheKey GraspKey(const PartCache& cache, const Part& part, const GraspSpec& spec,
                  const AntipodalOptions& jaw, const SuctionOptions* suction) {
  KeyHasher hasher;
  cache.Start(&hasher, "grasps 1");
  hasher.Geometry(part.mesh);
  hasher.Value(part.mass.volume_mm3).Value(part.mass.center_of_mass);
  hasher.Fields(spec.gripper).Fields(jaw).Value<uint8_t>(suction != nullptr);
  if (suction != nullptr) hasher.Fields(spec.cup).Fields(*suction);
  return hasher.Key();
}

// A scene's placed grasps in the part cache (kind "scene_grasps"): keyed by each object's grasp
// key (what decides its grasps), the scene's instances and fixtures, the floor, the tools and the
// labels asked for, so a second shard or worker reads them instead of placing them again.
CacheKey SceneGraspKey(const PartCache& cache, const std::vector<Part>& parts,
                       const cadsynth::Scene& scene, const GraspSpec& spec) {
  KeyHasher hasher;
  cache.Start(&hasher, "scene grasps 1");
  for (size_t p = 0; p < parts.size(); ++p) {
    AntipodalOptions jaw = spec.sampling;
    jaw.seed = Hash(spec.sampling.seed, p);
    SuctionOptions suction = spec.suction_sampling;
    suction.seed = Hash(spec.suction_sampling.seed, p);
    const CacheKey part = GraspKey(cache, parts[p], spec, jaw, spec.suction ? &suction : nullptr);
    hasher.Value(part.high).Value(part.low);
  }
  hasher.Fields(spec.scene).Fields(spec.labels).Value(scene.floor);
  for (const cadsynth::Scene::Fixture& fixture : scene.fixtures) hasher.Geometry(fixture.mesh);
  for (const Instance& instance : scene.instances)
    hasher.Value(instance.part).Value(Eigen::Matrix4d(instance.world_from_model.matrix()));
  return hasher.Key();
}

}  // namespace

void FrameSource::SampleGraspsOnce() const {
  if (!grasps_) throw Error("the recipe asks for no grasps (grasps:)");
  std::call_once(grasps_->sampled, [&] {
    const auto start = std::chrono::steady_clock::now();
    const GraspSpec& spec = spec_.grasps;
    const std::vector<Part>& parts = prepared_.parts;
    grasps_->jaw.resize(parts.size());
    std::vector<std::vector<SuctionGrasp>> suction_grasps(parts.size());
    std::optional<PartCache> cache;
    if (options_.cache) cache.emplace(*options_.cache, BuildId());
    // Every object from its own seed; each object's grasps kept in the part cache.
    tbb::parallel_for(size_t{0}, parts.size(), [&](size_t p) {
      AntipodalOptions options = spec.sampling;
      options.seed = Hash(spec.sampling.seed, p);
      SuctionOptions suction = spec.suction_sampling;
      suction.seed = Hash(spec.suction_sampling.seed, p);
      std::optional<CacheKey> key;
      if (cache) {
        key = GraspKey(*cache, parts[p], spec, options, spec.suction ? &suction : nullptr);
        if (const std::optional<std::string> bytes = cache->Load("grasps", *key)) {
          try {
            DecodeGrasps(*bytes, &grasps_->jaw[p], &suction_grasps[p]);
            return;
          } catch (const Error&) {  // damaged: sampled again below
          }
        }
      }
      grasps_->jaw[p] = SampleAntipodalGrasps(parts[p], spec.gripper, options);
      suction_grasps[p].clear();
      if (spec.suction) suction_grasps[p] = SampleSuctionGrasps(parts[p], spec.cup, suction);
      if (key) cache->Store("grasps", *key, EncodeGrasps(grasps_->jaw[p], suction_grasps[p]));
    });
    if (spec.suction) grasps_->suction = std::move(suction_grasps);
    if (spec.suction) {
      for (const Part& part : parts) {
        if (!(part.mass.volume_mm3 > 0))
          Warn("grasps: '" + part.name +
               "' has no known volume (an open mesh): its suction grasps are scored without its "
               "weight");
      }
    }
    if (options_.info) {
      std::ostringstream line;
      line << "grasps (" << spec.gripper.name << ", mu " << spec.sampling.friction;
      if (spec.suction) line << "; suction cup " << spec.cup.name;
      line << "):";
      for (size_t p = 0; p < parts.size(); ++p) {
        line << " obj " << p + 1 << ": " << grasps_->jaw[p].size();
        if (spec.suction) line << " + " << grasps_->suction[p].size() << " suction";
      }
      line << " ("
           << std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()
           << " s)";
      options_.info(line.str());
    }
  });
}

const std::vector<std::vector<ParallelJawGrasp>>& FrameSource::ObjectJawGrasps() const {
  SampleGraspsOnce();
  return grasps_->jaw;
}

const std::vector<std::vector<SuctionGrasp>>& FrameSource::ObjectSuctionGrasps() const {
  SampleGraspsOnce();
  return grasps_->suction;
}

const SceneGrasps& FrameSource::PlacedGrasps(size_t s) const {
  SampleGraspsOnce();
  if (s >= prepared_.scenes.size()) throw Error("no scene " + std::to_string(s));
  std::call_once(grasps_->placed_once[s], [&] {
    const auto placing = std::chrono::steady_clock::now();
    const GraspSpec& spec = spec_.grasps;
    const cadsynth::Scene& scene = prepared_.scenes[s];
    GraspObstacles obstacles;
    obstacles.floor = scene.floor;
    for (const cadsynth::Scene::Fixture& fixture : scene.fixtures)
      obstacles.fixtures.push_back(&fixture.mesh);
    SceneGrasps out;  // assigned at the end: a placement that throws leaves nothing behind
    for (const Instance& instance : scene.instances) {
      obstacles.instances.push_back({&prepared_.parts[static_cast<size_t>(instance.part)].mesh,
                                     instance.world_from_model, instance.part});
      out.part_of_instance.push_back(instance.part);
    }
    out.obj_id_of_instance = prepared_.obj_ids[s];
    out.gripper = spec.gripper;
    out.cup = spec.cup;
    if (spec.labels.graspnet) out.jaw = &grasps_->jaw;
    if (spec.labels.suctionnet) out.suction = &grasps_->suction;
    std::optional<PartCache> cache;
    std::optional<CacheKey> key;
    bool cached = false;
    if (options_.cache) {
      cache.emplace(*options_.cache, BuildId());
      key = SceneGraspKey(*cache, prepared_.parts, scene, spec);
      if (const std::optional<std::string> bytes = cache->Load("scene_grasps", *key)) {
        try {
          ByteReader reader(*bytes);
          out.jaw_placed = reader.GetArray<PlacedGrasp>();
          out.suction_placed = reader.GetArray<PlacedGrasp>();
          cached = true;
        } catch (const Error&) {  // damaged: placed again below
        }
      }
    }
    if (!cached) {
      out.jaw_placed.clear();
      out.suction_placed.clear();
      if (spec.labels.graspnet)
        out.jaw_placed = PlaceParallelJawGrasps(obstacles, grasps_->jaw, spec.gripper, spec.scene);
      if (spec.labels.suctionnet)
        out.suction_placed = PlaceSuctionGrasps(obstacles, grasps_->suction, spec.cup, spec.scene);
      if (key) {
        ByteWriter writer;
        writer.PutArray(out.jaw_placed);
        writer.PutArray(out.suction_placed);
        cache->Store("scene_grasps", *key, writer.bytes());
      }
    }
    if (options_.info) {
      std::ostringstream line;
      line << "scene '" << prepared_.scene_names[s]
           << "': grasps free of the scene: " << out.jaw_placed.size();
      if (spec.labels.suctionnet) line << " + " << out.suction_placed.size() << " suction";
      line << " ("
           << std::chrono::duration<double>(std::chrono::steady_clock::now() - placing).count()
           << " s)";
      options_.info(line.str());
    }
    grasps_->placed[s] = std::move(out);
  });
  return grasps_->placed[s];
}

}  // namespace cadsynth
