#include "dataset/coco.h"

#include <gtest/gtest.h>

#include <random>

#include "cad/core/error.h"

namespace cadsynth {
namespace {

TEST(CocoRle, ColumnMajorRunsStartWithBackground) {
  // 3 rows x 2 columns, row-major:  1 0 / 1 1 / 0 1.  Column-major: 1 1 0 | 0 1 1.
  const std::vector<uint8_t> mask = {1, 0, 1, 1, 0, 1};
  const RleMask rle = EncodeRle(2, 3, 0, 0, 2, 3, [&](size_t p) { return mask[p] != 0; });
  EXPECT_EQ(rle.counts, (std::vector<uint32_t>{0, 2, 2, 2}));
  EXPECT_EQ(DecodeRle(rle), mask);
  // A box that leaves out the on pixels leaves only background.
  EXPECT_EQ(EncodeRle(2, 3, 0, 2, 1, 3, [&](size_t p) { return mask[p] != 0; }).counts,
            (std::vector<uint32_t>{6}));
}

TEST(CocoRle, CompressedStringsAsTheCocoApiWritesThem) {
  // Worked by hand from pycocotools' rleToString: 5 bits per character plus 48, bit 0x20 for
  // "more"; from the fourth count on, the difference to the count two before.
  EXPECT_EQ(CompressRleCounts({1, 2, 6}), "126");          // the first three are stored as they are
  EXPECT_EQ(CompressRleCounts({1, 2, 6, 1}), "126O");      // 1 - 2 = -1: 0x1f, sign bit set, done
  EXPECT_EQ(CompressRleCounts({100}), "T3");               // 100 = 4 + 3 x 32: 'T' = 48 + 0x20 + 4
  EXPECT_EQ(CompressRleCounts({0, 50, 0, 10}), "0b10hN");  // 50 -> "b1"; 10 - 50 = -40 -> "hN"
  EXPECT_EQ(DecompressRleCounts("0b10hN"), (std::vector<uint32_t>{0, 50, 0, 10}));
  EXPECT_THROW(DecompressRleCounts("b"), Error);  // a continuation with nothing after it
}

TEST(CocoRle, RandomMasksSurviveTheRoundTrip) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 50; ++trial) {
    const int w = 1 + static_cast<int>(rng() % 40), h = 1 + static_cast<int>(rng() % 40);
    std::vector<uint8_t> mask(static_cast<size_t>(w) * h);
    // Blobs with long runs, so that counts go well past 32 and differences turn negative.
    const int fill = static_cast<int>(rng() % 4);
    for (size_t p = 0; p < mask.size(); ++p) mask[p] = (p / 7 + fill) % 5 < 2 || rng() % 13 == 0;
    const RleMask rle = EncodeRle(w, h, 0, 0, w, h, [&](size_t p) { return mask[p] != 0; });
    RleMask back{h, w, DecompressRleCounts(CompressRleCounts(rle.counts))};
    EXPECT_EQ(back.counts, rle.counts);
    EXPECT_EQ(DecodeRle(back), mask);
  }
  EXPECT_THROW(DecodeRle(RleMask{2, 2, {1, 1}}), Error);  // covers 2 of 4 pixels
}

}  // namespace
}  // namespace cadsynth
