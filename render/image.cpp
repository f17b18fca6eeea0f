#include "render/image.h"

#include <algorithm>
#include <cmath>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "cad/core/error.h"

namespace cadsynth {

float SrgbToLinear(float c) {
  return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

float LinearToSrgb(float c) {
  c = std::clamp(c, 0.0f, 1.0f);
  return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

std::shared_ptr<const LinearImage> LoadLinearImage(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw Error(path.string() + ": no such file");
  cv::Mat image;
  try {
    image = cv::imread(path.string(), cv::IMREAD_ANYDEPTH | cv::IMREAD_COLOR);
  } catch (const cv::Exception& e) {
    throw Error(path.string() + ": not an image OpenCV can read (" + e.msg + ")");
  }
  if (image.empty()) throw Error(path.string() + ": not an image OpenCV can read");
  const int depth = image.depth();
  const bool encoded = depth == CV_8U || depth == CV_16U;
  cv::Mat rgb;
  image.convertTo(rgb, CV_32F,
                  depth == CV_8U ? 1.0 / 255.0 : (depth == CV_16U ? 1.0 / 65535.0 : 1.0));
  auto out = std::make_shared<LinearImage>();
  out->width = rgb.cols;
  out->height = rgb.rows;
  out->rgb.resize(3 * static_cast<size_t>(rgb.cols) * rgb.rows);
  for (int y = 0; y < rgb.rows; ++y) {
    const cv::Vec3f* row = rgb.ptr<cv::Vec3f>(y);
    for (int x = 0; x < rgb.cols; ++x) {
      for (int c = 0; c < 3; ++c) {
        float value = row[x][2 - c];  // OpenCV stores BGR
        if (!std::isfinite(value) || value < 0) {
          throw Error(path.string() + ": pixel (" + std::to_string(x) + ", " + std::to_string(y) +
                      ") holds a negative or non-finite value");
        }
        out->rgb[3 * (static_cast<size_t>(y) * rgb.cols + x) + c] =
            encoded ? SrgbToLinear(value) : value;
      }
    }
  }
  return out;
}

}  // namespace cadsynth
