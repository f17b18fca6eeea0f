#include "dataset/coco.h"

#include "cad/core/error.h"

namespace cadsynth {

std::string CompressRleCounts(const std::vector<uint32_t>& counts) {
  std::string out;
  for (size_t i = 0; i < counts.size(); ++i) {
    int64_t x = counts[i];
    if (i > 2) x -= counts[i - 2];
    for (bool more = true; more;) {
      char c = static_cast<char>(x & 0x1f);
      x >>= 5;  // arithmetic: negative differences end in all ones
      more = (c & 0x10) ? x != -1 : x != 0;
      if (more) c |= 0x20;
      out += static_cast<char>(c + 48);
    }
  }
  return out;
}

std::vector<uint32_t> DecompressRleCounts(const std::string& text) {
  std::vector<uint32_t> counts;
  size_t p = 0;
  while (p < text.size()) {
    int64_t x = 0;
    int k = 0;
    for (bool more = true; more; ++k) {
      if (p >= text.size() || text[p] < 48 || text[p] > 48 + 63 || k > 12) {
        throw Error("RLE counts: malformed string at character " + std::to_string(p));
      }
      const int c = text[p++] - 48;
      x |= static_cast<int64_t>(c & 0x1f) << (5 * k);
      more = (c & 0x20) != 0;
      if (!more && (c & 0x10)) x |= -(int64_t{1} << (5 * (k + 1)));
    }
    if (counts.size() > 2) x += counts[counts.size() - 2];
    if (x < 0) throw Error("RLE counts: negative run");
    counts.push_back(static_cast<uint32_t>(x));
  }
  return counts;
}

std::vector<uint8_t> DecodeRle(const RleMask& rle) {
  const size_t n = static_cast<size_t>(rle.height) * rle.width;
  std::vector<uint8_t> mask(n, 0);
  size_t pos = 0;
  for (size_t i = 0; i < rle.counts.size(); ++i) {
    if (pos + rle.counts[i] > n) throw Error("RLE: runs exceed the image");
    for (uint32_t j = 0; j < rle.counts[i]; ++j, ++pos) {
      if (i % 2 == 1) {
        const size_t u = pos / rle.height, v = pos % rle.height;
        mask[v * rle.width + u] = 1;
      }
    }
  }
  if (pos != n)
    throw Error("RLE: runs cover " + std::to_string(pos) + " of " + std::to_string(n) + " pixels");
  return mask;
}

}  // namespace cadsynth
