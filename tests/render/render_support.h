// Cameras, materials, scenes and options shared by the render tests.
#pragma once

#include <numbers>

#include <tbb/global_control.h>
#include <Eigen/Geometry>

#include "render/material.h"
#include "render/renderer.h"
#include "render/scene.h"

namespace cadsynth::testing {

inline constexpr double kPi = std::numbers::pi;

// A camera at `eye` looking straight down (-z), image x along world +x, image y along world -y.
inline Eigen::Isometry3d LookingDown(const Eigen::Vector3d& eye) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  T.translation() = eye;
  return T;
}

// Pure Lambert of the given albedo: no dielectric layer.
inline Material Lambert(float albedo) {
  Material m;
  m.surface.base_color = Eigen::Vector3f::Constant(albedo);
  m.surface.metallic = 0;
  m.surface.specular = 0;
  m.surface.roughness = 1;
  return m;
}

// A scene with no light: no light sources, a black environment.
inline Scene Dark() {
  Scene scene;
  scene.light_sources.clear();
  scene.environment.color.setZero();
  return scene;
}

// A disc light of `power` W and `radius` mm facing straight down from `height` mm above the
// origin, and the radiance of a white Lambert floor straight under its centre: the irradiance
// pi L sin^2(alpha) over pi, L = P / (4 A) (Blender's area light), sin^2(alpha) = r^2 / (r^2 +
// h^2).
inline LightSource DownwardDisc(double radius, double height, double power) {
  LightSource disc;
  disc.kind = LightSource::Kind::kDisc;
  disc.radius_mm = radius;
  disc.position = {0, 0, height};
  disc.direction = {0, 0, -1};
  disc.power = power;
  return disc;
}
inline double WhiteFloorUnderDisc(double radius, double height, double power) {
  const double l = power / (4 * kPi * radius * radius * 1e-6);
  const double sin2 = radius * radius / (radius * radius + height * height);
  return kPi * l * sin2 / kPi;
}

// The physically based mode at `samples` paths per pixel (every pixel gets them all), the linear
// radiance kept (Frame::radiance), the standard display transform, no amodal masks.
inline RenderOptions Pbr(int samples, int bounces) {
  RenderOptions o;
  o.mode = RenderOptions::Mode::kPbr;
  o.samples = samples;
  o.bounces = bounces;
  o.hdr = true;
  o.view = RenderOptions::View::kStandard;
  o.amodal_masks = false;
  return o;
}

// Renders view `view` with TBB limited to `threads` threads (same-bytes tests).
inline Frame RenderOnThreads(const Renderer& renderer, const Camera& camera, uint64_t view,
                             int threads) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                            static_cast<size_t>(threads));
  return renderer.Render(camera, view);
}

}  // namespace cadsynth::testing
