#include "render/image_codec.h"

#include <algorithm>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>

#include <Iex.h>
#include <ImfChannelList.h>
#include <ImfCompression.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <jpeglib.h>
#include <png.h>
#include <zlib.h>

#include "cad/core/error.h"

namespace cadsynth {
namespace {

constexpr char kPngSignature[] = "\x89PNG\r\n\x1a\n";

bool LittleEndian() {
  const uint16_t one = 1;
  uint8_t first;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

std::string Shape(const ImageView& image) {
  return std::to_string(image.width) + " x " + std::to_string(image.height) + " x " +
         std::to_string(image.channels) + " x " + std::to_string(image.bits) + " bits";
}

void CheckView(const ImageView& image, const char* format) {
  if (image.pixels == nullptr || image.width <= 0 || image.height <= 0 ||
      image.Stride() < image.RowBytes())
    throw Error(std::string(format) + ": no pixels to encode (" + Shape(image) + ")");
}

// ---- PNG ----------------------------------------------------------------------------------------
// libpng reports errors by longjmp. The functions calling setjmp hold nothing with a destructor
// that is created after it, and read no local they change after it (C's rule for setjmp).

struct PngMessage {
  char text[200] = "";
};

void PngError(png_structp png, png_const_charp message) {
  auto* out = static_cast<PngMessage*>(png_get_error_ptr(png));
  std::snprintf(out->text, sizeof out->text, "%s", message);
  png_longjmp(png, 1);
}

void PngWarning(png_structp, png_const_charp) {}  // e.g. "known incorrect sRGB profile"

void PngAppend(png_structp png, png_bytep data, size_t size) {
  static_cast<std::string*>(png_get_io_ptr(png))->append(reinterpret_cast<const char*>(data), size);
}

void PngFlush(png_structp) {}

// Returns false with `message` filled when libpng fails.
bool PngEncode(const ImageView& image, std::string* out, PngMessage* message) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, message, PngError, PngWarning);
  if (png == nullptr) return false;
  png_infop info = png_create_info_struct(png);
  if (info == nullptr || setjmp(png_jmpbuf(png)) != 0) {
    png_destroy_write_struct(&png, &info);
    return false;
  }
  png_set_write_fn(png, out, PngAppend, PngFlush);
  png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB);
  png_set_compression_level(png, Z_BEST_SPEED);
  png_set_compression_strategy(png, Z_RLE);
  static constexpr int kColourType[] = {0, PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA,
                                        PNG_COLOR_TYPE_RGB, PNG_COLOR_TYPE_RGB_ALPHA};
  png_set_IHDR(png, info, static_cast<png_uint_32>(image.width),
               static_cast<png_uint_32>(image.height), image.bits, kColourType[image.channels],
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  if (image.bgr) png_set_bgr(png);
  if (image.bits == 16 && LittleEndian()) png_set_swap(png);
  const auto* row = static_cast<const uint8_t*>(image.pixels);
  for (int y = 0; y < image.height; ++y)
    png_write_row(png, const_cast<png_bytep>(row + static_cast<size_t>(y) * image.Stride()));
  png_write_end(png, info);
  png_destroy_write_struct(&png, &info);
  return true;
}

// The decoded image, or false with `message` filled.
bool PngDecode(std::string_view bytes, DecodedImage* out, PngMessage* message) {
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, message, PngError, PngWarning);
  if (png == nullptr) return false;
  png_infop info = png_create_info_struct(png);
  struct Source {
    std::string_view bytes;
    size_t at = 0;
  } source{bytes, 0};
  if (info == nullptr || setjmp(png_jmpbuf(png)) != 0) {
    png_destroy_read_struct(&png, &info, nullptr);
    return false;
  }
  png_set_read_fn(png, &source, [](png_structp p, png_bytep data, size_t size) {
    auto* s = static_cast<Source*>(png_get_io_ptr(p));
    if (size > s->bytes.size() - s->at) png_error(p, "truncated (the file ends early)");
    std::memcpy(data, s->bytes.data() + s->at, size);
    s->at += size;
  });
  png_read_info(png, info);
  const int colour = png_get_color_type(png, info);
  const int depth = png_get_bit_depth(png, info);
  if (colour == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (colour == PNG_COLOR_TYPE_GRAY && depth < 8) png_set_expand_gray_1_2_4_to_8(png);
  if (png_get_valid(png, info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(png);
  if (depth == 16 && LittleEndian()) png_set_swap(png);
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  out->width = static_cast<int>(png_get_image_width(png, info));
  out->height = static_cast<int>(png_get_image_height(png, info));
  out->channels = png_get_channels(png, info);
  out->bits = png_get_bit_depth(png, info);
  out->bytes.resize(out->RowBytes() * static_cast<size_t>(out->height));
  // Row pointers without a vector (nothing created after setjmp may need a destructor): libpng
  // reads interlaced images in passes over all rows, so every row is handed over each pass.
  const int passes = (png_get_interlace_type(png, info) == PNG_INTERLACE_ADAM7) ? 7 : 1;
  for (int pass = 0; pass < passes; ++pass) {
    for (int y = 0; y < out->height; ++y)
      png_read_row(png, out->bytes.data() + static_cast<size_t>(y) * out->RowBytes(), nullptr);
  }
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  return true;
}

// ---- JPEG ---------------------------------------------------------------------------------------

struct JpegError {
  jpeg_error_mgr manager;
  std::jmp_buf jump;
  char text[JMSG_LENGTH_MAX] = "";
};

void JpegExit(j_common_ptr info) {
  auto* error = reinterpret_cast<JpegError*>(info->err);
  (*info->err->format_message)(info, error->text);
  std::longjmp(error->jump, 1);
}

void JpegSilent(j_common_ptr, int) {}  // warnings (e.g. extraneous bytes) are not errors

// The encoded bytes (malloc'ed by libjpeg, *size of them), or false with the error's text.
bool JpegEncode(const ImageView& image, int quality, unsigned char** buffer, unsigned long* size,
                JpegError* error) {
  jpeg_compress_struct info{};
  info.err = jpeg_std_error(&error->manager);
  error->manager.error_exit = JpegExit;
  error->manager.emit_message = JpegSilent;
  if (setjmp(error->jump) != 0) {
    jpeg_destroy_compress(&info);
    return false;
  }
  jpeg_create_compress(&info);
  jpeg_mem_dest(&info, buffer, size);
  info.image_width = static_cast<JDIMENSION>(image.width);
  info.image_height = static_cast<JDIMENSION>(image.height);
  info.input_components = image.channels;
  info.in_color_space =
      image.channels == 1 ? JCS_GRAYSCALE : (image.bgr ? JCS_EXT_BGR : JCS_EXT_RGB);
  jpeg_set_defaults(&info);
  jpeg_set_quality(&info, quality, TRUE);
  jpeg_start_compress(&info, TRUE);
  const auto* pixels = static_cast<const uint8_t*>(image.pixels);
  while (info.next_scanline < info.image_height) {
    JSAMPROW row =
        const_cast<JSAMPROW>(pixels + static_cast<size_t>(info.next_scanline) * image.Stride());
    jpeg_write_scanlines(&info, &row, 1);
  }
  jpeg_finish_compress(&info);
  jpeg_destroy_compress(&info);
  return true;
}

bool JpegDecode(std::string_view bytes, DecodedImage* out, JpegError* error) {
  jpeg_decompress_struct info{};
  info.err = jpeg_std_error(&error->manager);
  error->manager.error_exit = JpegExit;
  error->manager.emit_message = JpegSilent;
  if (setjmp(error->jump) != 0) {
    jpeg_destroy_decompress(&info);
    return false;
  }
  jpeg_create_decompress(&info);
  jpeg_mem_src(&info, reinterpret_cast<const unsigned char*>(bytes.data()),
               static_cast<unsigned long>(bytes.size()));
  jpeg_read_header(&info, TRUE);
  const bool grey = info.jpeg_color_space == JCS_GRAYSCALE;
  info.out_color_space = grey ? JCS_GRAYSCALE : JCS_RGB;  // CMYK and YCCK: libjpeg refuses
  jpeg_start_decompress(&info);
  out->width = static_cast<int>(info.output_width);
  out->height = static_cast<int>(info.output_height);
  out->channels = info.output_components;
  out->bits = 8;
  out->bytes.resize(out->RowBytes() * static_cast<size_t>(out->height));
  while (info.output_scanline < info.output_height) {
    JSAMPROW row = out->bytes.data() + static_cast<size_t>(info.output_scanline) * out->RowBytes();
    jpeg_read_scanlines(&info, &row, 1);
  }
  jpeg_finish_decompress(&info);
  jpeg_destroy_decompress(&info);
  return true;
}

// ---- OpenEXR ------------------------------------------------------------------------------------

class ExrMemoryOut : public Imf::OStream {
 public:
  ExrMemoryOut() : Imf::OStream("memory") {}
  void write(const char c[], int n) override {
    if (at_ + n > bytes_.size()) bytes_.resize(at_ + n);
    std::memcpy(bytes_.data() + at_, c, static_cast<size_t>(n));
    at_ += static_cast<size_t>(n);
  }
  uint64_t tellp() override { return at_; }
  void seekp(uint64_t pos) override { at_ = static_cast<size_t>(pos); }
  std::string Take() { return std::move(bytes_); }

 private:
  std::string bytes_;
  size_t at_ = 0;
};

class ExrMemoryIn : public Imf::IStream {
 public:
  explicit ExrMemoryIn(std::string_view bytes) : Imf::IStream("memory"), bytes_(bytes) {}
  bool read(char c[], int n) override {
    if (static_cast<size_t>(n) > bytes_.size() - std::min(at_, bytes_.size()))
      throw Iex::InputExc("the file ends early");
    std::memcpy(c, bytes_.data() + at_, static_cast<size_t>(n));
    at_ += static_cast<size_t>(n);
    return at_ < bytes_.size();
  }
  uint64_t tellg() override { return at_; }
  void seekg(uint64_t pos) override { at_ = static_cast<size_t>(pos); }

 private:
  std::string_view bytes_;
  size_t at_ = 0;
};

std::string ExrEncode(const ImageView& image) {
  // Uncompressed: a rendered float image's low mantissa bits are noise, and ZIP (OpenEXR's
  // default) saved 3-5 % of a 640 x 480 radiance image's bytes at 10-20 times the time of writing
  // it (about 110 ms against 7; docs/benchmarks.md).
  Imf::Header header(image.width, image.height);  // increasing y
  header.compression() = Imf::NO_COMPRESSION;
  const char* names[3] = {"R", "G", "B"};
  if (image.bgr) std::swap(names[0], names[2]);
  if (image.channels == 1) names[0] = "Y";
  for (int c = 0; c < image.channels; ++c)
    header.channels().insert(names[c], Imf::Channel(Imf::FLOAT));
  Imf::FrameBuffer frame;
  char* base = static_cast<char*>(const_cast<void*>(image.pixels));
  for (int c = 0; c < image.channels; ++c) {
    frame.insert(names[c], Imf::Slice(Imf::FLOAT, base + c * sizeof(float),
                                      image.channels * sizeof(float), image.Stride()));
  }
  ExrMemoryOut stream;
  {
    Imf::OutputFile file(stream, header);
    file.setFrameBuffer(frame);
    file.writePixels(image.height);
  }
  return stream.Take();
}

DecodedImage ExrDecode(std::string_view bytes) {
  ExrMemoryIn stream(bytes);
  Imf::InputFile file(stream);
  const Imath::Box2i window = file.header().dataWindow();
  DecodedImage out;
  out.width = window.max.x - window.min.x + 1;
  out.height = window.max.y - window.min.y + 1;
  const Imf::ChannelList& channels = file.header().channels();
  const bool colour = channels.findChannel("R") != nullptr ||
                      channels.findChannel("G") != nullptr || channels.findChannel("B") != nullptr;
  if (!colour && channels.findChannel("Y") == nullptr)
    throw Iex::InputExc("no R, G, B or Y channel");
  out.channels = colour ? 3 : 1;
  out.bits = 32;
  out.bytes.assign(out.RowBytes() * static_cast<size_t>(out.height), 0);
  // The slices' base points at pixel (0, 0) of the data window's coordinates.
  const ptrdiff_t pixel = out.channels * static_cast<ptrdiff_t>(sizeof(float));
  const ptrdiff_t row = static_cast<ptrdiff_t>(out.RowBytes());
  char* origin =
      reinterpret_cast<char*>(out.bytes.data()) - window.min.x * pixel - window.min.y * row;
  Imf::FrameBuffer frame;
  static const char* const kColour[] = {"R", "G", "B"};
  for (int c = 0; c < out.channels; ++c) {
    frame.insert(colour ? kColour[c] : "Y",
                 Imf::Slice(Imf::FLOAT, origin + c * sizeof(float), pixel, row, 1, 1, 0.0));
  }
  file.setFrameBuffer(frame);
  file.readPixels(window.min.y, window.max.y);
  return out;
}

// ---- Radiance HDR (RGBE) ------------------------------------------------------------------------
// Greg Ward's format: text header lines up to an empty one, the resolution line "-Y h +X w",
// then per row either flat 4-byte RGBE pixels or the newer run-length scanlines (2, 2, width high,
// width low, then each of the four components run-length encoded in turn).

DecodedImage HdrDecode(std::string_view bytes) {
  size_t at = 0;
  const auto line = [&]() {
    const size_t end = bytes.find('\n', at);
    if (end == std::string_view::npos) throw Error("header never ends");
    std::string_view text = bytes.substr(at, end - at);
    at = end + 1;
    return text;
  };
  std::string_view text = line();
  while (!(text = line()).empty()) {
    if (text.substr(0, 7) == "FORMAT=" && text != "FORMAT=32-bit_rle_rgbe")
      throw Error("only the RGBE format is read, not " + std::string(text.substr(7)));
  }
  const std::string resolution(line());
  int width = 0, height = 0;
  char y_axis[3] = "", x_axis[3] = "";
  if (std::sscanf(resolution.c_str(), "%2s %d %2s %d", y_axis, &height, x_axis, &width) != 4 ||
      std::string(y_axis) != "-Y" || std::string(x_axis) != "+X" || width <= 0 || height <= 0 ||
      width > (1 << 16) || height > (1 << 16))
    throw Error(std::string("only the standard orientation \"-Y height +X width\" ") +
                "is read, not \"" + resolution + "\"");
  DecodedImage out;
  out.width = width;
  out.height = height;
  out.channels = 3;
  out.bits = 32;
  out.bytes.resize(out.RowBytes() * static_cast<size_t>(height));
  std::vector<uint8_t> rgbe(4 * static_cast<size_t>(width));
  const auto byte = [&]() -> uint8_t {
    if (at >= bytes.size()) throw Error("the file ends early");
    return static_cast<uint8_t>(bytes[at++]);
  };
  for (int y = 0; y < height; ++y) {
    const bool rle = width >= 8 && width < 32768 && at + 4 <= bytes.size() && bytes[at] == 2 &&
                     bytes[at + 1] == 2 && (static_cast<uint8_t>(bytes[at + 2]) & 0x80) == 0;
    if (rle) {
      at += 2;
      const int stated = (byte() << 8) | byte();
      if (stated != width)
        throw Error("row " + std::to_string(y) + " states width " + std::to_string(stated) +
                    ", not " + std::to_string(width));
      for (int c = 0; c < 4; ++c) {
        for (int x = 0; x < width;) {
          int count = byte();
          const bool run = count > 128;
          if (run) count -= 128;
          if (count == 0 || x + count > width)
            throw Error("row " + std::to_string(y) + " is damaged");
          if (run) {
            const uint8_t value = byte();
            for (int i = 0; i < count; ++i) rgbe[4 * static_cast<size_t>(x++) + c] = value;
          } else {
            for (int i = 0; i < count; ++i) rgbe[4 * static_cast<size_t>(x++) + c] = byte();
          }
        }
      }
    } else {
      for (auto& value : rgbe) value = byte();
    }
    float* row = reinterpret_cast<float*>(out.bytes.data() + out.RowBytes() * y);
    for (int x = 0; x < width; ++x) {
      const uint8_t* p = &rgbe[4 * static_cast<size_t>(x)];
      const float scale = p[3] == 0 ? 0.0f : std::ldexp(1.0f, p[3] - (128 + 8));
      for (int c = 0; c < 3; ++c) row[3 * x + c] = p[c] * scale;
    }
  }
  return out;
}

}  // namespace

ImageFormat SniffImageFormat(std::string_view bytes) {
  if (bytes.substr(0, 8) == std::string_view(kPngSignature, 8)) return ImageFormat::kPng;
  if (bytes.size() >= 3 && static_cast<uint8_t>(bytes[0]) == 0xff &&
      static_cast<uint8_t>(bytes[1]) == 0xd8 && static_cast<uint8_t>(bytes[2]) == 0xff)
    return ImageFormat::kJpeg;
  if (bytes.substr(0, 4) == std::string_view("\x76\x2f\x31\x01", 4)) return ImageFormat::kExr;
  if (bytes.substr(0, 10) == "#?RADIANCE" || bytes.substr(0, 6) == "#?RGBE")
    return ImageFormat::kRadianceHdr;
  return ImageFormat::kUnknown;
}

std::string EncodePng(const ImageView& image) {
  CheckView(image, "PNG");
  if (image.channels < 1 || image.channels > 4 || (image.bits != 8 && image.bits != 16))
    throw Error("PNG: an image must be 1 to 4 channels of 8 or 16 bits, " + Shape(image) +
                " given");
  std::string out;
  out.reserve(image.RowBytes() * static_cast<size_t>(image.height) / 4 + 256);
  PngMessage message;
  if (!PngEncode(image, &out, &message))
    throw Error(std::string("PNG encoding failed: ") + message.text);
  return out;
}

std::string EncodeJpeg(const ImageView& image, int quality) {
  CheckView(image, "JPEG");
  if ((image.channels != 1 && image.channels != 3) || image.bits != 8)
    throw Error("JPEG: an image must be 1 or 3 channels of 8 bits, " + Shape(image) + " given");
  if (quality < 1 || quality > 100)
    throw Error("JPEG: quality must be 1 to 100, not " + std::to_string(quality));
  unsigned char* buffer = nullptr;
  unsigned long size = 0;
  JpegError error;
  const bool done = JpegEncode(image, quality, &buffer, &size, &error);
  std::string out = done ? std::string(reinterpret_cast<const char*>(buffer), size) : "";
  std::free(buffer);
  if (!done) throw Error(std::string("JPEG encoding failed: ") + error.text);
  return out;
}

std::string EncodeExr(const ImageView& image) {
  CheckView(image, "EXR");
  if ((image.channels != 1 && image.channels != 3) || image.bits != 32)
    throw Error("EXR: an image must be 1 or 3 float channels, " + Shape(image) + " given");
  try {
    return ExrEncode(image);
  } catch (const std::exception& e) {
    throw Error(std::string("EXR encoding failed: ") + e.what());
  }
}

DecodedImage DecodeImageBytes(std::string_view bytes, const std::string& origin) {
  DecodedImage out;
  switch (SniffImageFormat(bytes)) {
    case ImageFormat::kPng: {
      PngMessage message;
      if (!PngDecode(bytes, &out, &message))
        throw Error(origin + ": not a readable PNG (" + message.text + ")");
      return out;
    }
    case ImageFormat::kJpeg: {
      JpegError error;
      if (!JpegDecode(bytes, &out, &error))
        throw Error(origin + ": not a readable JPEG (" + error.text + ")");
      return out;
    }
    case ImageFormat::kExr:
      try {
        return ExrDecode(bytes);
      } catch (const std::exception& e) {
        throw Error(origin + ": not a readable OpenEXR image (" + e.what() + ")");
      }
    case ImageFormat::kRadianceHdr:
      try {
        return HdrDecode(bytes);
      } catch (const Error& e) {
        throw Error(origin + ": not a readable Radiance HDR image (" + e.what() + ")");
      }
    case ImageFormat::kUnknown:
      break;
  }
  throw Error(origin + ": not an image cadsynth reads (PNG, JPEG, OpenEXR or Radiance HDR)");
}

DecodedImage ReadImageBytesFile(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw Error(path.string() + ": no such file");
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (!in.good() && !in.eof()) throw Error(path.string() + ": cannot be read");
  return DecodeImageBytes(bytes, path.string());
}

}  // namespace cadsynth
