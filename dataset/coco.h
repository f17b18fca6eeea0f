// COCO instance masks: run-length encoding as the COCO API (pycocotools) stores it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace cadsynth {

// Run lengths of a binary mask in column-major order (down each column, columns left to right),
// alternating background and foreground and starting with background (possibly a zero run).
struct RleMask {
  int height = 0, width = 0;
  std::vector<uint32_t> counts;
};

// Encodes the pixels of a width x height row-major image where `is_on(pixel index)` holds, looking
// only inside the box [u0, u1) x [v0, v1) (everything outside is background).
template <typename Predicate>
RleMask EncodeRle(int width, int height, int u0, int v0, int u1, int v1, Predicate is_on);

// The COCO "counts" string (LEB128-like, 5 bits per character, each count after the second
// stored as the difference to the count two before), as pycocotools' rleToString writes it.
std::string CompressRleCounts(const std::vector<uint32_t>& counts);
// The inverse; throws Error on a malformed string.
std::vector<uint32_t> DecompressRleCounts(const std::string& text);
// The row-major mask (1 = on) of `rle`; throws Error when the counts do not add up.
std::vector<uint8_t> DecodeRle(const RleMask& rle);

// Implementation.
template <typename Predicate>
RleMask EncodeRle(int width, int height, int u0, int v0, int u1, int v1, Predicate is_on) {
  RleMask rle{height, width, {}};
  bool on = false;
  uint32_t run = 0;
  const auto push = [&](bool value, uint32_t n) {
    if (n == 0) return;
    if (value != on) {
      rle.counts.push_back(run);
      on = value;
      run = 0;
    }
    run += n;
  };
  for (int u = 0; u < width; ++u) {
    if (u < u0 || u >= u1 || v0 >= v1) {
      push(false, static_cast<uint32_t>(height));
      continue;
    }
    push(false, static_cast<uint32_t>(v0));
    for (int v = v0; v < v1; ++v) push(is_on(static_cast<size_t>(v) * width + u), 1);
    push(false, static_cast<uint32_t>(height - v1));
  }
  rle.counts.push_back(run);
  return rle;
}

}  // namespace cadsynth
