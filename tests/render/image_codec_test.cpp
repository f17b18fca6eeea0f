#include "render/image_codec.h"

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <zlib.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "cad/core/error.h"
#include "dataset/image_mat.h"

// The codecs are checked against OpenCV's imgcodecs, a second implementation the tests still
// link: its decoder reads our files to the same pixels, and its encoder (what the datasets were
// written with before) gives the same PNG and JPEG bytes, so a dataset's files are unchanged.

namespace cadsynth {
namespace {

std::vector<uint8_t> Bytes(const std::string& s) {
  return std::vector<uint8_t>(s.begin(), s.end());
}

// A smooth test image with some structure: w x h x channels values of type T.
template <typename T>
cv::Mat Pattern(int w, int h, int channels, double full) {
  cv::Mat image(h, w, CV_MAKETYPE(cv::DataType<T>::depth, channels));
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      for (int c = 0; c < channels; ++c) {
        const double v = 0.5 + 0.45 * std::sin(0.21 * x + 0.9 * c) * std::cos(0.13 * y - 0.4 * c);
        image.ptr<T>(y)[x * channels + c] = static_cast<T>(v * full);
      }
    }
  }
  return image;
}

// The matrix's pixels with the channel order stated (image_mat::ViewOf assumes OpenCV's B, G, R).
ImageView View(const cv::Mat& m, bool bgr) {
  ImageView view = image_mat::ViewOf(m);
  view.bgr = bgr;
  return view;
}

// The decoded image as an OpenCV matrix, channels as decoded (R, G, B).
cv::Mat AsMat(const DecodedImage& image) {
  const int depth = image.bits == 32 ? CV_32F : image.bits == 16 ? CV_16U : CV_8U;
  return cv::Mat(image.height, image.width, CV_MAKETYPE(depth, image.channels),
                 const_cast<uint8_t*>(image.bytes.data()))
      .clone();
}

bool Same(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() &&
         cv::countNonZero(cv::Mat(a != b).reshape(1)) == 0;
}

cv::Mat Swapped(const cv::Mat& m) {  // channels 0 and 2 exchanged
  std::vector<cv::Mat> planes;
  cv::split(m, planes);
  std::swap(planes[0], planes[2]);
  cv::Mat out;
  cv::merge(planes, out);
  return out;
}

TEST(ImageCodec, PngGivesOpenCvsBytesAndItsDecoderReadsThePixelsBack) {
  struct Case {
    cv::Mat image;
    const char* name;
  };
  const Case cases[] = {{Pattern<uint8_t>(37, 23, 1, 255), "8-bit grey"},
                        {Pattern<uint8_t>(37, 23, 3, 255), "8-bit colour"},
                        {Pattern<uint8_t>(37, 23, 4, 255), "8-bit colour and alpha"},
                        {Pattern<uint16_t>(37, 23, 1, 65535), "16-bit grey (depth)"},
                        {Pattern<uint16_t>(37, 23, 3, 65535), "16-bit colour"}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    // OpenCV's matrices are B, G, R: encoded as such, the file holds R, G, B.
    const std::string ours = EncodePng(View(c.image, c.image.channels() >= 3));
    std::vector<uchar> theirs;
    ASSERT_TRUE(cv::imencode(".png", c.image, theirs));
    EXPECT_EQ(Bytes(ours), theirs);
    const cv::Mat back = cv::imdecode(Bytes(ours), cv::IMREAD_UNCHANGED);
    EXPECT_TRUE(Same(back, c.image));
    // Our decoder: the same values in R, G, B order.
    const DecodedImage decoded = DecodeImageBytes(ours, "test");
    EXPECT_EQ(decoded.channels, c.image.channels());
    EXPECT_EQ(decoded.bits, static_cast<int>(c.image.elemSize1()) * 8);
    EXPECT_TRUE(Same(AsMat(decoded), c.image.channels() >= 3 ? Swapped(c.image) : c.image));
  }
}

TEST(ImageCodec, PngRowsAreReadThroughTheStrideAndTheChannelOrderIsAsDeclared) {
  const cv::Mat big = Pattern<uint8_t>(50, 30, 3, 255);
  const cv::Mat part = big(cv::Rect(5, 4, 20, 10));  // rows 150 bytes apart, 60 used
  ASSERT_GT(part.step, static_cast<size_t>(part.cols * 3));
  const DecodedImage as_rgb = DecodeImageBytes(EncodePng(View(part, false)), "test");
  EXPECT_TRUE(Same(AsMat(as_rgb), part.clone()));
  const DecodedImage as_bgr = DecodeImageBytes(EncodePng(View(part, true)), "test");
  EXPECT_TRUE(Same(AsMat(as_bgr), Swapped(part.clone())));
}

// PNG chunks by hand (length, type, data, CRC-32 of type and data).
std::string Chunk(const char* type, const std::string& data) {
  std::string out;
  const uint32_t n = static_cast<uint32_t>(data.size());
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<char>(n >> shift));
  out += std::string(type, 4) + data;
  uLong crc = crc32(0, reinterpret_cast<const Bytef*>(type), 4);
  crc = crc32(crc, reinterpret_cast<const Bytef*>(data.data()), static_cast<uInt>(data.size()));
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<char>(crc >> shift));
  return out;
}

TEST(ImageCodec, AOneBitPaletteWithTransparencyIsReadAsRgba) {
  // 3 x 2 pixels of palette indices at 1 bit: row 0 = 1 0 1, row 1 = 0 1 1. Palette: 0 = red
  // (transparent, tRNS 0), 1 = (10, 200, 30) opaque.
  std::string ihdr = {0, 0, 0, 3, 0, 0, 0, 2, 1, 3, 0, 0, 0};  // 1 bit, colour type 3
  const std::string plte = {'\xff', 0, 0, 10, '\xc8', 30};
  const std::string trns = {0, '\xff'};
  const std::string raw = {0, static_cast<char>(0b10100000), 0, static_cast<char>(0b01100000)};
  std::string packed(compressBound(raw.size()), '\0');
  uLongf size = packed.size();
  ASSERT_EQ(compress(reinterpret_cast<Bytef*>(packed.data()), &size,
                     reinterpret_cast<const Bytef*>(raw.data()), raw.size()),
            Z_OK);
  packed.resize(size);
  const std::string png = std::string("\x89PNG\r\n\x1a\n", 8) + Chunk("IHDR", ihdr) +
                          Chunk("PLTE", plte) + Chunk("tRNS", trns) + Chunk("IDAT", packed) +
                          Chunk("IEND", "");
  const DecodedImage image = DecodeImageBytes(png, "palette.png");
  ASSERT_EQ(image.width, 3);
  ASSERT_EQ(image.height, 2);
  ASSERT_EQ(image.channels, 4);
  ASSERT_EQ(image.bits, 8);
  const std::vector<uint8_t> red = {255, 0, 0, 0}, green = {10, 200, 30, 255};
  const int index[2][3] = {{1, 0, 1}, {0, 1, 1}};
  for (int y = 0; y < 2; ++y) {
    for (int x = 0; x < 3; ++x) {
      const uint8_t* p = &image.bytes[4 * (3 * y + x)];
      EXPECT_EQ(std::vector<uint8_t>(p, p + 4), index[y][x] ? green : red) << x << ", " << y;
    }
  }
}

TEST(ImageCodec, JpegGivesOpenCvsBytesAndDecodesAsOpenCvDoes) {
  for (const int channels : {1, 3}) {
    SCOPED_TRACE(channels);
    const cv::Mat image = Pattern<uint8_t>(64, 48, channels, 255);
    const std::string ours = EncodeJpeg(View(image, channels == 3), 90);
    std::vector<uchar> theirs;
    ASSERT_TRUE(cv::imencode(".jpg", image, theirs, {cv::IMWRITE_JPEG_QUALITY, 90}));
    EXPECT_EQ(Bytes(ours), theirs);
    const DecodedImage decoded = DecodeImageBytes(ours, "test");
    ASSERT_EQ(decoded.channels, channels);
    const cv::Mat opencv = cv::imdecode(Bytes(ours), cv::IMREAD_UNCHANGED);
    EXPECT_TRUE(Same(AsMat(decoded), channels == 3 ? Swapped(opencv) : opencv));
    // Lossy, but close to the smooth original at quality 90 (colour loses more: its chroma is
    // kept at half resolution, and the pattern's channels vary out of phase).
    cv::Mat diff;
    cv::absdiff(AsMat(decoded), channels == 3 ? Swapped(image) : image, diff);
    double worst = 0;
    cv::minMaxLoc(diff.reshape(1), nullptr, &worst);
    EXPECT_LT(cv::mean(diff.reshape(1))[0], 2.0);
    EXPECT_LT(worst, channels == 1 ? 8 : 24);
  }
}

TEST(ImageCodec, ExrKeepsFloatsExactlyBothWays) {
  cv::Mat image(7, 11, CV_32FC3);
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      image.at<cv::Vec3f>(y, x) = cv::Vec3f(1e-6f * (x + 1), 3.25f * y + 0.125f, 12345.678f);
    }
  }
  // Ours read by OpenCV (B, G, R) and by us (R, G, B).
  const std::string ours = EncodeExr(View(image, true));
  EXPECT_TRUE(Same(cv::imdecode(Bytes(ours), cv::IMREAD_UNCHANGED), image));
  EXPECT_TRUE(Same(AsMat(DecodeImageBytes(ours, "test")), Swapped(image)));
  // OpenCV's read by us.
  std::vector<uchar> theirs;
  ASSERT_TRUE(
      cv::imencode(".exr", image, theirs, {cv::IMWRITE_EXR_TYPE, cv::IMWRITE_EXR_TYPE_FLOAT}));
  const DecodedImage back =
      DecodeImageBytes(std::string(theirs.begin(), theirs.end()), "opencv.exr");
  EXPECT_TRUE(Same(AsMat(back), Swapped(image)));
  // One channel: Y.
  const cv::Mat grey = Pattern<float>(9, 5, 1, 3.0);
  const DecodedImage y = DecodeImageBytes(EncodeExr(View(grey, false)), "test");
  ASSERT_EQ(y.channels, 1);
  EXPECT_TRUE(Same(AsMat(y), grey));
}

TEST(ImageCodec, ExrIsWrittenUncompressed) {
  // A flat image ZIP would shrink to a few hundred bytes: uncompressed it keeps every float's
  // four bytes (rendered radiance's low bits are noise, where ZIP saves a few per cent at ten
  // times the writing time).
  const cv::Mat flat(64, 48, CV_32FC3, cv::Scalar(0.25, 0.5, 2.0));
  const std::string bytes = EncodeExr(View(flat, false));
  EXPECT_GE(bytes.size(), static_cast<size_t>(64 * 48 * 3 * 4));
  EXPECT_LT(bytes.size(), static_cast<size_t>(64 * 48 * 3 * 4 + 4096));
  EXPECT_TRUE(Same(AsMat(DecodeImageBytes(bytes, "flat.exr")), flat));
}

TEST(ImageCodec, RadianceHdrFlatAndRunLengthRowsGiveTheRgbeValuesByHand) {
  // RGBE (m_r, m_g, m_b, e) is m * 2^(e - 136): (128, 64, 32, 129) = (1, 0.5, 0.25); e = 0 is 0.
  std::string file = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\nEXPOSURE=1.0\n\n-Y 2 +X 8\n";
  // Row 0 run-length encoded: each component of all 8 pixels in turn; R as a run of 8 x 128, G
  // as 8 literals, B as runs of 4 and 4, E as a run of 8 x 129.
  file += std::string({2, 2, 0, 8});
  file += std::string({static_cast<char>(128 + 8), static_cast<char>(128)});
  file += std::string({8, 0, 16, 32, 48, 64, 80, 96, 112});
  file += std::string({static_cast<char>(128 + 4), 32, static_cast<char>(128 + 4), 64});
  file += std::string({static_cast<char>(128 + 8), static_cast<char>(129)});
  // Row 1 flat: 8 pixels of (128, 64, 32, 129) except pixel 3, which is black (e = 0).
  for (int x = 0; x < 8; ++x) {
    file += x == 3 ? std::string({10, 20, 30, 0})
                   : std::string({static_cast<char>(128), 64, 32, static_cast<char>(129)});
  }
  const DecodedImage image = DecodeImageBytes(file, "sky.hdr");
  ASSERT_EQ(image.width, 8);
  ASSERT_EQ(image.height, 2);
  ASSERT_EQ(image.channels, 3);
  ASSERT_EQ(image.bits, 32);
  const auto at = [&](int x, int y, int c) {
    float v;
    std::memcpy(&v, &image.bytes[4 * (3 * (8 * y + x) + c)], 4);
    return v;
  };
  for (int x = 0; x < 8; ++x) {
    EXPECT_EQ(at(x, 0, 0), 1.0f);
    EXPECT_EQ(at(x, 0, 1), 16 * x / 128.0f);
    EXPECT_EQ(at(x, 0, 2), x < 4 ? 0.25f : 0.5f);
    EXPECT_EQ(at(x, 1, 0), x == 3 ? 0.0f : 1.0f);
    EXPECT_EQ(at(x, 1, 1), x == 3 ? 0.0f : 0.5f);
    EXPECT_EQ(at(x, 1, 2), x == 3 ? 0.0f : 0.25f);
  }
  // OpenCV's reader gives the same floats (B, G, R).
  const cv::Mat opencv = cv::imdecode(Bytes(file), cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(opencv.empty());
  EXPECT_TRUE(Same(AsMat(image), Swapped(opencv)));
}

TEST(ImageCodec, BrokenAndUnknownFilesAreErrorsThatNameThem) {
  const cv::Mat image = Pattern<uint8_t>(16, 16, 3, 255);
  const std::string png = EncodePng(View(image, false));
  const std::string jpeg = EncodeJpeg(View(image, false), 80);
  const std::string exr = EncodeExr(View(Pattern<float>(4, 4, 3, 1.0), false));
  const auto message = [](const std::string& bytes) {
    try {
      DecodeImageBytes(bytes, "parts/texture.img");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  for (const std::string& bytes :
       {png.substr(0, png.size() / 2), jpeg.substr(0, 40), exr.substr(0, exr.size() / 2),
        std::string("GIF89a......"), std::string("#?RADIANCE\n\n-Y 4 +X 4\n")}) {
    const std::string what = message(bytes);
    EXPECT_EQ(what.rfind("parts/texture.img: ", 0), 0u) << what;
  }
  EXPECT_NE(message("GIF89a").find("PNG, JPEG, OpenEXR or Radiance HDR"), std::string::npos);
  EXPECT_THROW(EncodeJpeg(View(Pattern<uint16_t>(4, 4, 1, 100), false), 90), Error);
  EXPECT_THROW(EncodeJpeg(View(image, false), 0), Error);
  EXPECT_THROW(EncodePng(View(Pattern<float>(4, 4, 1, 1), false)), Error);
}

}  // namespace
}  // namespace cadsynth
