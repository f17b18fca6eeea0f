// Every pixel of the renderer's depth and visible-instance images against a reference cast ray by
// ray: Embree's single-ray query on one flat (not instanced) robust scene, rays built in double
// precision through each pixel centre. Finely tessellated parts with many shared edges (a sphere, a
// gear, a plate with holes) over the floor, seen straight down, obliquely and at grazing angles.
//
// A pixel may differ only in a documented tie: its centre ray passes within kTiePx of a silhouette
// edge, so that the reference itself changes its answer when the ray is moved by kTiePx. A
// see-through pixel (a surface behind the front surface) is no tie: the reference, moved a
// little, still sees the front.
#include <embree3/rtcore.h>
#include <tbb/global_control.h>

#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cad/shape.h"
#include "render/renderer.h"
#include "variants/gear.h"
#include "variants/standard_parts.h"

namespace cadsynth {
namespace {

constexpr double kTiePx = 1e-3;       // how far from a silhouette edge a tie may be, in pixels
constexpr double kDepthTolMm = 0.01;  // float error of a hit at 1.5 m is ~1e-4 mm

struct Hit {
  int owner = 0;  // instance index + 1; 0 = nothing or the floor
  float depth = 0.0f;
};

// The reference: every instance's triangles moved to the world, one robust scene, single rays.
class ReferenceCaster {
 public:
  ReferenceCaster(const std::vector<Part>& parts, const Scene& scene) {
    device_ = rtcNewDevice(nullptr);
    scene_ = rtcNewScene(device_);
    rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
    for (size_t i = 0; i < scene.instances.size(); ++i) {
      const Mesh& mesh = parts[scene.instances[i].part].mesh;
      const Eigen::Isometry3d& T = scene.instances[i].world_from_model;
      std::vector<Eigen::Vector3f> world;
      for (const Eigen::Vector3f& p : mesh.positions)
        world.push_back((T * p.cast<double>()).cast<float>());
      std::vector<uint32_t> indices;
      for (const auto& t : mesh.triangles) indices.insert(indices.end(), {t[0], t[1], t[2]});
      Add(world, indices, static_cast<unsigned>(i + 1));
    }
    const float h = static_cast<float>(scene.floor_half_size_mm);
    Add({{-h, -h, 0}, {h, -h, 0}, {h, h, 0}, {-h, h, 0}}, {0, 1, 2, 0, 2, 3}, 0);
    rtcCommitScene(scene_);
  }
  ~ReferenceCaster() {
    rtcReleaseScene(scene_);
    rtcReleaseDevice(device_);
  }

  // The first hit of the ray through image point (x, y) (pixel centres at u + 0.5).
  Hit Cast(const Camera& camera, double x, double y) const {
    const Intrinsics& k = camera.intrinsics;
    const Eigen::Vector3d d =
        camera.world_from_cam.linear() * Eigen::Vector3d((x - k.cx) / k.fx, (y - k.cy) / k.fy, 1);
    const Eigen::Vector3d o = camera.world_from_cam.translation();
    RTCRayHit rh;
    rh.ray.org_x = static_cast<float>(o.x());
    rh.ray.org_y = static_cast<float>(o.y());
    rh.ray.org_z = static_cast<float>(o.z());
    rh.ray.dir_x = static_cast<float>(d.x());
    rh.ray.dir_y = static_cast<float>(d.y());
    rh.ray.dir_z = static_cast<float>(d.z());
    rh.ray.tnear = 1.0f;
    rh.ray.tfar = 1e7f;
    rh.ray.time = 0.0f;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    rtcIntersect1(scene_, &context, &rh);
    Hit hit;
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return hit;
    hit.depth = rh.ray.tfar;  // camera-frame z, since d has z = 1 in the camera frame
    hit.owner = static_cast<int>(rh.hit.geomID);
    return hit;
  }

 private:
  void Add(const std::vector<Eigen::Vector3f>& positions, const std::vector<uint32_t>& indices,
           unsigned id) {
    RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(
        g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), positions.size()));
    for (size_t i = 0; i < positions.size(); ++i) {
      for (int c = 0; c < 3; ++c) v[3 * i + c] = positions[i][c];
    }
    auto* t = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
        g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), indices.size() / 3));
    std::copy(indices.begin(), indices.end(), t);
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(scene_, g, id);
    rtcReleaseGeometry(g);
  }
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
};

bool Same(const Hit& a, const Hit& b, double depth_tol) {
  return a.owner == b.owner && std::abs(a.depth - b.depth) <= depth_tol;
}

struct Comparison {
  long pixels = 0, ties = 0, wrong = 0, mask_outside_amodal = 0;
  std::string first_wrong;
};

Comparison CompareEveryPixel(const Renderer& renderer, const ReferenceCaster& reference,
                             const Camera& camera, const std::string& view) {
  const Frame frame = renderer.Render(camera);
  const int w = camera.intrinsics.width, h = camera.intrinsics.height;
  Comparison c;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const size_t p = static_cast<size_t>(v) * w + u;
      ++c.pixels;
      const Hit got{frame.instance[p], frame.depth[p]};
      if (got.owner > 0 && !frame.instances[got.owner - 1].Covers(u, v, w, h))
        ++c.mask_outside_amodal;
      const Hit want = reference.Cast(camera, u + 0.5, v + 0.5);
      if (Same(got, want, kDepthTolMm)) continue;
      // A tie: the reference, moved by kTiePx, gives the renderer's answer (the depth allowed to
      // change along the surface by as much as the move can make it).
      bool tie = false;
      for (const auto& [du, dv] :
           {std::pair{kTiePx, 0.0}, {-kTiePx, 0.0}, {0.0, kTiePx}, {0.0, -kTiePx}}) {
        tie = tie || Same(got, reference.Cast(camera, u + 0.5 + du, v + 0.5 + dv), 0.5);
      }
      if (tie) {
        ++c.ties;
        continue;
      }
      if (c.wrong++ == 0) {
        c.first_wrong = view + " pixel (" + std::to_string(u) + ", " + std::to_string(v) +
                        "): rendered owner " + std::to_string(got.owner) + " at " +
                        std::to_string(got.depth) + " mm, reference owner " +
                        std::to_string(want.owner) + " at " + std::to_string(want.depth) + " mm";
      }
    }
  }
  return c;
}

TEST(ExactLabels, EveryPixelMatchesRobustSingleRays) {
  const TessellationOptions fine{0.01, 0.1};
  GearOptions gear;
  gear.teeth = 31;
  gear.module_mm = 3.0;
  gear.face_width_mm = 20.0;
  gear.bore_diameter_mm = 30.0;
  const std::vector<Part> parts = {
      MakePart("sphere", MakeSphere(60.0), fine),
      MakePart("gear", MakeGear(gear), fine),
      MakePart("plate", MakeFaceplate(160.0, 120.0, 8.0, 3, 4, 14.0, 20.0).shape, fine),
  };
  for (const Part& part : parts) ASSERT_GT(part.mesh.num_triangles(), 2000u) << part.name;
  Scene scene;
  // Part `part` turned by `yaw` about z, its lowest point at height `base`, centred at (x, y).
  const auto place = [&](int part, double x, double y, double yaw, double base) {
    const Eigen::AlignedBox3d box = parts[part].mesh.Bounds().cast<double>();
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    T.translation() = Eigen::Vector3d(x, y, base - box.min().z());
    scene.instances.push_back(Instance{part, parts[part].name, T});
  };
  // Straight-down views look at the sphere's pole, where many triangles share a vertex, on top of
  // the plate at the image centre.
  place(2, 0.0, 0.0, 0.0, 0.0);
  place(0, 0.0, 0.0, 0.3, 8.0);
  place(1, 150.0, -40.0, 0.7, 0.0);
  place(0, -140.0, 60.0, 0.0, 0.0);
  const Renderer renderer(parts, scene);
  const ReferenceCaster reference(parts, scene);

  Comparison total;
  int views = 0;
  const Eigen::Vector3d target(0, 0, 0);
  for (const double radius : {650.0, 1050.0, 1450.0}) {
    for (const double pitch_deg : {90.0, 60.0, 30.0, 8.0}) {
      for (int yaw_deg = 0; yaw_deg < 360; yaw_deg += pitch_deg == 90.0 ? 45 : 60) {
        Camera camera;
        camera.world_from_cam =
            WorldFromCamOnSphere(target, yaw_deg * M_PI / 180.0, pitch_deg * M_PI / 180.0, radius);
        const std::string view = "radius " + std::to_string(radius) + " pitch " +
                                 std::to_string(pitch_deg) + " yaw " + std::to_string(yaw_deg);
        const Comparison c = CompareEveryPixel(renderer, reference, camera, view);
        total.pixels += c.pixels;
        total.ties += c.ties;
        total.wrong += c.wrong;
        total.mask_outside_amodal += c.mask_outside_amodal;
        if (total.first_wrong.empty()) total.first_wrong = c.first_wrong;
        ++views;
      }
    }
  }
  EXPECT_EQ(total.wrong, 0) << "first: " << total.first_wrong;
  EXPECT_EQ(total.mask_outside_amodal, 0)
      << "visible pixels outside their instance's full silhouette";
  EXPECT_LE(total.ties, total.pixels / 100000)
      << "silhouette-edge ties in " << total.pixels << " pixels";
  std::cout << views << " views, " << total.pixels << " pixels, " << total.ties
            << " silhouette ties\n";
}

}  // namespace
}  // namespace cadsynth
