// Linear RGB images read from files (texture and environment images of the physically based
// mode), and the sRGB transfer function.
#pragma once

#include <filesystem>
#include <memory>
#include <vector>

namespace cadsynth {

// width x height linear RGB floats, row-major, row 0 at the top.
struct LinearImage {
  int width = 0, height = 0;
  std::vector<float> rgb;
  const float* at(int x, int y) const { return &rgb[3 * (static_cast<size_t>(y) * width + x)]; }
};

// Reads an image with OpenCV (PNG, JPEG, TIFF, Radiance .hdr, OpenEXR, ...): 8- and 16-bit images
// are decoded from sRGB, float images are taken as linear. Throws Error naming the file when it is
// missing, not an image, or holds negative or non-finite values.
std::shared_ptr<const LinearImage> LoadLinearImage(const std::filesystem::path& path);

// Linear value of an sRGB-encoded component in [0, 1] (IEC 61966-2-1), and back (clamped).
float SrgbToLinear(float c);
float LinearToSrgb(float c);

}  // namespace cadsynth
