#include "dataset/verify.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>
#include <tbb/parallel_for.h>
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "cad/core/error.h"
#include "dataset/bop_read.h"
#include "dataset/coco.h"
#include "dataset/file_io.h"
#include "dataset/image_mat.h"
#include "dataset/manifest.h"

namespace cadsynth {

namespace fs = std::filesystem;

namespace {

enum CheckId { kManifest, kGtInfo, kCoco, kModels, kRecast, kChecks };
constexpr std::array<const char*, kChecks> kCheckNames = {"manifest", "gt_info", "coco",
                                                          "models_info", "recast"};
constexpr std::array<const char*, kChecks> kCheckUnits = {"files", "instances", "annotations",
                                                          "models", "pixels"};

// What one task (an image, a model, the manifest) found; merged in task order, so the report
// does not depend on the thread count.
struct Findings {
  std::array<size_t, kChecks> checked{}, failed{};
  std::vector<VerifyReport::Problem> problems;
  std::vector<std::string> notes;
  void Fail(CheckId check, const std::string& file, const std::string& reason) {
    ++failed[check];
    problems.push_back({file, reason});
  }
  void Merge(Findings&& other) {
    for (int c = 0; c < kChecks; ++c) {
      checked[c] += other.checked[c];
      failed[c] += other.failed[c];
    }
    for (auto& p : other.problems) problems.push_back(std::move(p));
    for (auto& n : other.notes) notes.push_back(std::move(n));
  }
};

std::string BoxText(const std::array<int, 4>& b) {
  std::ostringstream s;
  s << "[" << b[0] << ", " << b[1] << ", " << b[2] << ", " << b[3] << "]";
  return s.str();
}

// ---- The manifest ----

Findings CheckManifest(const fs::path& root, std::string* run_key) {
  Findings f;
  DatasetManifest manifest;
  try {
    manifest = ReadManifest(root);
  } catch (const Error& e) {
    f.Fail(kManifest, kManifestFile, e.what());
    return f;
  }
  *run_key = manifest.run_key;
  std::vector<std::string> reasons(manifest.files.size());
  tbb::parallel_for(size_t{0}, manifest.files.size(),
                    [&](size_t i) { reasons[i] = CheckFile(root, manifest.files[i]); });
  f.checked[kManifest] = manifest.files.size();
  for (size_t i = 0; i < reasons.size(); ++i) {
    if (!reasons[i].empty()) f.Fail(kManifest, manifest.files[i].path, reasons[i]);
  }
  // Files the manifest does not list: noted (a user may add files beside a dataset).
  std::vector<std::string> listed;
  for (const FileRecord& r : manifest.files) listed.push_back(r.path);
  std::sort(listed.begin(), listed.end());
  std::vector<std::string> extra;
  std::error_code ec;
  for (fs::recursive_directory_iterator it(root, ec), end; !ec && it != end; it.increment(ec)) {
    const fs::path relative = it->path().lexically_relative(root);
    if (it->is_directory(ec)) {
      if (relative.filename().string().starts_with(".")) it.disable_recursion_pending();
      continue;
    }
    if (IsDatasetContent(relative) &&
        !std::binary_search(listed.begin(), listed.end(), relative.generic_string()))
      extra.push_back(relative.generic_string());
  }
  if (!extra.empty()) {
    std::sort(extra.begin(), extra.end());
    f.notes.push_back(std::to_string(extra.size()) + " file(s) not in the manifest, e.g. " +
                      extra.front());
  }
  return f;
}

// ---- Models ----

using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, std::vector<Triangle>::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

struct Model {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Triangle> triangles;
  std::unique_ptr<Tree> tree;
  Eigen::AlignedBox3d box;
};

// A PLY mesh as cadsynth writes it (binary little-endian; vertex x, y, z first among float or
// double properties; faces as lists), read here without the writer's code. Throws Error (the
// reason) on anything else.
Model ReadPly(const fs::path& path) {
  const std::string bytes = ReadFileText(path);
  const size_t header_end = bytes.find("end_header\n");
  if (bytes.rfind("ply\n", 0) != 0 || header_end == std::string::npos)
    throw Error("not a PLY file");
  std::istringstream header(bytes.substr(0, header_end));
  std::string line, element;
  size_t vertices = 0, faces = 0, vertex_stride = 0;
  std::vector<std::pair<std::string, size_t>> vertex_offsets;  // name, offset
  std::string list_count, list_index;
  bool binary_le = false;
  while (std::getline(header, line)) {
    std::istringstream in(line);
    std::string word;
    in >> word;
    if (word == "format") {
      std::string format;
      in >> format;
      binary_le = format == "binary_little_endian";
    } else if (word == "element") {
      size_t n = 0;
      in >> element >> n;
      if (element == "vertex") vertices = n;
      if (element == "face") faces = n;
    } else if (word == "property") {
      std::string type;
      in >> type;
      if (element == "vertex") {
        std::string name;
        in >> name;
        const size_t size = type == "float" ? 4 : type == "double" ? 8 : type == "uchar" ? 1 : 0;
        if (size == 0) throw Error("vertex property type " + type + " is not read");
        vertex_offsets.push_back({type + " " + name, vertex_stride});
        vertex_stride += size;
      } else if (element == "face" && type == "list") {
        in >> list_count >> list_index;
      }
    }
  }
  if (!binary_le) throw Error("only binary_little_endian PLY is read");
  if (list_count != "uchar" || (list_index != "int" && list_index != "uint"))
    throw Error("faces must be lists of uchar count and int indices");
  std::array<int, 3> xyz{-1, -1, -1};
  bool doubles = false;
  for (size_t k = 0; k < vertex_offsets.size(); ++k) {
    const std::string& name = vertex_offsets[k].first;
    for (int a = 0; a < 3; ++a) {
      const std::string axis(1, static_cast<char>('x' + a));
      if (name == "float " + axis || name == "double " + axis) {
        xyz[a] = static_cast<int>(vertex_offsets[k].second);
        doubles = name[0] == 'd';
      }
    }
  }
  if (xyz[0] < 0 || xyz[1] < 0 || xyz[2] < 0) throw Error("vertices lack x, y or z");
  size_t at = header_end + std::strlen("end_header\n");
  if (bytes.size() < at + vertices * vertex_stride) throw Error("truncated vertex data");
  Model m;
  m.vertices.resize(vertices);
  for (size_t v = 0; v < vertices; ++v) {
    const char* p = bytes.data() + at + v * vertex_stride;
    for (int a = 0; a < 3; ++a) {
      if (doubles) {
        double x;
        std::memcpy(&x, p + xyz[a], 8);
        m.vertices[v][a] = x;
      } else {
        float x;
        std::memcpy(&x, p + xyz[a], 4);
        m.vertices[v][a] = x;
      }
    }
    m.box.extend(m.vertices[v]);
  }
  at += vertices * vertex_stride;
  for (size_t f = 0; f < faces; ++f) {
    if (at >= bytes.size()) throw Error("truncated face data");
    const int n = static_cast<unsigned char>(bytes[at++]);
    if (at + 4 * static_cast<size_t>(n) > bytes.size()) throw Error("truncated face data");
    std::vector<uint32_t> index(n);
    if (n > 0) std::memcpy(index.data(), bytes.data() + at, 4 * static_cast<size_t>(n));
    at += 4 * static_cast<size_t>(n);
    for (uint32_t i : index) {
      if (i >= vertices) throw Error("face " + std::to_string(f) + " has a bad vertex index");
    }
    const auto point = [&](uint32_t i) {
      return Point(m.vertices[i].x(), m.vertices[i].y(), m.vertices[i].z());
    };
    for (int k = 1; k + 1 < n; ++k) {  // a fan
      const Triangle t(point(index[0]), point(index[k]), point(index[k + 1]));
      if (!t.is_degenerate()) m.triangles.push_back(t);
    }
  }
  m.tree = std::make_unique<Tree>(m.triangles.begin(), m.triangles.end());
  m.tree->build();
  return m;
}

// The largest distance between two vertices (bop_toolkit's misc.calc_pts_diameter), over the
// vertices of their convex hull.
double VertexDiameter(const std::vector<Eigen::Vector3d>& vertices) {
  std::vector<Point> points;
  for (const Eigen::Vector3d& v : vertices) points.emplace_back(v.x(), v.y(), v.z());
  std::vector<Point> hull;
  if (points.size() >= 4) {
    CGAL::Surface_mesh<Point> mesh;
    CGAL::convex_hull_3(points.begin(), points.end(), mesh);
    for (const auto v : mesh.vertices()) hull.push_back(mesh.point(v));
  }
  if (hull.size() < 2) hull = points;
  double best = 0;
  for (size_t i = 0; i < hull.size(); ++i) {
    for (size_t j = i + 1; j < hull.size(); ++j)
      best = std::max(best, CGAL::squared_distance(hull[i], hull[j]));
  }
  return std::sqrt(best);
}

struct Models {
  std::map<int, Model> by_id;  // models that could be read
};

Findings CheckModels(const fs::path& root, Models* models) {
  Findings f;
  const fs::path info_path = root / "models" / "models_info.json";
  const std::string origin = "models/models_info.json";
  nlohmann::json info;
  try {
    const std::string text = ReadFileText(info_path);
    try {
      info = nlohmann::json::parse(text);
    } catch (const nlohmann::json::exception& e) {
      f.Fail(kModels, origin, JsonErrorMessage(origin, text, e));
      return f;
    }
  } catch (const Error& e) {
    f.Fail(kModels, origin, "cannot be read");
    return f;
  }
  std::vector<std::pair<int, nlohmann::json>> entries;
  for (const auto& [key, value] : info.items()) {
    const std::optional<int> id = ParseBopId(key);
    if (!id || !value.is_object()) {
      f.Fail(kModels, origin, "entry \"" + key + "\" is not an obj_id with an object");
      continue;
    }
    entries.push_back({*id, value});
  }
  std::vector<std::optional<Model>> read(entries.size());
  std::vector<Findings> found(entries.size());
  tbb::parallel_for(size_t{0}, entries.size(), [&](size_t i) {
    // Not a structured binding: clang 14 cannot capture one in the lambda below.
    const int id = entries[i].first;
    const nlohmann::json& value = entries[i].second;
    Findings& g = found[i];
    const std::string file = "models/obj_" + Id6(id) + ".ply";
    ++g.checked[kModels];
    try {
      Model m = ReadPly(root / file);
      const double diameter = VertexDiameter(m.vertices);
      const Eigen::Vector3d min = m.box.min(), size = m.box.sizes();
      std::vector<std::string> wrong;
      const auto expect = [&](const char* key, double actual) {
        // The PLY holds floats: its values are the written ones to float precision.
        const double tolerance = 1e-3 + 1e-5 * std::abs(actual);
        if (!value.contains(key) || !value[key].is_number()) {
          wrong.push_back(std::string(key) + " is missing");
        } else if (std::abs(value[key].get<double>() - actual) > tolerance) {
          std::ostringstream s;
          s << key << " is " << value[key].get<double>() << ", the model's vertices give "
            << actual;
          wrong.push_back(s.str());
        }
      };
      expect("diameter", diameter);
      const char* axes[3] = {"x", "y", "z"};
      for (int a = 0; a < 3; ++a) {
        expect(("min_" + std::string(axes[a])).c_str(), min[a]);
        expect(("size_" + std::string(axes[a])).c_str(), size[a]);
      }
      for (const std::string& w : wrong)
        g.Fail(kModels, origin, "obj " + std::to_string(id) + ": " + w);
      if (wrong.empty()) read[i] = std::move(m);
    } catch (const Error& e) {
      g.Fail(kModels, file, e.what());
    }
  });
  for (size_t i = 0; i < entries.size(); ++i) {
    f.Merge(std::move(found[i]));
    if (read[i]) models->by_id.emplace(entries[i].first, std::move(*read[i]));
  }
  return f;
}

// ---- Scenes ----

using SceneSensor = BopSceneFolder;

// A 1-channel image, or nothing (with the reason) when the file is missing or does not decode.
std::optional<cv::Mat> ReadImage(const fs::path& path, std::string* why) {
  std::error_code ec;
  if (!fs::exists(path, ec)) {
    *why = "missing";
    return std::nullopt;
  }
  const std::string bytes = ReadFileText(path);
  // A PNG ends with its IEND chunk: a truncated one is told without asking libpng (which would
  // print its own complaint).
  static constexpr char kIend[] = {0, 0, 0, 0, 'I', 'E', 'N', 'D', '\xae', 'B', '`', '\x82'};
  if (path.extension() == ".png" &&
      (bytes.size() < sizeof kIend ||
       bytes.compare(bytes.size() - sizeof kIend, sizeof kIend, kIend, sizeof kIend) != 0)) {
    *why = "is truncated (no PNG end chunk)";
    return std::nullopt;
  }
  cv::Mat image;
  try {
    image = image_mat::MatOf(DecodeImageBytes(bytes, path.string()), image_mat::Want::kUnchanged,
                             path.string());
  } catch (const Error&) {
  }
  if (image.empty() || image.channels() != 1) {
    *why = image.empty() ? "does not decode (a damaged or truncated PNG)" : "is not one channel";
    return std::nullopt;
  }
  return image;
}

// One image's instance: its masks as read and what they give.
struct InstanceMasks {
  cv::Mat mask, visib;  // 8-bit, > 0 = on
  size_t all = 0, visible = 0, valid = 0;
  std::array<int, 4> mask_box{-1, -1, -1, -1}, visib_box{-1, -1, -1, -1};  // x0, y0, x1, y1
  std::vector<std::pair<int, int>> samples;  // visible pixels for the re-cast (reservoir)
};

uint64_t Mix(uint64_t x) {  // splitmix64
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

void Extend(std::array<int, 4>& b, int u, int v) {
  if (b[0] < 0) {
    b = {u, v, u, v};
    return;
  }
  b[0] = std::min(b[0], u), b[1] = std::min(b[1], v);
  b[2] = std::max(b[2], u), b[3] = std::max(b[3], v);
}

// bop_toolkit's box: x, y, x_max - x_min, y_max - y_min ([-1, -1, -1, -1]: none).
std::array<int, 4> BopBox(const std::array<int, 4>& b) {
  if (b[0] < 0) return {-1, -1, -1, -1};
  return {b[0], b[1], b[2] - b[0], b[3] - b[1]};
}

std::array<int, 4> JsonBox(const nlohmann::json& j) {
  std::array<int, 4> b{};
  for (int k = 0; k < 4; ++k) b[k] = j.at(k).get<int>();
  return b;
}

struct Camera {
  double fx = 0, fy = 0, cx = 0, cy = 0, depth_scale = 1;
  std::vector<double> dist;  // OpenCV's k1, k2, p1, p2, k3 (empty: none)
  // The camera-frame ray (x, y, 1) of image point (u, v); false where the distortion cannot be
  // inverted (the point then is not judged).
  bool Ray(double u, double v, Eigen::Vector3d* ray) const {
    const double xd = (u - cx) / fx, yd = (v - cy) / fy;
    double x = xd, y = yd;
    if (!dist.empty()) {
      const double k1 = dist[0], k2 = dist[1], p1 = dist[2], p2 = dist[3],
                   k3 = dist.size() > 4 ? dist[4] : 0;
      const auto distort = [&](double a, double b, double* da, double* db) {
        const double r2 = a * a + b * b, radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3));
        *da = a * radial + 2 * p1 * a * b + p2 * (r2 + 2 * a * a);
        *db = b * radial + p1 * (r2 + 2 * b * b) + 2 * p2 * a * b;
      };
      for (int it = 0; it < 50; ++it) {  // fixed point: x = xd - (distort(x) - x)
        double dx, dy;
        distort(x, y, &dx, &dy);
        x += xd - dx;
        y += yd - dy;
      }
      double dx, dy;
      distort(x, y, &dx, &dy);
      if (std::abs(dx - xd) > 1e-9 || std::abs(dy - yd) > 1e-9) return false;
    }
    *ray = {x, y, 1};
    return true;
  }
};

// The nearest hit of the camera ray `ray` (camera frame, from the origin) on `model` at pose
// `pose`: the hit's camera z, or nothing.
std::optional<double> Cast(const Model& model, const Eigen::Isometry3d& pose,
                           const Eigen::Vector3d& ray) {
  const Eigen::Isometry3d inverse = pose.inverse();
  const Eigen::Vector3d o = inverse.translation(), d = inverse.linear() * ray;
  const Kernel::Ray_3 query(Point(o.x(), o.y(), o.z()), Kernel::Vector_3(d.x(), d.y(), d.z()));
  const auto hit = model.tree->first_intersection(query);
  if (!hit) return std::nullopt;
  Point p;
  if (const Point* point = boost::get<Point>(&hit->first)) {
    p = *point;
  } else if (const auto* segment = boost::get<Kernel::Segment_3>(&hit->first)) {
    p = CGAL::squared_distance(query.source(), segment->source()) <
                CGAL::squared_distance(query.source(), segment->target())
            ? segment->source()
            : segment->target();
  } else {
    return std::nullopt;
  }
  return (pose * Eigen::Vector3d(p.x(), p.y(), p.z())).z();
}

struct ImageTask {
  const SceneSensor* scene = nullptr;
  int im_id = 0;
  const nlohmann::json* gt = nullptr;       // scene_gt entry (array)
  const nlohmann::json* gt_info = nullptr;  // scene_gt_info entry (array), may be null
  const nlohmann::json* camera = nullptr;   // scene_camera entry
  std::vector<const nlohmann::json*> coco;  // scene_gt_coco annotations of this image
  bool has_coco = false;
};

// What the re-cast sees at one image point: per instance its hit depth, and the nearest.
struct CastResult {
  std::vector<std::optional<double>> z;
  int nearest = -1;
};

CastResult CastAll(const std::vector<const Model*>& models,
                   const std::vector<Eigen::Isometry3d>& poses, const Camera& camera, double u,
                   double v, bool* ok) {
  CastResult r;
  Eigen::Vector3d ray;
  *ok = camera.Ray(u, v, &ray);
  r.z.resize(models.size());
  if (!*ok) return r;
  for (size_t i = 0; i < models.size(); ++i) {
    if (models[i] == nullptr) continue;
    r.z[i] = Cast(*models[i], poses[i], ray);
    if (r.z[i] && *r.z[i] > 0 && (r.nearest < 0 || *r.z[i] < *r.z[r.nearest]))
      r.nearest = static_cast<int>(i);
  }
  return r;
}

// What ReadImageData reads of one image, for the checks after it.
struct ImageData {
  std::string im;  // the image id as a file name stem (NNNNNN)
  size_t n = 0;    // instances
  Camera camera;
  std::vector<Eigen::Isometry3d> poses;
  std::vector<int> obj_ids;
  std::optional<cv::Mat> depth, exact;  // the written depth; the exact one (depth_gt or depth)
  std::string exact_file;               // the exact depth's path, relative to the root
  std::vector<InstanceMasks> masks;
  std::vector<bool> readable;  // per instance: both masks read
  uint64_t seed = 0;           // of the image's pixel samples
};

// Reads an image's camera, poses, depth and masks, counting and sampling the masks' pixels on
// the way; false (with the problem in *out) when its JSON entries are unreadable.
bool ReadImageData(const ImageTask& task, const VerifyOptions& options, ImageData* d,
                   Findings* out) {
  Findings& f = *out;
  const SceneSensor& scene = *task.scene;
  const std::string& im = d->im = Id6(task.im_id);
  const size_t n = d->n = task.gt->size();
  Camera& camera = d->camera;
  std::vector<Eigen::Isometry3d>& poses = d->poses;
  std::vector<int>& obj_ids = d->obj_ids;
  poses.assign(n, Eigen::Isometry3d::Identity());
  obj_ids.assign(n, 0);
  try {
    const nlohmann::json& c = *task.camera;
    const nlohmann::json& k = c.at("cam_K");
    camera.fx = k.at(0), camera.cx = k.at(2), camera.fy = k.at(4), camera.cy = k.at(5);
    camera.depth_scale = c.at("depth_scale");
    if (c.contains("cam_dist_coeffs"))
      camera.dist = c["cam_dist_coeffs"].get<std::vector<double>>();
    for (size_t i = 0; i < n; ++i) {
      const nlohmann::json& g = (*task.gt)[i];
      obj_ids[i] = g.at("obj_id");
      const std::vector<double> r = g.at("cam_R_m2c"), t = g.at("cam_t_m2c");
      Eigen::Matrix3d rotation;
      for (int a = 0; a < 9; ++a) rotation(a / 3, a % 3) = r.at(a);
      poses[i].linear() = rotation;
      poses[i].translation() = Eigen::Vector3d(t.at(0), t.at(1), t.at(2));
    }
  } catch (const nlohmann::json::exception& e) {
    f.Fail(kGtInfo, scene.Relative("scene_gt" + scene.suffix + ".json"),
           "image " + std::to_string(task.im_id) + ": unreadable entry (" + e.what() + ")");
    return false;
  }
  // Depth: the exact one (depth_gt, beside a sensor's) for the re-cast; the written one for
  // px_count_valid.
  std::string why;
  const std::string depth_rel = scene.Relative("depth" + scene.suffix + "/" + im + ".png");
  const std::string exact_rel = scene.Relative("depth_gt" + scene.suffix + "/" + im + ".png");
  std::error_code ec;
  const fs::path root = scene.dir.parent_path().parent_path();
  std::optional<cv::Mat>& depth = d->depth;
  depth = ReadImage(root / depth_rel, &why);
  if (!depth) f.Fail(kGtInfo, depth_rel, why);
  d->exact = depth;
  d->exact_file = depth_rel;
  if (fs::exists(root / exact_rel, ec)) {
    d->exact = ReadImage(root / exact_rel, &why);
    d->exact_file = exact_rel;
    if (!d->exact) f.Fail(kRecast, exact_rel, why);
  }

  const uint64_t seed = d->seed = Mix(
      Mix(static_cast<uint64_t>(scene.scene_id) * 1000003u + static_cast<uint64_t>(task.im_id)) ^
      Crc32(scene.split + scene.suffix));  // not std::hash: the same samples with any library
  const int per_instance = n == 0 || options.pixels_per_image <= 0
                               ? 0
                               : std::max(1, options.pixels_per_image / 2 / static_cast<int>(n));
  std::vector<InstanceMasks>& masks = d->masks;
  std::vector<bool>& readable = d->readable;
  masks.assign(n, {});
  readable.assign(n, false);
  for (size_t i = 0; i < n; ++i) {
    InstanceMasks& m = masks[i];
    const std::string name = im + "_" + Id6(static_cast<int>(i)) + ".png";
    const std::string mask_rel = scene.Relative("mask" + scene.suffix + "/" + name);
    const std::string visib_rel = scene.Relative("mask_visib" + scene.suffix + "/" + name);
    std::optional<cv::Mat> mask = ReadImage(root / mask_rel, &why);
    if (!mask) f.Fail(kGtInfo, mask_rel, why);
    std::optional<cv::Mat> visib = ReadImage(root / visib_rel, &why);
    if (!visib) f.Fail(kGtInfo, visib_rel, why);
    if (!mask || !visib) continue;
    if (mask->size() != visib->size() || (depth && depth->size() != mask->size())) {
      f.Fail(kGtInfo, mask_rel, "its size differs from mask_visib's or the depth image's");
      continue;
    }
    m.mask = *mask, m.visib = *visib;
    readable[i] = true;
    uint64_t state = Mix(seed + i);
    size_t outside = 0;  // visible pixels outside the mask (reported once)
    for (int v = 0; v < m.mask.rows; ++v) {
      const uint8_t* a = m.mask.ptr<uint8_t>(v);
      const uint8_t* b = m.visib.ptr<uint8_t>(v);
      for (int u = 0; u < m.mask.cols; ++u) {
        if (a[u]) {
          ++m.all;
          Extend(m.mask_box, u, v);
          if (depth) {
            const bool has = depth->depth() == CV_16U ? depth->at<uint16_t>(v, u) != 0
                                                      : depth->at<uint8_t>(v, u) != 0;
            if (has) ++m.valid;
          }
        }
        if (b[u]) {
          ++m.visible;
          Extend(m.visib_box, u, v);
          // Reservoir sampling of the visible pixels.
          if (m.samples.size() < static_cast<size_t>(per_instance)) {
            m.samples.push_back({u, v});
          } else {
            state = Mix(state);
            const size_t slot = state % m.visible;
            if (slot < m.samples.size()) m.samples[slot] = {u, v};
          }
          if (!a[u] && outside++ == 0) {
            f.Fail(kGtInfo, visib_rel,
                   "pixel (" + std::to_string(u) + ", " + std::to_string(v) +
                       ") is visible but not in the instance's mask");
          }
        }
      }
    }
  }
  return true;
}

// scene_gt_info, as bop_toolkit computes it from the masks.
void CheckGtInfo(const ImageTask& task, const ImageData& d, Findings* out) {
  Findings& f = *out;
  const SceneSensor& scene = *task.scene;
  const std::string info_file = scene.Relative("scene_gt_info" + scene.suffix + ".json");
  const size_t n = d.n;
  const std::vector<InstanceMasks>& masks = d.masks;
  const std::vector<bool>& readable = d.readable;
  const std::optional<cv::Mat>& depth = d.depth;
  for (size_t i = 0; i < n; ++i) {
    if (!readable[i]) continue;
    ++f.checked[kGtInfo];
    const InstanceMasks& m = masks[i];
    const std::string where =
        "image " + std::to_string(task.im_id) + " instance " + std::to_string(i) + ": ";
    if (task.gt_info == nullptr || i >= task.gt_info->size()) {
      f.Fail(kGtInfo, info_file, where + "no entry");
      continue;
    }
    try {
      const nlohmann::json& g = (*task.gt_info)[i];
      const size_t all = g.at("px_count_all"), visible = g.at("px_count_visib"),
                   valid = g.at("px_count_valid");
      const double fract = g.at("visib_fract");
      const std::array<int, 4> bbox_obj = JsonBox(g.at("bbox_obj")),
                               bbox_visib = JsonBox(g.at("bbox_visib"));
      std::vector<std::string> wrong;
      if (visible != m.visible)
        wrong.push_back("px_count_visib is " + std::to_string(visible) + ", mask_visib has " +
                        std::to_string(m.visible) + " pixels");
      if (bbox_visib != BopBox(m.visib_box))
        wrong.push_back("bbox_visib is " + BoxText(bbox_visib) + ", mask_visib gives " +
                        BoxText(BopBox(m.visib_box)));
      if (depth && valid != m.valid)
        wrong.push_back("px_count_valid is " + std::to_string(valid) + ", mask and depth give " +
                        std::to_string(m.valid));
      // The full silhouette: in the image, the mask's; a truncated one reaches outside it, and
      // the part in the image (the mask) lies in its box.
      const int w = m.mask.cols, h = m.mask.rows;
      if (m.visible > 0) {
        const bool inside = bbox_obj[0] >= 0 && bbox_obj[1] >= 0 && bbox_obj[0] + bbox_obj[2] < w &&
                            bbox_obj[1] + bbox_obj[3] < h;
        const std::array<int, 4>& b = m.mask_box;
        const bool contained = b[0] >= bbox_obj[0] && b[1] >= bbox_obj[1] &&
                               b[2] <= bbox_obj[0] + bbox_obj[2] &&
                               b[3] <= bbox_obj[1] + bbox_obj[3];
        if (inside ? BopBox(b) != bbox_obj : !contained)
          wrong.push_back("bbox_obj is " + BoxText(bbox_obj) + ", the mask gives " +
                          BoxText(BopBox(b)) + (inside ? "" : ", which it must contain"));
        if (inside ? all != m.all : all < m.all)
          wrong.push_back("px_count_all is " + std::to_string(all) + ", the mask has " +
                          std::to_string(m.all) + " pixels");
      } else if (bbox_obj != std::array<int, 4>{-1, -1, -1, -1}) {
        wrong.push_back("bbox_obj is " + BoxText(bbox_obj) +
                        " for an instance without a visible pixel");
      }
      const double expected = all > 0 ? static_cast<double>(visible) / static_cast<double>(all) : 0;
      if (std::abs(fract - expected) > 1e-9)
        wrong.push_back("visib_fract is " + std::to_string(fract) +
                        ", px_count_visib / px_count_all is " + std::to_string(expected));
      for (const std::string& reason : wrong) f.Fail(kGtInfo, info_file, where + reason);
    } catch (const nlohmann::json::exception& e) {
      f.Fail(kGtInfo, info_file, where + "unreadable entry (" + e.what() + ")");
    }
  }
}

// COCO: each annotation's RLE against mask_visib, and an annotation for each visible instance.
void CheckCoco(const ImageTask& task, const ImageData& d, Findings* out) {
  Findings& f = *out;
  const SceneSensor& scene = *task.scene;
  const size_t n = d.n;
  const std::vector<InstanceMasks>& masks = d.masks;
  const std::vector<bool>& readable = d.readable;
  if (!task.has_coco) return;
  {
    const std::string coco_file = scene.Relative("scene_gt_coco" + scene.suffix + ".json");
    std::vector<bool> annotated(n, false);
    for (const nlohmann::json* a : task.coco) {
      ++f.checked[kCoco];
      const std::string where = "image " + std::to_string(task.im_id) + " annotation " +
                                std::to_string(a->value("id", -1)) + ": ";
      try {
        const int inst = a->at("inst_id");
        if (inst < 0 || static_cast<size_t>(inst) >= n) {
          f.Fail(kCoco, coco_file, where + "inst_id " + std::to_string(inst) + " is no instance");
          continue;
        }
        annotated[inst] = true;
        if (!readable[inst]) continue;
        const InstanceMasks& m = masks[inst];
        const nlohmann::json& seg = a->at("segmentation");
        RleMask rle;
        rle.height = seg.at("size").at(0), rle.width = seg.at("size").at(1);
        rle.counts = DecompressRleCounts(seg.at("counts").get<std::string>());
        const std::vector<uint8_t> decoded = DecodeRle(rle);
        if (rle.width != m.visib.cols || rle.height != m.visib.rows) {
          f.Fail(kCoco, coco_file, where + "its mask's size differs from the image's");
          continue;
        }
        size_t differ = 0;
        std::pair<int, int> first{-1, -1};
        for (int v = 0; v < rle.height; ++v) {
          for (int u = 0; u < rle.width; ++u) {
            if ((decoded[static_cast<size_t>(v) * rle.width + u] != 0) !=
                (m.visib.at<uint8_t>(v, u) != 0)) {
              if (differ++ == 0) first = {u, v};
            }
          }
        }
        std::vector<std::string> wrong;
        if (differ > 0)
          wrong.push_back("its RLE differs from mask_visib in " + std::to_string(differ) +
                          " pixels, first (" + std::to_string(first.first) + ", " +
                          std::to_string(first.second) + ")");
        if (a->at("area").get<size_t>() != m.visible)
          wrong.push_back("area is " + a->at("area").dump() + ", mask_visib has " +
                          std::to_string(m.visible) + " pixels");
        // COCO's box: width max - min + 1, of the full (amodal) or the visible silhouette.
        const std::array<int, 4> box = JsonBox(a->at("bbox"));
        const auto coco_box = [](const std::array<int, 4>& b) {
          return std::array<int, 4>{b[0], b[1], b[2] - b[0] + 1, b[3] - b[1] + 1};
        };
        if (box != coco_box(m.mask_box) && box != coco_box(m.visib_box))
          wrong.push_back("bbox is " + BoxText(box) + ", the masks give " +
                          BoxText(coco_box(m.mask_box)) + " (full) or " +
                          BoxText(coco_box(m.visib_box)) + " (visible)");
        for (const std::string& reason : wrong) f.Fail(kCoco, coco_file, where + reason);
      } catch (const nlohmann::json::exception& e) {
        f.Fail(kCoco, coco_file, where + "unreadable (" + e.what() + ")");
      } catch (const Error& e) {
        f.Fail(kCoco, coco_file, where + e.what());
      }
    }
    for (size_t i = 0; i < n; ++i) {
      if (readable[i] && masks[i].visible > 0 && !annotated[i])
        f.Fail(kCoco, coco_file,
               "image " + std::to_string(task.im_id) + ": instance " + std::to_string(i) +
                   " is visible but has no annotation");
    }
  }
}

// The re-cast: rays through the models at the poses as written, against the masks and the
// exact depth.
void Recast(const ImageTask& task, const ImageData& d, const Models& models,
            const VerifyOptions& options, Findings* out) {
  Findings& f = *out;
  const SceneSensor& scene = *task.scene;
  const size_t n = d.n;
  const std::string& im = d.im;
  const Camera& camera = d.camera;
  const std::vector<Eigen::Isometry3d>& poses = d.poses;
  const std::vector<InstanceMasks>& masks = d.masks;
  const std::vector<bool>& readable = d.readable;
  const std::optional<cv::Mat>& exact = d.exact;
  std::vector<const Model*> instance_models(n, nullptr);
  for (size_t i = 0; i < n; ++i) {
    const auto it = models.by_id.find(d.obj_ids[i]);
    if (it != models.by_id.end()) instance_models[i] = &it->second;
  }
  if (n == 0 || !exact || std::find(readable.begin(), readable.end(), false) != readable.end())
    return;
  std::vector<std::pair<int, int>> pixels;
  for (const InstanceMasks& m : masks)
    pixels.insert(pixels.end(), m.samples.begin(), m.samples.end());
  uint64_t state = Mix(d.seed ^ 0x5bd1e995u);
  const int w = masks[0].mask.cols, h = masks[0].mask.rows;
  for (int k = 0; k < options.pixels_per_image / 2; ++k) {
    state = Mix(state);
    pixels.push_back({static_cast<int>(state % static_cast<uint64_t>(w)),
                      static_cast<int>((state >> 32) % static_cast<uint64_t>(h))});
  }
  const std::string& exact_file = d.exact_file;
  for (const auto& [u, v] : pixels) {
    bool ok = true;
    const CastResult c = CastAll(instance_models, poses, camera, u + 0.5, v + 0.5, &ok);
    if (!ok) continue;
    // A ray that grazes an edge: the answer changes within 0.02 px; not judged.
    bool edge = false;
    double spread = 0;
    for (const auto& [du, dv] : {std::pair{0.02, 0.0}, {-0.02, 0.0}, {0.0, 0.02}, {0.0, -0.02}}) {
      bool near_ok = true;
      const CastResult o =
          CastAll(instance_models, poses, camera, u + 0.5 + du, v + 0.5 + dv, &near_ok);
      if (!near_ok || o.nearest != c.nearest) edge = true;
      for (size_t i = 0; i < n && !edge; ++i) {
        if (o.z[i].has_value() != c.z[i].has_value()) edge = true;
      }
      if (!edge && c.nearest >= 0)
        spread = std::max(spread, std::abs(*o.z[c.nearest] - *c.z[c.nearest]));
    }
    if (edge) continue;
    ++f.checked[kRecast];
    // The models at the written poses disagree with a mask or the depth: the pose, the mask or
    // the depth is wrong; scene_gt is named, the image in the reason.
    const std::string gt_file = scene.Relative("scene_gt" + scene.suffix + ".json");
    const std::string at = "image " + std::to_string(task.im_id) + " pixel (" + std::to_string(u) +
                           ", " + std::to_string(v) + ")";
    const auto mask_name = [&](const char* folder, int i) {
      return std::string(folder) + scene.suffix + "/" + im + "_" + Id6(i) + ".png";
    };
    std::vector<std::pair<std::string, std::string>> wrong;
    for (size_t i = 0; i < n; ++i) {
      if (instance_models[i] == nullptr) continue;
      const bool on = masks[i].mask.at<uint8_t>(v, u) != 0, hit = c.z[i].has_value() && *c.z[i] > 0;
      if (on != hit) {
        wrong.push_back(
            {gt_file, at + ": instance " + std::to_string(i) + " at this pose " +
                          (hit ? "covers it, its mask (" : "does not cover it, its mask (") +
                          mask_name("mask", static_cast<int>(i)) +
                          (hit ? ") does not" : ") does")});
      }
    }
    const double stored =
        exact->depth() == CV_16U ? exact->at<uint16_t>(v, u) : exact->at<uint8_t>(v, u);
    const double z = stored * camera.depth_scale;
    int visible_instance = -1;
    for (size_t i = 0; i < n; ++i) {
      if (masks[i].visib.at<uint8_t>(v, u) != 0) visible_instance = static_cast<int>(i);
    }
    if (c.nearest >= 0) {
      const double cast = *c.z[c.nearest];
      const double tolerance = camera.depth_scale + 1e-4 * cast + 2 * spread + 0.01;
      std::ostringstream s;
      s << at << ": ";
      if (visible_instance >= 0 && visible_instance != c.nearest) {
        s << mask_name("mask_visib", visible_instance) << " shows instance " << visible_instance
          << ", but at these poses instance " << c.nearest << " is nearer";
        wrong.push_back({gt_file, s.str()});
      } else if (visible_instance == c.nearest && stored != 0 && std::abs(z - cast) > tolerance) {
        s << "the depth (" << exact_file << ") is " << z << " mm, instance " << c.nearest
          << " at this pose is met at " << cast << " mm";
        wrong.push_back({gt_file, s.str()});
      } else if (visible_instance < 0 && stored != 0 && z > cast - tolerance) {
        s << "instance " << c.nearest << " at this pose is met at " << cast
          << " mm and nothing nearer shows in the depth (" << z << " mm), but "
          << mask_name("mask_visib", c.nearest) << " is off";
        wrong.push_back({gt_file, s.str()});
      }
    } else if (visible_instance >= 0 && instance_models[visible_instance] != nullptr) {
      wrong.push_back({gt_file, at + ": " + mask_name("mask_visib", visible_instance) +
                                    " shows instance " + std::to_string(visible_instance) +
                                    ", but no model at these poses covers it"});
    }
    if (!wrong.empty()) {
      ++f.failed[kRecast];
      for (auto& [file, reason] : wrong) f.problems.push_back({file, reason});
    }
  }
}

Findings CheckImage(const ImageTask& task, const Models& models, const VerifyOptions& options) {
  Findings f;
  ImageData d;
  if (!ReadImageData(task, options, &d, &f)) return f;
  CheckGtInfo(task, d, &f);
  CheckCoco(task, d, &f);
  Recast(task, d, models, options, &f);
  return f;
}

// Reads one of a scene's JSON files; a problem (and nothing) when it is missing or damaged.
std::optional<nlohmann::json> ReadSceneJson(const fs::path& root, const std::string& rel,
                                            CheckId check, Findings* f, bool required = true) {
  std::error_code ec;
  if (!fs::exists(root / rel, ec)) {
    if (required) f->Fail(check, rel, "missing");
    return std::nullopt;
  }
  const std::string text = ReadFileText(root / rel);
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    f->Fail(check, rel, JsonErrorMessage(rel, text, e));
    return std::nullopt;
  }
}

}  // namespace

std::string VerifyReport::Verdict() const {
  std::ostringstream s;
  if (passed()) {
    s << "PASS: " << images << " images, " << instances << " instances";
    for (const Check& c : checks) s << ", " << c.checked << " " << c.unit << " (" << c.name << ")";
    return s.str();
  }
  s << "FAIL: " << problem_count << " problem" << (problem_count == 1 ? "" : "s");
  for (size_t k = 0; k < std::min<size_t>(problems.size(), 3); ++k)
    s << (k ? "; " : " (") << problems[k].file << ": " << problems[k].reason;
  if (!problems.empty()) s << (problem_count > 3 ? "; ...)" : ")");
  return s.str();
}

std::string VerifyReport::CertificateJson() const {
  nlohmann::json checks_json = nlohmann::json::array(), problems_json = nlohmann::json::array();
  for (const Check& c : checks)
    checks_json.push_back(
        {{"name", c.name}, {"checked", c.checked}, {"failed", c.failed}, {"unit", c.unit}});
  for (const Problem& p : problems)
    problems_json.push_back({{"file", p.file}, {"reason", p.reason}});
  const nlohmann::json j = {{"verdict", passed() ? "pass" : "fail"},
                            {"summary", Verdict()},
                            {"dataset", dataset},
                            {"run_key", run_key},
                            {"images", images},
                            {"instances", instances},
                            {"problem_count", problem_count},
                            {"checks", checks_json},
                            {"problems", problems_json},
                            {"notes", notes}};
  return j.dump(2) + "\n";
}

VerifyReport VerifyDataset(const fs::path& root, const VerifyOptions& options) {
  std::error_code ec;
  if (!fs::is_directory(root, ec)) throw Error(root.string() + ": no such folder");
  const std::vector<SceneSensor> scenes = FindBopScenes(root);
  if (scenes.empty())
    throw Error(root.string() + ": not a BOP dataset (no SPLIT/NNNNNN/scene_camera.json)");
  VerifyReport report;
  report.dataset = root.string();
  Findings all;
  all.Merge(CheckManifest(root, &report.run_key));
  Models models;
  all.Merge(CheckModels(root, &models));
  if (models.by_id.empty()) all.notes.push_back("no model could be read: nothing was re-cast");

  for (const SceneSensor& scene : scenes) {
    Findings f;
    const std::string s = scene.suffix + ".json";
    const auto gt = ReadSceneJson(root, scene.Relative("scene_gt" + s), kGtInfo, &f);
    const auto info = ReadSceneJson(root, scene.Relative("scene_gt_info" + s), kGtInfo, &f);
    const auto camera = ReadSceneJson(root, scene.Relative("scene_camera" + s), kGtInfo, &f);
    const auto coco = ReadSceneJson(root, scene.Relative("scene_gt_coco" + s), kCoco, &f, false);
    if (!gt || !camera || !gt->is_object() || !camera->is_object()) {
      all.Merge(std::move(f));
      continue;
    }
    std::map<int, std::vector<const nlohmann::json*>> annotations;
    if (coco && coco->contains("annotations")) {
      for (const nlohmann::json& a : (*coco)["annotations"])
        annotations[a.value("image_id", -1)].push_back(&a);
    }
    std::vector<ImageTask> tasks;
    for (const auto& [key, value] : gt->items()) {
      const std::optional<int> id = ParseBopId(key);
      ImageTask t;
      t.scene = &scene;
      t.im_id = id.value_or(-1);
      if (!id || !value.is_array() || !camera->contains(key)) {
        f.Fail(kGtInfo, scene.Relative("scene_gt" + s),
               "image \"" + key + "\": not an image id with instances and a camera");
        continue;
      }
      t.gt = &value;
      t.camera = &(*camera)[key];
      if (info && info->contains(key)) t.gt_info = &(*info)[key];
      t.has_coco = coco.has_value();
      if (annotations.count(*id)) t.coco = annotations[*id];
      tasks.push_back(t);
    }
    std::sort(tasks.begin(), tasks.end(),
              [](const ImageTask& a, const ImageTask& b) { return a.im_id < b.im_id; });
    std::vector<Findings> found(tasks.size());
    tbb::parallel_for(size_t{0}, tasks.size(),
                      [&](size_t i) { found[i] = CheckImage(tasks[i], models, options); });
    report.images += tasks.size();
    for (const ImageTask& t : tasks) report.instances += t.gt->size();
    all.Merge(std::move(f));
    for (Findings& g : found) all.Merge(std::move(g));
  }
  for (int c = 0; c < kChecks; ++c)
    report.checks.push_back({kCheckNames[c], all.checked[c], all.failed[c], kCheckUnits[c]});
  report.problem_count = all.problems.size();
  if (all.problems.size() > options.max_problems) all.problems.resize(options.max_problems);
  report.problems = std::move(all.problems);
  report.notes = std::move(all.notes);
  return report;
}

}  // namespace cadsynth
