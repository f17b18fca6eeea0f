// The module's functions beside its classes (images as the writer encodes and reads them, the
// evaluation, the default part cache), and the arguments Recipe and Run both take.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cstring>
#include <string>
#include <vector>

#include "cad/core/error.h"
#include "cad/part_cache.h"
#include "dataset/bop.h"
#include "tools/pipeline/eval.h"
#include "tools/python/bindings.h"

using namespace pybind11::literals;

namespace cadsynth::python {

std::optional<std::filesystem::path> CacheFolder(const py::object& cache) {
  if (cache.is_none()) return std::nullopt;
  if (py::isinstance<py::bool_>(cache)) {
    if (!cache.cast<bool>()) return std::nullopt;
    return PartCache::DefaultDirectory();
  }
  return cache.cast<std::filesystem::path>();
}

std::optional<ShardSpec> ShardOf(const py::object& shard) {
  if (shard.is_none()) return std::nullopt;
  if (py::isinstance<py::str>(shard)) return ParseShard(shard.cast<std::string>());
  const auto pair = shard.cast<std::pair<int, int>>();
  return ParseShard(std::to_string(pair.first) + "/" + std::to_string(pair.second));
}

GenerateOptions WriteOptions(const std::filesystem::path& output, bool overwrite,
                             const py::object& shard) {
  GenerateOptions options;
  options.output = output;
  options.overwrite = overwrite;
  options.shard = ShardOf(shard);
  return options;
}

py::dict SummaryDict(const GenerateSummary& s) {
  return py::dict("frames"_a = s.frames, "resumed"_a = s.resumed,
                  "skipped_empty"_a = s.skipped_empty, "skipped_sparse"_a = s.skipped_sparse,
                  "scenes"_a = s.scenes, "objects"_a = s.objects, "instances"_a = s.instances,
                  "seconds"_a = s.seconds);
}

void BindHelpers(py::module_& m) {
  m.def(
      "encode_png",
      [](const py::array& image) {
        const py::buffer_info info = image.request();
        if (info.ndim != 2 && !(info.ndim == 3 && (info.shape[2] == 1 || info.shape[2] == 3)))
          throw Error("encode_png: an image is H x W or H x W x 3");
        const bool deep = info.itemsize == 2;
        if (!(info.itemsize == 1 || deep) || !(py::isinstance<py::array_t<uint8_t>>(image) ||
                                               py::isinstance<py::array_t<uint16_t>>(image)))
          throw Error("encode_png: pixels are uint8 or uint16");
        const py::array contiguous =
            py::array::ensure(image, py::array::c_style | py::array::forcecast);
        const py::buffer_info c = contiguous.request();
        const int channels = info.ndim == 3 ? static_cast<int>(info.shape[2]) : 1;
        const std::string png =
            EncodeImagePng(c.ptr, static_cast<int>(info.shape[1]), static_cast<int>(info.shape[0]),
                           channels, deep ? 16 : 8);
        return py::bytes(png);
      },
      "image"_a, "PNG bytes of an H x W (x 3, RGB) uint8 or uint16 image, as the writer encodes.");
  m.def(
      "encode_depth",
      [](const py::array_t<float, py::array::c_style | py::array::forcecast>& depth,
         double depth_scale) {
        const auto in = depth.unchecked();
        std::vector<py::ssize_t> shape(depth.shape(), depth.shape() + depth.ndim());
        py::array_t<uint16_t> out(shape);
        const float* src = depth.data();
        uint16_t* dst = out.mutable_data();
        for (py::ssize_t i = 0; i < in.size(); ++i) dst[i] = EncodeDepth(src[i], depth_scale);
        return out;
      },
      "depth_mm"_a, "depth_scale"_a = 1.0,
      "Depth in mm as BOP's uint16 image holds it (value * depth_scale = mm; 0: none).");
  const auto to_array = [](DecodedImage image) -> py::array {
    std::vector<py::ssize_t> shape = {image.height, image.width};
    if (image.channels == 3) shape.push_back(3);
    if (image.bits == 8) return Own(std::move(image.bytes), shape);
    if (image.bits == 32) {
      std::vector<float> values(image.bytes.size() / 4);
      std::memcpy(values.data(), image.bytes.data(), image.bytes.size());
      return Own(std::move(values), shape);
    }
    std::vector<uint16_t> values(image.bytes.size() / 2);
    std::memcpy(values.data(), image.bytes.data(), image.bytes.size());
    return Own(std::move(values), shape);
  };
  m.def(
      "read_image",
      [to_array](const std::filesystem::path& path) { return to_array(ReadImageFile(path)); },
      "path"_a,
      "Reads a PNG, JPEG or EXR image (RGB order for colour; uint8, uint16, or float32 for "
      "EXR such as rgb_hdr/).");
  m.def(
      "decode_image",
      [to_array](const py::bytes& data) {
        const std::string_view bytes = data;
        DecodedImage image;
        {
          py::gil_scoped_release release;
          image = DecodeImage(bytes, "decode_image");
        }
        return to_array(std::move(image));
      },
      "data"_a,
      "Decodes a PNG, JPEG or EXR file's bytes, as read_image (a webdataset member, for "
      "example).");
  m.def(
      "evaluate",
      [](const std::filesystem::path& dataset, const std::filesystem::path& results,
         const std::string& sensor) {
        EvalReport report;
        {
          py::gil_scoped_release release;
          report = Evaluate(dataset, results, sensor);
        }
        const py::object json = py::module_::import("json").attr("loads")(EvalJson(report));
        return py::make_tuple(EvalTable(report), json);
      },
      "dataset"_a, "results"_a, "sensor"_a = "",
      "Scores a BOP results CSV against a dataset, as `cadsynth eval`: (the table it prints, its "
      "--json report as a dict).");
  m.def(
      "default_cache", [] { return PartCache::DefaultDirectory(); },
      "The part cache folder the command line uses by default.");
}

}  // namespace cadsynth::python
