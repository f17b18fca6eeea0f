#include "render/image.h"

#include <algorithm>
#include <cmath>

#include <cstring>

#include "cad/core/error.h"
#include "render/image_codec.h"

namespace cadsynth {

float SrgbToLinear(float c) {
  return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

float LinearToSrgb(float c) {
  c = std::clamp(c, 0.0f, 1.0f);
  return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

std::shared_ptr<const LinearImage> LoadLinearImage(const std::filesystem::path& path) {
  const DecodedImage image = ReadImageBytesFile(path);
  const int n = image.channels;
  const bool encoded = image.bits != 32;
  const float scale = image.bits == 8 ? 1.0f / 255.0f : 1.0f / 65535.0f;
  auto out = std::make_shared<LinearImage>();
  out->width = image.width;
  out->height = image.height;
  out->rgb.resize(3 * static_cast<size_t>(image.width) * image.height);
  for (int y = 0; y < image.height; ++y) {
    const uint8_t* row = image.bytes.data() + image.RowBytes() * static_cast<size_t>(y);
    for (int x = 0; x < image.width; ++x) {
      for (int c = 0; c < 3; ++c) {
        const int k = x * n + (n <= 2 ? 0 : c);  // grey (and alpha): the grey value thrice
        float value;
        if (image.bits == 8) {
          value = row[k] * scale;
        } else if (image.bits == 16) {
          uint16_t v;
          std::memcpy(&v, row + 2 * k, 2);
          value = v * scale;
        } else {
          std::memcpy(&value, row + 4 * k, 4);
        }
        if (!std::isfinite(value) || value < 0) {
          throw Error(path.string() + ": pixel (" + std::to_string(x) + ", " + std::to_string(y) +
                      ") holds a negative or non-finite value");
        }
        out->rgb[3 * (static_cast<size_t>(y) * image.width + x) + c] =
            encoded ? SrgbToLinear(value) : value;
      }
    }
  }
  return out;
}

}  // namespace cadsynth
