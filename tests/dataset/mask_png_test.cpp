// Mask PNGs written by cadsynth's own encoder, read back by independent decoders: libpng (through
// OpenCV) for the pixels and the chunk CRCs, zlib's inflate for the stream and its Adler-32.
#include "dataset/mask_png.h"

#include <cstring>
#include <random>

#include <zlib.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <gtest/gtest.h>

namespace cadsynth {
namespace {

// A mask with random blobs of 255 in rows [first, end).
cv::Mat Blobs(int w, int h, int first, int end, uint32_t seed) {
  cv::Mat m = cv::Mat::zeros(h, w, CV_8UC1);
  std::mt19937 rng(seed);
  for (int y = first; y < end; ++y) {
    auto* row = m.ptr<uint8_t>(y);
    for (int x = 0; x < w; ++x) row[x] = (rng() % 7 < 3) ? 255 : 0;
  }
  return m;
}

uint32_t BigEndian(const std::string& s, size_t at) {
  const auto* p = reinterpret_cast<const unsigned char*>(s.data() + at);
  return uint32_t{p[0]} << 24 | uint32_t{p[1]} << 16 | uint32_t{p[2]} << 8 | p[3];
}

void ExpectDecodesTo(const cv::Mat& m, int first, int end) {
  SCOPED_TRACE(std::to_string(m.cols) + " x " + std::to_string(m.rows) + ", rows " +
               std::to_string(first) + "-" + std::to_string(end));
  const std::string png = EncodeMaskPng(m.data, m.step, m.cols, m.rows, first, end);
  const cv::Mat back =
      cv::imdecode(cv::Mat(1, static_cast<int>(png.size()), CV_8UC1, const_cast<char*>(png.data())),
                   cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(back.empty()) << "libpng refused the file";
  ASSERT_EQ(back.type(), CV_8UC1);
  ASSERT_EQ(back.size(), m.size());
  EXPECT_EQ(cv::countNonZero(back != m), 0);

  // The IDAT chunk inflates (zlib checks the Adler-32) to the filtered rows: a 0 before each.
  ASSERT_EQ(png.compare(12, 4, "IHDR"), 0);
  const size_t idat = 8 + 12 + 13;
  ASSERT_EQ(png.compare(idat + 4, 4, "IDAT"), 0);
  const uint32_t n = BigEndian(png, idat);
  std::vector<unsigned char> raw(static_cast<size_t>(m.rows) * (m.cols + 1) + 1);
  uLongf raw_size = raw.size();
  ASSERT_EQ(
      uncompress(raw.data(), &raw_size, reinterpret_cast<const Bytef*>(png.data() + idat + 8), n),
      Z_OK);
  ASSERT_EQ(raw_size, static_cast<uLongf>(m.rows) * (m.cols + 1));
  for (int y = 0; y < m.rows; ++y) {
    ASSERT_EQ(raw[y * (m.cols + 1)], 0) << "row " << y << "'s filter";
    ASSERT_EQ(std::memcmp(&raw[y * (m.cols + 1) + 1], m.ptr(y), m.cols), 0) << "row " << y;
  }
  EXPECT_EQ(png.compare(png.size() - 8, 4, "IEND"), 0);
}

TEST(MaskPng, DecodesToTheSamePixelsWhateverTheBand) {
  ExpectDecodesTo(Blobs(640, 480, 100, 180, 1), 100, 180);
  ExpectDecodesTo(Blobs(1440, 1080, 0, 1080, 2), 0, 1080);        // the whole image
  ExpectDecodesTo(Blobs(1440, 1080, 0, 3, 3), 0, 3);              // at the top
  ExpectDecodesTo(Blobs(1440, 1080, 1077, 1080, 4), 1077, 1080);  // at the bottom
  ExpectDecodesTo(Blobs(1440, 1080, 500, 500, 5), 500, 500);      // no band: all zero
  ExpectDecodesTo(Blobs(1, 1, 0, 1, 6), 0, 1);
  ExpectDecodesTo(Blobs(4095, 3, 1, 2, 7), 1, 2);  // rows of exactly one splice unit
  // ITODD-MV's grey cameras: 4224 x 2838, a small part near the middle (zero runs of megabytes).
  ExpectDecodesTo(Blobs(4224, 2838, 1400, 1460, 8), 1400, 1460);
  // A band larger than the non-zero rows, and one clamped to the image.
  ExpectDecodesTo(Blobs(300, 200, 50, 60, 9), 10, 190);
  ExpectDecodesTo(Blobs(300, 200, 0, 200, 10), -5, 900);
}

TEST(MaskPng, AsSmallAsLibpngsFiles) {
  // Deflate codes at most 258 bytes per match: 1.5 MB of zeros take about 1.5 KB whoever writes
  // them. The spliced zero blocks cost little more than one stream would.
  const cv::Mat m = Blobs(1440, 1080, 600, 610, 11);
  const cv::Mat zero = cv::Mat::zeros(1080, 1440, CV_8UC1);
  for (const cv::Mat* image : {&m, &zero}) {
    const int end = image == &m ? 610 : 0;
    const std::string png = EncodeMaskPng(image->data, image->step, 1440, 1080, 600, end);
    std::vector<uchar> libpng;
    ASSERT_TRUE(cv::imencode(".png", *image, libpng));
    EXPECT_LT(png.size(), libpng.size() + 300) << "libpng: " << libpng.size();
  }
}

}  // namespace
}  // namespace cadsynth
