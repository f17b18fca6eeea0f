#include "render/renderer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "cad/core/error.h"
#include "render/denoise.h"
#include "render/image.h"
#include "render/path_tracer.h"
#include "render/pixel_rays.h"
#include "render/ray_packet.h"
#include "render/sensor.h"

namespace cadsynth {

namespace {
// Embree's kernel widths, narrowest first, as its `isa=` device setting names them.
constexpr const char* kIsas[] = {"sse2", "sse4.2", "avx", "avx2", "avx512"};
}  // namespace

std::string TracingIsa(const std::string& requested) {
  // What this CPU (and its OS) supports, the way Embree decides: AVX-512 means the Skylake-server
  // set (F, CD, DQ, BW, VL); AVX2 comes with FMA and BMI1/2.
  int cpu = 0;
#if defined(__x86_64__) || defined(__i386__)
  __builtin_cpu_init();
  if (__builtin_cpu_supports("sse4.2")) cpu = 1;
  if (cpu == 1 && __builtin_cpu_supports("avx")) cpu = 2;
  if (cpu == 2 && __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
      __builtin_cpu_supports("bmi") && __builtin_cpu_supports("bmi2")) {
    cpu = 3;
  }
  if (cpu == 3 && __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512cd") &&
      __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512bw") &&
      __builtin_cpu_supports("avx512vl")) {
    cpu = 4;
  }
#endif
  int wanted = 4;
  for (int i = 0; i < 5; ++i) {
    if (requested == kIsas[i]) wanted = i;
  }
  return kIsas[std::min(cpu, wanted)];
}

bool RenderOptions::Check(std::string* why) const {
  if (!(near_mm >= 0) || !(far_mm > near_mm)) {
    *why = "the clip range needs 0 <= near < far";
  } else if (supersampling < 1 || supersampling > 8) {
    *why = "supersampling must be 1 to 8 samples per axis";
  } else if (std::find(std::begin(kIsas), std::end(kIsas), isa) == std::end(kIsas) &&
             isa != "auto") {
    *why = "isa must be auto, sse2, sse4.2, avx, avx2 or avx512, got '" + isa + "'";
  } else if (samples < 1 || samples > 65536) {
    *why = "samples must be 1 to 65536 paths per pixel";
  } else if (!(noise_threshold >= 0 && noise_threshold <= 1)) {
    *why = "noise_threshold must be 0 (off) or a display-value error in (0, 1]";
  } else if (min_samples < 0 || min_samples > samples) {
    *why = "min_samples must be 0 (automatic) to samples";
  } else if (background_samples < 0 || background_samples > samples) {
    *why = "background_samples must be 0 (as the objects' pixels) to samples";
  } else if (bounces < 0 || bounces > 64) {
    *why = "bounces must be 0 to 64";
  } else if (!(filter_glossy >= 0 && filter_glossy <= 10)) {
    *why = "filter_glossy must be 0 (off) to 10 (Cycles' Filter Glossy; Blender's default 1)";
  } else if (glossy_bounces < 0 || glossy_bounces > 1024) {
    *why = "glossy_bounces must be 0 to 1024 (at or above bounces: no limit of their own)";
  } else if (!(clamp_indirect >= 0 && clamp_indirect <= 1e8)) {
    *why = "clamp_indirect must be 0 (off) to 1e8 (Cycles' Clamp Indirect; Blender's default 10)";
  } else if (!(exposure >= -20 && exposure <= 20)) {
    *why = "exposure must lie between -20 and 20 stops";
  } else if (mode == Mode::kPbr && supersampling != 1) {
    *why = "supersampling is for the fast mode; pbr samples each pixel `samples` times";
  } else {
    return true;
  }
  return false;
}

namespace {

// Embree reports failures through a callback; collect the first message and throw at the API edge.
struct DeviceErrors {
  std::mutex mutex;
  std::string first;
};

void OnEmbreeError(void* user, RTCError code, const char* message) {
  auto* errors = static_cast<DeviceErrors*>(user);
  std::lock_guard<std::mutex> lock(errors->mutex);
  if (errors->first.empty()) {
    errors->first = "Embree error " + std::to_string(static_cast<int>(code)) + ": " +
                    (message != nullptr ? message : "");
  }
}

struct PartBuffers {
  std::vector<float> positions;  // xyz per vertex, plus 1 float of padding at the end for SSE loads
  std::vector<uint32_t> indices;  // 3 per triangle
  std::vector<Eigen::Vector3f> normals;
  std::vector<Eigen::Vector2f> uvs;  // per vertex, or empty
  Eigen::Vector3f box_centre = Eigen::Vector3f::Zero(), box_size = Eigen::Vector3f::Ones();
};

constexpr unsigned kInvalid = RTC_INVALID_GEOMETRY_ID;

// A mesh's arrays as Embree shares them (parts in their model frame, fixtures in the world).
PartBuffers MakeBuffers(const Mesh& mesh) {
  PartBuffers buffers;
  buffers.positions.reserve(3 * mesh.num_vertices() + 1);
  Eigen::AlignedBox3f box;
  for (const Eigen::Vector3f& p : mesh.positions) {
    buffers.positions.insert(buffers.positions.end(), {p.x(), p.y(), p.z()});
    box.extend(p);
  }
  if (!box.isEmpty()) {
    buffers.box_centre = box.center();
    buffers.box_size = box.sizes();
  }
  buffers.positions.push_back(0.0f);
  buffers.indices.reserve(3 * mesh.num_triangles());
  for (const auto& t : mesh.triangles) {
    buffers.indices.insert(buffers.indices.end(), {t[0], t[1], t[2]});
  }
  buffers.normals = mesh.normals;
  if (mesh.has_uvs()) buffers.uvs = mesh.uvs;
  return buffers;
}

}  // namespace

struct Renderer::Impl {
  RenderOptions options;
  Scene scene;
  DeviceErrors errors;
  RTCDevice device = nullptr;
  std::vector<RTCScene> part_scenes;
  RTCScene world = nullptr;    // every instance and the floor
  std::vector<RTCScene> solo;  // one instance alone, for amodal masks
  std::vector<PartBuffers> parts;
  std::vector<Eigen::AlignedBox3d> model_bounds;   // per part, model frame
  std::vector<Eigen::Matrix3f> instance_rotation;  // world_from_model rotation per instance
  std::vector<Eigen::Vector3f> albedo_of;          // colour per instance
  std::vector<Eigen::Vector3f> light_dirs;         // directional lights: unit travel direction

  struct Shaded;
  // Colours and normals of a traced packet's lanes: ambient plus every light it sees (without
  // `lights`, only the ambient term: for the normals, albedo and points alone).
  void ShadePacket(const RTCRayHit16& rh, const int valid[16], Shaded out[16],
                   bool lights = true) const;
  // A depth sensor's projector at `projector` (world): for the hits of a packet of camera rays,
  // whether it sees them (a shadow ray) and how much of its light they return to the camera
  // (render/sensor.h), written to pixel (u0 + j % 4, v0 + j / 4) of the w-wide images.
  void ProjectorPacket(const PathTracer* tracer, const RTCRayHit16& rh, const int valid[16],
                       const Shaded shaded[16], const Eigen::Vector3f& projector, float spread,
                       int u0, int v0, int w, uint8_t* seen, float* signal) const;
  // active_stereo: the noiseless IR values of a traced and shaded packet (render/sensor.h), written
  // to pixel (u0 + j % 4, v0 + j / 4) of the w-wide `out`: the dots of the projector at `projector`
  // (world; `projector_from_world` turns world directions into its frame, whose axes are the
  // camera's) where it lights the point (`seen`, `signal`: ProjectorPacket's), plus the ambient
  // share of the Lambert shading.
  void InfraredPacket(const RTCRayHit16& rh, const int valid[16], const Shaded shaded[16],
                      const uint8_t* seen, const float* signal, int u0, int v0, int w,
                      const DotTable& dots, const DepthModel& model,
                      const Eigen::Vector3f& projector, const Eigen::Matrix3f& projector_from_world,
                      float* out) const;
  // active_stereo: the noiseless IR image `camera` sees: every tile traced, shaded, lit by the
  // projector and InfraredPacket.
  std::vector<float> InfraredPass(const PathTracer* tracer, const Camera& camera,
                                  const DotTable& dots, const DepthModel& model,
                                  const Eigen::Vector3f& projector) const;
  // active_stereo: the projector's dots over the directions it lights in the field of view of a
  // camera with intrinsics `k` and of the second camera beside it, widened by the parallax of
  // points down to min_depth (closer ones are drawn as they go). Built once and kept while the
  // frames' sensor and camera stay the same.
  mutable std::mutex dots_mutex;
  mutable std::shared_ptr<const DotTable> dots_cache;
  std::shared_ptr<const DotTable> DotsOf(const DepthModel& model, const Intrinsics& k) const;
  // Per 4 x 4 tile of a w x h image seen through `rays` from `cam_from_world`: 1 where an instance
  // or a fixture may be seen. The other tiles see the floor or nothing, and skip the scene's
  // traversal (TracePacket). Exact: the rectangle of a box's projected corners holds its whole
  // projection, with a pixel of margin.
  std::vector<uint8_t> ReachableTiles(const PixelRays& rays,
                                      const Eigen::Isometry3d& cam_from_world,
                                      const std::vector<Eigen::Isometry3d>& cam_from_model) const;
  // The first hits of a packet of camera rays in a tile: the scene's traversal where `reachable`,
  // else the floor's plane alone.
  void TracePacket(bool reachable, RTCIntersectContext* context, const int* valid,
                   RTCRayHit16* rh) const;
  unsigned floor_id = kInvalid;
  // Fixtures: top-level geometry ids first_fixture_id + f, their triangles and normals (world).
  unsigned first_fixture_id = kInvalid;
  std::vector<PartBuffers> fixtures;
  std::vector<Eigen::Vector3f> fixture_albedo;
  // The fixture a hit is on, or -1.
  int FixtureOf(unsigned geom_id) const {
    if (first_fixture_id == kInvalid || geom_id == kInvalid || geom_id < first_fixture_id)
      return -1;
    const unsigned f = geom_id - first_fixture_id;
    return f < fixtures.size() ? static_cast<int>(f) : -1;
  }
  std::unique_ptr<PathTracer> tracer;            // RenderOptions::Mode::kPbr
  PathTracerScene traced;                        // what `tracer` was built from
  std::vector<Eigen::Vector3f> instance_linear;  // the instances' own colours, linear
  // The pixel rays of the cameras seen so far (a distorted camera's table costs a Newton solve
  // per pixel): a few per rig, kept for the renderer's life.
  mutable std::mutex rays_mutex;
  mutable std::vector<std::shared_ptr<const PixelRays>> rays_cache;  // at most 8
  std::shared_ptr<const PixelRays> RaysOf(const Intrinsics& k) const {
    const auto same = [&k](const Intrinsics& o) {
      const Distortion &a = k.distortion, &b = o.distortion;
      return k.width == o.width && k.height == o.height && k.fx == o.fx && k.fy == o.fy &&
             k.cx == o.cx && k.cy == o.cy && a.k1 == b.k1 && a.k2 == b.k2 && a.p1 == b.p1 &&
             a.p2 == b.p2 && a.k3 == b.k3;
    };
    std::lock_guard<std::mutex> lock(rays_mutex);
    for (const auto& r : rays_cache) {
      if (same(r->intrinsics())) return r;
    }
    // Built once, under the lock (frames rendered at the same time wait for it instead of each
    // building it), isolated so that this thread takes on no other frame's work, which would
    // wait for the lock it holds, while the table's rows run in parallel.
    std::shared_ptr<const PixelRays> rays;
    tbb::this_task_arena::isolate([&] { rays = std::make_shared<const PixelRays>(k); });
    if (rays_cache.size() >= 8) rays_cache.erase(rays_cache.begin());
    rays_cache.push_back(rays);
    return rays;
  }

  ~Impl() {
    for (RTCScene s : solo) rtcReleaseScene(s);
    if (world != nullptr) rtcReleaseScene(world);
    for (RTCScene s : part_scenes) rtcReleaseScene(s);
    if (device != nullptr) rtcReleaseDevice(device);
  }

  void ThrowIfFailed(const char* stage) {
    std::lock_guard<std::mutex> lock(errors.mutex);
    if (!errors.first.empty())
      throw Error(std::string("renderer (") + stage + "): " + errors.first);
  }

  RTCGeometry NewInstance(int index) {
    const Instance& instance = scene.instances[index];
    RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(geometry, part_scenes[instance.part]);
    const Eigen::Matrix<float, 3, 4> m =
        instance.world_from_model.matrix().topRows<3>().cast<float>();
    rtcSetGeometryTransform(geometry, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, m.data());
    rtcCommitGeometry(geometry);
    return geometry;
  }

  // The constructor's stages, in the order it runs them.
  void BuildParts(const std::vector<Part>& from);
  void BuildWorld();
  void AddFloor();
  void AddFixtures();
  void PrepareLights();
  void BuildSolo();
  void BuildTracer();

  // The path tracer a frame is shaded with (Renderer::Render): for a frame with a look of its
  // own, one over the same geometry, kept in `own`; else the renderer's (null in the fast mode).
  const PathTracer* TracerFor(const FrameLook* look, std::unique_ptr<PathTracer>* own) const;
  // One frame's state and passes (Renderer::Render).
  struct FramePasses;
};

Renderer::Renderer(const std::vector<Part>& parts, const Scene& scene, const RenderOptions& options)
    : impl_(std::make_unique<Impl>()) {
  std::string why;
  if (!options.Check(&why)) throw Error("render options: " + why);
  Impl& im = *impl_;
  im.options = options;
  im.scene = scene;
  for (const Instance& instance : scene.instances) {
    if (instance.part < 0 || static_cast<size_t>(instance.part) >= parts.size()) {
      throw Error("renderer: instance '" + instance.name + "' refers to a missing part");
    }
  }
  if (scene.instances.size() >= std::numeric_limits<uint16_t>::max()) {
    throw Error("renderer: at most 65534 instances per scene");
  }

  const std::string device_config = options.isa == "auto" ? std::string() : "isa=" + options.isa;
  im.device = rtcNewDevice(device_config.empty() ? nullptr : device_config.c_str());
  if (im.device == nullptr) throw Error("renderer: could not create an Embree device");
  rtcSetDeviceErrorFunction(im.device, OnEmbreeError, &im.errors);

  im.BuildParts(parts);
  im.ThrowIfFailed("building part geometry");
  im.BuildWorld();
  im.PrepareLights();
  im.BuildSolo();
  im.ThrowIfFailed("building the scene");
  if (options.mode == RenderOptions::Mode::kPbr) im.BuildTracer();
}

// One bottom-level scene per part, in the part's model frame.
void Renderer::Impl::BuildParts(const std::vector<Part>& from) {
  for (const Part& part : from) {
    parts.push_back(MakeBuffers(part.mesh));
    model_bounds.push_back(part.mesh.Bounds());
  }
  for (PartBuffers& buffers : parts) {
    RTCScene part_scene = rtcNewScene(device);
    // Built once per run and traced for thousands of frames: spend the build time.
    rtcSetSceneBuildQuality(part_scene, RTC_BUILD_QUALITY_HIGH);
    // Watertight triangle tests and conservative traversal: without them a ray that lands exactly
    // on an edge shared by two triangles can miss both and show the surface behind.
    rtcSetSceneFlags(part_scene, RTC_SCENE_FLAG_ROBUST);
    RTCGeometry mesh = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    const size_t num_vertices = (buffers.positions.size() - 1) / 3;
    rtcSetSharedGeometryBuffer(mesh, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                               buffers.positions.data(), 0, 3 * sizeof(float), num_vertices);
    rtcSetSharedGeometryBuffer(mesh, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                               buffers.indices.data(), 0, 3 * sizeof(uint32_t),
                               buffers.indices.size() / 3);
    rtcCommitGeometry(mesh);
    rtcAttachGeometryByID(part_scene, mesh, 0);
    rtcReleaseGeometry(mesh);
    rtcCommitScene(part_scene);
    part_scenes.push_back(part_scene);
  }
}

// The world: instance i has geometry id i; the floor comes after them.
void Renderer::Impl::BuildWorld() {
  world = rtcNewScene(device);
  // Not robust: its traversal decides only which instances a ray enters, and a ray can be lost
  // there only where it grazes an instance's bounding box, at the silhouette. Robust traversal of
  // this level cost a third of the tracing speed.
  rtcSetSceneBuildQuality(world, RTC_BUILD_QUALITY_HIGH);
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    RTCGeometry geometry = NewInstance(static_cast<int>(i));
    rtcAttachGeometryByID(world, geometry, static_cast<unsigned>(i));
    rtcReleaseGeometry(geometry);
    instance_rotation.push_back(scene.instances[i].world_from_model.linear().cast<float>());
    albedo_of.push_back(scene.InstanceColor(i));
  }
  if (scene.floor) AddFloor();
  AddFixtures();
  rtcCommitScene(world);
}

void Renderer::Impl::AddFloor() {
  const float h = static_cast<float>(scene.floor_half_size_mm);
  RTCGeometry floor = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(floor, RTC_BUFFER_TYPE_VERTEX, 0,
                                                        RTC_FORMAT_FLOAT3, 3 * sizeof(float), 4));
  const float corners[12] = {-h, -h, 0, h, -h, 0, h, h, 0, -h, h, 0};
  std::copy(corners, corners + 12, v);
  auto* idx = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
      floor, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), 2));
  const uint32_t tris[6] = {0, 1, 2, 0, 2, 3};
  std::copy(tris, tris + 6, idx);
  rtcCommitGeometry(floor);
  floor_id = static_cast<unsigned>(scene.instances.size());
  rtcAttachGeometryByID(world, floor, floor_id);
  rtcReleaseGeometry(floor);
}

void Renderer::Impl::AddFixtures() {
  first_fixture_id = static_cast<unsigned>(scene.instances.size()) + 1;
  for (size_t f = 0; f < scene.fixtures.size(); ++f) {
    const Mesh& mesh = scene.fixtures[f].mesh;
    if (mesh.empty()) throw Error("renderer: fixture '" + scene.fixtures[f].name + "' is empty");
    PartBuffers buffers = MakeBuffers(mesh);
    if (buffers.normals.size() != mesh.positions.size()) {
      throw Error("renderer: fixture '" + scene.fixtures[f].name + "' needs one normal per vertex");
    }
    fixtures.push_back(std::move(buffers));
    const PartBuffers& b = fixtures.back();
    RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                               b.positions.data(), 0, 3 * sizeof(float), mesh.positions.size());
    rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                               b.indices.data(), 0, 3 * sizeof(uint32_t), mesh.triangles.size());
    rtcCommitGeometry(geometry);
    rtcAttachGeometryByID(world, geometry, first_fixture_id + static_cast<unsigned>(f));
    rtcReleaseGeometry(geometry);
    fixture_albedo.push_back(scene.fixtures[f].color);
  }
}

void Renderer::Impl::PrepareLights() {
  for (const Scene::Light& light : scene.lights) {
    if (light.kind == Scene::Light::Kind::kDirectional && light.direction.norm() == 0) {
      throw Error("renderer: a directional light needs a direction");
    }
    light_dirs.push_back(light.direction.normalized().cast<float>());
  }
}

// Each instance alone, for its amodal mask.
void Renderer::Impl::BuildSolo() {
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    RTCScene alone = rtcNewScene(device);
    RTCGeometry geometry = NewInstance(static_cast<int>(i));
    rtcAttachGeometryByID(alone, geometry, 0);
    rtcReleaseGeometry(geometry);
    rtcCommitScene(alone);
    solo.push_back(alone);
  }
}

// The pbr mode's path tracer: the scene's materials, lights and environment over the world.
void Renderer::Impl::BuildTracer() {
  PathTracerScene pts;
  pts.world = world;
  pts.floor_id = floor_id;
  pts.bounces = options.bounces;
  pts.scalar_shading = options.shading == RenderOptions::Shading::kScalar;
  pts.filter_glossy = static_cast<float>(options.filter_glossy);
  pts.glossy_bounces = options.glossy_bounces;
  pts.clamp_indirect = static_cast<float>(options.clamp_indirect);
  pts.near_mm = static_cast<float>(options.near_mm);
  pts.far_mm = static_cast<float>(options.far_mm);
  pts.floor = scene.floor_material;
  pts.first_fixture_id = first_fixture_id;
  for (size_t f = 0; f < fixtures.size(); ++f) {
    TracedFixture tf;
    tf.indices = fixtures[f].indices.data();
    tf.normals = fixtures[f].normals.data();
    tf.box_centre = fixtures[f].box_centre;
    tf.box_size = fixtures[f].box_size;
    tf.material = scene.fixtures[f].material;
    pts.fixtures.push_back(std::move(tf));
  }
  pts.lights = scene.light_sources;
  pts.environment = scene.environment;
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    const Instance& instance = scene.instances[i];
    const PartBuffers& buffers = parts[static_cast<size_t>(instance.part)];
    TracedInstance ti;
    ti.indices = buffers.indices.data();
    ti.normals = buffers.normals.data();
    ti.uvs = buffers.uvs.empty() ? nullptr : buffers.uvs.data();
    ti.rotation = instance_rotation[i];
    ti.translation = instance.world_from_model.translation().cast<float>();
    ti.box_centre = buffers.box_centre;
    ti.box_size = buffers.box_size;
    ti.material = scene.InstanceMaterial(i);
    Eigen::Vector3f linear;
    for (int c = 0; c < 3; ++c) linear[c] = SrgbToLinear(albedo_of[i][c]);
    instance_linear.push_back(linear);
    pts.instances.push_back(std::move(ti));
  }
  std::string why;
  for (const Material& m : scene.materials) {
    if (!m.Check(&why)) throw Error("renderer: material: " + why);
  }
  if (!scene.floor_material.Check(&why)) throw Error("renderer: floor material: " + why);
  for (const Scene::Fixture& f : scene.fixtures) {
    if (!f.material.Check(&why)) throw Error("renderer: fixture '" + f.name + "': " + why);
  }
  for (const LightSource& l : scene.light_sources) {
    if (!l.Check(&why)) throw Error("renderer: light: " + why);
  }
  if (!scene.environment.Check(&why)) throw Error("renderer: environment: " + why);
  traced = pts;
  tracer = std::make_unique<PathTracer>(std::move(pts));
}
FrameLook Renderer::BaseLook() const {
  const Impl& im = *impl_;
  FrameLook look;
  for (const TracedInstance& ti : im.traced.instances)
    look.instance_materials.push_back(ti.material);
  look.instance_colors = im.instance_linear;
  look.floor = im.traced.floor;
  for (const TracedFixture& tf : im.traced.fixtures) look.fixture_materials.push_back(tf.material);
  look.lights = im.traced.lights;
  look.environment = im.traced.environment;
  return look;
}

Renderer::~Renderer() = default;

namespace {

constexpr int kTile = 4;  // 4 x 4 pixels: one 16-ray packet

inline uint8_t ToByte(float value) {
  // Round half up; for values clamped to [0, 255] this equals std::lround, at a fraction of the
  // cost.
  return static_cast<uint8_t>(std::clamp(value, 0.0f, 1.0f) * 255.0f + 0.5f);
}

// Pixel rectangle [u0, u1) x [v0, v1) covering the projection of a box, or the whole image when
// part of the box is behind the camera.
struct PixelRect {
  int u0, v0, u1, v1;
};

// The pixels that can see `model_box`, clamped to `bounds` (all of it when a corner lies behind
// the camera).
PixelRect ProjectedRect(const Eigen::AlignedBox3d& model_box,
                        const Eigen::Isometry3d& cam_from_model, const Intrinsics& k,
                        const PixelRect& bounds) {
  const PixelRect whole = bounds;
  double umin = std::numeric_limits<double>::infinity(), vmin = umin;
  double umax = -umin, vmax = -umin;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d corner =
        model_box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c));
    const Eigen::Vector3d p = cam_from_model * corner;
    if (p.z() <= 1e-6) return whole;
    const double u = k.fx * p.x() / p.z() + k.cx, v = k.fy * p.y() / p.z() + k.cy;
    umin = std::min(umin, u);
    umax = std::max(umax, u);
    vmin = std::min(vmin, v);
    vmax = std::max(vmax, v);
  }
  // Pixel centres at +0.5: pixel u is inside when umin <= u + 0.5 <= umax. One pixel of margin.
  PixelRect r;
  const auto clamp = [](double x, int lo, int hi) {
    return static_cast<int>(std::clamp(x, static_cast<double>(lo), static_cast<double>(hi)));
  };
  r.u0 = clamp(std::floor(umin - 0.5) - 1, bounds.u0, bounds.u1);
  r.u1 = clamp(std::ceil(umax - 0.5) + 2, bounds.u0, bounds.u1);
  r.v0 = clamp(std::floor(vmin - 0.5) - 1, bounds.v0, bounds.v1);
  r.v1 = clamp(std::ceil(vmax - 0.5) + 2, bounds.v0, bounds.v1);
  return r;
}

// The camera's rays: origin, and direction with camera-frame z = 1 so that t is the depth:
// world direction = col0 * x + col1 * y + col2 for the ray (x, y, 1) of a pixel (PixelRays).
struct RayGen {
  Eigen::Matrix3f rotation;
  Eigen::Vector3f origin;
  const PixelRays* rays;
  Eigen::Vector3f col0, col1, col2;
  RayGen(const Eigen::Matrix3f& r, const Eigen::Vector3f& o, const PixelRays* pixel_rays)
      : rotation(r), origin(o), rays(pixel_rays), col0(r.col(0)), col1(r.col(1)), col2(r.col(2)) {}
};

// The pixels that can see `model_box`, clamped to `bounds`: ProjectedRect for a pinhole camera,
// and through the lens distortion otherwise.
PixelRect ImageRect(const PixelRays& rays, const Eigen::AlignedBox3d& model_box,
                    const Eigen::Isometry3d& cam_from_model, const PixelRect& bounds) {
  if (!rays.distorted()) return ProjectedRect(model_box, cam_from_model, rays.intrinsics(), bounds);
  const double inf = std::numeric_limits<double>::infinity();
  double x0 = inf, y0 = inf, x1 = -inf, y1 = -inf;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d p =
        cam_from_model * model_box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c));
    if (p.z() <= 1e-6) {  // behind the camera: any ray may reach it
      x0 = y0 = -inf, x1 = y1 = inf;
      break;
    }
    x0 = std::min(x0, p.x() / p.z()), x1 = std::max(x1, p.x() / p.z());
    y0 = std::min(y0, p.y() / p.z()), y1 = std::max(y1, p.y() / p.z());
  }
  const int b[4] = {bounds.u0, bounds.v0, bounds.u1, bounds.v1};
  int r[4];
  rays.RectOfPlane(x0, y0, x1, y1, b, r);
  return PixelRect{r[0], r[1], r[2], r[3]};
}

// Sets lane j of a shadow packet: from surface point `p` along unit `d` up to `tfar`, starting a
// little off the surface (float error at a metre is ~1e-4 mm).
void SetShadowLane(RTCRay16* ray, int j, const Eigen::Vector3f& p, const Eigen::Vector3f& d,
                   float tfar) {
  SetRayLane(ray, j, p, d, 0.05f, tfar);
}

// Sets lane j of a packet to the camera ray along world direction `d`, with no hit yet.
void SetLane(RTCRayHit16* rh, int j, const Eigen::Vector3f& origin, const Eigen::Vector3f& d,
             float tnear, float tfar) {
  SetRayLane(&rh->ray, j, origin, d, tnear, tfar);
  rh->hit.geomID[j] = kInvalid;
  rh->hit.primID[j] = kInvalid;
  rh->hit.instID[0][j] = kInvalid;
}

// Fills a 16-ray packet for the 4 x 4 tile at (u0, v0) through points (u + du, v + dv) of its
// pixels: from tabulated x(u), y(v) when `xs` is given (a pinhole camera), else from the pixel
// rays (lanes without a ray are off).
void InitPacket(const RayGen& gen, int u0, int v0, int w, int h, const std::vector<float>* xs,
                const std::vector<float>* ys, float du, float dv, float tnear, float tfar,
                RTCRayHit16* rh, int valid[16]) {
  for (int j = 0; j < 16; ++j) {
    const int u = u0 + j % kTile, v = v0 + j / kTile;
    bool in = u < w && v < h;
    Eigen::Vector2f xy = Eigen::Vector2f::Zero();
    if (xs != nullptr) {
      xy = Eigen::Vector2f((*xs)[static_cast<size_t>(u)], (*ys)[static_cast<size_t>(v)]);
    } else if (in) {
      in = gen.rays->At(u, v, du, dv, &xy);
    }
    valid[j] = in ? -1 : 0;
    SetLane(rh, j, gen.origin, gen.col0 * xy.x() + gen.col1 * xy.y() + gen.col2, tnear, tfar);
  }
}

// A 4 x 4 packet at any pixel (u0, v0) of the 3x canvas, where the tabulated directions do not
// reach; lanes outside `rect` or without a ray are off. Same directions as InitPacket inside the
// image.
void InitCanvasPacket(const RayGen& gen, int u0, int v0, const PixelRect& rect, float tnear,
                      float tfar, RTCRayHit16* rh, int valid[16]) {
  for (int j = 0; j < 16; ++j) {
    const int u = u0 + j % kTile, v = v0 + j / kTile;
    Eigen::Vector2f xy = Eigen::Vector2f::Zero();
    const bool in = u < rect.u1 && v < rect.v1 && gen.rays->Anywhere(u, v, &xy);
    valid[j] = in ? -1 : 0;
    SetLane(rh, j, gen.origin, gen.col0 * xy.x() + gen.col1 * xy.y() + gen.col2, tnear, tfar);
  }
}

// Intersects the valid lanes of a packet with the floor, the square |x|, |y| <= half of the plane
// z = 0, directly: for tiles that no instance can reach, where the floor is all there is to hit.
void IntersectFloor(const int valid[16], float half, unsigned floor_id, RTCRayHit16* rh) {
  for (int j = 0; j < 16; ++j) {
    if (!valid[j] || rh->ray.dir_z[j] == 0.0f) continue;
    const float t = -rh->ray.org_z[j] / rh->ray.dir_z[j];
    if (!(t >= rh->ray.tnear[j] && t <= rh->ray.tfar[j])) continue;
    const float x = rh->ray.org_x[j] + t * rh->ray.dir_x[j],
                y = rh->ray.org_y[j] + t * rh->ray.dir_y[j];
    if (!(std::abs(x) <= half && std::abs(y) <= half)) continue;
    rh->ray.tfar[j] = t;
    rh->hit.geomID[j] = floor_id;
    rh->hit.primID[j] = 0;
    rh->hit.u[j] = rh->hit.v[j] = 0.0f;
    rh->hit.Ng_x[j] = rh->hit.Ng_y[j] = 0.0f;
    rh->hit.Ng_z[j] = 1.0f;
  }
}

}  // namespace

// One shaded sample of a packet lane.
struct Renderer::Impl::Shaded {
  Eigen::Vector3f color;
  Eigen::Vector3f normal;  // world, facing the camera (zero when nothing was hit)
  Eigen::Vector3f albedo;  // the Lambert colour (zero when nothing was hit)
  Eigen::Vector3f point;   // world (when something was hit)
};

void Renderer::Impl::ShadePacket(const RTCRayHit16& rh, const int valid[16], Shaded out[16],
                                 bool lights) const {
  const Eigen::Vector3f background = scene.background_color;
  Eigen::Vector3f albedo[16];
  Eigen::Vector3f point[16];
  bool hit[16];
  for (int j = 0; j < 16; ++j) {
    hit[j] = valid[j] != 0 && rh.hit.geomID[j] != kInvalid;
    out[j].color = background;
    out[j].normal.setZero();
    out[j].albedo.setZero();
    if (!hit[j]) continue;
    const Eigen::Vector3f dir(rh.ray.dir_x[j], rh.ray.dir_y[j], rh.ray.dir_z[j]);
    const unsigned inst = rh.hit.instID[0][j];
    Eigen::Vector3f normal;
    if (inst != kInvalid) {
      const PartBuffers& buffers = parts[scene.instances[inst].part];
      const uint32_t* tri = &buffers.indices[3 * rh.hit.primID[j]];
      const float b1 = rh.hit.u[j], b2 = rh.hit.v[j], b0 = 1.0f - b1 - b2;
      normal =
          instance_rotation[inst] * (b0 * buffers.normals[tri[0]] + b1 * buffers.normals[tri[1]] +
                                     b2 * buffers.normals[tri[2]]);
      albedo[j] = albedo_of[inst];
    } else if (const int f = FixtureOf(rh.hit.geomID[j]); f >= 0) {
      const PartBuffers& buffers = fixtures[static_cast<size_t>(f)];
      const uint32_t* tri = &buffers.indices[3 * rh.hit.primID[j]];
      const float b1 = rh.hit.u[j], b2 = rh.hit.v[j], b0 = 1.0f - b1 - b2;
      normal = b0 * buffers.normals[tri[0]] + b1 * buffers.normals[tri[1]] +
               b2 * buffers.normals[tri[2]];
      albedo[j] = fixture_albedo[static_cast<size_t>(f)];
    } else {
      normal = Eigen::Vector3f::UnitZ();
      albedo[j] = scene.floor_color;
    }
    normal.normalize();
    if (normal.dot(dir) > 0.0f) normal = -normal;  // shade the side the camera sees
    out[j].normal = normal;
    out[j].albedo = albedo[j];
    point[j] =
        Eigen::Vector3f(rh.ray.org_x[j], rh.ray.org_y[j], rh.ray.org_z[j]) + rh.ray.tfar[j] * dir;
    out[j].point = point[j];
    out[j].color = albedo[j] * scene.ambient;
  }
  if (!lights) return;
  for (size_t l = 0; l < scene.lights.size(); ++l) {
    const Scene::Light& light = scene.lights[l];
    Eigen::Vector3f to_light[16];
    float distance[16];
    alignas(64) int lit[16];
    float cosine[16];
    bool any = false;
    for (int j = 0; j < 16; ++j) {
      lit[j] = 0;
      if (!hit[j]) continue;
      if (light.kind == Scene::Light::Kind::kDirectional) {
        to_light[j] = -light_dirs[l];
        distance[j] = std::numeric_limits<float>::infinity();
      } else {
        const Eigen::Vector3f d = light.position.cast<float>() - point[j];
        distance[j] = d.norm();
        to_light[j] = d / std::max(distance[j], 1e-6f);
      }
      cosine[j] = out[j].normal.dot(to_light[j]);
      if (cosine[j] > 0.0f) lit[j] = -1, any = true;
    }
    if (!any) continue;
    if (scene.shadows) {
      RTCRay16 shadow;
      for (int j = 0; j < 16; ++j) {
        if (lit[j]) {
          SetShadowLane(&shadow, j, point[j], to_light[j], distance[j]);
        } else {
          SetShadowLane(&shadow, j, Eigen::Vector3f::Zero(), Eigen::Vector3f::UnitZ(), 0.0f);
        }
      }
      RTCIntersectContext context;
      rtcInitIntersectContext(&context);
      rtcOccluded16(lit, world, &context, &shadow);
      for (int j = 0; j < 16; ++j) {
        if (lit[j] && shadow.tfar[j] < 0.0f) lit[j] = 0;  // occluded: tfar = -inf
      }
    }
    for (int j = 0; j < 16; ++j) {
      if (lit[j]) out[j].color += albedo[j] * (light.intensity * cosine[j]);
    }
  }
}

void Renderer::Impl::ProjectorPacket(const PathTracer* tracer, const RTCRayHit16& rh,
                                     const int valid[16], const Shaded shaded[16],
                                     const Eigen::Vector3f& projector, float spread, int u0, int v0,
                                     int w, uint8_t* seen, float* signal) const {
  float value[16];
  if (tracer) {
    tracer->ProjectorSignal(rh, valid, projector, spread, value);
  } else {
    for (int j = 0; j < 16; ++j) {
      value[j] = 0.0f;
      if (!valid[j] || rh.hit.geomID[j] == kInvalid) continue;
      const float cosine = shaded[j].normal.dot((projector - shaded[j].point).normalized());
      value[j] = cosine > 0.0f ? Luminance(shaded[j].albedo) * cosine : 0.0f;
    }
  }
  // Shadow rays from each hit to the projector (which is not geometry: they stop short of it).
  RTCRay16 ray;
  alignas(64) int lit[16];
  for (int j = 0; j < 16; ++j) {
    lit[j] = valid[j] && rh.hit.geomID[j] != kInvalid && value[j] > 0.0f ? -1 : 0;
    if (!lit[j]) {
      SetShadowLane(&ray, j, Eigen::Vector3f::Zero(), Eigen::Vector3f::UnitZ(), 0.0f);
      continue;
    }
    const Eigen::Vector3f d = projector - shaded[j].point;
    const float distance = d.norm();
    SetShadowLane(&ray, j, shaded[j].point, d / std::max(distance, 1e-6f),
                  distance * (1.0f - 1e-5f));
  }
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  rtcOccluded16(lit, world, &context, &ray);
  for (int j = 0; j < 16; ++j) {
    const int u = u0 + j % kTile, v = v0 + j / kTile;
    if (!valid[j]) continue;
    const size_t pixel = static_cast<size_t>(v) * w + u;
    const bool visible = lit[j] && !(ray.tfar[j] < 0.0f);
    seen[pixel] = visible ? 1 : 0;
    signal[pixel] = value[j];
  }
}

void Renderer::Impl::InfraredPacket(const RTCRayHit16& rh, const int valid[16],
                                    const Shaded shaded[16], const uint8_t* seen,
                                    const float* signal, int u0, int v0, int w,
                                    const DotTable& pattern, const DepthModel& m,
                                    const Eigen::Vector3f& projector,
                                    const Eigen::Matrix3f& projector_from_world, float* out) const {
  // The directions of the lit points in the projector's frame, then their dots all at once.
  int lane[16], n = 0;
  double xs[16], ys[16];
  float weight[16];
  for (int j = 0; j < 16; ++j) {
    if (!valid[j] || rh.hit.geomID[j] == kInvalid) continue;
    const size_t pixel = static_cast<size_t>(v0 + j / kTile) * w + (u0 + j % kTile);
    out[pixel] = static_cast<float>(m.ambient) * Luminance(shaded[j].color);
    if (!seen[pixel]) continue;
    const Eigen::Vector3f q = projector_from_world * (shaded[j].point - projector);
    const float distance_m = q.norm() / 1000.0f;
    if (!(q.z() > 0.0f && distance_m > 0.0f)) continue;
    lane[n] = j;
    xs[n] = q.x() / q.z(), ys[n] = q.y() / q.z();
    weight[n] = static_cast<float>(m.dot_power) * signal[pixel] / (distance_m * distance_m);
    ++n;
  }
  if (n == 0) return;
  float dots[16];
  pattern(n, xs, ys, dots);
  for (int i = 0; i < n; ++i) {
    const int j = lane[i];
    out[static_cast<size_t>(v0 + j / kTile) * w + (u0 + j % kTile)] += weight[i] * dots[i];
  }
}

std::vector<float> Renderer::Impl::InfraredPass(const PathTracer* tracer, const Camera& camera,
                                                const DotTable& pattern, const DepthModel& m,
                                                const Eigen::Vector3f& projector) const {
  const Intrinsics& k = camera.intrinsics;
  const int w = k.width, h = k.height;
  const size_t num_pixels = static_cast<size_t>(w) * h;
  std::vector<float> out(num_pixels, 0.0f);
  std::vector<uint8_t> seen(num_pixels, 0);
  std::vector<float> signal(num_pixels, 0.0f);
  const std::shared_ptr<const PixelRays> rays = RaysOf(k);
  const RayGen gen(camera.world_from_cam.linear().cast<float>(),
                   camera.world_from_cam.translation().cast<float>(), rays.get());
  std::vector<float> xs, ys;
  if (!rays->distorted()) rays->Tabulate(0.5, 0.5, kTile, &xs, &ys);
  const std::vector<float>* pxs = rays->distorted() ? nullptr : &xs;
  const std::vector<float>* pys = rays->distorted() ? nullptr : &ys;
  const Eigen::Matrix3f projector_from_world = gen.rotation.transpose();
  const float tnear = static_cast<float>(options.near_mm),
              tfar = static_cast<float>(options.far_mm);
  const float spread = static_cast<float>(1.0 / std::min(k.fx, k.fy));
  const int tiles_x = (w + kTile - 1) / kTile, tiles_y = (h + kTile - 1) / kTile;
  const Eigen::Isometry3d cam_from_world = camera.world_from_cam.inverse();
  std::vector<Eigen::Isometry3d> cam_from_model(scene.instances.size());
  for (size_t i = 0; i < scene.instances.size(); ++i)
    cam_from_model[i] = cam_from_world * scene.instances[i].world_from_model;
  const std::vector<uint8_t> reachable = ReachableTiles(*rays, cam_from_world, cam_from_model);
  tbb::parallel_for(
      tbb::blocked_range<int>(0, tiles_x * tiles_y, 16), [&](const tbb::blocked_range<int>& range) {
        RTCIntersectContext context;
        RTCRayHit16 rh;
        alignas(64) int valid[16];
        Shaded shaded[16];
        for (int tile = range.begin(); tile < range.end(); ++tile) {
          const int u0 = (tile % tiles_x) * kTile, v0 = (tile / tiles_x) * kTile;
          InitPacket(gen, u0, v0, w, h, pxs, pys, 0.5f, 0.5f, tnear, tfar, &rh, valid);
          TracePacket(reachable[tile], &context, valid, &rh);
          ShadePacket(rh, valid, shaded, m.ambient > 0.0);
          ProjectorPacket(tracer, rh, valid, shaded, projector, spread, u0, v0, w, seen.data(),
                          signal.data());
          InfraredPacket(rh, valid, shaded, seen.data(), signal.data(), u0, v0, w, pattern, m,
                         projector, projector_from_world, out.data());
        }
      });
  return out;
}

std::shared_ptr<const DotTable> Renderer::Impl::DotsOf(const DepthModel& m,
                                                       const Intrinsics& k) const {
  const double parallax = m.baseline_mm / std::max(m.min_depth_mm, 1.0);
  const double x0 = -k.cx / k.fx - parallax, x1 = (k.width - k.cx) / k.fx + parallax;
  const double y0 = -k.cy / k.fy - parallax, y1 = (k.height - k.cy) / k.fy + parallax;
  std::lock_guard<std::mutex> lock(dots_mutex);
  if (dots_cache == nullptr || !dots_cache->Is(m, k.fx, x0, x1, y0, y1)) {
    // Built under the lock, isolated (as RaysOf's tables): its rows run in parallel.
    tbb::this_task_arena::isolate(
        [&] { dots_cache = std::make_shared<const DotTable>(m, k.fx, x0, x1, y0, y1); });
  }
  return dots_cache;
}

std::vector<uint8_t> Renderer::Impl::ReachableTiles(
    const PixelRays& rays, const Eigen::Isometry3d& cam_from_world,
    const std::vector<Eigen::Isometry3d>& cam_from_model) const {
  const Intrinsics& k = rays.intrinsics();
  const int w = k.width, h = k.height;
  const int tiles_x = (w + kTile - 1) / kTile, tiles_y = (h + kTile - 1) / kTile;
  std::vector<uint8_t> reachable(static_cast<size_t>(tiles_x) * tiles_y, 0);
  const auto mark = [&](const PixelRect& r) {
    for (int ty = r.v0 / kTile; ty * kTile < r.v1; ++ty) {
      for (int tx = r.u0 / kTile; tx * kTile < r.u1; ++tx)
        reachable[static_cast<size_t>(ty) * tiles_x + tx] = 1;
    }
  };
  for (size_t i = 0; i < scene.instances.size(); ++i)
    mark(ImageRect(rays, model_bounds[scene.instances[i].part], cam_from_model[i],
                   PixelRect{0, 0, w, h}));
  for (const Scene::Fixture& fixture : scene.fixtures)
    mark(ImageRect(rays, fixture.mesh.Bounds(), cam_from_world, PixelRect{0, 0, w, h}));
  return reachable;
}

void Renderer::Impl::TracePacket(bool reachable, RTCIntersectContext* context, const int* valid,
                                 RTCRayHit16* rh) const {
  if (reachable) {
    rtcInitIntersectContext(context);
    rtcIntersect16(valid, world, context, rh);
  } else if (floor_id != kInvalid) {
    IntersectFloor(valid, static_cast<float>(scene.floor_half_size_mm), floor_id, rh);
  }
}

namespace {

// The camera and sensor settings a frame can be rendered with (`pbr`: the mode has a path tracer).
void CheckCamera(const Intrinsics& k, const SensorOptions& sensor, bool pbr) {
  std::string why;
  if (!k.Check(&why)) throw Error("camera: " + why);
  if (!sensor.depth.Check(&why)) throw Error("camera.depth: " + why);
  if (!sensor.Check(&why)) throw Error("camera: " + why);
  if (!pbr && (sensor.lens.active() || sensor.motion.active()))
    throw Error("camera: depth of field and motion blur need render.mode: pbr");
  if (k.distortion.active() && sensor.depth.kind == DepthModel::Kind::kActiveStereo) {
    throw Error(
        "camera: active_stereo matches rectified IR images; give the lens distortion to another "
        "camera of the rig");
  }
}

}  // namespace

const PathTracer* Renderer::Impl::TracerFor(const FrameLook* look,
                                            std::unique_ptr<PathTracer>* own) const {
  if (look == nullptr) return tracer.get();
  if (tracer == nullptr) throw Error("renderer: a frame's own look needs render.mode: pbr");
  if (look->instance_materials.size() != traced.instances.size() ||
      look->fixture_materials.size() != traced.fixtures.size()) {
    throw Error("renderer: the frame's look has materials for another scene");
  }
  std::string why;
  for (const Material& m : look->instance_materials) {
    if (!m.Check(&why)) throw Error("renderer: material: " + why);
  }
  for (const Material& m : look->fixture_materials) {
    if (!m.Check(&why)) throw Error("renderer: fixture material: " + why);
  }
  if (!look->floor.Check(&why)) throw Error("renderer: floor material: " + why);
  for (const LightSource& l : look->lights) {
    if (!l.Check(&why)) throw Error("renderer: light: " + why);
  }
  if (!look->environment.Check(&why)) throw Error("renderer: environment: " + why);
  PathTracerScene pts = traced;
  for (size_t i = 0; i < pts.instances.size(); ++i)
    pts.instances[i].material = look->instance_materials[i];
  for (size_t f = 0; f < pts.fixtures.size(); ++f)
    pts.fixtures[f].material = look->fixture_materials[f];
  pts.floor = look->floor;
  pts.lights = look->lights;
  pts.environment = look->environment;
  *own = std::make_unique<PathTracer>(std::move(pts), tracer.get());
  return own->get();
}

// One frame of Renderer::Render: what its passes share (the options as this frame resolves them,
// the camera's rays, the planes the passes fill besides the frame's own) and the passes, in the
// order Render runs them. Labels and colour come from one traversal of the image's 4 x 4 tiles, in
// stages per tile (CastLabels, Shade, SenseAndDisplay) that share the tile's packet of centre rays.
struct Renderer::Impl::FramePasses {
  FramePasses(const Impl& im, const Camera& camera, uint64_t view, const SensorOptions& sensor,
              const FrameLook* look, const PathTracer* tracer, Frame* out);

  // Every tile: its labels, its colour, and that colour as the image sensor reads it and the
  // display shows it (with the denoiser, only marks the pixels DenoiseColour finishes).
  void TraceTiles();
  // pbr with the denoiser: the filtered radiance of every pixel, then its reading and display.
  void DenoiseColour();
  // Each instance's visible pixels.
  void CountVisible();
  // A depth model other than the ideal: the depth the sensor returns, and its IR images.
  void SimulateSensorDepth();
  // The look's background photo where the centre ray hit nothing.
  void PasteBackground();
  // Each instance's full silhouette (the instance traced alone): mask, counts, boxes.
  void TraceAmodalMasks();

  // A thread's packet in TraceTiles, reused by each tile's centre rays and supersamples.
  struct TilePacket {
    RTCIntersectContext context;
    RTCRayHit16 rh;
    alignas(64) int valid[16];  // Embree reads packet masks as aligned vectors
    Shaded shaded[16];
  };
  // The stages of a tile at pixel (u0, v0), and the first hits of a packet of camera rays. All are
  // declared inline: the library is compiled position-independent, where a member that is not
  // could be replaced at link time and is never inlined. CastLabels and Shade are forced inline:
  // they are the body of the tile loop, split for reading only.
  [[gnu::always_inline]] inline void CastLabels(int tile, int u0, int v0, TilePacket* p,
                                                int centre_valid[16]);
  [[gnu::always_inline]] inline void Shade(int tile, int u0, int v0, TilePacket* p,
                                           const AdaptiveSampling& tile_sampling,
                                           Eigen::Vector3f radiance[16], Eigen::Vector3f color[16]);
  // Whether pixel j of a packet CastLabels traced shows an object: an instance, or a fixture
  // sampled as one (Scene::Fixture::object).
  bool ShowsObject(const RTCRayHit16& rh, int j) const {
    if (rh.hit.geomID[j] == kInvalid) return false;
    if (rh.hit.instID[0][j] != kInvalid) return true;
    const int f = im.FixtureOf(rh.hit.geomID[j]);
    return f >= 0 && im.scene.fixtures[static_cast<size_t>(f)].object;
  }
  inline void SenseAndDisplay(int u, int v, Eigen::Vector3f radiance, Eigen::Vector3f color);

  const Impl& im;
  const Camera& camera;
  const uint64_t view;
  const SensorOptions& sensor;
  const FrameLook* look;
  const PathTracer* tracer;  // pbr: this frame's (Impl::TracerFor)
  Frame& frame;
  const RenderOptions& o;
  const Intrinsics& k;
  const int w, h;
  const size_t num_pixels;

  const DepthModel& depth_model;
  const bool noisy_depth;
  const bool projector;
  // Normals also for the depth model (incidence angles), kept in the frame only when asked for.
  const bool need_normals;
  std::vector<Eigen::Vector3f> normals;
  // What the projector sees (ProjectorPacket): the depth model's (projector), or active_stereo's
  // dot projector's (stereo).
  std::vector<uint8_t> projector_seen;
  std::vector<float> signal;
  const Eigen::Vector3f projector_world;
  const float pixel_spread;
  // active_stereo: the left IR camera is the camera, whose centre rays give its IR image as they
  // give the labels; the dot projector sits half the baseline along its x axis, the right IR
  // camera the whole baseline (SimulateSensorDepth).
  const bool stereo;
  const Eigen::Vector3f dots_world;
  std::shared_ptr<const DotTable> dots;
  std::vector<float> infrared_left;  // noiseless, linear

  const bool gray;
  const ImageSensor& imager;
  const uint64_t noise_seed;
  std::vector<float> grey_noise;
  const bool pbr;
  const uint64_t frame_seed;
  const float exposure_scale;
  const Eigen::Vector3f white_balance;
  const bool balanced;
  const bool filmic;
  const AdaptiveSampling sampling;
  // Tiles that show no object (render.background_samples; `sampling` where it is 0).
  const AdaptiveSampling background_sampling;

  const std::shared_ptr<const PixelRays> rays;
  const bool distorted;
  const RayGen gen;
  std::vector<float> xs, ys;  // pixel centres (pinhole)
  // Supersampling offsets (sx + 0.5) / ss, tabulated per sample (pinhole).
  std::vector<std::vector<float>> sample_xs, sample_ys;
  const Eigen::Matrix3f cam_from_world_rotation;
  const int tiles_x, tiles_y;
  const float tnear, tfar;
  const int ss;
  const Eigen::Isometry3d cam_from_world;
  std::vector<uint8_t> reachable;  // per tile (Impl::ReachableTiles)

  // The denoiser (pbr) needs every pixel's radiance and guides first; the colour follows.
  const bool denoising;
  const bool keep_denoiser_inputs;  // RenderOptions::denoiser_inputs
  const bool need_denoiser_inputs;  // denoising or keeping them
  std::vector<float> radiance_plane, albedo_plane, normal_plane, variance_plane;
  std::vector<uint8_t> coloured;  // pixels with a colour to finish (a ray through the centre)
};

Renderer::Impl::FramePasses::FramePasses(const Impl& im, const Camera& camera, uint64_t view,
                                         const SensorOptions& sensor, const FrameLook* look,
                                         const PathTracer* tracer, Frame* out)
    : im(im),
      camera(camera),
      view(view),
      sensor(sensor),
      look(look),
      tracer(tracer),
      frame(*out),
      o(im.options),
      k(camera.intrinsics),
      w(k.width),
      h(k.height),
      num_pixels(static_cast<size_t>(w) * h),
      depth_model(sensor.depth),
      noisy_depth(depth_model.kind != DepthModel::Kind::kIdeal),
      projector(depth_model.needs_projector()),
      need_normals(o.normals || noisy_depth),
      projector_world((camera.world_from_cam * Eigen::Vector3d(depth_model.baseline_mm, 0.0, 0.0))
                          .cast<float>()),
      pixel_spread(static_cast<float>(1.0 / std::min(k.fx, k.fy))),
      stereo(depth_model.kind == DepthModel::Kind::kActiveStereo),
      dots_world((camera.world_from_cam * Eigen::Vector3d(0.5 * depth_model.baseline_mm, 0.0, 0.0))
                     .cast<float>()),
      gray(sensor.image != SensorOptions::Image::kRgb),
      imager(sensor.imager),
      noise_seed(ImageNoiseSeed(imager, view)),
      pbr(tracer != nullptr),
      frame_seed(FrameSeed(o.seed, view)),
      exposure_scale(
          static_cast<float>(std::exp2(o.exposure + (look != nullptr ? look->exposure : 0.0)))),
      white_balance(look != nullptr ? look->white_balance : Eigen::Vector3f::Ones()),
      balanced(white_balance != Eigen::Vector3f::Ones()),
      filmic(o.view == RenderOptions::View::kFilmic),
      sampling{o.samples, o.FirstSamples(), static_cast<float>(o.noise_threshold), exposure_scale,
               filmic},
      background_sampling(sampling.Capped(o.background_samples)),
      rays(im.RaysOf(k)),
      distorted(rays->distorted()),
      gen(camera.world_from_cam.linear().cast<float>(),
          camera.world_from_cam.translation().cast<float>(), rays.get()),
      cam_from_world_rotation(gen.rotation.transpose()),
      tiles_x((w + kTile - 1) / kTile),
      tiles_y((h + kTile - 1) / kTile),
      tnear(static_cast<float>(o.near_mm)),
      tfar(static_cast<float>(o.far_mm)),
      ss(o.supersampling),
      cam_from_world(camera.world_from_cam.inverse()),
      denoising(pbr && o.shade && o.denoise),
      keep_denoiser_inputs(pbr && o.shade && o.denoiser_inputs),
      need_denoiser_inputs(denoising || keep_denoiser_inputs) {
  frame.camera = camera;
  frame.rgb.assign(3 * num_pixels, 0);
  frame.depth.assign(num_pixels, 0.0f);
  frame.instance.assign(num_pixels, 0);
  if (need_normals) normals.assign(num_pixels, Eigen::Vector3f::Zero());
  if (projector || stereo) projector_seen.assign(num_pixels, 0), signal.assign(num_pixels, 0.0f);
  if (gray) frame.gray.assign(num_pixels, 0.0f);
  if (o.hdr) frame.radiance.assign(3 * num_pixels, 0.0f);
  if (pbr && o.shade) frame.samples.assign(num_pixels, 0);

  if (!distorted) rays->Tabulate(0.5, 0.5, kTile, &xs, &ys);
  for (int sy = 0; sy < o.supersampling && o.supersampling > 1; ++sy) {
    for (int sx = 0; sx < o.supersampling; ++sx) {
      sample_xs.emplace_back();
      sample_ys.emplace_back();
      const double n = o.supersampling;
      if (!distorted)
        rays->Tabulate((sx + 0.5) / n, (sy + 0.5) / n, kTile, &sample_xs.back(), &sample_ys.back());
    }
  }

  // Per-instance truth: pose, amodal silhouette (the instance traced alone), pixel counts.
  frame.instances.resize(im.scene.instances.size());
  for (size_t i = 0; i < im.scene.instances.size(); ++i) {
    frame.instances[i].cam_from_model = cam_from_world * im.scene.instances[i].world_from_model;
  }
  std::vector<Eigen::Isometry3d> cam_from_model(frame.instances.size());
  for (size_t i = 0; i < frame.instances.size(); ++i)
    cam_from_model[i] = frame.instances[i].cam_from_model;
  reachable = im.ReachableTiles(*rays, cam_from_world, cam_from_model);
  if (stereo) {
    dots = im.DotsOf(depth_model, k);
    infrared_left.assign(num_pixels, 0.0f);
  }
  if (gray && imager.full_well > 0.0) grey_noise = GreyImageNoise(noise_seed, num_pixels);
  if (need_denoiser_inputs) {
    radiance_plane.assign(3 * num_pixels, 0.0f);
    albedo_plane.assign(3 * num_pixels, 1.0f);
    normal_plane.assign(3 * num_pixels, 0.0f);
    variance_plane.assign(num_pixels, 0.0f);
  }
  if (denoising) coloured.assign(num_pixels, 0);
}

// The labels from a tile's pixel centres: depth, instance, normals (through the Lambert shading,
// which also gives the fast mode's colour without supersampling) and what the depth sensor's
// projector sees. `centre_valid`: the pixels with a centre ray.
void Renderer::Impl::FramePasses::CastLabels(int tile, int u0, int v0, TilePacket* p,
                                             int centre_valid[16]) {
  RTCRayHit16& rh = p->rh;
  int* valid = p->valid;
  Shaded* shaded = p->shaded;
  // The pixel centres: depth, instance, normal, and (without supersampling) colour.
  InitPacket(gen, u0, v0, w, h, distorted ? nullptr : &xs, distorted ? nullptr : &ys, 0.5f, 0.5f,
             tnear, tfar, &rh, valid);
  // Incoherent packet traversal: Embree's coherent mode
  // (RTC_INTERSECT_CONTEXT_FLAG_COHERENT) lost parts near the image centre of straight-down
  // views, also with robust scenes.
  im.TracePacket(reachable[tile], &p->context, valid, &rh);
  std::copy(valid, valid + 16, centre_valid);
  // The fast mode's colour needs the lights; normals, albedo and points (for the sensor)
  // do not.
  const bool fast_colour = o.shade && ss == 1 && !pbr;
  // The IR image's ambient share is the Lambert shading too.
  const bool lights = fast_colour || (stereo && depth_model.ambient > 0.0);
  if (fast_colour || need_normals) im.ShadePacket(rh, valid, shaded, lights);
  for (int j = 0; j < 16; ++j) {
    if (!valid[j]) continue;
    const size_t pixel = static_cast<size_t>(v0 + j / kTile) * w + (u0 + j % kTile);
    if (rh.hit.geomID[j] != kInvalid) {
      frame.depth[pixel] = rh.ray.tfar[j];
      const unsigned inst = rh.hit.instID[0][j];
      if (inst != kInvalid) frame.instance[pixel] = static_cast<uint16_t>(inst + 1);
      if (need_normals) normals[pixel] = cam_from_world_rotation * shaded[j].normal;
    }
  }
  if (projector) {
    im.ProjectorPacket(tracer, rh, valid, shaded, projector_world, pixel_spread, u0, v0, w,
                       projector_seen.data(), signal.data());
  }
  if (stereo) {
    im.ProjectorPacket(tracer, rh, valid, shaded, dots_world, pixel_spread, u0, v0, w,
                       projector_seen.data(), signal.data());
    im.InfraredPacket(rh, valid, shaded, projector_seen.data(), signal.data(), u0, v0, w, *dots,
                      depth_model, dots_world, cam_from_world_rotation, infrared_left.data());
  }
}

// The colour of a tile's pixels after CastLabels (whose packet it reuses): the fast mode's
// Lambert colour at the centre or the mean of a grid of supersamples; pbr, the path tracer's
// radiance, also kept for the HDR image and the denoiser.
void Renderer::Impl::FramePasses::Shade(int tile, int u0, int v0, TilePacket* p,
                                        const AdaptiveSampling& tile_sampling,
                                        Eigen::Vector3f radiance[16], Eigen::Vector3f color[16]) {
  RTCRayHit16& rh = p->rh;
  int* valid = p->valid;
  Shaded* shaded = p->shaded;
  for (int j = 0; j < 16; ++j) {
    if (!valid[j]) continue;
    color[j] = (ss == 1 && o.shade && !pbr) ? shaded[j].color : Eigen::Vector3f::Zero();
  }
  for (int j = 0; j < 16; ++j) radiance[j].setZero();
  if (pbr && o.shade) {
    TileFeatures features;
    int taken[16];
    tracer->TraceTile(camera, *rays, sensor.lens, sensor.motion, u0, v0, tile_sampling, frame_seed,
                      radiance, need_denoiser_inputs ? &features : nullptr, taken);
    for (int j = 0; j < 16; ++j) {
      if (!valid[j]) continue;
      const size_t pixel = static_cast<size_t>(v0 + j / kTile) * w + (u0 + j % kTile);
      frame.samples[pixel] = static_cast<uint32_t>(taken[j]);
      if (o.hdr) {
        for (int c = 0; c < 3; ++c) frame.radiance[3 * pixel + c] = radiance[j][c];
      }
      if (need_denoiser_inputs) {
        for (int c = 0; c < 3; ++c) {
          radiance_plane[3 * pixel + c] = radiance[j][c];
          albedo_plane[3 * pixel + c] = features.albedo[j][c];
          normal_plane[3 * pixel + c] = features.normal[j][c];
        }
        variance_plane[pixel] = features.variance[j];
      }
    }
  }
  // Supersampled colour: a regular grid of samples in each pixel.
  // (Points of a pixel without a ray, beyond a lens's fold, are left out of its mean.)
  int counted[16];
  std::fill(counted, counted + 16, 0);
  for (int sy = 0; o.shade && ss > 1 && sy < ss; ++sy) {
    for (int sx = 0; sx < ss; ++sx) {
      const size_t n = static_cast<size_t>(sy * ss + sx);
      InitPacket(gen, u0, v0, w, h, distorted ? nullptr : &sample_xs[n],
                 distorted ? nullptr : &sample_ys[n], (sx + 0.5f) / ss, (sy + 0.5f) / ss, tnear,
                 tfar, &rh, valid);
      im.TracePacket(reachable[tile], &p->context, valid, &rh);
      im.ShadePacket(rh, valid, shaded);
      for (int j = 0; j < 16; ++j) {
        if (!valid[j]) continue;
        color[j] += shaded[j].color / float(ss * ss);
        ++counted[j];
      }
    }
  }
  for (int j = 0; o.shade && ss > 1 && j < 16; ++j) {
    if (counted[j] > 0 && counted[j] < ss * ss)
      color[j] *= static_cast<float>(ss * ss) / static_cast<float>(counted[j]);
  }
}

// A pixel's colour from its radiance (pbr) or Lambert colour (fast): the image sensor's reading,
// the display transform (pbr) and 8 bits, and the grey camera's value.
void Renderer::Impl::FramePasses::SenseAndDisplay(int u, int v, Eigen::Vector3f radiance,
                                                  Eigen::Vector3f color) {
  const size_t pixel = static_cast<size_t>(v) * w + u;
  const bool pbr_colour = pbr && o.shade;
  // The linear value the image sensor reads (pbr: the exposed radiance; fast: the
  // Lambert colour), then the display transform (pbr) and 8 bits.
  Eigen::Vector2f centre;
  rays->Centre(u, v, &centre);
  const double vignette = imager.active() ? imager.Vignette(centre.x(), centre.y()) : 1.0;
  // Noise draws: a colour camera's R, G and B (two pairs of sensor.image per pixel); a grey
  // camera's one number per pixel (GreyImageNoise, worked out for the frame above; its colour
  // image is not written and gets no noise).
  double normal[4] = {0.0, 0.0, 0.0, 0.0};
  if (imager.full_well > 0.0) {
    if (gray) {
      normal[3] = grey_noise[pixel];
    } else {
      const Eigen::Vector2d rg = ImageNoisePair(noise_seed, pixel, 0);
      const Eigen::Vector2d bk = ImageNoisePair(noise_seed, pixel, 1);
      normal[0] = rg.x(), normal[1] = rg.y(), normal[2] = bk.x(), normal[3] = bk.y();
    }
  }
  const auto read = [&](float linear, int channel) {
    if (!imager.active()) return linear;
    return static_cast<float>(imager.Read(linear, vignette, normal[channel]));
  };
  // The camera's white balance (domain randomisation) scales what the sensor reads.
  if (pbr_colour && balanced) radiance = radiance.cwiseProduct(white_balance);
  const Eigen::Vector3f linear = pbr_colour ? Eigen::Vector3f(exposure_scale * radiance) : color;
  for (int c = 0; c < 3; ++c) {
    const float value = read(linear[c], c);
    color[c] = pbr_colour ? DisplayValue(value, filmic) : value;
    frame.rgb[3 * pixel + c] = ToByte(color[c]);
  }
  if (o.hdr && !pbr) {
    for (int c = 0; c < 3; ++c) frame.radiance[3 * pixel + c] = color[c];
  }
  // A grey camera sees the luminance of the same linear value, with its own noise.
  if (gray) {
    // (pbr: exposure times luminance, in the order earlier versions computed it.)
    const float value =
        read(pbr_colour ? exposure_scale * Luminance(radiance) : Luminance(linear), 3);
    frame.gray[pixel] = pbr_colour ? DisplayValue(value, filmic) : std::clamp(value, 0.0f, 1.0f);
  }
}

void Renderer::Impl::FramePasses::TraceTiles() {
  const int num_tiles = tiles_x * tiles_y;
  // body(tile, u0, v0, packet) for every tile, in parallel; a packet per range of tiles.
  const auto for_each_tile = [&](auto&& body) {
    tbb::parallel_for(tbb::blocked_range<int>(0, num_tiles, 16),
                      [&](const tbb::blocked_range<int>& range) {
                        TilePacket packet;
                        for (int tile = range.begin(); tile < range.end(); ++tile)
                          body(tile, (tile % tiles_x) * kTile, (tile / tiles_x) * kTile, &packet);
                      });
  };
  // A tile's pixels once shaded: their reading and display, or (denoising) a mark.
  const auto finish = [&](int u0, int v0, const int centre_valid[16],
                          const Eigen::Vector3f radiance[16], const Eigen::Vector3f color[16]) {
    for (int j = 0; j < 16; ++j) {
      if (!centre_valid[j]) continue;
      const int u = u0 + j % kTile, v = v0 + j / kTile;
      if (denoising) {
        coloured[static_cast<size_t>(v) * w + u] = 1;
        continue;
      }
      SenseAndDisplay(u, v, radiance[j], color[j]);
    }
  };
  if (!(pbr && o.shade && background_sampling.samples < sampling.samples)) {
    for_each_tile([&](int tile, int u0, int v0, TilePacket* packet) {
      alignas(64) int centre_valid[16];  // the pixels (supersamples reuse the packet's mask)
      CastLabels(tile, u0, v0, packet, centre_valid);
      Eigen::Vector3f radiance[16], color[16];
      Shade(tile, u0, v0, packet, sampling, radiance, color);
      finish(u0, v0, centre_valid, radiance, color);
    });
    return;
  }
  // render.background_samples: every tile's labels first, to know which tiles show an object;
  // those and the tiles next to them (their contact shadows, the pixels their edges cover in
  // part) get `sampling`, the rest `background_sampling`. Both depend on the labels only.
  std::vector<uint16_t> centres(static_cast<size_t>(num_tiles), 0);
  std::vector<uint8_t> object(static_cast<size_t>(num_tiles), 0);
  for_each_tile([&](int tile, int u0, int v0, TilePacket* packet) {
    alignas(64) int centre_valid[16];
    CastLabels(tile, u0, v0, packet, centre_valid);
    uint16_t mask = 0;
    for (int j = 0; j < 16; ++j) {
      if (!centre_valid[j]) continue;
      mask = static_cast<uint16_t>(mask | (1u << j));
      if (ShowsObject(packet->rh, j)) object[static_cast<size_t>(tile)] = 1;
    }
    centres[static_cast<size_t>(tile)] = mask;
  });
  const auto near_object = [&](int tile) {
    const int tx = tile % tiles_x, ty = tile / tiles_x;
    for (int y = std::max(0, ty - 1); y <= std::min(tiles_y - 1, ty + 1); ++y) {
      for (int x = std::max(0, tx - 1); x <= std::min(tiles_x - 1, tx + 1); ++x) {
        if (object[static_cast<size_t>(y) * tiles_x + x]) return true;
      }
    }
    return false;
  };
  for_each_tile([&](int tile, int u0, int v0, TilePacket* packet) {
    alignas(64) int centre_valid[16];
    for (int j = 0; j < 16; ++j) {
      centre_valid[j] = (centres[static_cast<size_t>(tile)] >> j) & 1 ? -1 : 0;
      packet->valid[j] = centre_valid[j];
    }
    Eigen::Vector3f radiance[16], color[16];
    Shade(tile, u0, v0, packet, near_object(tile) ? sampling : background_sampling, radiance,
          color);
    finish(u0, v0, centre_valid, radiance, color);
  });
}

void Renderer::Impl::FramePasses::DenoiseColour() {
  DenoiseInput input;
  input.width = w;
  input.height = h;
  input.radiance = radiance_plane.data();
  input.albedo = albedo_plane.data();
  input.normal = normal_plane.data();
  input.depth = frame.depth.data();
  input.variance = variance_plane.data();
  const std::vector<float> clean =
      o.denoiser == RenderOptions::Denoiser::kNetwork ? DenoiseWithNetwork(input) : Denoise(input);
  tbb::parallel_for(0, h, [&](int v) {
    for (int u = 0; u < w; ++u) {
      const size_t pixel = static_cast<size_t>(v) * w + u;
      if (!coloured[pixel]) continue;
      const Eigen::Vector3f radiance(clean[3 * pixel], clean[3 * pixel + 1], clean[3 * pixel + 2]);
      if (o.hdr) {
        for (int c = 0; c < 3; ++c) frame.radiance[3 * pixel + c] = radiance[c];
      }
      SenseAndDisplay(u, v, radiance, Eigen::Vector3f::Zero());
    }
  });
}

void Renderer::Impl::FramePasses::CountVisible() {
  for (size_t p = 0; p < num_pixels; ++p) {
    if (frame.instance[p] != 0) ++frame.instances[frame.instance[p] - 1].px_count_visib;
  }
}

void Renderer::Impl::FramePasses::SimulateSensorDepth() {
  DepthSensorInput input;
  input.intrinsics = k;
  input.rays = rays.get();
  input.depth = frame.depth.data();
  input.normals = normals.data();
  input.projector_seen = projector ? projector_seen.data() : nullptr;
  input.signal = projector ? signal.data() : nullptr;
  input.rgb = frame.rgb.data();
  std::vector<uint8_t> ir_left, ir_right;
  if (stereo) {
    Camera right = camera;
    right.world_from_cam =
        camera.world_from_cam * Eigen::Translation3d(depth_model.baseline_mm, 0, 0);
    const double gain = InfraredGain(infrared_left);
    std::array<std::vector<uint8_t>, 2> ir =
        InfraredImages(depth_model, view, infrared_left,
                       im.InfraredPass(tracer, right, *dots, depth_model, dots_world), gain);
    ir_left = std::move(ir[0]), ir_right = std::move(ir[1]);
    input.ir_left = ir_left.data();
    input.ir_right = ir_right.data();
  }
  frame.sensor_depth = SimulateDepth(depth_model, input, view);
  frame.infrared = std::move(ir_left);
}

void Renderer::Impl::FramePasses::PasteBackground() {
  // The photo where the centre ray hit nothing: scaled to cover the image, centred, sampled
  // bilinearly (linear values), shown as the display shows them; after the depth model, which
  // reads the rendered colour only (the photo is not in the scene).
  const LinearImage& photo = *look->background;
  if (photo.width <= 0 || photo.height <= 0 || photo.rgb.size() != 3u * photo.width * photo.height)
    throw Error("renderer: the background photo has no pixels");
  const double scale =
      std::max(static_cast<double>(w) / photo.width, static_cast<double>(h) / photo.height);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const size_t pixel = static_cast<size_t>(v) * w + u;
      if (frame.depth[pixel] != 0.0f) continue;
      const double x = (u + 0.5 - 0.5 * w) / scale + 0.5 * photo.width - 0.5;
      const double y = (v + 0.5 - 0.5 * h) / scale + 0.5 * photo.height - 0.5;
      const int x0 = std::clamp(static_cast<int>(std::floor(x)), 0, photo.width - 1);
      const int y0 = std::clamp(static_cast<int>(std::floor(y)), 0, photo.height - 1);
      const int x1 = std::min(x0 + 1, photo.width - 1), y1 = std::min(y0 + 1, photo.height - 1);
      const float fx = static_cast<float>(std::clamp(x - x0, 0.0, 1.0));
      const float fy = static_cast<float>(std::clamp(y - y0, 0.0, 1.0));
      Eigen::Vector3f linear;
      for (int c = 0; c < 3; ++c) {
        linear[c] = (1 - fy) * ((1 - fx) * photo.at(x0, y0)[c] + fx * photo.at(x1, y0)[c]) +
                    fy * ((1 - fx) * photo.at(x0, y1)[c] + fx * photo.at(x1, y1)[c]);
        frame.rgb[3 * pixel + c] = ToByte(LinearToSrgb(linear[c]));
        if (o.hdr) {
          // The scene radiance that would show as the photo (before exposure and white balance).
          frame.radiance[3 * pixel + c] =
              pbr ? linear[c] / (exposure_scale * (balanced ? white_balance[c] : 1.0f)) : linear[c];
        }
      }
      if (gray) frame.gray[pixel] = LinearToSrgb(Luminance(linear));
    }
  }
}

void Renderer::Impl::FramePasses::TraceAmodalMasks() {
  // The silhouette is traced on bop_toolkit's canvas of three times the image size, [-w, 2w) x
  // [-h, 2h), so that counts and boxes of truncated instances include their parts outside the
  // image.
  const PixelRect canvas{-w, -h, 2 * w, 2 * h};
  tbb::parallel_for(size_t{0}, im.scene.instances.size(), [&](size_t i) {
    Frame::InstanceTruth& truth = frame.instances[i];
    const PixelRect r =
        ImageRect(*rays, im.model_bounds[im.scene.instances[i].part], truth.cam_from_model, canvas);
    truth.roi[0] = std::clamp(r.u0, 0, w);
    truth.roi[1] = std::clamp(r.v0, 0, h);
    truth.roi[2] = std::clamp(r.u1, 0, w);
    truth.roi[3] = std::clamp(r.v1, 0, h);
    const int roi_w = truth.roi[2] - truth.roi[0];
    const size_t roi_pixels = static_cast<size_t>(roi_w) * (truth.roi[3] - truth.roi[1]);
    truth.amodal_mask.assign(roi_pixels, 0);
    if (o.amodal_depth) truth.amodal_depth.assign(roi_pixels, 0.0f);
    int count = 0, canvas_count = 0;
    int box[4] = {std::numeric_limits<int>::max(), std::numeric_limits<int>::max(),
                  std::numeric_limits<int>::min(), std::numeric_limits<int>::min()};
    RTCIntersectContext context;
    RTCRayHit16 rh;
    alignas(64) int valid[16];  // Embree reads packet masks as aligned vectors
    for (int v0 = r.v0; v0 < r.v1; v0 += kTile) {
      for (int u0 = r.u0; u0 < r.u1; u0 += kTile) {
        InitCanvasPacket(gen, u0, v0, r, tnear, tfar, &rh, valid);
        rtcInitIntersectContext(&context);
        rtcIntersect16(valid, im.solo[i], &context, &rh);
        for (int j = 0; j < 16; ++j) {
          if (!valid[j] || rh.hit.geomID[j] == kInvalid) continue;
          const int u = u0 + j % kTile, v = v0 + j / kTile;
          ++canvas_count;
          box[0] = std::min(box[0], u), box[1] = std::min(box[1], v);
          box[2] = std::max(box[2], u), box[3] = std::max(box[3], v);
          if (u < 0 || v < 0 || u >= w || v >= h) continue;
          const size_t in_roi = static_cast<size_t>(v - truth.roi[1]) * roi_w + (u - truth.roi[0]);
          truth.amodal_mask[in_roi] = 1;
          if (o.amodal_depth) truth.amodal_depth[in_roi] = rh.ray.tfar[j];
          ++count;
        }
      }
    }
    truth.px_count_all = count;
    truth.px_count_canvas = canvas_count;
    if (canvas_count > 0) std::copy(box, box + 4, truth.bbox_canvas);
  });
}

// The passes in order: labels and colour (sensor reading and display included) tile by tile, the
// denoiser, the visible counts, the depth sensor (which reads the finished colour), the
// background photo (after it: the photo is not in the scene), the amodal masks.
Frame Renderer::Render(const Camera& camera, uint64_t view, const SensorOptions& sensor,
                       const FrameLook* look) const {
  const Impl& im = *impl_;
  std::unique_ptr<PathTracer> own;  // a frame's own look: a path tracer of its own
  const PathTracer* tracer = im.TracerFor(look, &own);
  CheckCamera(camera.intrinsics, sensor, tracer != nullptr);
  const RenderOptions& o = im.options;

  Frame frame;
  Impl::FramePasses passes(im, camera, view, sensor, look, tracer, &frame);
  passes.TraceTiles();
  if (passes.denoising) passes.DenoiseColour();
  if (passes.keep_denoiser_inputs) {
    frame.denoiser_inputs = {std::move(passes.radiance_plane), std::move(passes.albedo_plane),
                             std::move(passes.normal_plane), std::move(passes.variance_plane)};
  }
  passes.CountVisible();
  if (passes.noisy_depth) passes.SimulateSensorDepth();
  if (look != nullptr && look->background && o.shade) passes.PasteBackground();
  if (o.normals) frame.normals = std::move(passes.normals);
  if (o.amodal_masks) passes.TraceAmodalMasks();
  return frame;
}

}  // namespace cadsynth
