// Ray casting of a Scene with Embree: RGB, depth, visible instance ids and amodal masks.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "cad/core/schema.h"
#include "cad/part.h"
#include "render/camera.h"
#include "render/frame.h"
#include "render/scene.h"
#include "render/sensor.h"

namespace cadsynth {

struct RenderOptions {
  // Depth clip (mm along the optical axis): nothing nearer than `near_mm` or farther than `far_mm`
  // is seen (depth 0, no instance).
  double near_mm = 1.0;
  double far_mm = 1e7;
  // Supersampled anti-aliasing of RGB only: samples x samples rays per pixel (1: off). Depth,
  // instance ids and masks always come from the pixel centre.
  int supersampling = 1;
  bool normals = false;  // fill Frame::normals (camera frame)
  // For profiling only (a dataset needs both): skip shading (RGB stays black) or the amodal masks.
  bool shade = true;
  bool amodal_masks = true;
  // Also keep each instance's depth rendered alone (Frame::InstanceTruth::amodal_depth), for
  // visibility rules that compare it with the scene's depth (bop_toolkit's).
  bool amodal_depth = false;
  // Embree's kernels: "auto" (the widest this CPU has) or the widest to use: sse2, sse4.2, avx,
  // avx2, avx512. Kernels of different widths differ in the last bits of some hit distances, so
  // machines that must write the same bytes (the shards of one farm run) must use the same ones.
  std::string isa = "auto";

  // Shading of the colour image: kFast is Lambert with hard shadows (Scene's colours and lights);
  // kPbr path-traces Scene's materials, light sources and environment (render/path_tracer.h).
  enum class Mode { kFast, kPbr };
  Mode mode = Mode::kFast;
  int samples = 16;  // pbr: paths per pixel (with noise_threshold: at most)
  // pbr: adaptive sampling (render/path_tracer.h, AdaptiveSampling): a pixel stops once the
  // standard error of its displayed value (0-1) is at most noise_threshold, after min_samples
  // (0: the square root of samples, at least 8). 0: off, every pixel gets `samples`.
  double noise_threshold = 0.0;
  int min_samples = 0;
  // pbr: the most paths a pixel gets in a 4 x 4 tile where no pixel centre shows an object (an
  // instance or a distractor, Scene::Fixture::object) and none of the 8 tiles around does: the
  // floor, containers and sky away from the parts, which users do not train on and the denoiser
  // cleans well from one path. 0: as the objects' pixels. Adaptive sampling's min_samples is
  // capped by it there too. The tiles are chosen from the labels alone.
  int background_samples = 0;
  int bounces = 3;  // pbr: surface interactions after the first (Blender's max bounces)
  // pbr: Cycles' Filter Glossy (blur_glossy; Blender's default 1, cadsynth's 0: off). After a
  // bounce whose BSDF sample was unlikely (a diffuse or rough one), the glossy lobes a path meets
  // are widened: GGX alpha at least sqrt(1 - min_pdf / filter_glossy) / 2, min_pdf the smallest
  // sampling density (1/sr) of the path's bounces so far. Rare bright paths (light reflected by
  // a glossy part onto a diffuse one and seen in another glossy part) lose most of their noise
  // for some bias; the first surface a camera ray meets is never changed.
  double filter_glossy = 0.0;
  // pbr: of the bounces, how many may be glossy (Blender's Glossy bounces; BlenderProc sets 0):
  // a path whose BSDF sample comes from a glossy lobe once more than this only gathers the light
  // and sky its next segment finds. At or above `bounces`: no limit of their own.
  int glossy_bounces = 64;
  // pbr: Cycles' Clamp Indirect (Blender's default 10, cadsynth's 0: off): a path's light that
  // met more than one surface (found after two bounces, or sampled from the second surface on)
  // is scaled down to an RGB sum of at most this, in linear radiance before the exposure.
  // Biased (darker), as in Cycles; fireflies from rare paths are cut.
  double clamp_indirect = 0.0;
  // pbr: how the BSDF is evaluated: kSimd, a packet's lanes four at a time (EvalLanes); kScalar,
  // lane by lane (PrincipledBsdf::EvalWithPdf), the reference the tests hold the SIMD path to.
  // The same image to within float rounding (to the byte on x86-64 builds without FMA).
  enum class Shading { kSimd, kScalar };
  Shading shading = Shading::kSimd;
  double exposure = 0.0;  // pbr: stops; the linear value is scaled by 2^exposure
  // pbr: display transform of the exposed linear value: kStandard clips and encodes sRGB;
  // kFilmic compresses highlights first (a filmic curve, see path_tracer.h), then encodes sRGB.
  enum class View { kStandard, kFilmic };
  View view = View::kFilmic;
  int seed = 0;  // pbr: the sampler's stream; pixels' samples depend on (seed, view, pixel)
  // Also keep the colour as floats (Frame::radiance, written as EXR): pbr, the linear radiance
  // before exposure; fast, the Lambert colour before it is rounded to bytes.
  bool hdr = false;
  // pbr: filter the colour's sampling noise, guided by the first surfaces' albedo, normals and
  // depth (render/denoise.h): fewer samples for a clean image, at the price of some blur of
  // glossy reflections and soft shadows. Only the colour image (and its HDR) changes.
  bool denoise = false;
  // pbr with denoise: which denoiser. kFilter: the edge-aware a-trous filter (render/denoise.h,
  // Denoise); kNetwork: a small convolutional network trained on cadsynth's own renders
  // (DenoiseWithNetwork; tools/denoiser/ trains it): a lower RMSE than the filter at 2-4 samples
  // but blotchier glossy detail to the eye, a higher one at 1, about 0.1 s more per 640 x 480
  // frame on 2 cores (docs/rendering.md).
  enum class Denoiser { kFilter, kNetwork };
  Denoiser denoiser = Denoiser::kFilter;
  // Training a denoiser: also keep what it reads (Frame::denoiser_inputs), also where denoise is
  // off. Not a dataset output: tools/denoiser/ sets it through Python.
  bool denoiser_inputs = false;

  bool Check(std::string* why) const;
  // The paths a pixel gets before adaptive sampling's first check.
  int FirstSamples() const {
    if (min_samples > 0) return min_samples;
    return std::min(samples,
                    std::max(8, static_cast<int>(std::sqrt(static_cast<double>(samples)))));
  }

  // Every field, once (cad/core/schema.h): the recipe's `render:` section, the run key, the shard
  // file.
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.near_mm,
          Field{"near", "length", "nothing nearer than this (along the optical axis) is seen"});
    visit(o.far_mm, Field{"far", "length", "nothing farther than this is seen"});
    visit(o.supersampling,
          Field{"supersampling", "integer",
                "N x N rays per pixel for the colour image only (1-8; labels use the centre)"});
    visit(o.normals, Field{"normals", "bool", "also write normal/ images (camera-frame normals)"});
    visit(o.isa,
          Field{"isa", "text",
                "Embree kernels: auto, sse2, sse4.2, avx, avx2 or avx512 (pin for mixed farms)"});
    visit(o.mode, Field{"mode",
                        "choice",
                        "colour image: fast (Lambert, hard shadows) or pbr (path traced)",
                        {"fast", "pbr"}});
    visit(o.samples, Field{"samples", "integer",
                           "pbr: paths per pixel (1-65536; the most with noise_threshold)"});
    visit(o.noise_threshold,
          Field{"noise_threshold", "number",
                "pbr: adaptive sampling: a pixel stops when the standard error of its displayed "
                "value (0-1) is at most this (0: off; samples is then the most)"});
    visit(o.min_samples,
          Field{"min_samples", "integer",
                "pbr: adaptive sampling: paths before the first check (0: sqrt(samples), "
                "at least 8)"});
    visit(o.background_samples,
          Field{"background_samples", "integer",
                "pbr: the most paths a pixel gets in a 4 x 4 tile that neither shows an object "
                "nor touches a tile that does (floor, containers, sky; 0: as the objects' "
                "pixels, up to samples)"});
    visit(o.bounces, Field{"bounces", "integer", "pbr: bounces after the first hit (0-64)"});
    visit(o.filter_glossy,
          Field{"filter_glossy", "number",
                "pbr: Cycles' Filter Glossy: widen glossy lobes after unlikely bounces, less "
                "noise for some bias (0: off, Blender's default 1; 0-10)"});
    visit(o.glossy_bounces,
          Field{"glossy_bounces", "integer",
                "pbr: of the bounces, at most this many glossy ones (Blender's Glossy bounces; "
                "BlenderProc's 0; at or above bounces: no limit)"});
    visit(o.clamp_indirect,
          Field{"clamp_indirect", "number",
                "pbr: Cycles' Clamp Indirect: indirect light of a path scaled to an RGB sum of "
                "at most this (0: off, Blender's default 10)"});
    visit(o.shading,
          Field{"shading",
                "choice",
                "pbr: BSDF evaluation, simd (lanes of a packet at once) or scalar (the reference)",
                {"simd", "scalar"}});
    visit(o.exposure, Field{"exposure", "number", "pbr: exposure in stops (-20 to 20)"});
    visit(o.view, Field{"view", "choice", "pbr: display transform", {"standard", "filmic"}});
    visit(o.seed, RunSeed("seed", "pbr: sampler seed"));
    visit(o.hdr,
          Field{"hdr", "bool", "also write the colour as float EXR (rgb_hdr/; pbr: radiance)"});
    visit(o.denoise,
          Field{"denoise", "bool", "pbr: denoise the colour, guided by albedo, normals and depth"});
    visit(o.denoiser, Field{"denoiser",
                            "choice",
                            "pbr with denoise: filter (edge-aware a-trous) or network (trained on "
                            "cadsynth's renders; best at 2-4 samples)",
                            {"filter", "network"}});
    visit(o.shade, Field{"", "bool", "profiling: shade the colour image", {}, true, "shade"});
    visit(o.amodal_masks,
          Field{"", "bool", "profiling: trace the full silhouettes", {}, true, "amodal_masks"});
    visit(o.amodal_depth,
          Field{"", "bool", "set by output.visibility: bop19", {}, true, "amodal_depth"});
    visit(o.denoiser_inputs,
          Field{"", "bool", "training a denoiser: keep its inputs", {}, true, "denoiser_inputs"});
  }
};

// The kernels Embree traces with on this machine for `requested` (see RenderOptions::isa): the
// requested width, or the widest this CPU has if it is narrower. E.g. "avx512", "avx2".
std::string TracingIsa(const std::string& requested = "auto");

// The `view` key of sensor k of a camera rig at view `view` (Renderer::Render): the view itself
// for the first sensor, so a rig's first sensor renders what the single camera would, and keys
// no view of a run reaches (2^40 apart) for the others, so each sensor has noise of its own.
inline uint64_t SensorFrameKey(uint64_t view, size_t sensor) {
  return view + (static_cast<uint64_t>(sensor) << 40);
}

// Builds the acceleration structures once; Render() may then be called from many threads.
// One ray per pixel through its centre, traced as 16-ray packets over 4 x 4 pixel tiles (tiles in
// parallel; the output does not depend on the thread count); depth is the camera-frame z of the
// first hit. The full (amodal) silhouette of each instance comes from tracing that instance alone.
class Renderer {
 public:
  // `parts` are copied into the renderer's own buffers; `scene.instances` refer to them by index.
  Renderer(const std::vector<Part>& parts, const Scene& scene, const RenderOptions& options = {});
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // `view` numbers the frame for the path tracer's sampler and the sensor's noise (the view index
  // of the run), so that every frame has its own noise and the same view renders the same bytes
  // anywhere. `sensor` adds a grey image and the depth a real sensor returns (render/sensor.h).
  // `look` (pbr only) shades this frame with its own materials, lights, environment, exposure
  // and white balance (domain randomisation, render/randomize.h) over the same geometry; labels
  // and the exact depth do not depend on it (a depth model's projector return does).
  Frame Render(const Camera& camera, uint64_t view = 0, const SensorOptions& sensor = {},
               const FrameLook* look = nullptr) const;
  // The scene's own look in the pbr mode (materials with base colours resolved, lights,
  // environment): what a frame's look is drawn around. Empty in the fast mode.
  FrameLook BaseLook() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cadsynth
