// PNG files of 8-bit grey masks that are zero outside a band of rows, written with zlib directly.
//
// A pile's frame writes two full-size masks per instance (BOP's mask/ and mask_visib/): 120 PNGs
// of 1440 x 1080 for 60 parts, 190 MB of pixels per frame that are almost all zero. libpng (via
// OpenCV) compresses every byte; here only the band of rows that may hold non-zero pixels is
// compressed, and the zero rows above and below it are spliced in from deflate blocks of zeros
// compressed once per process. The file decodes to exactly the same pixels.
#pragma once

#include <cstdint>
#include <string>

namespace cadsynth {

// The PNG bytes (8-bit greyscale, no interlace) of a `width` x `height` image whose row y starts
// at pixels + y * stride. Rows outside [first_row, end_row) must be zero and are not read; the
// band is clamped to the image (an empty band: an all-zero image).
std::string EncodeMaskPng(const uint8_t* pixels, size_t stride, int width, int height,
                          int first_row, int end_row);

}  // namespace cadsynth
