// Linear RGB images read from files (texture and environment images of the physically based
// mode), and the sRGB transfer function.
#pragma once

#include <filesystem>
#include <memory>
#include <vector>

#include <Eigen/Core>

namespace cadsynth {

// width x height linear RGB floats, row-major, row 0 at the top.
struct LinearImage {
  int width = 0, height = 0;
  std::vector<float> rgb;
  const float* at(int x, int y) const { return &rgb[3 * (static_cast<size_t>(y) * width + x)]; }
};

// Reads an image (PNG, JPEG, OpenEXR, Radiance .hdr; render/image_codec.h): 8- and 16-bit images
// are decoded from sRGB, float images are taken as linear. Throws Error naming the file when it is
// missing, not an image, or holds negative or non-finite values.
std::shared_ptr<const LinearImage> LoadLinearImage(const std::filesystem::path& path);

// Linear value of an sRGB-encoded component in [0, 1] (IEC 61966-2-1), and back (clamped).
float SrgbToLinear(float c);
// Luminance of linear RGB (Rec. 709 / sRGB primaries): 0.2126 R + 0.7152 G + 0.0722 B.
inline float Luminance(const Eigen::Vector3f& c) {
  return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2];
}
float LinearToSrgb(float c);

}  // namespace cadsynth
