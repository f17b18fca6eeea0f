#include "tools/pipeline/sensor_test.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "cad/core/error.h"
#include "cad/shape.h"
#include "render/renderer.h"

namespace cadsynth {

bool PlaneTestOptions::Check(std::string* why) const {
  std::ostringstream out;
  std::string inner;
  if (!intrinsics.Check(&inner)) {
    out << "camera: " << inner;
  } else if (!sensor.Check(&inner)) {
    out << "camera.depth: " << inner;
  } else if (sensor.depth.kind == DepthModel::Kind::kIdeal && !figures.empty()) {
    out << "the ideal model has no published figures";
  } else if (!(albedo >= 0.0 && albedo <= 1.0)) {
    out << "albedo must lie between 0 and 1";
  } else if (Material m; !material.empty() && !MaterialPreset(material, &m)) {
    out << "no material preset called '" << material << "'";
  } else if (distances_mm.empty()) {
    out << "no distances";
  } else if (std::any_of(distances_mm.begin(), distances_mm.end(),
                         [](double d) { return !(d >= 10.0 && d <= 20000.0); })) {
    out << "distances must lie between 10 mm and 20 m";
  } else if (tilts_rad.empty() || std::any_of(tilts_rad.begin(), tilts_rad.end(), [](double t) {
               return !(std::abs(t) <= 80.0 * M_PI / 180.0);
             })) {
    out << "tilts must lie between -80 and 80 degrees";
  } else if (frames < 2 || frames > 1000) {
    out << "frames must lie between 2 and 1000 (the temporal noise needs two)";
  } else if (!(roi > 0.0 && roi <= 1.0)) {
    out << "roi must lie in (0, 1]";
  } else if (!(step_mm >= 0.0 && step_mm <= 1000.0)) {
    out << "step must lie between 0 and 1000 mm";
  } else {
    return true;
  }
  *why = out.str();
  return false;
}

bool PlaneTestResult::AllMet() const {
  return std::all_of(checks.begin(), checks.end(), [](const FigureCheck& c) { return c.met; });
}

PlaneTestOptions PlaneTestFor(const SensorPreset& preset) {
  PlaneTestOptions o;
  o.name = preset.name;
  const CameraPreset* camera = FindCameraPreset(preset.camera);
  if (camera == nullptr)
    throw Error("sensor preset " + preset.name + ": no camera " + preset.camera);
  o.intrinsics = camera->intrinsics;
  o.sensor.depth = preset.depth;
  o.albedo = preset.albedo;
  o.figures = preset.figures;
  o.distances_mm.clear();
  for (const PublishedFigure& f : preset.figures) o.distances_mm.push_back(f.distance_mm);
  std::sort(o.distances_mm.begin(), o.distances_mm.end());
  o.distances_mm.erase(std::unique(o.distances_mm.begin(), o.distances_mm.end()),
                       o.distances_mm.end());
  return o;
}

namespace {

// The camera at `distance` from the floor's origin along its optical axis, turned by `tilt` about
// its own y axis around that point; at tilt 0 it looks straight down with image x along world +x.
Camera PlaneCamera(const Intrinsics& k, double distance, double tilt) {
  Eigen::Matrix3d down;
  down << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  // Turning the camera by -tilt about world y turns the floor's normal, seen from the camera, by
  // +tilt towards the camera's +x (the projector's side).
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(-tilt, Eigen::Vector3d::UnitY()).matrix();
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = turn * down;
  pose.translation() = -distance * pose.linear().col(2);  // the axis ends at the origin
  return Camera{k, pose};
}

// The depth the sensor returned (the ideal model returns the exact one, which the frame keeps
// once).
const std::vector<float>& SensedDepth(const Frame& frame) {
  return frame.sensor_depth.empty() ? frame.depth : frame.sensor_depth;
}

struct Region {
  int u0, u1, v0, v1;
  size_t Pixels() const { return static_cast<size_t>(u1 - u0) * (v1 - v0); }
};

Region RegionOfInterest(const Intrinsics& k, double roi) {
  const int mu = static_cast<int>(std::lround(0.5 * (1.0 - roi) * k.width));
  const int mv = static_cast<int>(std::lround(0.5 * (1.0 - roi) * k.height));
  return Region{mu, k.width - mu, mv, k.height - mv};
}

// The RMS of depth about the plane fitted (total least squares) to the frame's points in the
// region, trimmed by 0.5 % at each end of the residuals. NaN with fewer than 3 points.
double PlaneFitRms(const Intrinsics& k, const Region r, const std::vector<float>& depth) {
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3d> rays;
  for (int v = r.v0; v < r.v1; ++v) {
    for (int u = r.u0; u < r.u1; ++u) {
      const float z = depth[static_cast<size_t>(v) * k.width + u];
      if (!(z > 0.0f)) continue;
      const Eigen::Vector3d ray((u + 0.5 - k.cx) / k.fx, (v + 0.5 - k.cy) / k.fy, 1.0);
      rays.push_back(ray);
      points.push_back(ray * z);
    }
  }
  if (points.size() < 3) return std::nan("");
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const auto& p : points) centre += p;
  centre /= static_cast<double>(points.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const auto& p : points) scatter += (p - centre) * (p - centre).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(scatter);
  const Eigen::Vector3d n = eigen.eigenvectors().col(0);  // the smallest eigenvalue's
  // Residual along the pixel's ray, in depth: the plane n . X = n . centre meets the ray at
  // z_p = n . centre / n . ray.
  std::vector<double> residuals;
  residuals.reserve(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    const double along = n.dot(rays[i]);
    if (std::abs(along) < 1e-9) continue;
    residuals.push_back(points[i].z() - n.dot(centre) / along);
  }
  std::sort(residuals.begin(), residuals.end());
  const size_t trim = residuals.size() / 200;
  double sum2 = 0.0;
  size_t n_kept = 0;
  for (size_t i = trim; i + trim < residuals.size(); ++i)
    sum2 += residuals[i] * residuals[i], ++n_kept;
  return n_kept > 0 ? std::sqrt(sum2 / static_cast<double>(n_kept)) : std::nan("");
}

// The scene: the floor as the target and, for the edge test, a slab of `step` covering x < 0.
struct Target {
  std::vector<Part> parts;
  Scene scene;
  RenderOptions render;
};

Target MakeTarget(const PlaneTestOptions& o, double step) {
  Target t;
  t.scene.floor_half_size_mm = 1e5;
  t.scene.floor_color.setConstant(static_cast<float>(o.albedo));
  if (!o.material.empty()) {
    Material m;
    MaterialPreset(o.material, &m);
    t.scene.floor_material = m;
    t.render.mode = RenderOptions::Mode::kPbr;
    t.render.samples = 1;
  }
  t.render.amodal_masks = false;
  if (step > 0.0) {
    constexpr double kSide = 1e5;
    TessellationOptions flat;  // a box's faces are flat: any deflection gives its 12 triangles
    flat.linear_deflection_mm = 10.0;
    t.parts.push_back(MakePart("step", MakeBox(kSide, 2.0 * kSide, step), flat));
    t.scene.instances = {
        Instance{0, "step", Eigen::Isometry3d(Eigen::Translation3d(-0.5 * kSide, 0, 0.5 * step))}};
    t.scene.part_colors = {Eigen::Vector3f::Constant(static_cast<float>(o.albedo))};
    if (!o.material.empty()) {
      t.scene.materials = {t.scene.floor_material};
      t.scene.instance_material = {0};
    }
  }
  return t;
}

PlaneTestRow MeasurePlane(const PlaneTestOptions& o, const Renderer& renderer, double distance,
                          double tilt) {
  PlaneTestRow row;
  row.distance_mm = distance, row.tilt_rad = tilt;
  const Intrinsics& k = o.intrinsics;
  const Region r = RegionOfInterest(k, o.roi);
  const Camera camera = PlaneCamera(k, distance, tilt);
  const size_t n = r.Pixels();
  // Per pixel of the region: frames with a value, and their running mean and sum of squared
  // deviations (Welford's update: depths of metres with noise of micrometres keep their digits).
  std::vector<int> count(n, 0);
  std::vector<double> mean(n, 0.0), m2(n, 0.0);
  double bias_sum = 0.0, rms_sum = 0.0;
  size_t valid = 0, seen = 0;
  int rms_frames = 0;
  for (int f = 0; f < o.frames; ++f) {
    const Frame frame = renderer.Render(camera, static_cast<uint64_t>(f), o.sensor);
    const std::vector<float>& sensed = SensedDepth(frame);
    size_t i = 0;
    for (int v = r.v0; v < r.v1; ++v) {
      for (int u = r.u0; u < r.u1; ++u, ++i) {
        const size_t p = static_cast<size_t>(v) * k.width + u;
        if (!(frame.depth[p] > 0.0f)) continue;  // beyond the target (a steep tilt's horizon)
        ++seen;
        const float z = sensed[p];
        if (!(z > 0.0f)) continue;
        ++valid;
        bias_sum += z - frame.depth[p];
        const double delta = z - mean[i];
        mean[i] += delta / ++count[i];
        m2[i] += delta * (z - mean[i]);
      }
    }
    const double rms = PlaneFitRms(k, r, sensed);
    if (std::isfinite(rms)) rms_sum += rms, ++rms_frames;
  }
  row.fill = seen > 0 ? static_cast<double>(valid) / static_cast<double>(seen) : 0.0;
  row.bias_mm = valid > 0 ? bias_sum / static_cast<double>(valid) : std::nan("");
  row.plane_rms_mm = rms_frames > 0 ? rms_sum / rms_frames : std::nan("");
  double var_sum = 0.0;
  size_t pixels = 0;
  for (size_t i = 0; i < n; ++i) {
    if (count[i] < 2) continue;
    var_sum += m2[i] / (count[i] - 1);
    ++pixels;
  }
  row.temporal_mm = pixels > 0 ? std::sqrt(var_sum / static_cast<double>(pixels)) : std::nan("");
  return row;
}

// The edge test at tilt 0: the step's edge runs down the image's middle column.
void MeasureEdge(const PlaneTestOptions& o, const Renderer& renderer, PlaneTestRow* row) {
  const Intrinsics& k = o.intrinsics;
  const Region r = RegionOfInterest(k, o.roi);
  const Camera camera = PlaneCamera(k, row->distance_mm, 0.0);
  const double tolerance =
      std::max(4.0 * (std::isfinite(row->plane_rms_mm) ? row->plane_rms_mm : 0.0), 1.0);
  constexpr int kBand = 16;
  const int edge = static_cast<int>(std::lround(k.cx + 0.5));
  size_t holes = 0, wrong = 0, rows = 0;
  for (int f = 0; f < std::min(o.frames, 4); ++f) {
    const Frame frame = renderer.Render(camera, static_cast<uint64_t>(f), o.sensor);
    const std::vector<float>& sensed = SensedDepth(frame);
    for (int v = r.v0; v < r.v1; ++v, ++rows) {
      for (int u = std::max(0, edge - kBand); u < std::min(k.width, edge + kBand); ++u) {
        const size_t p = static_cast<size_t>(v) * k.width + u;
        if (!(frame.depth[p] > 0.0f)) continue;
        const float z = sensed[p];
        if (!(z > 0.0f)) {
          ++holes;
        } else if (std::abs(z - frame.depth[p]) > tolerance) {
          ++wrong;
        }
      }
    }
  }
  row->edge_holes_px = rows > 0 ? static_cast<double>(holes) / rows : 0.0;
  row->edge_wrong_px = rows > 0 ? static_cast<double>(wrong) / rows : 0.0;
}

double Measured(const PlaneTestRow& row, PublishedFigure::Quantity q) {
  switch (q) {
    case PublishedFigure::Quantity::kTemporalNoise:
      return row.temporal_mm;
    case PublishedFigure::Quantity::kPlaneFitRms:
      return row.plane_rms_mm;
    case PublishedFigure::Quantity::kBias:
      return std::abs(row.bias_mm);
    case PublishedFigure::Quantity::kFillRate:
      return row.fill;
  }
  return std::nan("");
}

const char* BoundName(PublishedFigure::Bound b) {
  switch (b) {
    case PublishedFigure::Bound::kAbout:
      return "about";
    case PublishedFigure::Bound::kAtMost:
      return "at most";
    case PublishedFigure::Bound::kAtLeast:
      return "at least";
  }
  return "";
}

}  // namespace

PlaneTestResult RunPlaneTest(const PlaneTestOptions& options) {
  std::string why;
  if (!options.Check(&why)) throw Error("sensor-test: " + why);
  PlaneTestResult result;
  result.options = options;
  const Target plane = MakeTarget(options, 0.0);
  const Renderer plane_renderer(plane.parts, plane.scene, plane.render);
  std::unique_ptr<Renderer> step_renderer;
  if (options.step_mm > 0.0) {
    const Target step = MakeTarget(options, options.step_mm);
    step_renderer = std::make_unique<Renderer>(step.parts, step.scene, step.render);
  }
  for (const double tilt : options.tilts_rad) {
    for (const double distance : options.distances_mm) {
      PlaneTestRow row = MeasurePlane(options, plane_renderer, distance, tilt);
      if (step_renderer && tilt == 0.0 && distance > options.step_mm + 10.0) {
        MeasureEdge(options, *step_renderer, &row);
      }
      result.rows.push_back(row);
    }
  }
  for (const PublishedFigure& figure : options.figures) {
    // Figures at distances the run did not measure are left out.
    if (std::find(options.distances_mm.begin(), options.distances_mm.end(), figure.distance_mm) ==
            options.distances_mm.end() ||
        std::find(options.tilts_rad.begin(), options.tilts_rad.end(), 0.0) ==
            options.tilts_rad.end()) {
      continue;
    }
    FigureCheck check;
    check.figure = figure;
    check.measured = std::nan("");
    for (const PlaneTestRow& row : result.rows) {
      if (row.tilt_rad == 0.0 && row.distance_mm == figure.distance_mm) {
        check.measured = Measured(row, figure.quantity);
      }
    }
    check.met = figure.Met(check.measured);
    result.checks.push_back(check);
  }
  return result;
}

std::string PlaneTestTable(const PlaneTestResult& result) {
  const PlaneTestOptions& o = result.options;
  std::ostringstream out;
  out << std::fixed;
  out << "plane test of " << o.name << ": " << o.intrinsics.width << " x " << o.intrinsics.height
      << ", target " << (o.material.empty() ? "albedo " : o.material);
  if (o.material.empty()) out << std::setprecision(2) << o.albedo;
  out << ", " << o.frames << " frames, central " << std::setprecision(0) << 100.0 * o.roi
      << " % of the image\n";
  out << " distance   tilt  temporal  plane-fit      bias    fill   edge: holes  wrong (px/row)\n";
  out << "     (mm)  (deg)      (mm)   RMS (mm)      (mm)     (%)\n";
  for (const PlaneTestRow& r : result.rows) {
    out << std::setw(9) << std::setprecision(0) << r.distance_mm << std::setw(7)
        << r.tilt_rad * 180.0 / M_PI << std::setprecision(3) << std::setw(10) << r.temporal_mm
        << std::setw(11) << r.plane_rms_mm << std::setw(10) << r.bias_mm << std::setprecision(1)
        << std::setw(8) << 100.0 * r.fill;
    if (r.edge_holes_px >= 0.0) {
      out << std::setw(14) << r.edge_holes_px << std::setw(7) << r.edge_wrong_px;
    }
    out << "\n";
  }
  if (!result.checks.empty()) {
    out << "published figures:\n";
    for (const FigureCheck& c : result.checks) {
      const bool fill = c.figure.quantity == PublishedFigure::Quantity::kFillRate;
      const double scale = fill ? 100.0 : 1.0;
      const char* unit = fill ? " %" : " mm";
      out << "  " << (c.met ? "met    " : "NOT MET") << "  " << QuantityName(c.figure.quantity)
          << " at " << std::setprecision(0) << c.figure.distance_mm
          << " mm: " << BoundName(c.figure.bound) << " " << std::setprecision(3)
          << scale * c.figure.value << unit;
      if (c.figure.bound == PublishedFigure::Bound::kAbout) {
        out << " +- " << std::setprecision(0) << 100.0 * c.figure.tolerance << " %";
      }
      out << ", measured " << std::setprecision(3) << scale * c.measured << unit << "  ("
          << c.figure.source << ")\n";
    }
  }
  return out.str();
}

std::string PlaneTestJson(const PlaneTestResult& result) {
  const PlaneTestOptions& o = result.options;
  nlohmann::ordered_json j;
  j["sensor"] = o.name;
  j["width"] = o.intrinsics.width;
  j["height"] = o.intrinsics.height;
  j["fx"] = o.intrinsics.fx;
  if (o.material.empty()) {
    j["albedo"] = o.albedo;
  } else {
    j["material"] = o.material;
  }
  j["frames"] = o.frames;
  j["roi"] = o.roi;
  const auto number = [](double x) {
    return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json();
  };
  for (const PlaneTestRow& r : result.rows) {
    nlohmann::ordered_json row;
    row["distance_mm"] = r.distance_mm;
    row["tilt_deg"] = r.tilt_rad * 180.0 / M_PI;
    row["temporal_noise_mm"] = number(r.temporal_mm);
    row["plane_fit_rms_mm"] = number(r.plane_rms_mm);
    row["bias_mm"] = number(r.bias_mm);
    row["fill_rate"] = r.fill;
    if (r.edge_holes_px >= 0.0) {
      row["edge_holes_px_per_row"] = r.edge_holes_px;
      row["edge_wrong_px_per_row"] = r.edge_wrong_px;
    }
    j["rows"].push_back(row);
  }
  j["published"] = nlohmann::json::array();
  for (const FigureCheck& c : result.checks) {
    nlohmann::ordered_json f;
    f["quantity"] = QuantityName(c.figure.quantity);
    f["bound"] = BoundName(c.figure.bound);
    f["distance_mm"] = c.figure.distance_mm;
    f["value"] = c.figure.value;
    if (c.figure.bound == PublishedFigure::Bound::kAbout) f["tolerance"] = c.figure.tolerance;
    f["measured"] = number(c.measured);
    f["met"] = c.met;
    f["source"] = c.figure.source;
    j["published"].push_back(f);
  }
  return j.dump(2) + "\n";
}

namespace {

// A small SVG line chart: x = distance (linear), y = value (linear from 0), series as polylines,
// marks as symbols with a bound's direction.
struct Series {
  std::string label, colour;
  std::vector<std::pair<double, double>> points;
};
struct Mark {
  double x, y;
  std::string colour;
  PublishedFigure::Bound bound;
};

std::string Escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '<') {
      out += "&lt;";
    } else if (c == '>') {
      out += "&gt;";
    } else if (c == '&') {
      out += "&amp;";
    } else {
      out += c;
    }
  }
  return out;
}

void Panel(std::ostringstream& svg, double left, double top, double width, double height,
           const std::string& title, const std::string& y_label, double x_max,
           const std::vector<Series>& series, const std::vector<Mark>& marks, double y_fixed = 0) {
  double y_max = y_fixed;
  if (y_max <= 0.0) {
    for (const Series& s : series) {
      for (const auto& [x, y] : s.points) {
        if (std::isfinite(y)) y_max = std::max(y_max, y);
      }
    }
    for (const Mark& m : marks) y_max = std::max(y_max, m.y);
    y_max = y_max > 0.0 ? 1.15 * y_max : 1.0;
  }
  const auto px = [&](double x) { return left + width * x / x_max; };
  const auto py = [&](double y) {
    return top + height - height * std::clamp(y / y_max, 0.0, 1.05);
  };
  svg << std::fixed << std::setprecision(1);
  svg << "<rect x='" << left << "' y='" << top << "' width='" << width << "' height='" << height
      << "' fill='none' stroke='#999'/>\n";
  svg << "<text x='" << left << "' y='" << top - 8 << "' font-size='13'>" << Escape(title)
      << "</text>\n";
  for (int i = 0; i <= 4; ++i) {
    const double y = y_max * i / 4.0, x = x_max * i / 4.0;
    svg << "<text x='" << left - 6 << "' y='" << py(y) + 4 << "' font-size='10' text-anchor='end'>"
        << std::setprecision(y_max < 1 ? 3 : 1) << y << "</text>\n"
        << std::setprecision(1);
    svg << "<text x='" << px(x) << "' y='" << top + height + 14
        << "' font-size='10' text-anchor='middle'>" << std::setprecision(0) << x << "</text>\n"
        << std::setprecision(1);
  }
  svg << "<text x='" << left + width / 2 << "' y='" << top + height + 28
      << "' font-size='11' text-anchor='middle'>distance (mm)</text>\n";
  svg << "<text x='" << left - 44 << "' y='" << top + height / 2 << "' font-size='11' "
      << "text-anchor='middle' transform='rotate(-90 " << left - 44 << " " << top + height / 2
      << ")'>" << Escape(y_label) << "</text>\n";
  // The legend in the top left, or the bottom left for a fixed scale (fill rates near its top).
  double legend_y =
      y_fixed > 0.0 ? top + height - 14.0 * (series.size() + (marks.empty() ? 0 : 1)) : top + 14;
  for (const Series& s : series) {
    svg << "<polyline fill='none' stroke='" << s.colour << "' stroke-width='2' points='";
    for (const auto& [x, y] : s.points) {
      if (std::isfinite(y)) svg << px(x) << "," << py(y) << " ";
    }
    svg << "'/>\n";
    for (const auto& [x, y] : s.points) {
      if (std::isfinite(y)) {
        svg << "<circle cx='" << px(x) << "' cy='" << py(y) << "' r='2.5' fill='" << s.colour
            << "'/>\n";
      }
    }
    svg << "<line x1='" << left + 10 << "' y1='" << legend_y - 4 << "' x2='" << left + 28
        << "' y2='" << legend_y - 4 << "' stroke='" << s.colour << "' stroke-width='2'/>"
        << "<text x='" << left + 32 << "' y='" << legend_y << "' font-size='11'>" << Escape(s.label)
        << "</text>\n";
    legend_y += 14;
  }
  for (const Mark& m : marks) {
    const double x = px(m.x), y = py(m.y);
    if (m.bound == PublishedFigure::Bound::kAbout) {
      svg << "<rect x='" << x - 5 << "' y='" << y - 5 << "' width='10' height='10' fill='none' "
          << "stroke='" << m.colour << "' stroke-width='2'/>\n";
    } else {
      // A bar with a tick pointing to the side the measurement must lie on.
      const double d = m.bound == PublishedFigure::Bound::kAtMost ? 7 : -7;
      svg << "<path d='M" << x - 8 << "," << y << " H" << x + 8 << " M" << x << "," << y << " V"
          << y + d << "' stroke='" << m.colour << "' stroke-width='2' fill='none'/>\n";
    }
  }
  if (!marks.empty()) {
    svg << "<text x='" << left + 10 << "' y='" << legend_y
        << "' font-size='10' fill='#444'>published: square = about, bar = bound</text>\n";
  }
}

}  // namespace

std::string PlaneTestSvg(const PlaneTestResult& result) {
  const PlaneTestOptions& o = result.options;
  double x_max = 0.0;
  for (const double d : o.distances_mm) x_max = std::max(x_max, d);
  x_max *= 1.1;
  std::vector<Series> noise, fill;
  static const char* kColours[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#8c564b"};
  for (size_t t = 0; t < o.tilts_rad.size(); ++t) {
    const std::string tilt =
        o.tilts_rad.size() > 1
            ? " (" + std::to_string(static_cast<int>(std::lround(o.tilts_rad[t] * 180 / M_PI))) +
                  " deg)"
            : "";
    Series temporal{"temporal noise" + tilt, kColours[(2 * t) % 5], {}};
    Series rms{"plane-fit RMS" + tilt, kColours[(2 * t + 1) % 5], {}};
    Series bias{"|bias|" + tilt, "#7f7f7f", {}};
    Series filled{"fill rate" + tilt, kColours[t % 5], {}};
    for (const PlaneTestRow& r : result.rows) {
      if (r.tilt_rad != o.tilts_rad[t]) continue;
      temporal.points.push_back({r.distance_mm, r.temporal_mm});
      rms.points.push_back({r.distance_mm, r.plane_rms_mm});
      bias.points.push_back({r.distance_mm, std::abs(r.bias_mm)});
      filled.points.push_back({r.distance_mm, 100.0 * r.fill});
    }
    noise.push_back(temporal), noise.push_back(rms);
    if (t == 0) noise.push_back(bias);
    fill.push_back(filled);
  }
  std::vector<Mark> noise_marks, fill_marks;
  for (const FigureCheck& c : result.checks) {
    const PublishedFigure& f = c.figure;
    switch (f.quantity) {
      case PublishedFigure::Quantity::kTemporalNoise:
        noise_marks.push_back({f.distance_mm, f.value, kColours[0], f.bound});
        break;
      case PublishedFigure::Quantity::kPlaneFitRms:
        noise_marks.push_back({f.distance_mm, f.value, kColours[1], f.bound});
        break;
      case PublishedFigure::Quantity::kBias:
        noise_marks.push_back({f.distance_mm, f.value, "#7f7f7f", f.bound});
        break;
      case PublishedFigure::Quantity::kFillRate:
        fill_marks.push_back({f.distance_mm, 100.0 * f.value, kColours[0], f.bound});
        break;
    }
  }
  std::ostringstream svg;
  svg << "<svg xmlns='http://www.w3.org/2000/svg' width='900' height='330' "
      << "font-family='sans-serif'>\n<rect width='900' height='330' fill='white'/>\n";
  std::ostringstream title;
  title << o.name << ": " << o.intrinsics.width << " x " << o.intrinsics.height << ", "
        << (o.material.empty() ? "albedo " + std::to_string(o.albedo).substr(0, 4) : o.material)
        << ", " << o.frames << " frames";
  Panel(svg, 70, 40, 480, 240, title.str(), "mm", x_max, noise, noise_marks);
  Panel(svg, 640, 40, 230, 240, "fill rate", "%", x_max, fill, fill_marks, 105.0);
  svg << "</svg>\n";
  return svg.str();
}

}  // namespace cadsynth
