// An edge-aware denoiser for the physically based mode's colour (render.denoise): the spatial
// filter of SVGF (Schied et al. 2017), an edge-avoiding a-trous wavelet transform (Dammertz et
// al. 2010) guided by planes that have no sampling noise or little of it:
//
//   - the radiance is divided by the first surface's albedo before filtering and multiplied by it
//     after, so textures (wood grain, machining marks, printed colours) pass untouched and only
//     the lighting is smoothed;
//   - taps across an edge of the first surface's normal (weight (n_p . n_q)^128) or depth (the
//     difference against what the local depth slope predicts) count for nothing;
//   - taps whose luminance differs from the centre's by much more than the centre's remaining
//     noise (its standard deviation, itself filtered alongside) count for little, so that
//     highlights, hard shadow edges and converged pixels are kept.
//
// Five passes of a 3 x 3 kernel (1/4, 1/2, 1/4 per axis) with holes of 1, 2, 4, 8 and 16 pixels
// reach 31 pixels from the centre. Pixels that see nothing (depth 0) are left as they are. A pure
// function of its inputs: the same bytes on any number of threads.
#pragma once

#include <cstddef>
#include <vector>

namespace cadsynth {

struct DenoiseInput {
  int width = 0, height = 0;
  const float* radiance = nullptr;  // 3 per pixel, linear
  // 3 per pixel: the first surface's base colour (after textures), mean over the pixel's paths;
  // what filtering divides out.
  const float* albedo = nullptr;
  const float* normal = nullptr;    // 3 per pixel: the first surface's shading normal (mean)
  const float* depth = nullptr;     // 1 per pixel: depth of the pixel's centre (mm; 0: nothing)
  const float* variance = nullptr;  // 1 per pixel: the variance of the pixel's mean luminance
};

struct DenoiseOptions {
  int passes = 5;  // kernel holes 1, 2, 4, ... 2^(passes - 1) pixels (at most 16 passes)
  // A tap's weight is kernel * (n_p . n_q)^128 * f(|dz| / tol_z + |dl| / (luminance_sigma sigma_l))
  // with f(x) = (1 - x / 16)^16 (exp(-x) within 0.018), tol_z = depth_sigma times the depth change
  // the local slope predicts over the offset (the sum of both axes' for a diagonal tap) plus a
  // thousandth of the depth, dl the difference of the demodulated luminance and sigma_l the
  // centre's remaining noise (standard deviation).
  float depth_sigma = 1.0f;
  float luminance_sigma = 4.0f;
};

// What both denoisers work on at pixel p: the lighting, its radiance over the albedo (each
// channel's albedo at least kDenoiseAlbedoFloor, so that black paint keeps its highlights; a
// value that is not finite, which the tracer never gives, counts as black, a negative one as 0),
// and its luminance's variance grown as the division grows the luminance (by the ratio of the two
// luminances, so a coloured albedo amplifies the channels it lacks; by the albedo's where the
// pixel is black).
constexpr float kDenoiseAlbedoFloor = 0.01f;
struct DemodulatedPixel {
  float light[3];
  float albedo[3];  // what `light` was divided by
  float variance;
};
DemodulatedPixel Demodulate(const DenoiseInput& input, size_t p);
// Rec. 709 luminance of 3 linear values.
inline float DenoiseLuma(const float* c) {
  return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2];
}

// The filtered radiance, 3 per pixel.
std::vector<float> Denoise(const DenoiseInput& input, const DenoiseOptions& options = {});

// The denoiser network (RenderOptions::Denoiser::kNetwork): a small U-Net (three 2 x 2 strided
// convolutions down, three transposed ones up, a 3 x 3 convolution at each level, one at full
// resolution over the input again) trained by
// tools/denoiser/ on cadsynth's own renders, embedded in the library (render/models/) and run
// through OpenCV's dnn module. Like the filter it sees the lighting only: it reads, per pixel,
//
//   0-2  log(1 + L / s), L the radiance divided by the albedo (at least 0.01 per channel) and s
//        the median luminance of L over the pixels that see a surface (the frame's scale, so
//        that exposure and light power do not matter), L / s at most 10^4;
//   3-5  the albedo (clamped to [0, 1]);
//   6-8  the shading normal;
//   9    log(z / z_median), z the depth;
//   10   log(1 + sigma / s), sigma the standard deviation of the mean luminance, demodulated as
//        L is, at most 10^4 s;
//   11   1,
//
// all 0 where the pixel sees nothing. It gives back its own estimate of log(1 + L / s) (channels
// 0-2) and a weight (channel 3, through a sigmoid) that blends that estimate with the input's L /
// s, so that it can pass on pixels that are clean already; the blend is multiplied by s and the
// albedo. Pixels that see nothing keep their radiance. tools/denoiser/features.py is the
// same in numpy: the two must change together. The bytes depend only on the input and on the
// CPU's vector instructions (OpenCV picks its kernels by them, as Embree does), not on the number
// of threads.
std::vector<float> DenoiseWithNetwork(const DenoiseInput& input);

}  // namespace cadsynth
