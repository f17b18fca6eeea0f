// Named random streams. Every random number cadsynth draws comes from one stream listed here, as a
// fixed function of (seed, stream, index): never of the clock, the thread or the order of work,
// so that any thread count, shard or resumed run draws the same numbers.
//
// A stream's id is the 64-bit FNV-1a hash of its name, so streams never share draws (two magic
// numbers could), adding a stream moves no other, and a draw can be named in documentation and
// in a bug report. kRandomStreams lists every stream once; docs/recipes.md's "Random streams" table
// is written from it, and a test checks that names and ids are unique.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string_view>

namespace cadsynth {

// 64-bit FNV-1a of `text`.
constexpr uint64_t Fnv1a64(std::string_view text) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (char c : text) {
    h ^= static_cast<uint8_t>(c);
    h *= 0x100000001b3ull;
  }
  return h;
}

struct RandomStream {
  std::string_view name;  // dotted: module.what
  std::string_view what;  // what one draw decides, and what its index counts
  constexpr uint64_t id() const { return Fnv1a64(name); }
};

// The streams, by the seed they use. Indices that combine several counters are written as
// (a << k) + b in the code that draws.
namespace streams {
// recipes: parts.random.seed
inline constexpr RandomStream kFamilyParam{
    "family.param",
    "a random family variant's parameter: stream 'family.param.NAME', index = variant"};
// recipes: scene.seed (arrangement)
inline constexpr RandomStream kAssembledPose{
    "arrange.assembled_pose", "the stable pose of an assembled scene (pose: random); index 0"};
inline constexpr RandomStream kCopyPose{
    "arrange.copy_pose",
    "the stable pose of one copy (pose: random); index = (group << 32) + copy"};
inline constexpr RandomStream kCopyYaw{
    "arrange.copy_yaw", "the yaw of one copy (clutter, pose: random); index as arrange.copy_pose"};
inline constexpr RandomStream kClutterRadius{
    "arrange.clutter_radius",
    "a clutter placement's distance from the centre; index = (body << 20) + attempt"};
inline constexpr RandomStream kClutterAngle{
    "arrange.clutter_angle", "a clutter placement's direction; index as arrange.clutter_radius"};
inline constexpr RandomStream kPilePhysics{
    "pile.physics",
    "a part's density, friction or restitution drawn from its range (layout: pile, pose: "
    "dropped); index = (part << 2) + which"};
inline constexpr RandomStream kDropSeed{
    "arrange.drop_seed",
    "the seed of one copy's fall onto the floor (pose: dropped), for its pile.rotation and "
    "pile.position draws; index as arrange.copy_pose"};
inline constexpr RandomStream kRedropSeed{
    "arrange.redrop_seed",
    "the seed of a drop again of the parts that left a pile's container (out_of_container: "
    "redrop); index = round"};
// recipes: randomize.seed (distractors, per scene)
inline constexpr RandomStream kDistractorOrder{
    "arrange.distractor_order",
    "where a distractor falls in a pile's drop order (before which copy); index = distractor"};
// recipes: scene.seed (a pile's pick sequence, pick: random)
inline constexpr RandomStream kPickRandom{
    "sequence.pick",
    "the part a pick sequence's random rule takes (among those left); index = step"};
// grasps: the grasp seed (per part)
inline constexpr RandomStream kGraspPoint{
    "grasp.point",
    "an antipodal grasp's first contact: its triangle (by area) and barycentrics; index = "
    "(sample << 2) + draw"};
inline constexpr RandomStream kGraspApproach{
    "grasp.approach", "the first of a contact pair's evenly spaced approaches; index = sample"};
inline constexpr RandomStream kSuctionPoint{
    "grasp.suction_point",
    "a suction grasp's contact: its triangle (by area) and barycentrics; index = (sample << 2) + "
    "draw"};
// recipes: sweep.seed (random view samplers)
inline constexpr RandomStream kViewYaw{"view.yaw", "a random view's yaw; index = view"};
inline constexpr RandomStream kViewPitch{"view.pitch",
                                         "a random view's pitch (uniform by area); index = view"};
inline constexpr RandomStream kViewRadius{"view.radius", "a random view's distance; index = view"};
inline constexpr RandomStream kTargetHeight{"view.target_z",
                                            "the target jitter's height; index = view"};
inline constexpr RandomStream kTargetAzimuth{"view.target_azimuth",
                                             "the target jitter's direction; index = view"};
inline constexpr RandomStream kTargetRadius{"view.target_radius",
                                            "the target jitter's distance; index = view"};
inline constexpr RandomStream kViewRoll{"view.roll", "a view's roll jitter; index = view"};
// recipes: output.split_seed
inline constexpr RandomStream kTestImage{
    "split.test_image", "whether an image is a test image (test_fraction); index = image"};
// recipes: output.point_seed (+ the object's index)
inline constexpr RandomStream kPointTriangle{
    "points.triangle", "the triangle of a model point (by area); index = point"};
inline constexpr RandomStream kPointU{"points.u",
                                      "a model point's first barycentric draw; index = point"};
inline constexpr RandomStream kPointV{"points.v",
                                      "a model point's second barycentric draw; index = point"};
// recipes: render.seed (render.mode: pbr)
inline constexpr RandomStream kRenderPixel{
    "render.pixel",
    "a frame's path-tracing sampler: index = view (a rig's sensor k: view + k 2^40); each pixel's "
    "Owen-scrambled Sobol sequence "
    "hashes its (v * 65536 + u) onto that"};
// recipes: a material's texture.seed
inline constexpr RandomStream kTexturePattern{
    "texture.pattern",
    "a procedural texture's noise lattice, boards and scratches; the texture's seed picks the "
    "pattern, the lattice cell indexes it"};
// recipes: scene.seed (layout: pile)
inline constexpr RandomStream kDropRotation{
    "pile.rotation",
    "a dropped body's orientation (uniform on SO(3), three draws); index = (body << 2) + draw"};
inline constexpr RandomStream kDropPosition{
    "pile.position",
    "a dropped body's start above the drop region; index = (body << 8) + (attempt << 1) + axis"};
// recipes: camera.depth.seed (depth sensor models, render/sensor.h)
inline constexpr RandomStream kSensorFrame{
    "sensor.frame",
    "the seed of one frame's depth noise; index = view (a rig's sensor k: view + k 2^40)"};
inline constexpr RandomStream kSensorLateral{
    "sensor.lateral",
    "a pixel's lateral shift, seeded by sensor.frame; index = (pixel << 1) + draw (Box-Muller: "
    "both axes from one pair)"};
inline constexpr RandomStream kSensorAxial{
    "sensor.axial",
    "a pixel's depth noise, seeded by sensor.frame; index = ((pixel >> 1) << 1) + draw (one "
    "Box-Muller pair for pixels 2k and 2k + 1: the cosine's number, then the sine's)"};
inline constexpr RandomStream kSensorInfrared{
    "sensor.infrared",
    "active_stereo: an IR pixel's read noise in the left and right images (one draw, a normal "
    "pair), seeded by sensor.frame; index = pixel"};
inline constexpr RandomStream kSensorDots{
    "sensor.dots",
    "active_stereo: the projector's dot pattern, seeded by camera.depth.seed; index = (cell << 2) "
    "+ "
    "draw (present, x, y), cell = ((i + 2^20) << 21) + j + 2^20 for grid cell (i, j)"};
// recipes: camera.imager.seed (image sensor noise, render/sensor.h)
inline constexpr RandomStream kImageFrame{
    "sensor.image_frame",
    "the seed of one frame's image noise; index = view (a rig's sensor k: view + k 2^40)"};
inline constexpr RandomStream kImageNoise{
    "sensor.image",
    "a pixel's image noise, seeded by sensor.image_frame; index = (((pixel << 1) + pair) << 1) + "
    "draw (a colour camera's Box-Muller pairs: R and G, then B and an unused number)"};
inline constexpr RandomStream kImageNoiseGrey{
    "sensor.image_grey",
    "a grey camera's image noise, seeded by sensor.image_frame; index = ((pixel >> 1) << 1) + "
    "draw (one Box-Muller pair for pixels 2k and 2k + 1)"};
// recipes: randomize.seed (domain randomisation, render/randomize.h)
inline constexpr RandomStream kRandomizeFrame{
    "randomize.frame",
    "the seed of one frame's (or scene's) randomised draws; index = (scene << 40) + view, or "
    "(scene << 40) + 2^40 - 1 for draws made once per scene"};
inline constexpr RandomStream kRandomizeDraw{
    "randomize.draw",
    "a randomised quantity, seeded by randomize.frame: stream 'randomize.draw.' + the quantity's "
    "name (part.2.roughness, light.0.power, ...), index = draw (0; 1: Box-Muller's second)"};
}  // namespace streams

inline constexpr RandomStream kRandomStreams[] = {
    streams::kFamilyParam,    streams::kAssembledPose,  streams::kCopyPose,
    streams::kCopyYaw,        streams::kClutterRadius,  streams::kClutterAngle,
    streams::kViewYaw,        streams::kViewPitch,      streams::kViewRadius,
    streams::kTargetHeight,   streams::kTargetAzimuth,  streams::kTargetRadius,
    streams::kViewRoll,       streams::kTestImage,      streams::kPointTriangle,
    streams::kPointU,         streams::kPointV,         streams::kRenderPixel,
    streams::kTexturePattern, streams::kDropRotation,   streams::kDropPosition,
    streams::kDropSeed,       streams::kPilePhysics,    streams::kDistractorOrder,
    streams::kSensorFrame,    streams::kSensorLateral,  streams::kSensorAxial,
    streams::kSensorInfrared, streams::kSensorDots,     streams::kImageFrame,
    streams::kImageNoise,     streams::kImageNoiseGrey, streams::kRandomizeFrame,
    streams::kRandomizeDraw,  streams::kGraspPoint,     streams::kGraspApproach,
    streams::kSuctionPoint,   streams::kPickRandom,     streams::kRedropSeed,
};

namespace random_detail {
// Two SplitMix64 rounds over (seed, stream id, index): 64 random bits.
inline uint64_t DrawBits(uint64_t seed, uint64_t stream, uint64_t index) {
  uint64_t x = seed * 0x9E3779B97F4A7C15ull ^
               (stream + 0x632BE59BD9B4E019ull) * 0xBF58476D1CE4E5B9ull ^
               (index + 0x85EBCA77C2B2AE63ull) * 0x94D049BB133111EBull;
  for (int round = 0; round < 2; ++round) {
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    x ^= x >> 31;
  }
  return x;
}
// Their top 53 bits as a number in [0, 1).
inline double Draw(uint64_t seed, uint64_t stream, uint64_t index) {
  return static_cast<double>(DrawBits(seed, stream, index) >> 11) * 0x1.0p-53;
}
}  // namespace random_detail

// Box-Muller: two independent standard normal numbers from two uniform numbers in [0, 1),
//   z0 = r cos(2 pi u2), z1 = r sin(2 pi u2), r = sqrt(-2 ln(1 - u1)).
// u1 and u2 must lie in [0, 1) (UniformDraw's range). Short polynomials stand in for libm's log,
// cos and sin, which took a sixth of a bin-picking run (sensor noise draws a pair or two per
// pixel): within 1e-10 of the formula through libm (tests/cad/random_test.cpp), far below any
// sensor's noise, and independent of the libm (as everything else, they depend on the compiler's
// floating-point contraction: one build gives one set of bytes).
inline void NormalPair(double u1, double u2, double* z0, double* z1) {
  // ln x for x = 1 - u1 in (0, 1]: x = m 2^e with m in (sqrt(1/2), sqrt(2)], then
  // ln m = 2 atanh(s) = 2 s (1 + s^2/3 + ... + s^10/11), s = (m - 1) / (m + 1), |s| <= 0.172:
  // the rest of the series is at most 5.1e-11 of the sum.
  const double x = 1.0 - u1;
  uint64_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  const int e = static_cast<int>((bits >> 52) & 0x7ff) - 1023;
  bits = (bits & 0x000fffffffffffffull) | 0x3ff0000000000000ull;
  double m;
  std::memcpy(&m, &bits, sizeof m);
  const bool high = m > 1.4142135623730951;  // selects, not branches: the draws are random
  m *= high ? 0.5 : 1.0;
  const double s = (m - 1.0) / (m + 1.0), s2 = s * s, s4 = s2 * s2;
  // Estrin's scheme: short dependency chains.
  const double atanh_over_s =
      (1.0 + s2 * (1.0 / 3)) + s4 * ((1.0 / 5 + s2 * (1.0 / 7)) + s4 * (1.0 / 9 + s2 * (1.0 / 11)));
  const double ln_x = (e + high) * 0.6931471805599453 + 2.0 * s * atanh_over_s;
  const double r = std::sqrt(std::max(0.0, -2.0 * ln_x));
  // 2 pi u2 = q pi/2 + t with q a whole number of quadrants and |t| <= pi/4; Taylor series of
  // sin t to t^11 and cos t to t^12 (remainders below 7e-12 and 4e-13).
  const double quarter = 4.0 * u2;
  const int q = static_cast<int>(quarter + 0.5);
  const double t = (quarter - q) * 1.5707963267948966, t2 = t * t, t4 = t2 * t2, t8 = t4 * t4;
  const double sin_t = t * ((1.0 - t2 * (1.0 / 6)) + t4 * (1.0 / 120 - t2 * (1.0 / 5040)) +
                            t8 * (1.0 / 362880 - t2 * (1.0 / 39916800)));
  const double cos_t = (1.0 - t2 * (1.0 / 2)) + t4 * (1.0 / 24 - t2 * (1.0 / 720)) +
                       t8 * ((1.0 / 40320 - t2 * (1.0 / 3628800)) + t4 * (1.0 / 479001600));
  // cos and sin of q pi/2 + t: odd quadrants swap them, quadrants 1 and 2 negate the cosine,
  // 2 and 3 the sine.
  const bool odd = q & 1;
  const double c = (odd ? sin_t : cos_t) * (((q + 1) & 2) ? -1.0 : 1.0);
  const double sn = (odd ? cos_t : sin_t) * ((q & 2) ? -1.0 : 1.0);
  *z0 = r * c;
  *z1 = r * sn;
}

// Box-Muller in single precision for many pairs at once, where a pair needs less than
// NormalPair's 1e-10 and many are drawn (an image's read noise): z0[i] and z1[i] from the 64 bits
// of bits[i] (random_detail::DrawBits), u1 from the top 23 bits and u2 from the next 23, each the
// centre of its 2^-23 step, so |z| < 5.8. Within 2e-6 of the formula; about one tenth of
// NormalPair's time per pair (the loops run 4 pairs at a time).
void NormalPairsFloat(const uint64_t* bits, int n, float* z0, float* z1);

// A uniform number in [0, 1) from (seed, stream, index): SplitMix64 rounds, the same on every
// machine and compiler (std:: distributions are not). Inline, so that the stream's id (a hash of
// its name) folds to a constant in per-pixel loops.
inline double UniformDraw(uint64_t seed, const RandomStream& stream, uint64_t index) {
  return random_detail::Draw(seed, stream.id(), index);
}
// The same for a stream named at run time ("family.param.teeth").
double UniformDraw(uint64_t seed, std::string_view stream_name, uint64_t index);

}  // namespace cadsynth
