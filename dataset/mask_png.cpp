#include "dataset/mask_png.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <mutex>
#include <vector>

#include <zlib.h>

#include "cad/core/error.h"

namespace cadsynth {

namespace {

// Zero runs are spliced in as multiples of this many bytes (powers of two times it); shorter
// remainders go into the band's own deflate stream.
constexpr int kUnitLog2 = 12;
constexpr int kMaxLog2 = 40;

// Raw deflate (no zlib header) of `n` bytes, ended by a sync flush: complete non-final blocks
// ending on a byte boundary, which may be followed by further blocks of another stream. Each call
// is a fresh stream, so its blocks refer to nothing before them.
void DeflateSegment(const uint8_t* bytes, size_t n, std::string* out) {
  z_stream z{};
  if (deflateInit2(&z, Z_DEFAULT_COMPRESSION, Z_DEFLATED, -15, 8, Z_RLE) != Z_OK)
    throw Error("PNG: zlib's deflateInit2 failed");
  std::array<unsigned char, 1 << 14> buffer;
  size_t done = 0;
  int flush = Z_NO_FLUSH;
  do {
    // zlib takes lengths as uInt: feed large inputs in pieces.
    if (z.avail_in == 0 && flush == Z_NO_FLUSH) {
      const size_t piece = std::min<size_t>(n - done, 1u << 30);
      z.next_in = const_cast<Bytef*>(bytes + done);
      z.avail_in = static_cast<uInt>(piece);
      done += piece;
      if (done == n) flush = Z_SYNC_FLUSH;
    }
    z.next_out = buffer.data();
    z.avail_out = static_cast<uInt>(buffer.size());
    const int status = deflate(&z, flush);
    if (status != Z_OK && status != Z_BUF_ERROR) {
      deflateEnd(&z);
      throw Error("PNG: zlib's deflate failed");
    }
    out->append(reinterpret_cast<const char*>(buffer.data()), buffer.size() - z.avail_out);
    // Done once the flush was asked for, all input taken and the output not full.
  } while (!(flush == Z_SYNC_FLUSH && z.avail_in == 0 && z.avail_out != 0));
  deflateEnd(&z);
}

// The deflate segment of 2^(kUnitLog2 + k) zero bytes, made on first use.
const std::string& ZeroSegment(int k) {
  static std::array<std::string, kMaxLog2 - kUnitLog2> segments;
  static std::array<std::once_flag, kMaxLog2 - kUnitLog2> made;
  std::call_once(made[k], [k] {
    const std::vector<uint8_t> zeros(size_t{1} << (kUnitLog2 + k), 0);
    DeflateSegment(zeros.data(), zeros.size(), &segments[k]);
  });
  return segments[k];
}

// Appends the segments for `units` * 2^kUnitLog2 zero bytes.
void AppendZeroUnits(uint64_t units, std::string* out) {
  for (int k = kMaxLog2 - kUnitLog2 - 1; k >= 0; --k) {
    if (units >> k & 1) out->append(ZeroSegment(k));
  }
}

// Adler-32 of `n` zero bytes: its sum a stays 1, its sum b counts them.
uLong ZerosAdler(uint64_t n) { return static_cast<uLong>((n % 65521) << 16 | 1); }

void AppendBigEndian(uint32_t v, std::string* out) {
  const char b[4] = {static_cast<char>(v >> 24), static_cast<char>(v >> 16),
                     static_cast<char>(v >> 8), static_cast<char>(v)};
  out->append(b, 4);
}

void AppendChunk(const char* type, const std::string& data, std::string* out) {
  AppendBigEndian(static_cast<uint32_t>(data.size()), out);
  const size_t start = out->size();
  out->append(type, 4);
  out->append(data);
  const auto* p = reinterpret_cast<const Bytef*>(out->data() + start);
  uLong crc = ::crc32(0L, Z_NULL, 0);
  for (size_t done = 0, n = out->size() - start; done < n;) {
    const size_t piece = std::min<size_t>(n - done, 1u << 30);
    crc = ::crc32(crc, p + done, static_cast<uInt>(piece));
    done += piece;
  }
  AppendBigEndian(static_cast<uint32_t>(crc), out);
}

}  // namespace

std::string EncodeMaskPng(const uint8_t* pixels, size_t stride, int width, int height,
                          int first_row, int end_row) {
  if (width <= 0 || height <= 0) throw Error("PNG: an image needs a positive size");
  first_row = std::clamp(first_row, 0, height);
  end_row = std::clamp(end_row, first_row, height);
  const uint64_t row_bytes = static_cast<uint64_t>(width) + 1;  // filter type 0, then pixels
  const uint64_t unit = uint64_t{1} << kUnitLog2;
  const uint64_t top = first_row * row_bytes, bottom = (height - end_row) * row_bytes;

  // The filtered band, with the zero runs' remainders below a unit before and after it.
  std::vector<uint8_t> band(top % unit + (end_row - first_row) * row_bytes + bottom % unit, 0);
  uint8_t* row = band.data() + top % unit;
  for (int y = first_row; y < end_row; ++y, row += row_bytes)
    std::memcpy(row + 1, pixels + static_cast<size_t>(y) * stride, static_cast<size_t>(width));

  // zlib stream: header (deflate, 32 KiB window, no dictionary), blocks, final empty block,
  // Adler-32 of the uncompressed bytes.
  std::string idat = {'\x78', '\x01'};
  AppendZeroUnits(top / unit, &idat);
  DeflateSegment(band.data(), band.size(), &idat);
  AppendZeroUnits(bottom / unit, &idat);
  idat.append({'\x03', '\x00'});  // BFINAL, fixed Huffman codes, end of block
  uLong adler = ZerosAdler(top - top % unit);
  adler = adler32_combine(adler, adler32(1L, band.data(), static_cast<uInt>(band.size())),
                          static_cast<z_off_t>(band.size()));
  adler = adler32_combine(adler, ZerosAdler(bottom - bottom % unit),
                          static_cast<z_off_t>(bottom - bottom % unit));
  AppendBigEndian(static_cast<uint32_t>(adler), &idat);

  std::string ihdr;
  AppendBigEndian(static_cast<uint32_t>(width), &ihdr);
  AppendBigEndian(static_cast<uint32_t>(height), &ihdr);
  ihdr.append({'\x08', '\x00', '\x00', '\x00', '\x00'});  // 8 bit, grey, deflate, filters, none
  std::string png = "\x89PNG\r\n\x1a\n";
  AppendChunk("IHDR", ihdr, &png);
  AppendChunk("IDAT", idat, &png);
  AppendChunk("IEND", std::string(), &png);
  return png;
}

}  // namespace cadsynth
