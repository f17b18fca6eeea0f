// Image files in memory: PNG (libpng), JPEG (libjpeg-turbo), OpenEXR (the OpenEXR library) and
// Radiance HDR (read here), encoded and decoded without OpenCV's imgcodecs.
//
// Why not OpenCV's imgcodecs: Debian's build of it links GDAL, GDCM, Poppler, MariaDB and 60 more
// libraries, all loaded and relocated at start-up whether an image is read or not: 0.07 of the
// 0.19 s a bare `cadsynth --version` took, paid by every shard of a farm and every test process.
// The encoders use the settings OpenCV's did (PNG: the Sub filter, zlib level 1, the RLE strategy;
// JPEG: libjpeg's defaults, baseline, 4:2:0), so the datasets' bytes are what they were.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace cadsynth {

// Pixels to encode: rows of `width` pixels of `channels` interleaved values of `bits` bits (8 or
// 16: unsigned integers; 32: float), native-endian, `stride` bytes apart (0: packed).
struct ImageView {
  const void* pixels = nullptr;
  size_t stride = 0;
  int width = 0, height = 0, channels = 1, bits = 8;
  bool bgr = false;  // colour channels in B, G, R order (OpenCV's) instead of R, G, B
  size_t RowBytes() const { return static_cast<size_t>(width) * channels * (bits / 8); }
  size_t Stride() const { return stride != 0 ? stride : RowBytes(); }
};

// A decoded image: rows packed, channels R, G, B (and A when the file has alpha) or one grey
// channel (and alpha), `bits` 8 or 16 (unsigned) or 32 (float), native-endian.
struct DecodedImage {
  int width = 0, height = 0, channels = 0, bits = 0;
  std::vector<uint8_t> bytes;
  size_t RowBytes() const { return static_cast<size_t>(width) * channels * (bits / 8); }
};

enum class ImageFormat { kPng, kJpeg, kExr, kRadianceHdr, kUnknown };

// The format a file's first bytes announce (its signature), whatever its name says.
ImageFormat SniffImageFormat(std::string_view bytes);

// PNG bytes: 1, 2 (grey and alpha), 3 or 4 channels of 8 or 16 bits. Throws Error.
std::string EncodePng(const ImageView& image);
// Baseline JPEG bytes (JFIF, 4:2:0 for colour) at `quality` 1-100: 1 or 3 channels of 8 bits.
std::string EncodeJpeg(const ImageView& image, int quality);
// OpenEXR bytes, 32-bit float channels R, G, B (3 channels) or Y (1), ZIP compressed.
std::string EncodeExr(const ImageView& image);

// Decodes PNG (any bit depth, palette and interlace; below 8 bits widened to 8, palettes to RGB
// or RGBA), JPEG (grey or colour; EXIF orientation is not applied), OpenEXR (the R, G, B or Y
// channels as float, alpha dropped, missing colour channels zero) and Radiance HDR (RGBE, flat
// or run-length encoded; float). `origin` names the bytes in errors. Throws Error.
DecodedImage DecodeImageBytes(std::string_view bytes, const std::string& origin);
// The same from a file; errors name it.
DecodedImage ReadImageBytesFile(const std::filesystem::path& path);

}  // namespace cadsynth
