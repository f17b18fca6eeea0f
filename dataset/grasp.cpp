#include "dataset/grasp.h"

#include <bit>
#include <cstdio>
#include <cstring>

#include "cad/core/error.h"

#include "dataset/bop.h"
#include "dataset/output_formats.h"

namespace cadsynth {

std::vector<Eigen::Vector3f> BackProjectInstance(const Frame& frame, int instance,
                                                 double depth_scale) {
  const Intrinsics& k = frame.camera.intrinsics;
  const int w = frame.width(), h = frame.height();
  const uint16_t id = static_cast<uint16_t>(instance + 1);
  std::vector<Eigen::Vector3f> points;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const size_t p = static_cast<size_t>(v) * w + u;
      if (frame.instance[p] != id) continue;
      const uint16_t units = EncodeDepth(frame.depth[p], depth_scale);
      if (units == 0) continue;
      const double z = units * depth_scale / 1000.0;  // as a reader of the depth PNG gets it, in m
      if (k.distortion.active()) {
        Eigen::Vector2d ray;
        if (!k.Unproject(u + 0.5, v + 0.5, &ray)) continue;
        points.emplace_back(static_cast<float>(ray.x() * z), static_cast<float>(ray.y() * z),
                            static_cast<float>(z));
        continue;
      }
      points.emplace_back(static_cast<float>((u + 0.5 - k.cx) * z / k.fx),
                          static_cast<float>((v + 0.5 - k.cy) * z / k.fy), static_cast<float>(z));
    }
  }
  return points;
}

std::string EncodeNpy(const float* values, size_t rows, size_t cols) {
  static_assert(std::endian::native == std::endian::little,
                "the .npy writer copies floats as they are in memory");
  std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': (" +
                       std::to_string(rows) + ", " + std::to_string(cols) + "), }";
  // Magic (6) + version (2) + header length (2) + header, padded with spaces to a multiple of 64
  // bytes and ended by a newline.
  const size_t unpadded = 10 + header.size() + 1;
  header.append((64 - unpadded % 64) % 64, ' ');
  header += '\n';
  std::string out("\x93NUMPY\x01\x00", 8);
  out += static_cast<char>(header.size() & 0xff);
  out += static_cast<char>(header.size() >> 8);
  out += header;
  const size_t start = out.size();
  out.resize(start + rows * cols * sizeof(float));
  if (rows * cols > 0) std::memcpy(&out[start], values, rows * cols * sizeof(float));
  return out;
}

std::vector<float> DecodeNpy(const std::string& bytes, const std::string& origin, size_t* rows,
                             size_t* cols) {
  const auto fail = [&](const std::string& what) -> std::vector<float> {
    throw Error(origin + ": " + what);
  };
  if (bytes.size() < 10 || bytes.compare(0, 6, "\x93NUMPY") != 0 || bytes[6] != 1)
    return fail("not a version 1 .npy file");
  const size_t length =
      static_cast<uint8_t>(bytes[8]) | static_cast<size_t>(static_cast<uint8_t>(bytes[9])) << 8;
  if (bytes.size() < 10 + length) return fail("its header is cut short");
  const std::string header = bytes.substr(10, length);
  if (header.find("'descr': '<f4'") == std::string::npos ||
      header.find("'fortran_order': False") == std::string::npos)
    return fail("not a C-order float32 array");
  const size_t open = header.find("'shape': (");
  if (open == std::string::npos ||
      std::sscanf(header.c_str() + open + 10, "%zu, %zu)", rows, cols) != 2)
    return fail("not a 2-D array");
  if (*cols != 0 && *rows > (bytes.size() - 10 - length) / sizeof(float) / *cols)
    return fail("its data is cut short");
  std::vector<float> values(*rows * *cols);
  if (bytes.size() - 10 - length != values.size() * sizeof(float))
    return fail("its data does not match its shape");
  if (!values.empty())
    std::memcpy(values.data(), bytes.data() + 10 + length, bytes.size() - 10 - length);
  return values;
}

std::string EncodeNpy(const std::vector<Eigen::Vector3f>& points) {
  std::vector<float> values;
  values.reserve(points.size() * 3);
  for (const Eigen::Vector3f& p : points) values.insert(values.end(), {p.x(), p.y(), p.z()});
  return EncodeNpy(values.data(), points.size(), 3);
}

namespace {

// The `grasp` format: ROOT/grasp/SCENEID/IMID_INST.npy per visible instance.
class GraspPointsWriter : public FrameWriter {
 public:
  explicit GraspPointsWriter(const FormatScene& scene)
      : root_(scene.root),
        dir_(scene.root / "grasp" / Id6(scene.scene_id)),
        depth_scale_(scene.options.depth_scale) {
    CreateFolder(dir_);
  }

  void WriteFrame(int image_id, const Frame& frame, const BopFrameFiles&,
                  FileLog* files_or_null) const override {
    FileLog own(root_);
    FileLog& files = files_or_null != nullptr ? *files_or_null : own;
    const std::string im = Id6(image_id);
    for (size_t i = 0; i < frame.instances.size(); ++i) {
      if (frame.instances[i].px_count_visib == 0) continue;
      const auto points = BackProjectInstance(frame, static_cast<int>(i), depth_scale_);
      files.Write(dir_ / (im + "_" + Id6(static_cast<int>(i)) + ".npy"), EncodeNpy(points));
    }
  }

 private:
  std::filesystem::path root_, dir_;
  double depth_scale_;
};

}  // namespace

std::unique_ptr<FrameWriter> MakeGraspPointsWriter(const FormatScene& scene) {
  return std::make_unique<GraspPointsWriter>(scene);
}

}  // namespace cadsynth
