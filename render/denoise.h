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

// The filtered radiance, 3 per pixel.
std::vector<float> Denoise(const DenoiseInput& input, const DenoiseOptions& options = {});

}  // namespace cadsynth
