#include "render/renderer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "cad/error.h"

namespace cadsynth {

bool RenderOptions::Check(std::string* why) const {
  if (rows_per_task < 1) {
    *why = "rows_per_task must be at least 1";
    return false;
  }
  return true;
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
  std::vector<float> positions;   // xyz per vertex, plus 1 float of padding at the end for SSE loads
  std::vector<uint32_t> indices;  // 3 per triangle
  std::vector<Eigen::Vector3f> normals;
};

constexpr unsigned kInvalid = RTC_INVALID_GEOMETRY_ID;

}  // namespace

struct Renderer::Impl {
  RenderOptions options;
  Scene scene;
  DeviceErrors errors;
  RTCDevice device = nullptr;
  std::vector<RTCScene> part_scenes;
  RTCScene world = nullptr;                 // every instance and the floor
  std::vector<RTCScene> solo;               // one instance alone, for amodal masks
  std::vector<PartBuffers> parts;
  std::vector<Eigen::AlignedBox3d> model_bounds;  // per part, model frame
  std::vector<Eigen::Matrix3f> instance_rotation;  // world_from_model rotation per instance
  std::vector<Eigen::Vector3f> albedo;             // colour per instance
  unsigned floor_id = kInvalid;

  ~Impl() {
    for (RTCScene s : solo) rtcReleaseScene(s);
    if (world != nullptr) rtcReleaseScene(world);
    for (RTCScene s : part_scenes) rtcReleaseScene(s);
    if (device != nullptr) rtcReleaseDevice(device);
  }

  void ThrowIfFailed(const char* stage) {
    std::lock_guard<std::mutex> lock(errors.mutex);
    if (!errors.first.empty()) throw Error(std::string("renderer (") + stage + "): " + errors.first);
  }

  RTCGeometry NewInstance(int index) {
    const Instance& instance = scene.instances[index];
    RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(geometry, part_scenes[instance.part]);
    const Eigen::Matrix<float, 3, 4> m = instance.world_from_model.matrix().topRows<3>().cast<float>();
    rtcSetGeometryTransform(geometry, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, m.data());
    rtcCommitGeometry(geometry);
    return geometry;
  }
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

  im.device = rtcNewDevice(nullptr);
  if (im.device == nullptr) throw Error("renderer: could not create an Embree device");
  rtcSetDeviceErrorFunction(im.device, OnEmbreeError, &im.errors);

  // One bottom-level scene per part, in the part's model frame.
  for (const Part& part : parts) {
    PartBuffers buffers;
    buffers.positions.reserve(3 * part.mesh.num_vertices() + 1);
    for (const Eigen::Vector3f& p : part.mesh.positions) {
      buffers.positions.insert(buffers.positions.end(), {p.x(), p.y(), p.z()});
    }
    buffers.positions.push_back(0.0f);
    buffers.indices.reserve(3 * part.mesh.num_triangles());
    for (const auto& t : part.mesh.triangles) {
      buffers.indices.insert(buffers.indices.end(), {t[0], t[1], t[2]});
    }
    buffers.normals = part.mesh.normals;
    im.parts.push_back(std::move(buffers));
    im.model_bounds.push_back(part.mesh.Bounds());
  }
  for (PartBuffers& buffers : im.parts) {
    RTCScene part_scene = rtcNewScene(im.device);
    RTCGeometry mesh = rtcNewGeometry(im.device, RTC_GEOMETRY_TYPE_TRIANGLE);
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
    im.part_scenes.push_back(part_scene);
  }
  im.ThrowIfFailed("building part geometry");

  // The world: instance i has geometry id i; the floor comes after them.
  im.world = rtcNewScene(im.device);
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    RTCGeometry geometry = im.NewInstance(static_cast<int>(i));
    rtcAttachGeometryByID(im.world, geometry, static_cast<unsigned>(i));
    rtcReleaseGeometry(geometry);
    im.instance_rotation.push_back(scene.instances[i].world_from_model.linear().cast<float>());
    const Instance& instance = scene.instances[i];
    const size_t part = static_cast<size_t>(instance.part);
    im.albedo.push_back(instance.color             ? *instance.color
                        : part < scene.part_colors.size() ? scene.part_colors[part]
                                                          : Eigen::Vector3f(0.7f, 0.7f, 0.7f));
  }
  if (scene.floor) {
    const float h = static_cast<float>(scene.floor_half_size_mm);
    RTCGeometry floor = rtcNewGeometry(im.device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(floor, RTC_BUFFER_TYPE_VERTEX, 0,
                                                          RTC_FORMAT_FLOAT3, 3 * sizeof(float), 4));
    const float corners[12] = {-h, -h, 0, h, -h, 0, h, h, 0, -h, h, 0};
    std::copy(corners, corners + 12, v);
    auto* idx = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
        floor, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), 2));
    const uint32_t tris[6] = {0, 1, 2, 0, 2, 3};
    std::copy(tris, tris + 6, idx);
    rtcCommitGeometry(floor);
    im.floor_id = static_cast<unsigned>(scene.instances.size());
    rtcAttachGeometryByID(im.world, floor, im.floor_id);
    rtcReleaseGeometry(floor);
  }
  rtcCommitScene(im.world);

  for (size_t i = 0; i < scene.instances.size(); ++i) {
    RTCScene alone = rtcNewScene(im.device);
    RTCGeometry geometry = im.NewInstance(static_cast<int>(i));
    rtcAttachGeometryByID(alone, geometry, 0);
    rtcReleaseGeometry(geometry);
    rtcCommitScene(alone);
    im.solo.push_back(alone);
  }
  im.ThrowIfFailed("building the scene");
}

Renderer::~Renderer() = default;

namespace {

inline void InitRay(RTCRayHit* rh, const Eigen::Vector3f& origin, const Eigen::Vector3f& dir) {
  rh->ray.org_x = origin.x();
  rh->ray.org_y = origin.y();
  rh->ray.org_z = origin.z();
  rh->ray.dir_x = dir.x();
  rh->ray.dir_y = dir.y();
  rh->ray.dir_z = dir.z();
  rh->ray.tnear = 0.0f;
  rh->ray.tfar = std::numeric_limits<float>::infinity();
  rh->ray.time = 0.0f;
  rh->ray.mask = 0xFFFFFFFFu;  // Debian's Embree is built with ray masks: set every bit
  rh->ray.id = 0;
  rh->ray.flags = 0;
  rh->hit.geomID = kInvalid;
  rh->hit.primID = kInvalid;
  rh->hit.instID[0] = kInvalid;
}

inline uint8_t ToByte(float value) {
  return static_cast<uint8_t>(std::lround(std::clamp(value, 0.0f, 1.0f) * 255.0f));
}

// Pixel rectangle [u0, u1) x [v0, v1) covering the projection of a box, or the whole image when
// part of the box is behind the camera.
struct PixelRect {
  int u0, v0, u1, v1;
};

PixelRect ProjectedRect(const Eigen::AlignedBox3d& model_box, const Eigen::Isometry3d& cam_from_model,
                        const Intrinsics& k) {
  const PixelRect whole{0, 0, k.width, k.height};
  double umin = std::numeric_limits<double>::infinity(), vmin = umin;
  double umax = -umin, vmax = -umin;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d corner = model_box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c));
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
  r.u0 = std::clamp(static_cast<int>(std::floor(umin - 0.5)) - 1, 0, k.width);
  r.u1 = std::clamp(static_cast<int>(std::ceil(umax - 0.5)) + 2, 0, k.width);
  r.v0 = std::clamp(static_cast<int>(std::floor(vmin - 0.5)) - 1, 0, k.height);
  r.v1 = std::clamp(static_cast<int>(std::ceil(vmax - 0.5)) + 2, 0, k.height);
  return r;
}

}  // namespace

Frame Renderer::Render(const Camera& camera) const {
  const Impl& im = *impl_;
  const Intrinsics& k = camera.intrinsics;
  std::string why;
  if (!k.Check(&why)) throw Error("camera: " + why);
  const int w = k.width, h = k.height;
  const size_t num_pixels = static_cast<size_t>(w) * h;

  Frame frame;
  frame.camera = camera;
  frame.rgb.assign(3 * num_pixels, 0);
  frame.depth.assign(num_pixels, 0.0f);
  frame.instance.assign(num_pixels, 0);

  const Eigen::Matrix3f rotation = camera.world_from_cam.linear().cast<float>();
  const Eigen::Vector3f origin = camera.world_from_cam.translation().cast<float>();
  const auto ray_dir = [&](int u, int v) {
    const Eigen::Vector3f d_cam(static_cast<float>((u + 0.5 - k.cx) / k.fx),
                                static_cast<float>((v + 0.5 - k.cy) / k.fy), 1.0f);
    return Eigen::Vector3f(rotation * d_cam);  // z of d_cam is 1, so t is the depth
  };
  const Eigen::Vector3f to_light = -im.scene.light_direction.normalized().cast<float>();
  const Eigen::Vector3f background = im.scene.background_color;

  tbb::parallel_for(
      tbb::blocked_range<int>(0, h, im.options.rows_per_task), [&](const tbb::blocked_range<int>& rows) {
        RTCIntersectContext context;
        for (int v = rows.begin(); v < rows.end(); ++v) {
          for (int u = 0; u < w; ++u) {
            const size_t pixel = static_cast<size_t>(v) * w + u;
            const Eigen::Vector3f dir = ray_dir(u, v);
            RTCRayHit rh;
            InitRay(&rh, origin, dir);
            rtcInitIntersectContext(&context);
            rtcIntersect1(im.world, &context, &rh);
            Eigen::Vector3f color = background;
            if (rh.hit.geomID != kInvalid) {
              frame.depth[pixel] = rh.ray.tfar;
              Eigen::Vector3f normal, albedo;
              const unsigned inst = rh.hit.instID[0];
              if (inst != kInvalid) {
                const int part = im.scene.instances[inst].part;
                const PartBuffers& buffers = im.parts[part];
                const uint32_t* tri = &buffers.indices[3 * rh.hit.primID];
                const float b1 = rh.hit.u, b2 = rh.hit.v, b0 = 1.0f - b1 - b2;
                normal = im.instance_rotation[inst] *
                         (b0 * buffers.normals[tri[0]] + b1 * buffers.normals[tri[1]] +
                          b2 * buffers.normals[tri[2]]);
                albedo = im.albedo[inst];
                frame.instance[pixel] = static_cast<uint16_t>(inst + 1);
              } else {
                normal = Eigen::Vector3f::UnitZ();
                albedo = im.scene.floor_color;
              }
              normal.normalize();
              if (normal.dot(dir) > 0.0f) normal = -normal;  // shade the side the camera sees
              const float diffuse = std::max(0.0f, normal.dot(to_light));
              color = albedo * (im.scene.ambient + im.scene.light_intensity * diffuse);
            }
            for (int c = 0; c < 3; ++c) frame.rgb[3 * pixel + c] = ToByte(color[c]);
          }
        }
      });

  // Per-instance truth: pose, amodal silhouette (the instance traced alone), pixel counts.
  const Eigen::Isometry3d cam_from_world = camera.world_from_cam.inverse();
  frame.instances.resize(im.scene.instances.size());
  for (size_t i = 0; i < im.scene.instances.size(); ++i) {
    frame.instances[i].cam_from_model = cam_from_world * im.scene.instances[i].world_from_model;
  }
  for (size_t p = 0; p < num_pixels; ++p) {
    if (frame.instance[p] != 0) ++frame.instances[frame.instance[p] - 1].px_count_visib;
  }
  {
    tbb::parallel_for(size_t{0}, im.scene.instances.size(), [&](size_t i) {
      Frame::InstanceTruth& truth = frame.instances[i];
      truth.amodal_mask.assign(num_pixels, 0);
      const int part = im.scene.instances[i].part;
      const PixelRect r = ProjectedRect(im.model_bounds[part], truth.cam_from_model, k);
      int count = 0;
      RTCIntersectContext context;
      for (int v = r.v0; v < r.v1; ++v) {
        for (int u = r.u0; u < r.u1; ++u) {
          RTCRayHit rh;
          InitRay(&rh, origin, ray_dir(u, v));
          rtcInitIntersectContext(&context);
          rtcIntersect1(im.solo[i], &context, &rh);
          if (rh.hit.geomID != kInvalid) {
            truth.amodal_mask[static_cast<size_t>(v) * w + u] = 1;
            ++count;
          }
        }
      }
      truth.px_count_all = count;
    });
  }
  return frame;
}

}  // namespace cadsynth
