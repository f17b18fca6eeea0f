// OpenCV matrices to and from the image codecs (render/image_codec.h). Internal to dataset/: it
// brings in OpenCV, which the public headers keep out.
#pragma once

#include <cmath>
#include <cstring>
#include <string>
#include <utility>

#include <opencv2/core.hpp>

#include "cad/core/error.h"
#include "render/image_codec.h"

namespace cadsynth::image_mat {

// A matrix's pixels as the encoders take them: three or four channels are OpenCV's B, G, R (A).
inline ImageView ViewOf(const cv::Mat& image) {
  ImageView view;
  view.pixels = image.data;
  view.stride = image.step;
  view.width = image.cols;
  view.height = image.rows;
  view.channels = image.channels();
  view.bits = static_cast<int>(image.elemSize1()) * 8;
  view.bgr = image.channels() >= 3;
  return view;
}

// PNG bytes of a matrix; errors name `where`.
inline std::string Png(const cv::Mat& image, const std::string& where) {
  try {
    return EncodePng(ViewOf(image));
  } catch (const Error& e) {
    throw Error(where + ": " + e.what());
  }
}

// What a reader wants of a decoded image, as OpenCV's imread flags said it.
enum class Want {
  kUnchanged,  // channels and bits as stored; colour as B, G, R (A)
  kColour8,    // 8-bit B, G, R: grey repeated, alpha dropped, 16 bits to their high byte
  kGrey8,      // 8-bit grey: colour as 0.299 R + 0.587 G + 0.114 B, 16 bits to their high byte
};

// The decoded image as a matrix (float images only kUnchanged). Throws Error naming `origin`.
inline cv::Mat MatOf(const DecodedImage& image, Want want, const std::string& origin) {
  const int n = image.channels;
  const size_t count = static_cast<size_t>(image.width) * image.height;
  const uint8_t* in = image.bytes.data();
  cv::Mat out;
  if (want == Want::kUnchanged) {
    const int depth = image.bits == 32 ? CV_32F : image.bits == 16 ? CV_16U : CV_8U;
    out.create(image.height, image.width, CV_MAKETYPE(depth, n));
    std::memcpy(out.data, in, image.bytes.size());
    if (n >= 3) {  // R, G, B (A) to B, G, R (A)
      const size_t size = out.elemSize1();
      for (size_t i = 0; i < count; ++i) {
        uint8_t* pixel = out.data + i * n * size;
        for (size_t b = 0; b < size; ++b) std::swap(pixel[b], pixel[2 * size + b]);
      }
    }
    return out;
  }
  if (image.bits == 32) throw Error(origin + ": a float image where an 8-bit one was expected");
  // Value k of pixel i in 8 bits (16-bit values keep their high byte, as libpng's strip does).
  const auto value = [&](size_t i, int k) -> uint8_t {
    if (image.bits == 8) return in[i * n + k];
    uint16_t v;
    std::memcpy(&v, in + 2 * (i * n + k), 2);
    return static_cast<uint8_t>(v >> 8);
  };
  if (want == Want::kColour8) {
    out.create(image.height, image.width, CV_8UC3);
    for (size_t i = 0; i < count; ++i) {
      uint8_t* to = out.data + 3 * i;
      for (int c = 0; c < 3; ++c) to[c] = value(i, n <= 2 ? 0 : 2 - c);
    }
    return out;
  }
  out.create(image.height, image.width, CV_8UC1);
  for (size_t i = 0; i < count; ++i) {
    out.data[i] = n <= 2 ? value(i, 0)
                         : static_cast<uint8_t>(std::lround(
                               0.299 * value(i, 0) + 0.587 * value(i, 1) + 0.114 * value(i, 2)));
  }
  return out;
}

}  // namespace cadsynth::image_mat
