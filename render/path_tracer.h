// The physically based mode's light transport (internal to render/: the Renderer owns the Embree
// scene and calls it per 4 x 4 tile of pixels).
//
// A unidirectional path tracer: at every surface it samples one light (next-event estimation)
// and the BSDF, and weights both by Veach's power heuristic so that small bright lights and
// sharp reflections are both sampled well; the environment and area lights are also found by
// BSDF rays. `bounces` surface interactions follow the first (Blender's max bounces: 0 is direct
// light only); Russian roulette ends dim paths from the third interaction on. Every random number
// comes from the pixel's own Owen-scrambled Sobol sequence seeded by (seed, view, pixel), so the
// image is the same for any thread count, tile order or shard.
#pragma once

#include <algorithm>
#include <cstdint>
#include <memory>
#include <vector>

#include <embree3/rtcore.h>
#include <Eigen/Core>

#include "render/camera.h"
#include "render/lights.h"
#include "render/material.h"
#include "render/pixel_rays.h"

namespace cadsynth {

// What a hit needs from the renderer's geometry.
struct TracedInstance {
  const uint32_t* indices = nullptr;                       // 3 per triangle, of the part's mesh
  const Eigen::Vector3f* normals = nullptr;                // per vertex, model frame
  const Eigen::Vector2f* uvs = nullptr;                    // per vertex, or none
  Eigen::Matrix3f rotation = Eigen::Matrix3f::Identity();  // world_from_model
  Eigen::Vector3f translation = Eigen::Vector3f::Zero();
  // The mesh's bounding box in the model frame (Material::Tangent::kRadial).
  Eigen::Vector3f box_centre = Eigen::Vector3f::Zero(), box_size = Eigen::Vector3f::Ones();
  Material material;  // base colour already resolved
};

// A fixture (Scene::Fixture): triangles in the world frame.
struct TracedFixture {
  const uint32_t* indices = nullptr;
  const Eigen::Vector3f* normals = nullptr;  // per vertex, world frame
  // The fixture's bounding box, world frame (Material::Tangent::kRadial).
  Eigen::Vector3f box_centre = Eigen::Vector3f::Zero(), box_size = Eigen::Vector3f::Ones();
  Material material;
};

struct PathTracerScene {
  RTCScene world = nullptr;  // instance i is instID i; the floor is geomID floor_id at top level
  unsigned floor_id = RTC_INVALID_GEOMETRY_ID;
  std::vector<TracedInstance> instances;
  Material floor;
  unsigned first_fixture_id = RTC_INVALID_GEOMETRY_ID;  // fixture f is geomID first + f
  std::vector<TracedFixture> fixtures;
  std::vector<LightSource> lights;
  Environment environment;
  int bounces = 3;
  // Of the bounces, how many may be glossy (Blender's Glossy bounces; RenderOptions): after one
  // more, the path only gathers the light and sky its segment finds, as after its last bounce.
  int glossy_bounces = 64;
  // Cycles' Clamp Indirect (RenderOptions::clamp_indirect; 0: off): a path's contributions of
  // indirect light (emission its third segment or a later one finds, a light sample from its
  // second vertex on) are scaled down to an RGB sum of at most this.
  float clamp_indirect = 0.0f;
  float near_mm = 1.0f, far_mm = 1e7f;  // camera rays' clip (depth along the optical axis)
  // Evaluate the BSDF lane by lane (PrincipledBsdf::EvalWithPdf) instead of a packet's lanes at
  // once in SIMD (EvalLanes): the reference the tests hold the SIMD path to.
  bool scalar_shading = false;
  // Cycles' Filter Glossy (RenderOptions::filter_glossy; 0: off): at a vertex after bounces
  // whose smallest BSDF sampling density is min_pdf (1/sr), glossy lobes get GGX alpha at least
  // sqrt(1 - min_pdf / filter_glossy) / 2 (PrincipledBsdf's min_alpha) where that is positive.
  float filter_glossy = 0.0f;
};

// What the denoiser (render/denoise.h) needs of a tile's pixels: means over each pixel's paths.
struct TileFeatures {
  Eigen::Vector3f albedo[16];  // the first surface's base colour after textures (1: no surface)
  Eigen::Vector3f normal[16];  // the first surface's shading normal, world (0: no surface)
  float variance[16];          // of the pixel's mean luminance (the paths' sample variance / n)
};

// How many paths a tile's pixels get (render.samples, render.noise_threshold, render.min_samples).
// Without a threshold every pixel gets `samples`. With one, every pixel first gets `min_samples`,
// then more in steps until the standard error of its mean, carried through the exposure and the
// display transform, is at most `threshold` (on the [0, 1] scale of the 8-bit image: 0.01 is
// 2.5 grey levels) for it and its 4-neighbours in the tile, or it has `samples`: as Cycles'
// adaptive sampling, samples go where the image is still noisy. The error counts the brightest
// path of the pixel and its 8 neighbours in the tile as a value the pixel may still draw, with
// probability 1 / (n + 2) after n paths (Laplace's rule of succession): a dark pixel beside a
// highlight its own first paths missed goes on. The schedule is a function of the
// tile's own paths, so the image is the same for any thread count, tile order or shard.
struct AdaptiveSampling {
  int samples = 16;          // paths per pixel, at most
  int min_samples = 0;       // before the first check (adaptive only)
  float threshold = 0.0f;    // 0: off
  float exposure_scale = 1;  // linear radiance to the value the display transform takes
  bool filmic = true;

  bool adaptive() const { return threshold > 0 && min_samples < samples; }
  // The same with at most `most` paths a pixel (0: unchanged; render.background_samples).
  AdaptiveSampling Capped(int most) const {
    AdaptiveSampling c = *this;
    if (most > 0) {
      c.samples = std::min(samples, most);
      c.min_samples = std::min(min_samples, c.samples);
    }
    return c;
  }
  // Whether a pixel whose `n` paths have luminances summing to `sum` (squares: `sum_sq`) is done.
  // `peak`: the brightest path's luminance among the pixel and its neighbours (0: none); a value
  // that bright, not drawn yet, counts with probability 1 / (n + 2).
  bool Converged(int n, double sum, double sum_sq, double peak = 0.0) const;
};

class PathTracer {
 public:
  // Loads the environment's and textures' images that are not loaded yet; throws Error naming the
  // file when one cannot be read.
  // `like`: a path tracer of the same geometry built before, whose environment image's sampling
  // tables are reused when the environment shows the same pixels (a frame's own look).
  explicit PathTracer(PathTracerScene scene, const PathTracer* like = nullptr);
  ~PathTracer();

  // Mean linear radiance over the paths through each pixel of the 4 x 4 tile whose top-left
  // pixel is (u0, v0) (pixel u0 + j % 4, v0 + j / 4 in out[j]; lanes outside the image are 0), as
  // many as `sampling` gives it (`taken[j]`, when given). A packet's 16 lanes are paths of any of
  // the tile's pixels, so pixels that stopped early leave no lane idle.
  // Each path starts at a random point of its pixel (through `rays`, so lens distortion bends it
  // as it bends the labels' rays), of the thin lens's aperture when `lens` is active (depth of
  // field), and at a random time of the exposure when `motion` is active (the camera at
  // camera.world_from_cam * motion.At(tau); motion blur). `features`, when given, receives the
  // denoiser's guides for the same pixels (the radiance does not depend on it).
  void TraceTile(const Camera& camera, const PixelRays& rays, const ThinLens& lens,
                 const CameraMotion& motion, int u0, int v0, const AdaptiveSampling& sampling,
                 uint64_t frame_seed, Eigen::Vector3f out[16], TileFeatures* features = nullptr,
                 int taken[16] = nullptr) const;

  // A depth sensor's projector return at the hits of a packet of camera rays traced in
  // scene.world (render/sensor.h): pi * luminance(f(wo, wi)) * cos(wi) with the hit's textured
  // material, wi towards `projector` (world, mm) and wo back along the ray; 0 for lanes that are
  // off or hit nothing, and where the projector is behind the surface. `spread` is the rays'
  // angular width (1 / f) for texture filtering. Occlusion is not tested here.
  void ProjectorSignal(const RTCRayHit16& rh, const int valid[16], const Eigen::Vector3f& projector,
                       float spread, float out[16]) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The seed of frame `view` of stream `seed`.
uint64_t FrameSeed(int seed, uint64_t view);

// Display transforms (RenderOptions::View) of an exposed linear value, to an sRGB-encoded value
// in [0, 1]. Filmic: Narkowicz's fit of the ACES filmic tone curve,
// f(x) = x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14), per channel, then sRGB; middle grey 0.18
// shows as 0.55, and highlights roll off instead of clipping (f reaches 1 at x = 7.24).
float FilmicCurve(float x);
float DisplayValue(float linear, bool filmic);

}  // namespace cadsynth
