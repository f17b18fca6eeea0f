// Image files in the tests as OpenCV matrices, through cadsynth's codecs (render/image_codec.h)
// instead of OpenCV's imgcodecs, whose Debian build loads 67 more libraries (GDAL, GDCM, ...) into
// every test process: about half a second each under the sanitizers. Only the codec tests
// themselves (codec_tests) link imgcodecs, to check our files against a second implementation.
// The flags are imgcodecs' (the header is only an enum here): IMREAD_UNCHANGED, IMREAD_COLOR
// (8-bit B, G, R) and IMREAD_GRAYSCALE.
#pragma once

#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "cad/core/error.h"
#include "dataset/image_mat.h"
#include "render/image_codec.h"

namespace cadsynth::testing {

inline image_mat::Want WantOf(int flags) {
  if (flags == cv::IMREAD_COLOR) return image_mat::Want::kColour8;
  if (flags == cv::IMREAD_GRAYSCALE) return image_mat::Want::kGrey8;
  if (flags == cv::IMREAD_UNCHANGED) return image_mat::Want::kUnchanged;
  throw Error("image_support: flags " + std::to_string(flags) + " are not handled");
}

// Like cv::imdecode: an empty matrix when the bytes are not an image.
inline cv::Mat Imdecode(std::string_view bytes, int flags) {
  try {
    return image_mat::MatOf(DecodeImageBytes(bytes, "test image"), WantOf(flags), "test image");
  } catch (const Error&) {
    return cv::Mat();
  }
}

// Like cv::imread: an empty matrix when the file is missing or not an image.
inline cv::Mat Imread(const std::filesystem::path& path, int flags) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return cv::Mat();
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return Imdecode(bytes, flags);
}

// Like cv::imwrite for .png (8 or 16 bits) and .exr (float); throws on failure.
inline void Imwrite(const std::filesystem::path& path, const cv::Mat& image) {
  const std::string bytes = path.extension() == ".exr" ? EncodeExr(image_mat::ViewOf(image))
                                                       : EncodePng(image_mat::ViewOf(image));
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out) throw Error(path.string() + ": cannot be written");
}

}  // namespace cadsynth::testing
