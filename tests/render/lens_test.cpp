// Lens effects against answers worked out by hand or by OpenCV: the distortion model against
// calib3d's projectPoints and undistortPoints, the thin lens's blur disc and the motion blur's
// streak measured as the variance of an edge's line-spread function, and the rig's motion.
#include <cmath>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include <gtest/gtest.h>

#include "tests/render/render_support.h"

#include "cad/core/error.h"
#include "cad/shape.h"
#include "render/camera.h"
#include "render/renderer.h"

namespace cadsynth {
namespace {

using testing::LookingDown;

const Distortion kBarrel{-0.28, 0.09, 0.0012, -0.0008, -0.012};

TEST(Distortion, MatchesOpenCvProjectPoints) {
  const Intrinsics k{640, 480, 520.0, 515.0, 322.0, 236.5, kBarrel};
  std::vector<cv::Point3d> points;
  for (int i = -6; i <= 6; ++i) {
    for (int j = -5; j <= 5; ++j) points.emplace_back(0.07 * i, 0.06 * j, 1.0 + 0.01 * (i + j));
  }
  const cv::Matx33d K(k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1);
  const std::vector<double> dist = {kBarrel.k1, kBarrel.k2, kBarrel.p1, kBarrel.p2, kBarrel.k3};
  std::vector<cv::Point2d> projected;
  cv::projectPoints(points, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, dist, projected);
  for (size_t i = 0; i < points.size(); ++i) {
    Eigen::Vector2d uv;
    ASSERT_TRUE(k.Project(Eigen::Vector3d(points[i].x, points[i].y, points[i].z), &uv));
    EXPECT_NEAR(uv.x(), projected[i].x, 1e-9);
    EXPECT_NEAR(uv.y(), projected[i].y, 1e-9);
    // And back: the ray of that image point is the point's direction.
    Eigen::Vector2d xy;
    ASSERT_TRUE(k.Unproject(uv.x(), uv.y(), &xy));
    EXPECT_NEAR(xy.x(), points[i].x / points[i].z, 1e-10);
    EXPECT_NEAR(xy.y(), points[i].y / points[i].z, 1e-10);
  }
}

TEST(Distortion, FoldRadiusAndTheImagesItRefuses) {
  // r (1 + k1 r^2) stops growing where 1 + 3 k1 r^2 = 0.
  EXPECT_NEAR((Distortion{-0.3}).FoldRadius(), std::sqrt(1.0 / 0.9), 1e-12);
  // 1 + 3 k1 s + 5 k2 s^2 with k1 = -0.5, k2 = 0.05: roots s = 3 -+ sqrt(5), the first is the fold.
  EXPECT_NEAR((Distortion{-0.5, 0.05}).FoldRadius(), std::sqrt(3.0 - std::sqrt(5.0)), 1e-12);
  // A tiny k3 must not lose that fold to cancellation in the quadratic of g's turning points.
  EXPECT_NEAR((Distortion{-0.5, 0.05, 0, 0, 1e-19}).FoldRadius(), std::sqrt(3.0 - std::sqrt(5.0)),
              1e-9);
  EXPECT_TRUE((Distortion{-0.5, 0.05}).InsideFold(0.76));
  EXPECT_FALSE((Distortion{-0.5, 0.05}).InsideFold(0.77));
  EXPECT_FALSE((Distortion{-0.5, 0.05}).InsideFold(5.5));   // past the fold, though g > 0 again
  EXPECT_TRUE(std::isinf((Distortion{0.2}).FoldRadius()));  // pincushion never folds
  // Beyond the fold no ray: OpenCV's model is not a lens there.
  Eigen::Vector2d xy;
  EXPECT_FALSE((Distortion{-0.3}).Undistort({0.9, 0.0}, {0.9, 0.0}, &xy));  // max r' is 0.703
  EXPECT_TRUE((Distortion{-0.3}).Undistort({0.6, 0.0}, {0.6, 0.0}, &xy));
  EXPECT_NEAR(xy.x() * (1 - 0.3 * xy.x() * xy.x()), 0.6, 1e-12);
  // A 90-degree camera with k1 = -0.3 folds inside its corners (r = 1.41 > 1.054).
  std::string why;
  Intrinsics wide = Intrinsics::FromFov(640, 640, M_PI / 2);
  wide.distortion = Distortion{-0.3};
  EXPECT_FALSE(wide.Check(&why));
  EXPECT_NE(why.find("folds back inside the image"), std::string::npos) << why;
  const Intrinsics ok{640, 480, 520.0, 515.0, 322.0, 236.5, kBarrel};
  EXPECT_TRUE(ok.Check(&why)) << why;
}

// Boxes and a ball over the floor, seen from 600 mm straight down.
struct Table {
  std::vector<Part> parts = {MakePart("box", MakeBox(60, 40, 30), TessellationOptions{0.05, 0.1}),
                             MakePart("ball", MakeSphere(25.0), TessellationOptions{0.02, 0.05})};
  Scene scene;
  Table() {
    const auto at = [](double x, double y, double yaw) {
      Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
      t.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      t.translation() = Eigen::Vector3d(x, y, 15);  // the models are centred: boxes on the floor
      return t;
    };
    scene.instances = {Instance{0, "box", at(-150, -90, 0.3)},
                       Instance{0, "box", at(170, 110, -0.7)},
                       Instance{1, "ball", at(0, 0, 0) * Eigen::Translation3d(0, 0, 10)},
                       Instance{1, "ball", at(240, -170, 0) * Eigen::Translation3d(0, 0, 10)},
                       Instance{0, "box", at(-260, 180, 1.1)},
                       Instance{1, "ball", at(392, -5, 0) * Eigen::Translation3d(0, 0, 10)}};
  }
};

TEST(Distortion, RenderedLabelsAreThePinholeLabelsMovedByOpenCvsModel) {
  // The distorted camera's instance ids must be those the pinhole camera sees at the undistorted
  // image point OpenCV's undistortPoints gives for each pixel centre. The pinhole image is
  // rendered twice as large (same f) so that it holds every ray of the distorted one; nearest
  // pixel look-up leaves disagreements at silhouettes only.
  Table table;
  const Renderer renderer(table.parts, table.scene);
  Camera distorted;
  distorted.intrinsics = Intrinsics{640, 480, 560.0, 560.0, 321.5, 238.0, kBarrel};
  distorted.world_from_cam = LookingDown({10, -5, 600});
  Camera pinhole = distorted;
  pinhole.intrinsics = Intrinsics{1280, 960, 560.0, 560.0, 641.5, 478.0};
  const Frame d = renderer.Render(distorted);
  const Frame p = renderer.Render(pinhole);

  const Intrinsics& k = distorted.intrinsics;
  std::vector<cv::Point2d> centres;
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) centres.emplace_back(u + 0.5, v + 0.5);
  }
  const cv::Matx33d K(k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1);
  const std::vector<double> dist = {kBarrel.k1, kBarrel.k2, kBarrel.p1, kBarrel.p2, kBarrel.k3};
  std::vector<cv::Point2d> normalised;
  cv::undistortPoints(
      centres, normalised, K, dist, cv::noArray(), cv::noArray(),
      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-12));
  const Intrinsics& q = pinhole.intrinsics;
  size_t agree = 0, objects = 0, edge = 0;
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const size_t i = static_cast<size_t>(v) * k.width + u;
      const int pu = static_cast<int>(std::floor(q.fx * normalised[i].x + q.cx));
      const int pv = static_cast<int>(std::floor(q.fy * normalised[i].y + q.cy));
      ASSERT_TRUE(pu >= 0 && pv >= 0 && pu < q.width && pv < q.height) << u << "," << v;
      const uint16_t id = p.instance[static_cast<size_t>(pv) * q.width + pu];
      agree += d.instance[i] == id;
      objects += d.instance[i] != 0;
      // The floor's depth is the camera's height wherever it is seen, through any ray.
      if (d.instance[i] == 0 && id == 0 && d.depth[i] > 0) {
        EXPECT_NEAR(d.depth[i], 600.0f, 1e-3f);
      }
      // Pixels next to a silhouette in the pinhole image may fall either side.
      bool near_edge = false;
      for (int dv = -1; dv <= 1; ++dv) {
        for (int du = -1; du <= 1; ++du) {
          const int x = std::clamp(pu + du, 0, q.width - 1),
                    y = std::clamp(pv + dv, 0, q.height - 1);
          near_edge |= p.instance[static_cast<size_t>(y) * q.width + x] != id;
        }
      }
      if (!near_edge) {
        EXPECT_EQ(d.instance[i], id) << u << "," << v;
      } else {
        ++edge;
      }
    }
  }
  EXPECT_GT(objects, 8000u);
  EXPECT_GT(static_cast<double>(agree) / d.instance.size(), 0.995) << edge << " edge pixels";
  // The full silhouettes went through the same lens: an instance nothing hides has its mask.
  for (size_t i = 0; i < d.instances.size(); ++i) {
    int full = 0;
    for (uint8_t m : d.instances[i].amodal_mask) full += m;
    EXPECT_EQ(full, d.instances[i].px_count_visib) << i;
    EXPECT_EQ(d.instances[i].px_count_all, d.instances[i].px_count_visib) << i;
  }
  // A depth sensor behind the same lens (its incidence angles from the traced rays): on the floor
  // at 600 mm, unbiased, with noise of the Kinect's scale (axial sigma 1.28 mm, disparity steps
  // of 1 mm there) and returns on at least 90% of it.
  SensorOptions kinect;
  kinect.depth = DepthModel::Defaults(DepthModel::Kind::kKinectV1);
  const Frame n = renderer.Render(distorted, 0, kinect);
  double sum = 0, sum2 = 0;
  size_t floor = 0, returned = 0;
  for (size_t i = 0; i < n.depth.size(); ++i) {
    if (n.instance[i] != 0 || !(n.depth[i] > 0)) continue;
    ++floor;
    if (!(n.sensor_depth[i] > 0)) continue;
    const double e = n.sensor_depth[i] - n.depth[i];
    sum += e, sum2 += e * e, ++returned;
  }
  EXPECT_GT(returned, floor * 9 / 10);
  EXPECT_NEAR(sum / returned, 0.0, 0.5);
  EXPECT_LT(std::sqrt(sum2 / returned), 4.0);
  // The last ball lies across the right border: the 3x canvas traced through the lens beyond the
  // image holds the rest of it, as the pinhole's does.
  const Frame::InstanceTruth& cut = d.instances.back();
  EXPECT_GT(cut.px_count_all, 100);
  EXPECT_GT(cut.px_count_canvas, cut.px_count_all + 100);
  EXPECT_GE(cut.bbox_canvas[2], k.width);
  EXPECT_LT(cut.bbox_canvas[0], k.width);
}

// A 200 x 400 x 1 mm grey (albedo 0.5) plate with its edge along world y at x = 0, 300 mm below a
// camera looking down, in a uniform sky: the plate shows half the sky's radiance, the rest the sky.
struct Edge {
  std::vector<Part> parts = {MakePart("plate", MakeBox(200, 400, 1), TessellationOptions{})};
  Scene scene;
  Camera camera;
  Edge() {
    scene.floor = false;
    scene.light_sources.clear();
    scene.environment.color = Eigen::Vector3f::Ones();
    Material m;
    m.surface.base_color = Eigen::Vector3f::Constant(0.5f);
    m.surface.metallic = 0;
    m.surface.specular = 0;
    m.surface.roughness = 1;
    scene.materials = {m};
    scene.instance_material = {0};
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.translation() = Eigen::Vector3d(100, 0, -0.5);  // (the model is centred) top at z = 0
    scene.instances = {Instance{0, "plate", t}};
    camera.intrinsics = Intrinsics{96, 64, 200.0, 200.0, 48.0, 32.0};
    camera.world_from_cam = LookingDown({0, 0, 300});
  }
  RenderOptions Pbr() const {
    RenderOptions o;
    o.mode = RenderOptions::Mode::kPbr;
    o.samples = 64;
    o.bounces = 0;
    o.hdr = true;
    o.view = RenderOptions::View::kStandard;
    o.amodal_masks = false;
    return o;
  }
};

// The variance (px^2) of the line-spread function across the edge: the differences of the
// column means of the radiance, within `half` pixels of the edge at u = 48.
double EdgeSpreadVariance(const Frame& frame, int half) {
  const int w = frame.width(), h = frame.height();
  std::vector<double> column(static_cast<size_t>(w), 0.0);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u)
      column[u] += frame.radiance[3 * (static_cast<size_t>(v) * w + u)] / h;
  }
  double sum = 0, mean = 0, second = 0;
  for (int u = 48 - half; u < 48 + half; ++u) {
    const double d = column[u] - column[u + 1];  // sky (1) left, plate (0.5) right
    const double x = u + 1.0;                    // between pixels u and u + 1
    sum += d, mean += d * x, second += d * x * x;
  }
  EXPECT_NEAR(sum, 0.5, 0.01);
  mean /= sum;
  return second / sum - mean * mean;
}

TEST(ThinLens, EdgeBlursIntoTheDiscTheLensEquationGives) {
  Edge edge;
  const Renderer renderer(edge.parts, edge.scene, edge.Pbr());
  // The differences of pixel means sample the line-spread function convolved with the pixel's box
  // twice (a triangle, variance 1/6); a wide blur adds its own variance to that. A pinhole's edge
  // on a pixel border is one step: variance 0.
  SensorOptions sharp;
  EXPECT_NEAR(EdgeSpreadVariance(renderer.Render(edge.camera, 0, sharp), 6), 0.0, 0.01);
  // Focused at 150 mm, the plate at 300 mm: a disc of f A |1/150 - 1/300| = 200 * 27 / 300 = 18
  // px, whose projection on a line has variance (18 / 2)^2 / 4 = 20.25.
  SensorOptions blurred;
  blurred.lens.focal_length_mm = 54.0;
  blurred.lens.f_number = 2.0;
  blurred.lens.focus_distance_mm = 150.0;
  const Frame frame = renderer.Render(edge.camera, 0, blurred);
  EXPECT_NEAR(EdgeSpreadVariance(frame, 14), 20.25 + 1.0 / 6.0, 0.04 * 20.25);
  // Labels keep the pinhole's: the plate's pixels are those right of the edge.
  for (int v = 0; v < 64; ++v) {
    for (int u = 0; u < 96; ++u) EXPECT_EQ(frame.instance[v * 96 + u], u >= 48 ? 1 : 0);
  }
  // In focus, no blur.
  blurred.lens.focus_distance_mm = 300.0;
  EXPECT_NEAR(EdgeSpreadVariance(renderer.Render(edge.camera, 0, blurred), 6), 0.0, 0.01);
}

TEST(CameraMotion, EdgeSmearsIntoTheStreakTheMotionGives) {
  Edge edge;
  const Renderer renderer(edge.parts, edge.scene, edge.Pbr());
  // 3 m/s across the image for 10 ms: the scene moves f v T / z = 200 * 30 / 300 = 20 px, a box
  // of variance 20^2 / 12.
  SensorOptions moving;
  moving.motion.velocity_mm_s = Eigen::Vector3d(3000, 0, 0);
  moving.motion.exposure_s = 0.01;
  const Frame frame = renderer.Render(edge.camera, 0, moving);
  EXPECT_NEAR(EdgeSpreadVariance(frame, 14), 400.0 / 12 + 1.0 / 6.0, 0.03 * 400 / 12);
  for (int u = 0; u < 96; ++u) EXPECT_EQ(frame.instance[u], u >= 48 ? 1 : 0);  // mid-exposure
  // Panning about the camera's y axis by 0.1 rad: f tan(0.05) * 2 = 20.01 px at the centre.
  SensorOptions panning;
  panning.motion.angular_velocity_rad_s = Eigen::Vector3d(0, 10, 0);
  panning.motion.exposure_s = 0.01;
  const double w = 2 * 200 * std::tan(0.05);
  EXPECT_NEAR(EdgeSpreadVariance(renderer.Render(edge.camera, 0, panning), 14),
              w * w / 12 + 1.0 / 6.0, 0.03 * w * w / 12);
  // Motion along the optical axis leaves the edge through the principal point where it is.
  SensorOptions forward;
  forward.motion.velocity_mm_s = Eigen::Vector3d(0, 0, 3000);
  forward.motion.exposure_s = 0.01;
  EXPECT_NEAR(EdgeSpreadVariance(renderer.Render(edge.camera, 0, forward), 6), 0.0, 0.01);
}

TEST(CameraMotion, IsRigidAndSeenAlikeByEveryCameraOfARig) {
  CameraMotion m;
  m.velocity_mm_s = Eigen::Vector3d(120, -40, 300);
  m.angular_velocity_rad_s = Eigen::Vector3d(0.4, -1.1, 0.7);
  m.exposure_s = 0.05;
  // A one-parameter group: At(a) At(b) = At(a + b), and At(0) is the identity.
  const Eigen::Isometry3d ab = m.At(0.2) * m.At(0.25);
  EXPECT_LT((ab.matrix() - m.At(0.45).matrix()).norm(), 1e-12);
  EXPECT_LT((m.At(0.0).matrix() - Eigen::Matrix4d::Identity()).norm(), 1e-15);
  // Pure translation: v t.
  CameraMotion t;
  t.velocity_mm_s = Eigen::Vector3d(1000, 0, 0);
  t.exposure_s = 0.02;
  EXPECT_NEAR(t.At(0.5).translation().x(), 10.0, 1e-12);
  // A camera fixed to the rig at rig_from_cam moves with it: rig(tau) rig_from_cam equals
  // cam(0) times its own motion at tau.
  Eigen::Isometry3d rig_from_cam = Eigen::Isometry3d::Identity();
  rig_from_cam.linear() =
      Eigen::AngleAxisd(0.6, Eigen::Vector3d(1, 2, -1).normalized()).toRotationMatrix();
  rig_from_cam.translation() = Eigen::Vector3d(55, -20, 8);
  const CameraMotion seen = m.Seen(rig_from_cam);
  for (double tau : {-0.5, -0.1, 0.3, 0.5}) {
    const Eigen::Isometry3d a = m.At(tau) * rig_from_cam;
    const Eigen::Isometry3d b = rig_from_cam * seen.At(tau);
    EXPECT_LT((a.matrix() - b.matrix()).norm(), 1e-9) << tau;
  }
}

TEST(LensEffects, NeedThePathTracerAndRectifiedStereo) {
  Edge edge;
  const Renderer fast(edge.parts, edge.scene);
  SensorOptions lens;
  lens.lens.focal_length_mm = 16;
  EXPECT_THROW(fast.Render(edge.camera, 0, lens), Error);
  SensorOptions stereo;
  stereo.depth = DepthModel::Defaults(DepthModel::Kind::kActiveStereo);
  Camera camera = edge.camera;
  camera.intrinsics.distortion = Distortion{-0.05};
  EXPECT_THROW(fast.Render(camera, 0, stereo), Error);
}

}  // namespace
}  // namespace cadsynth
