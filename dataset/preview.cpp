#include "dataset/preview.h"

#include <algorithm>
#include <cmath>
#include <map>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/core/utils/logger.hpp>
#include <opencv2/imgproc.hpp>

#include "cad/core/error.h"
#include "dataset/bop.h"
#include "dataset/bop_read.h"
#include "dataset/file_io.h"
#include "dataset/grasp.h"
#include "dataset/image_mat.h"

namespace cadsynth {
namespace {

namespace fs = std::filesystem;

nlohmann::json ReadJsonFile(const fs::path& path) {
  const std::string text = ReadFileText(path);
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw Error(JsonErrorMessage(path.string(), text, e));
  }
}

cv::Mat ReadImage(const fs::path& path, image_mat::Want want) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw Error(path.string() + ": no such image");
  return image_mat::MatOf(ReadImageBytesFile(path), want, path.string());
}

// Distinct, saturated colours (BGR) for instance i.
cv::Scalar InstanceColour(size_t i) {
  cv::Mat hsv(1, 1, CV_8UC3, cv::Scalar(static_cast<double>((i * 47) % 180), 220, 255)), bgr;
  cv::cvtColor(hsv, bgr, cv::COLOR_HSV2BGR);
  const cv::Vec3b c = bgr.at<cv::Vec3b>(0, 0);
  return cv::Scalar(c[0], c[1], c[2]);
}

// Depth (uint16) to a colour map, near = warm; no depth = black.
// Depth in the turbo colour map over the range of `range` (default: its own), holes black.
cv::Mat ColourDepth(const cv::Mat& depth, const cv::Mat& range = {}) {
  double lo = 0, hi = 0;
  const cv::Mat& r = range.empty() ? depth : range;
  cv::minMaxLoc(r, &lo, &hi, nullptr, nullptr, r > 0);
  cv::Mat scaled;
  depth.convertTo(scaled, CV_8U, hi > lo ? -255.0 / (hi - lo) : 0.0,
                  hi > lo ? 255.0 * hi / (hi - lo) : 128.0);
  cv::Mat coloured;
  cv::applyColorMap(scaled, coloured, cv::COLORMAP_TURBO);
  coloured.setTo(cv::Scalar(0, 0, 0), depth == 0);
  return coloured;
}

Eigen::Matrix3d Matrix3(const nlohmann::json& v) {
  Eigen::Matrix3d m;
  for (int i = 0; i < 9; ++i) m(i / 3, i % 3) = v.at(i).get<double>();
  return m;
}

// Up to `count` rows of a grasp file whose labels (column 2 of the labels file) say the way in is
// free, spread over the instances (labels column 0): each instance's best first (scores in
// column 0), the instances in order of their best, then each one's second best, and so on. None
// when the files are not there.
std::vector<const float*> BestGrasps(const fs::path& rows_path, int count, size_t want_cols,
                                     std::vector<float>* rows, std::vector<float>* labels) {
  const fs::path labels_path =
      rows_path.parent_path() / (rows_path.stem().string() + "_labels.npy");
  if (!fs::exists(rows_path) || !fs::exists(labels_path)) return {};
  size_t n = 0, cols = 0, label_rows = 0, label_cols = 0;
  *rows = DecodeNpy(ReadFileText(rows_path), rows_path.string(), &n, &cols);
  *labels = DecodeNpy(ReadFileText(labels_path), labels_path.string(), &label_rows, &label_cols);
  if (cols != want_cols || label_rows != n || label_cols < 3)
    throw Error(rows_path.string() + ": not the grasp rows cadsynth writes");
  const auto score = [&](size_t i) { return (*rows)[i * cols]; };
  std::map<float, std::vector<size_t>> by_instance;
  for (size_t i = 0; i < n; ++i) {
    if ((*labels)[i * label_cols + 2] == 0) by_instance[(*labels)[i * label_cols]].push_back(i);
  }
  std::vector<std::vector<size_t>> groups;
  for (auto& [instance, group] : by_instance) {
    std::stable_sort(group.begin(), group.end(),
                     [&](size_t a, size_t b) { return score(a) > score(b); });
    groups.push_back(std::move(group));
  }
  std::stable_sort(groups.begin(), groups.end(),
                   [&](const auto& a, const auto& b) { return score(a[0]) > score(b[0]); });
  std::vector<const float*> best;
  for (size_t round = 0; best.size() < static_cast<size_t>(count); ++round) {
    bool any = false;
    for (const auto& group : groups) {
      if (round >= group.size() || best.size() >= static_cast<size_t>(count)) continue;
      best.push_back(rows->data() + group[round] * cols);
      any = true;
    }
    if (!any) break;
  }
  return best;
}

// Draws frame (scene, im)'s best grasps on `image` (see PreviewOptions::grasps), coloured from
// red (score 0) to green (1).
void DrawGrasps(const fs::path& dataset, int scene, int im, const Intrinsics& k, int count,
                int thickness, cv::Mat* image) {
  const auto colour = [](float score) {
    const double s = std::clamp(static_cast<double>(score), 0.0, 1.0);
    return cv::Scalar(0, 255 * s, 255 * (1 - s));
  };
  // A polyline of camera-frame points (m), drawn where every point is imaged.
  const auto line = [&](const std::vector<Eigen::Vector3d>& points, const cv::Scalar& c) {
    std::vector<cv::Point> pixels;
    for (const Eigen::Vector3d& p : points) {
      Eigen::Vector2d uv;
      if (!k.Project(1e3 * p, &uv)) return;
      pixels.emplace_back(cvRound(uv.x()), cvRound(uv.y()));
    }
    cv::polylines(*image, pixels, false, c, thickness, cv::LINE_AA);
  };
  std::vector<float> rows, labels;
  for (const float* g : BestGrasps(dataset / "graspnet" / Id6(scene) / (Id6(im) + ".npy"), count,
                                   17, &rows, &labels)) {
    // GraspNet's frame: columns approach, closing, height; the contacts' midpoint t lies `depth`
    // along the approach from the row's translation.
    Eigen::Matrix3d r;
    for (int i = 0; i < 9; ++i) r(i / 3, i % 3) = g[4 + i];
    const double half = 0.5 * g[1], depth = g[3], back = 0.02;
    const Eigen::Vector3d a = r.col(0), c = r.col(1),
                          t = Eigen::Vector3d(g[13], g[14], g[15]) + depth * a;
    const Eigen::Vector3d base = t - back * a;
    line({t + half * c + depth * a, base + half * c, base - half * c, t - half * c + depth * a},
         colour(g[0]));
    line({base, base - 2 * back * a}, colour(g[0]));
  }
  for (const float* g : BestGrasps(dataset / "suctionnet" / Id6(scene) / (Id6(im) + ".npy"), count,
                                   8, &rows, &labels)) {
    // The rim (10 mm radius drawn) about the point, perpendicular to the direction, and the axis.
    const Eigen::Vector3d n(g[1], g[2], g[3]), p(g[4], g[5], g[6]);
    const Eigen::Vector3d helper =
        std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    const Eigen::Vector3d e1 = n.cross(helper).normalized(), e2 = n.cross(e1);
    std::vector<Eigen::Vector3d> rim;
    for (int i = 0; i <= 24; ++i) {
      const double theta = 2 * M_PI * i / 24;
      rim.push_back(p + 0.01 * (std::cos(theta) * e1 + std::sin(theta) * e2));
    }
    line(rim, colour(g[0]));
    line({p, p + 0.04 * n}, colour(g[0]));
  }
}

}  // namespace

std::vector<Eigen::Vector2d> ProjectBox(const Eigen::Matrix3d& k,
                                        const Eigen::Isometry3d& cam_from_model,
                                        const Eigen::AlignedBox3d& box) {
  std::vector<Eigen::Vector2d> corners;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d p =
        k * (cam_from_model * box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c)));
    corners.emplace_back(p.x() / p.z(), p.y() / p.z());
  }
  return corners;
}

namespace {

// A split's scenes: every (scene, image) pair in order, to choose from, and each scene's
// scene_camera and scene_gt files by scene id.
struct Scenes {
  std::vector<std::pair<int, int>> all;
  std::map<int, nlohmann::json> cameras, gts;
};

Scenes ReadScenes(const fs::path& split_dir, const std::string& sfx) {
  Scenes scenes;
  std::vector<fs::path> scene_dirs;
  for (const auto& e : fs::directory_iterator(split_dir)) {
    if (fs::exists(e.path() / ("scene_gt" + sfx + ".json"))) scene_dirs.push_back(e.path());
  }
  std::sort(scene_dirs.begin(), scene_dirs.end());
  for (const fs::path& dir : scene_dirs) {
    const auto id = ParseBopId(dir.filename().string());
    if (!id) continue;  // not a scene folder
    const int scene = *id;
    scenes.cameras[scene] = ReadJsonFile(dir / ("scene_camera" + sfx + ".json"));
    scenes.gts[scene] = ReadJsonFile(dir / ("scene_gt" + sfx + ".json"));
    std::vector<int> ims;
    for (const auto& [key, value] : scenes.gts[scene].items()) {
      const auto im = ParseBopId(key);
      if (!im)
        throw Error((dir / ("scene_gt" + sfx + ".json")).string() + ": image id '" +
                    key.substr(0, 40) + "' is not a whole number");
      ims.push_back(*im);
    }
    std::sort(ims.begin(), ims.end());
    for (int im : ims) scenes.all.push_back({scene, im});
  }
  return scenes;
}

// Colour against colour: `rgb` and the same image of the other dataset (options.versus, its image
// folder `other_dir`), labelled with the folders.
cv::Mat VersusRow(const fs::path& dataset, const PreviewOptions& options, const cv::Mat& rgb,
                  const fs::path& other_dir, const std::string& name, const std::string& where) {
  fs::path other_path = other_dir / (name + ".png");
  if (!fs::exists(other_path)) other_path = other_dir / (name + ".jpg");
  std::vector<cv::Mat> panels = {rgb, ReadImage(other_path, image_mat::Want::kColour8)};
  const double scale = static_cast<double>(options.panel_width) / rgb.cols;
  const cv::Size size(options.panel_width, std::max(1, cvRound(rgb.rows * scale)));
  const std::string labels[2] = {dataset.filename().string(), options.versus.filename().string()};
  for (int p = 0; p < 2; ++p) {
    cv::resize(panels[p], panels[p], size, 0, 0, cv::INTER_AREA);
    cv::putText(panels[p], labels[p] + ", " + where, cv::Point(4, 14), cv::FONT_HERSHEY_SIMPLEX,
                0.4, cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  }
  cv::Mat row;
  cv::hconcat(panels, row);
  return row;
}

// Boxes and axes (x red, y green, z blue) of the instances `gt` lists (models_info.json: `info`)
// on the colour image.
void DrawBoxes(const nlohmann::json& gt, const nlohmann::json& info, const Intrinsics& k,
               int thickness, cv::Mat* rgb) {
  for (size_t i = 0; i < gt.size(); ++i) {
    const nlohmann::json& g = gt[i];
    const nlohmann::json& m = info.at(std::to_string(g.at("obj_id").get<int>()));
    const Eigen::Vector3d lo(m.at("min_x"), m.at("min_y"), m.at("min_z"));
    const Eigen::Vector3d size(m.at("size_x"), m.at("size_y"), m.at("size_z"));
    Eigen::Isometry3d m2c = Eigen::Isometry3d::Identity();
    m2c.linear() = Matrix3(g.at("cam_R_m2c"));
    m2c.translation() =
        Eigen::Vector3d(g.at("cam_t_m2c")[0], g.at("cam_t_m2c")[1], g.at("cam_t_m2c")[2]);
    if (m2c.translation().z() <= 0) continue;
    // Corners the camera does not image (behind it, beyond the lens's fold) draw no edges.
    std::vector<Eigen::Vector2d> c(8);
    bool imaged[8];
    for (int a = 0; a < 8; ++a) {
      const Eigen::Vector3d p = m2c * Eigen::AlignedBox3d(lo, lo + size)
                                          .corner(static_cast<Eigen::AlignedBox3d::CornerType>(a));
      imaged[a] = k.Project(p, &c[a]);
    }
    const auto pt = [](const Eigen::Vector2d& p) {
      return cv::Point(cvRound(p.x()), cvRound(p.y()));
    };
    for (int a = 0; a < 8; ++a) {
      for (int b = a + 1; b < 8; ++b) {
        const int diff = a ^ b;  // corners differ in one coordinate: an edge
        if ((diff == 1 || diff == 2 || diff == 4) && imaged[a] && imaged[b])
          cv::line(*rgb, pt(c[a]), pt(c[b]), InstanceColour(i), thickness, cv::LINE_AA);
      }
    }
    const double axis = 0.5 * size.maxCoeff();
    Eigen::Vector2d o, tip;
    const bool origin = k.Project(m2c.translation(), &o);
    for (int a = 0; a < 3; ++a) {
      if (!origin || !k.Project(m2c * (axis * Eigen::Vector3d::Unit(a)), &tip)) continue;
      cv::line(*rgb, pt(o), pt(tip),
               a == 0   ? cv::Scalar(0, 0, 255)
               : a == 1 ? cv::Scalar(0, 200, 0)
                        : cv::Scalar(255, 0, 0),
               thickness, cv::LINE_AA);
    }
  }
}

// One frame's row of panels: colour with boxes and axes, depth (exact and the sensor's), visible
// masks, grasps; or, with options.versus, the two colour images.
cv::Mat FrameRow(const fs::path& dataset, const PreviewOptions& options, const fs::path& split_dir,
                 const std::string& sfx, const nlohmann::json& info, const Scenes& scenes,
                 int scene, int im) {
  const std::string where = "scene " + std::to_string(scene) + " image " + std::to_string(im);
  if (!scenes.gts.count(scene) || !scenes.gts.at(scene).contains(std::to_string(im)))
    throw Error("preview: no " + where + " in " + split_dir.string());
  const fs::path dir = split_dir / Id6(scene);
  const std::string name = Id6(im);
  // The camera's image: rgb/, or gray/ for a grey camera.
  const fs::path image_dir =
      fs::exists(dir / ("rgb" + sfx)) ? dir / ("rgb" + sfx) : dir / ("gray" + sfx);
  fs::path rgb_path = image_dir / (name + ".png");
  if (!fs::exists(rgb_path)) rgb_path = image_dir / (name + ".jpg");
  cv::Mat rgb = ReadImage(rgb_path, image_mat::Want::kColour8);
  if (!options.versus.empty()) {
    // The other dataset's image of the same kind (grey against grey), else whichever it has.
    const fs::path other = options.versus / split_dir.filename() / Id6(scene);
    fs::path other_dir = other / image_dir.filename();
    if (!fs::exists(other_dir))
      other_dir =
          fs::exists(other / ("rgb" + sfx)) ? other / ("rgb" + sfx) : other / ("gray" + sfx);
    return VersusRow(dataset, options, rgb, other_dir, name, where);
  }
  const cv::Mat depth =
      ReadImage(dir / ("depth" + sfx) / (name + ".png"), image_mat::Want::kUnchanged);
  const nlohmann::json& gt = scenes.gts.at(scene).at(std::to_string(im));
  const nlohmann::json& camera = scenes.cameras.at(scene).at(std::to_string(im));
  const Eigen::Matrix3d kmat = Matrix3(camera.at("cam_K"));
  // The lens's distortion, when the camera has one, bends the drawn points as it bends the image.
  Intrinsics k;
  k.fx = kmat(0, 0), k.fy = kmat(1, 1), k.cx = kmat(0, 2), k.cy = kmat(1, 2);
  if (camera.contains("cam_dist_coeffs")) {
    const nlohmann::json& d = camera.at("cam_dist_coeffs");
    k.distortion = Distortion{d.at(0), d.at(1), d.at(2), d.at(3), d.at(4)};
  }

  cv::Mat masks = rgb * 0.35;
  for (size_t i = 0; i < gt.size(); ++i) {
    const fs::path mask_path =
        dir / ("mask_visib" + sfx) / (name + "_" + Id6(static_cast<int>(i)) + ".png");
    const cv::Mat mask = ReadImage(mask_path, image_mat::Want::kGrey8);
    masks.setTo(InstanceColour(i), mask > 0);
  }
  // Grasp labels on a copy of the colour image, the last panel.
  const int thickness = std::max(1, rgb.cols / 320);
  cv::Mat grasps;
  if (options.grasps > 0 && options.sensor.empty() &&
      (fs::exists(dataset / "graspnet" / Id6(scene)) ||
       fs::exists(dataset / "suctionnet" / Id6(scene)))) {
    grasps = rgb.clone();
    DrawGrasps(dataset, scene, im, k, options.grasps, thickness, &grasps);
  }
  DrawBoxes(gt, info, k, thickness, &rgb);
  // With a depth sensor model: the exact depth, then the sensor's, coloured over the same range.
  std::vector<cv::Mat> panels = {rgb};
  if (fs::exists(dir / ("depth_gt" + sfx))) {
    const cv::Mat exact =
        ReadImage(dir / ("depth_gt" + sfx) / (name + ".png"), image_mat::Want::kUnchanged);
    panels.push_back(ColourDepth(exact));
    panels.push_back(ColourDepth(depth, exact));
  } else {
    panels.push_back(ColourDepth(depth));
  }
  panels.push_back(masks);
  if (!grasps.empty()) panels.push_back(grasps);
  const double scale = static_cast<double>(options.panel_width) / rgb.cols;
  for (cv::Mat& p : panels) {
    cv::resize(p, p, cv::Size(options.panel_width, std::max(1, cvRound(rgb.rows * scale))), 0, 0,
               cv::INTER_AREA);
  }
  cv::putText(panels[0], where, cv::Point(4, 14), cv::FONT_HERSHEY_SIMPLEX, 0.4,
              cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  cv::Mat row;
  cv::hconcat(panels, row);
  return row;
}

std::string RenderPreviewUnchecked(const fs::path& dataset, const PreviewOptions& options,
                                   std::vector<std::pair<int, int>>* shown) {
  if (options.panel_width < 32 || options.panel_width > 4096)
    throw Error("preview: panel width must be 32 to 4096");
  const fs::path split_dir =
      options.split.empty() ? FindSceneFolder(dataset, options.sensor) : dataset / options.split;
  const std::string sfx = options.sensor.empty() ? "" : "_" + options.sensor;
  if (!fs::is_directory(split_dir)) throw Error(split_dir.string() + ": no such folder");
  const nlohmann::json info = ReadJsonFile(dataset / "models" / "models_info.json");

  const Scenes scenes = ReadScenes(split_dir, sfx);
  const std::vector<std::pair<int, int>>& all = scenes.all;
  if (all.empty()) throw Error(split_dir.string() + ": no images");
  std::vector<std::pair<int, int>> chosen = options.frames;
  if (chosen.empty()) {
    const int n = std::clamp(options.count, 1, static_cast<int>(all.size()));
    for (int i = 0; i < n; ++i) chosen.push_back(all[static_cast<size_t>(i) * all.size() / n]);
  }
  if (shown) *shown = chosen;

  std::vector<cv::Mat> rows;
  for (const auto& [scene, im] : chosen)
    rows.push_back(FrameRow(dataset, options, split_dir, sfx, info, scenes, scene, im));
  // Rows of 3 to 5 panels, heights may differ: narrower rows are padded on the right.
  int width = 0;
  for (const cv::Mat& row : rows) width = std::max(width, row.cols);
  for (cv::Mat& row : rows) {
    if (row.cols < width)
      cv::copyMakeBorder(row, row, 0, 0, 0, width - row.cols, cv::BORDER_CONSTANT,
                         cv::Scalar::all(0));
  }
  cv::Mat sheet;
  cv::vconcat(rows, sheet);
  try {
    const ImageView view = image_mat::ViewOf(sheet);
    return options.jpeg_quality > 0 ? EncodeJpeg(view, std::min(options.jpeg_quality, 100))
                                    : EncodePng(view);
  } catch (const Error& e) {
    throw Error(std::string("preview: ") + e.what());
  }
}

}  // namespace

std::string RenderPreview(const fs::path& dataset, const PreviewOptions& options,
                          std::vector<std::pair<int, int>>* shown) {
  try {
    return RenderPreviewUnchecked(dataset, options, shown);
  } catch (const nlohmann::json::exception& e) {
    // A value of the wrong type in a scene's JSON files (the syntax was checked on reading).
    throw Error(JsonErrorMessage(dataset.string() + ": damaged BOP files", "", e));
  }
}

void SilenceOpenCvWarnings() {
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_ERROR);
}

}  // namespace cadsynth
