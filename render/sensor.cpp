#include "render/sensor.h"

#include "render/pixel_rays.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "cad/core/random.h"

namespace cadsynth {

DepthModel DepthModel::Defaults(Kind kind) {
  DepthModel m;
  m.kind = kind;
  switch (kind) {
    case Kind::kIdeal:
      break;
    case Kind::kKinectV1:
      m.baseline_mm = 75.0;
      m.focal_px = 580.0;
      m.disparity_step_px = 0.125;
      m.lateral_px = 0.8;
      m.max_incidence_rad = 80.0 * M_PI / 180.0;
      m.jump_mm = 30.0;
      m.min_signal = 0.02;
      break;
    case Kind::kAzureKinect:
      m.lateral_px = 0.25;
      m.jump_mm = 800.0;
      m.dark_gray = 15;
      break;
    case Kind::kActiveStereo:
      // RealSense D435: 50 mm between the IR imagers, min-Z about 280 mm at 848 x 480.
      m.baseline_mm = 50.0;
      m.dot_spacing_px = 3.0;
      m.dot_power = 1.0;
      m.ambient = 0.15;
      m.ir_noise = 0.01;
      m.min_depth_mm = 280.0;
      m.block = 5;
      m.min_texture = 4.0;
      break;
    case Kind::kStructuredLight:
      m.baseline_mm = 200.0;
      m.noise_mm = 0.1;
      m.max_incidence_rad = 80.0 * M_PI / 180.0;
      m.min_signal = 0.03;
      m.max_signal = 4.0;
      break;
  }
  return m;
}

bool DepthModel::Check(std::string* why) const {
  std::ostringstream out;
  const auto finite_nonneg = [](double x) { return std::isfinite(x) && x >= 0.0; };
  if (!std::isfinite(baseline_mm) || std::abs(baseline_mm) > 1e4) {
    out << "baseline must be a length of at most 10 m";
  } else if (kind == Kind::kKinectV1 && baseline_mm == 0.0) {
    out << "baseline must not be 0 for kinect_v1 (its disparity is f B / z)";
  } else if (!(focal_px > 0.0) || !std::isfinite(focal_px)) {
    out << "focal must be positive";
  } else if (!finite_nonneg(disparity_step_px) || disparity_step_px > 16.0 ||
             (kind == Kind::kKinectV1 && disparity_step_px == 0.0)) {
    out << "disparity_step must lie in (0, 16] px";
  } else if (!finite_nonneg(noise_mm) || noise_mm > 1000.0) {
    out << "noise must be a length between 0 and 1 m";
  } else if (!finite_nonneg(lateral_px) || lateral_px > 16.0) {
    out << "lateral must lie between 0 and 16 px";
  } else if (!finite_nonneg(max_incidence_rad) || max_incidence_rad > 0.5 * M_PI + 1e-12) {
    out << "max_incidence must lie between 0 and 90 degrees";
  } else if (!finite_nonneg(jump_mm)) {
    out << "jump must not be negative";
  } else if (!finite_nonneg(min_signal) || min_signal > 1.0) {
    out << "min_signal must lie between 0 and 1";
  } else if (!finite_nonneg(max_signal) || (max_signal > 0.0 && max_signal <= min_signal)) {
    out << "max_signal must be 0 (none) or larger than min_signal";
  } else if (dark_gray < 0 || dark_gray > 255) {
    out << "dark_gray must lie between 0 and 255";
  } else if (kind == Kind::kActiveStereo && !(baseline_mm > 0.0)) {
    out << "baseline must be positive for active_stereo (the right camera's x)";
  } else if (kind == Kind::kActiveStereo && !(dot_spacing_px >= 1.0 && dot_spacing_px <= 100.0)) {
    out << "dot_spacing must lie between 1 and 100 px";
  } else if (!finite_nonneg(dot_power) || dot_power > 100.0) {
    out << "dot_power must lie between 0 and 100";
  } else if (!finite_nonneg(ambient) || ambient > 10.0) {
    out << "ambient must lie between 0 and 10";
  } else if (!finite_nonneg(ir_noise) || ir_noise > 1.0) {
    out << "ir_noise must lie between 0 and 1";
  } else if (kind == Kind::kActiveStereo && !(min_depth_mm >= 10.0 && min_depth_mm <= 1e6)) {
    out << "min_depth must lie between 10 mm and 1 km";
  } else if (kind == Kind::kActiveStereo && (block < 3 || block > 11 || block % 2 == 0)) {
    out << "block must be odd, between 3 and 11";
  } else if (!finite_nonneg(min_texture) || min_texture > 255.0) {
    out << "min_texture must lie between 0 and 255";
  } else if (!finite_nonneg(min_range_mm) || !finite_nonneg(max_range_mm) || max_range_mm > 1e6) {
    out << "min_range and max_range must be lengths between 0 and 1 km";
  } else if (max_range_mm > 0.0 && max_range_mm <= min_range_mm) {
    out << "max_range must be 0 (none) or larger than min_range";
  } else {
    return true;
  }
  *why = out.str();
  return false;
}

bool ImageSensor::Check(std::string* why) const {
  std::ostringstream out;
  if (!std::isfinite(full_well) || full_well < 0.0 || full_well > 1e9) {
    out << "full_well must lie between 0 (no noise) and 1e9 electrons";
  } else if (!std::isfinite(read_noise) || read_noise < 0.0 || read_noise > 1e6) {
    out << "read_noise must lie between 0 and 1e6 electrons";
  } else if (read_noise > 0.0 && full_well == 0.0) {
    out << "read_noise needs full_well (the electrons at full scale)";
  } else if (!std::isfinite(vignetting) || vignetting < 0.0 || vignetting > 1.0) {
    out << "vignetting must lie between 0 and 1";
  } else {
    return true;
  }
  *why = out.str();
  return false;
}

double KinectV1AxialSigma(double z_mm, double theta_rad) {
  const double d = z_mm / 1000.0 - 0.4;
  double sigma = 1.2 + 1.9 * d * d;
  if (theta_rad > M_PI / 3.0) {
    const double t = std::min(theta_rad, 89.0 * M_PI / 180.0);
    const double r = t / (0.5 * M_PI - t);
    sigma += 0.1 * r * r / std::sqrt(std::max(z_mm, 1.0) / 1000.0);
  }
  return sigma;
}

double StructuredLightSigma(double noise_mm, double z_mm, double signal) {
  const double z = z_mm / 1000.0;
  const double weak = signal < 1.0 ? 1.0 / std::sqrt(std::max(signal, 1e-6)) : 1.0;
  return noise_mm * z * z * weak;
}

double AzureKinectSigma(double z_mm) { return 0.5 + std::max(z_mm - 500.0, 0.0) / 1000.0; }

namespace {

// Two independent standard normal numbers from two uniform draws (Box-Muller).
Eigen::Vector2d GaussianPair(uint64_t seed, const RandomStream& stream, uint64_t index) {
  Eigen::Vector2d z;
  NormalPair(UniformDraw(seed, stream, 2 * index), UniformDraw(seed, stream, 2 * index + 1), &z.x(),
             &z.y());
  return z;
}

// Standard normal number `index` of a stream, numbers 2k and 2k + 1 from Box-Muller pair k: a
// loop over consecutive indices (a row of pixels) draws one pair for every two numbers.
class PairedNormals {
 public:
  // The stream's id is kept (hashed once), not the stream.
  PairedNormals(uint64_t seed, const RandomStream& stream) : seed_(seed), stream_id_(stream.id()) {}
  double operator()(uint64_t index) {
    if (index >> 1 != pair_) {
      pair_ = index >> 1;
      NormalPair(random_detail::Draw(seed_, stream_id_, 2 * pair_),
                 random_detail::Draw(seed_, stream_id_, 2 * pair_ + 1), &z_.x(), &z_.y());
    }
    return z_[index & 1];
  }

 private:
  uint64_t seed_;
  uint64_t stream_id_;
  uint64_t pair_ = ~uint64_t{0};
  Eigen::Vector2d z_;
};

// cos of the angle between the surface and the camera ray of pixel (u, v).
float CosIncidence(const DepthSensorInput& in, int u, int v, size_t p) {
  if (in.normals == nullptr) return 1.0f;
  const Intrinsics& k = in.intrinsics;
  Eigen::Vector3f ray(static_cast<float>((u + 0.5 - k.cx) / k.fx),
                      static_cast<float>((v + 0.5 - k.cy) / k.fy), 1.0f);
  if (k.distortion.active()) {  // the traced ray (a Newton solve per pixel without the table)
    Eigen::Vector2f xy;
    Eigen::Vector2d solved;
    if (in.rays != nullptr && in.rays->Centre(u, v, &xy)) {
      ray = Eigen::Vector3f(xy.x(), xy.y(), 1.0f);
    } else if (k.Unproject(u + 0.5, v + 0.5, &solved)) {
      ray = Eigen::Vector3f(static_cast<float>(solved.x()), static_cast<float>(solved.y()), 1.0f);
    }
  }
  return std::abs(in.normals[p].dot(ray.normalized()));
}

// The 3 x 3 neighbourhood of p spans more than `jump` (zero pixels count as depth 0).
bool Jump(const float* depth, int w, int h, int u, int v, double jump) {
  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
  for (int y = std::max(v - 1, 0); y <= std::min(v + 1, h - 1); ++y) {
    for (int x = std::max(u - 1, 0); x <= std::min(u + 1, w - 1); ++x) {
      const float z = depth[static_cast<size_t>(y) * w + x];
      lo = std::min(lo, z), hi = std::max(hi, z);
    }
  }
  return hi - lo > jump;
}

// The checks every model with a projector makes at pixel p: is there a return at all?
// `min_cos`: cos(m.max_incidence_rad), worked out once per frame.
bool Returns(const DepthModel& m, const DepthSensorInput& in, int u, int v, size_t p,
             float min_cos) {
  const int w = in.intrinsics.width, h = in.intrinsics.height;
  if (!(in.depth[p] > 0.0f) || !m.InRange(in.depth[p])) return false;
  if (in.projector_seen != nullptr && !in.projector_seen[p]) return false;
  const float signal = in.signal != nullptr ? in.signal[p] : 1.0f;
  if (signal < m.min_signal) return false;
  if (m.max_signal > 0.0 && signal > m.max_signal) return false;
  if (m.max_incidence_rad > 0.0 && CosIncidence(in, u, v, p) < min_cos) return false;
  if (m.jump_mm > 0.0 && Jump(in.depth, w, h, u, v, m.jump_mm)) return false;
  return true;
}

// The matcher's strips: an even number of them (two cores share them evenly), each at most 256
// rows, and the rows a strip computes above the rows it keeps (SGBM aggregates costs from the
// rows above, so a strip starts this far up; OpenCV's own stripes overlap by 3 rows and a tenth
// of their height, 11 rows here). Fixed by the image's height alone.
int StereoStrips(int height) { return 2 * std::max(1, (height + 511) / 512); }
constexpr int kStripMarginAbove = 16;

// The columns a strip's match keeps clear of its surfaces on either side: the matcher's paths
// start this far from the first surface pixel (through the dark around it, as on the whole
// image) and pixels beside a surface, whose windows overlap it, can still match (edge fattening).
constexpr int kCropMargin = 16;

// The texture test's window sums at row v of the w-wide 8-bit `image` of height h: for every
// column, the sum and the sum of squares of the block x block window around (u, v), with the
// image mirrored at its edges (OpenCV's BORDER_REFLECT: ...cba|abc...). Exact in integers.
void WindowSums(const uint8_t* image, int w, int h, int v, int block, std::vector<int32_t>* sum,
                std::vector<int32_t>* sum2) {
  const int half = block / 2;
  const auto reflect = [](int i, int n) {
    while (i < 0 || i >= n) i = i < 0 ? -i - 1 : 2 * n - i - 1;
    return i;
  };
  // Column sums over the window's rows, then their running sum along the row.
  std::vector<int32_t> column(static_cast<size_t>(w) + 2 * half), column2(column.size());
  for (int u = -half; u < w + half; ++u) {
    int32_t c = 0, c2 = 0;
    const int x = reflect(u, w);
    for (int dv = -half; dv <= half; ++dv) {
      const int32_t g = image[static_cast<size_t>(reflect(v + dv, h)) * w + x];
      c += g, c2 += g * g;
    }
    column[u + half] = c, column2[u + half] = c2;
  }
  int32_t run = 0, run2 = 0;
  for (int i = 0; i < block; ++i) run += column[i], run2 += column2[i];
  for (int u = 0; u < w; ++u) {
    (*sum)[u] = run, (*sum2)[u] = run2;
    if (u + block < static_cast<int>(column.size())) {
      run += column[u + block] - column[u], run2 += column2[u + block] - column2[u];
    }
  }
}

// active_stereo: OpenCV's StereoSGBM (its vectorised three-path variant, MODE_SGBM_3WAY) on the
// left and right IR images, then z = f B / d. The image is cut into StereoStrips(h) strips matched
// in parallel, each with kStripMarginAbove rows above it (and the window's half below) so that its
// paths start before its first kept row: a fixed cut, the same on any thread count. A strip
// matches only the rectangle around its surfaces (the exact depth), kStripMarginAbove rows above
// and kCropMargin columns either side of them, and searches only the disparities they lie at:
// where no surface is, the projector lights nothing, and the IR images hold read noise alone.
std::vector<float> StereoDepth(const DepthModel& m, const DepthSensorInput& in) {
  const Intrinsics& k = in.intrinsics;
  const int w = k.width, h = k.height;
  std::vector<float> out(static_cast<size_t>(w) * h, 0.0f);
  const int disparities = StereoDisparities(m, k);
  // Every column lies in the invalid band: nothing to match (and OpenCV's 3-way matcher fails on
  // images no wider than its search).
  if (disparities >= w) return out;
  const int strips = StereoStrips(h);
  const int strip_rows = (h + strips - 1) / strips;
  const double fb = k.fx * m.baseline_mm;
  // The texture test: the grey variance of each pixel's block x block window in the left image.
  const double min_variance = m.min_texture * m.min_texture;
  const int area = m.block * m.block;
  tbb::parallel_for(0, strips, [&](int s) {
    const int keep0 = std::min(h, s * strip_rows), keep1 = std::min(h, keep0 + strip_rows);
    if (keep0 >= keep1) return;
    // The surfaces' rows and columns in the kept rows, and the depths over the rows matched.
    int v_first = h, v_last = -1, u_first = w, u_last = -1;
    for (int v = keep0; v < keep1; ++v) {
      const float* row = in.depth + static_cast<size_t>(v) * w;
      int first = 0, last = w - 1;
      while (first < w && !(row[first] > 0.0f)) ++first;
      if (first == w) continue;
      while (!(row[last] > 0.0f)) --last;
      v_first = std::min(v_first, v), v_last = v;
      u_first = std::min(u_first, first), u_last = std::max(u_last, last);
    }
    if (v_last < 0) return;  // nothing in the strip
    const int row0 = std::max(0, v_first - kStripMarginAbove);
    const int row1 = std::min(h, v_last + 1 + m.block / 2 + 1);
    float z_near = std::numeric_limits<float>::infinity(), z_far = 0.0f;
    for (size_t p = size_t(row0) * w; p < size_t(row1) * w; ++p) {
      if (in.depth[p] > 0.0f)
        z_near = std::min(z_near, in.depth[p]), z_far = std::max(z_far, in.depth[p]);
    }
    // The disparities the strip's surfaces lie at (the exact depth), 2 px either side, within the
    // sensor's own range [0, disparities): the matcher searches only those. Its matches are the
    // ones a search of the whole range finds except where that would have matched a disparity no
    // surface has. OpenCV leaves the columns left of the largest disparity searched without a
    // match: about the band a real sensor loses, where the right imager sees nothing (f B / z).
    const double d_far = fb / z_far, d_near = fb / z_near;
    const int high = std::min(disparities, static_cast<int>(std::ceil(d_near)) + 3);
    int low = std::max(0, static_cast<int>(std::floor(d_far)) - 2);
    if (low >= high) return;  // every surface nearer than min_depth: no match
    const int count = std::max(16, 16 * ((high - low + 15) / 16));
    low = std::max(0, std::min(low, disparities - count));
    // The columns: from the first surface less the margin and the search (the right image's
    // columns it matches against), to the last surface and the margin. At least the search and
    // 16 more wide (OpenCV's 3-way matcher needs more columns than it searches).
    int col0 = std::max(0, u_first - kCropMargin - (low + count));
    const int col1 = std::min(w, std::max(u_last + 1 + kCropMargin, col0 + low + count + 16));
    col0 = std::max(0, std::min(col0, col1 - (low + count + 16)));
    // OpenCV reads the rectangle in place; it writes only `disparity`.
    const size_t corner = static_cast<size_t>(row0) * w + col0;
    const cv::Mat left(row1 - row0, col1 - col0, CV_8U, const_cast<uint8_t*>(in.ir_left) + corner,
                       static_cast<size_t>(w));
    const cv::Mat right(row1 - row0, col1 - col0, CV_8U, const_cast<uint8_t*>(in.ir_right) + corner,
                        static_cast<size_t>(w));
    cv::Ptr<cv::StereoSGBM> sgbm = cv::StereoSGBM::create(
        low, count, m.block, 8 * area, 32 * area, /*disp12MaxDiff=*/1,
        /*preFilterCap=*/63, /*uniquenessRatio=*/10,
        /*speckleWindowSize=*/100, /*speckleRange=*/2, cv::StereoSGBM::MODE_SGBM_3WAY);
    cv::Mat disparity;
    sgbm->compute(left, right, disparity);  // CV_16S, 1/16 px; invalid: (low - 1) * 16
    const int invalid = (low - 1) * 16;
    std::vector<int32_t> sum(w), sum2(w);
    for (int v = std::max(keep0, row0); v < std::min(keep1, row1); ++v) {
      const int16_t* row = disparity.ptr<int16_t>(v - row0);
      if (min_variance > 0.0) WindowSums(in.ir_left, w, h, v, m.block, &sum, &sum2);
      for (int u = col0; u < col1; ++u) {
        const int16_t d = row[u - col0];
        if (d <= 0 || d == invalid) continue;
        if (min_variance > 0.0) {
          const double mean = static_cast<double>(sum[u]) / area;
          if (static_cast<double>(sum2[u]) / area - mean * mean < min_variance) continue;
        }
        const size_t p = static_cast<size_t>(v) * w + u;
        if (in.depth[p] > 0.0f && !m.InRange(in.depth[p])) continue;
        out[p] = static_cast<float>(fb * 16.0 / d);
      }
    }
  });
  return out;
}

}  // namespace

int StereoDisparities(const DepthModel& m, const Intrinsics& k) {
  const double largest = k.fx * m.baseline_mm / m.min_depth_mm;
  const int n = 16 * static_cast<int>(std::ceil(largest / 16.0));
  // At most the image's width less one, rounded down to 16 (OpenCV's SGBM needs a multiple of 16;
  // at least 16 even for images narrower than 17 px, which then have no depth).
  return std::max(16, std::min(n, 16 * ((k.width - 1) / 16)));
}

uint64_t ImageNoiseSeed(const ImageSensor& sensor, uint64_t view) {
  return static_cast<uint64_t>(UniformDraw(sensor.seed, streams::kImageFrame, view) *
                               9007199254740992.0);
}

Eigen::Vector2d ImageNoisePair(uint64_t frame_seed, uint64_t pixel, int pair) {
  return GaussianPair(frame_seed, streams::kImageNoise, (pixel << 1) + static_cast<uint64_t>(pair));
}

std::vector<float> GreyImageNoise(uint64_t frame_seed, size_t pixels) {
  std::vector<float> noise(pixels);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, (pixels + 1) / 2, 4096),
                    [&](const tbb::blocked_range<size_t>& pairs) {
                      for (size_t k = pairs.begin(); k < pairs.end(); ++k) {
                        const Eigen::Vector2d z =
                            GaussianPair(frame_seed, streams::kImageNoiseGrey, k);
                        noise[2 * k] = static_cast<float>(z.x());
                        if (2 * k + 1 < pixels) noise[2 * k + 1] = static_cast<float>(z.y());
                      }
                    });
  return noise;
}

namespace {

// DotPattern at (x, y) with the dots of the cells around it given by `dot(i, j, &cx, &cy)` (false:
// cell (i, j) holds no dot): the hash of DotPattern or DotTable's table.
template <class Dots>
float PatternAt(const DepthModel& m, double fx, double x, double y, Dots&& dot) {
  const double pitch = m.dot_spacing_px / fx;
  const double gx = x / pitch, gy = y / pitch;
  const double fi = std::floor(gx), fj = std::floor(gy);
  if (!(std::abs(fi) < 1 << 20) || !(std::abs(fj) < 1 << 20)) return 0.0f;
  const int i0 = static_cast<int>(fi), j0 = static_cast<int>(fj);
  // A dot is a Gaussian of sigma 0.35 cell; a pixel sees it integrated over its footprint (1 /
  // dot_spacing cells across), which widens the Gaussian by the box's variance and keeps its mass.
  constexpr double kSigma2 = 0.35 * 0.35;
  const double footprint = 1.0 / m.dot_spacing_px;
  const double sigma2 = kSigma2 + footprint * footprint / 12.0;
  const double peak = kSigma2 / sigma2;
  double sum = 0.0;
  for (int j = j0 - 1; j <= j0 + 1; ++j) {
    for (int i = i0 - 1; i <= i0 + 1; ++i) {
      // Dots end at 3 sigma: cells farther from the point than that are skipped undrawn.
      const double ex = std::max({i - gx, gx - (i + 1), 0.0});
      const double ey = std::max({j - gy, gy - (j + 1), 0.0});
      if (ex * ex + ey * ey > 9.0 * sigma2) continue;
      double cx, cy;
      if (!dot(i, j, &cx, &cy)) continue;
      const double r2 = (gx - cx) * (gx - cx) + (gy - cy) * (gy - cy);
      if (r2 > 9.0 * sigma2) continue;
      sum += peak * std::exp(-r2 / (2.0 * sigma2));
    }
  }
  return static_cast<float>(std::min(sum, 1.0));
}

// The dot of cell (i, j), drawn from the sensor's seed: present with probability 1/2, at a uniform
// place in the cell.
bool HashedDot(uint64_t seed, int i, int j, double* cx, double* cy) {
  constexpr uint64_t kDots = streams::kSensorDots.id();  // hashed at compile time
  const auto draw = [&](uint64_t index) { return random_detail::Draw(seed, kDots, index); };
  const uint64_t cell =
      ((static_cast<uint64_t>(i + (1 << 20))) << 21) + static_cast<uint64_t>(j + (1 << 20));
  if (draw(cell << 2) >= 0.5) return false;
  *cx = i + draw((cell << 2) + 1);
  *cy = j + draw((cell << 2) + 2);
  return true;
}

}  // namespace

float DotPattern(const DepthModel& m, double fx, double x, double y) {
  return PatternAt(m, fx, x, y, [&](int i, int j, double* cx, double* cy) {
    return HashedDot(m.seed, i, j, cx, cy);
  });
}

DotTable::DotTable(const DepthModel& model, double fx, double x0, double x1, double y0, double y1)
    : model_(model), fx_(fx), x0_(x0), x1_(x1), y0_(y0), y1_(y1) {
  const double pitch = model.dot_spacing_px / fx;
  inv_pitch_ = 1.0 / pitch;
  // PatternAt's dot: peak exp(-r^2 / (2 sigma^2)) out to 3 sigma, in cells.
  constexpr double kSigma2 = 0.35 * 0.35;
  const double footprint = 1.0 / model.dot_spacing_px;
  const double sigma2 = kSigma2 + footprint * footprint / 12.0;
  peak_ = static_cast<float>(kSigma2 / sigma2);
  exponent_ = static_cast<float>(-0.5 / sigma2);
  cut2_ = static_cast<float>(9.0 * sigma2);
  const auto cell = [&](double t) {
    return static_cast<int>(std::clamp(std::floor(t / pitch), -1048575.0, 1048575.0));
  };
  i0_ = cell(std::min(x0, x1)) - 1, j0_ = cell(std::min(y0, y1)) - 1;
  ni_ = cell(std::max(x0, x1)) + 2 - i0_, nj_ = cell(std::max(y0, y1)) + 2 - j0_;
  if (static_cast<double>(ni_) * nj_ > 64e6) ni_ = nj_ = 0;  // a window too wide: hash every dot
  centres_.assign(static_cast<size_t>(ni_) * nj_, Eigen::Vector2f(kNone, kNone));
  tbb::parallel_for(0, nj_, [&](int b) {
    for (int a = 0; a < ni_; ++a) {
      double cx, cy;
      if (HashedDot(model.seed, i0_ + a, j0_ + b, &cx, &cy)) {
        // Kept relative to the cell's corner: the float keeps 1e-7 of a cell.
        centres_[static_cast<size_t>(b) * ni_ + a] =
            Eigen::Vector2f(static_cast<float>(cx - (i0_ + a)), static_cast<float>(cy - (j0_ + b)));
      }
    }
  });
}

bool DotTable::Is(const DepthModel& model, double fx, double x0, double x1, double y0,
                  double y1) const {
  return model.seed == model_.seed && model.dot_spacing_px == model_.dot_spacing_px && fx == fx_ &&
         x0 == x0_ && x1 == x1_ && y0 == y0_ && y1 == y1_;
}

float DotTable::operator()(double x, double y) const {
  float out;
  (*this)(1, &x, &y, &out);
  return out;
}

void DotTable::operator()(int n, const double* x, const double* y, float* out) const {
  // Per cell around a point (9) and point (16, the inner index): the point's offset from the
  // cell's dot, in cells, single precision relative to the point's cell. A cell without a dot, and
  // a point outside the table (drawn by the hash below), sit kNone away. Plain loops over the 144
  // pairs: the compiler runs them 4 or 8 at a time.
  constexpr int kLanes = 16, kPairs = 9 * kLanes;
  alignas(64) float dx[kPairs], dy[kPairs];
  std::fill(dx, dx + kPairs, kNone);
  std::fill(dy, dy + kPairs, kNone);
  bool hashed[kLanes] = {};
  n = std::min(n, kLanes);
  for (int l = 0; l < n; ++l) {
    const double gx = x[l] * inv_pitch_, gy = y[l] * inv_pitch_;
    const double fi = std::floor(gx), fj = std::floor(gy);
    const double a = fi - i0_, b = fj - j0_;
    if (!(a >= 1.0 && b >= 1.0 && a + 2.0 <= ni_ && b + 2.0 <= nj_)) {
      hashed[l] = true;
      continue;
    }
    const float px = static_cast<float>(gx - fi), py = static_cast<float>(gy - fj);
    const Eigen::Vector2f* row =
        &centres_[(static_cast<size_t>(b) - 1) * ni_ + static_cast<size_t>(a)];
    for (int dj = -1, c = 0; dj <= 1; ++dj, row += ni_) {
      for (int di = -1; di <= 1; ++di, ++c) {
        dx[c * kLanes + l] = px - (static_cast<float>(di) + row[di].x());
        dy[c * kLanes + l] = py - (static_cast<float>(dj) + row[di].y());
      }
    }
  }
  // exp(-r^2 / (2 sigma^2)) out to the cut (3 sigma): 2^t, t = k + f with k whole and |f| <= 1/2,
  // 2^f by its Taylor series to f^6 (within 1.2e-7 of it) and 2^k in the exponent's bits, which
  // are all 0 (the number 0) beyond the cut.
  alignas(64) float t[kPairs], dots[kPairs];
  alignas(64) int32_t k[kPairs], inside[kPairs];
  const float scale = exponent_ * 1.44269504f;  // log2(e)
  for (int i = 0; i < kPairs; ++i) {
    const float r2 = dx[i] * dx[i] + dy[i] * dy[i];
    inside[i] = r2 <= cut2_ ? -1 : 0;
    t[i] = std::min(r2, cut2_) * scale;        // in [-6.5, 0]
    k[i] = static_cast<int32_t>(t[i] - 0.5f);  // rounds to nearest: t <= 0, truncation
  }
  for (int i = 0; i < kPairs; ++i) {
    const float f = t[i] - static_cast<float>(k[i]);
    dots[i] =
        1.0f + f * (0.693147181f +
                    f * (0.240226507f +
                         f * (0.0555041087f +
                              f * (0.00961812911f + f * (0.00133335581f + f * 1.54035304e-4f)))));
    k[i] = ((k[i] + 127) << 23) & inside[i];
  }
  alignas(64) float two_k[kPairs];
  std::memcpy(two_k, k, sizeof two_k);
  for (int i = 0; i < kPairs; ++i) dots[i] *= two_k[i];
  for (int l = 0; l < n; ++l) {
    if (hashed[l]) {
      out[l] = PatternAt(model_, fx_, x[l], y[l], [&](int i, int j, double* cx, double* cy) {
        return HashedDot(model_.seed, i, j, cx, cy);
      });
      continue;
    }
    float sum = 0.0f;
    for (int c = 0; c < 9; ++c) sum += dots[c * kLanes + l];
    out[l] = std::min(sum * peak_, 1.0f);
  }
}

double InfraredGain(const std::vector<float>& linear) {
  if (linear.empty()) return 1.0;
  const size_t at = linear.size() * 99 / 100;
  // The 99th percentile exactly, without sorting the image: the floats' bits made into keys
  // that sort as the numbers do, counted in 4096 bins by their top 12 bits (in parallel: counts
  // add up the same in any order), then the value of rank `at` among the few in its bin.
  const auto key = [](float value) {
    uint32_t bits;
    std::memcpy(&bits, &value, sizeof bits);
    return bits ^ ((bits >> 31) != 0 ? 0xffffffffu : 0x80000000u);
  };
  using Histogram = std::vector<size_t>;
  const Histogram counts = tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, linear.size(), 1 << 16), Histogram(4096, 0),
      [&](const tbb::blocked_range<size_t>& r, Histogram h) {
        for (size_t p = r.begin(); p < r.end(); ++p) ++h[key(linear[p]) >> 20];
        return h;
      },
      [](Histogram a, const Histogram& b) {
        for (size_t i = 0; i < a.size(); ++i) a[i] += b[i];
        return a;
      });
  size_t below = 0;
  uint32_t bin = 0;
  while (below + counts[bin] <= at) below += counts[bin++];
  std::vector<float> in_bin;
  in_bin.reserve(counts[bin]);
  for (float value : linear) {
    if (key(value) >> 20 == bin) in_bin.push_back(value);
  }
  std::nth_element(in_bin.begin(), in_bin.begin() + (at - below), in_bin.end());
  const double top = in_bin[at - below];
  return top > 0.0 ? std::clamp(0.8 / top, 0.25, 64.0) : 1.0;
}

std::array<std::vector<uint8_t>, 2> InfraredImages(const DepthModel& m, uint64_t view,
                                                   const std::vector<float>& left,
                                                   const std::vector<float>& right, double gain) {
  if (left.size() != right.size()) throw std::invalid_argument("IR images of different sizes");
  const auto frame_seed =
      static_cast<uint64_t>(UniformDraw(m.seed, streams::kSensorFrame, view) * 9007199254740992.0);
  std::array<std::vector<uint8_t>, 2> out{std::vector<uint8_t>(left.size()),
                                          std::vector<uint8_t>(left.size())};
  const auto g = static_cast<float>(gain), sigma = static_cast<float>(m.ir_noise);
  // Blocks of pixels (the cut and the draws depend on the pixel alone, not on the thread).
  constexpr size_t kBlock = 256;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, (left.size() + kBlock - 1) / kBlock, 16),
                    [&](const tbb::blocked_range<size_t>& blocks) {
                      uint64_t bits[kBlock];
                      float zl[kBlock], zr[kBlock];
                      for (size_t b = blocks.begin(); b < blocks.end(); ++b) {
                        const size_t p0 = b * kBlock, n = std::min(kBlock, left.size() - p0);
                        if (sigma > 0.0f) {
                          // One draw per pixel: a normal pair, left and right.
                          constexpr uint64_t kStream = streams::kSensorInfrared.id();
                          for (size_t i = 0; i < n; ++i)
                            bits[i] = random_detail::DrawBits(frame_seed, kStream, p0 + i);
                          NormalPairsFloat(bits, static_cast<int>(n), zl, zr);
                        } else {
                          std::fill(zl, zl + n, 0.0f), std::fill(zr, zr + n, 0.0f);
                        }
                        // Rounded to 8 bits: + 0.5 and truncated, within [0, 255].
                        for (size_t i = 0; i < n; ++i) {
                          const float l = 255.0f * (g * left[p0 + i] + sigma * zl[i]) + 0.5f;
                          const float r = 255.0f * (g * right[p0 + i] + sigma * zr[i]) + 0.5f;
                          out[0][p0 + i] = static_cast<uint8_t>(std::clamp(l, 0.0f, 255.0f));
                          out[1][p0 + i] = static_cast<uint8_t>(std::clamp(r, 0.0f, 255.0f));
                        }
                      }
                    });
  return out;
}

std::vector<float> SimulateDepth(const DepthModel& m, const DepthSensorInput& in, uint64_t view) {
  const int w = in.intrinsics.width, h = in.intrinsics.height;
  const size_t n = static_cast<size_t>(w) * h;
  if (m.kind == DepthModel::Kind::kIdeal) return std::vector<float>(in.depth, in.depth + n);
  if (m.kind == DepthModel::Kind::kActiveStereo) {
    if (in.ir_left == nullptr || in.ir_right == nullptr)
      throw std::invalid_argument("active_stereo needs the two IR images");
    return StereoDepth(m, in);
  }
  std::vector<float> out(n, 0.0f);
  const auto min_cos = static_cast<float>(std::cos(m.max_incidence_rad));
  // One seed per frame: draws are indexed by pixel (and axis), never by thread or order.
  const auto frame_seed =
      static_cast<uint64_t>(UniformDraw(m.seed, streams::kSensorFrame, view) * 9007199254740992.0);

  if (m.kind == DepthModel::Kind::kKinectV1) {
    const double fb = m.focal_px * std::abs(m.baseline_mm);
    const double step = m.disparity_step_px;
    tbb::parallel_for(0, h, [&](int v) {
      PairedNormals axial(frame_seed, streams::kSensorAxial);
      for (int u = 0; u < w; ++u) {
        const size_t p = static_cast<size_t>(v) * w + u;
        // Lateral noise: the pixel reads the depth of a neighbour, further on oblique surfaces.
        int su = u, sv = v;
        if (m.lateral_px > 0.0 && in.depth[p] > 0.0f) {
          const double cos_t = std::clamp<double>(CosIncidence(in, u, v, p), 0.0, 1.0);
          const double theta = std::min(std::acos(cos_t), 89.0 * M_PI / 180.0);
          const double sigma = m.lateral_px + 0.035 * theta / (0.5 * M_PI - theta);
          const Eigen::Vector2d shift =
              sigma * GaussianPair(frame_seed, streams::kSensorLateral, p);
          const double du = shift.x(), dv = shift.y();
          su = std::clamp(u + static_cast<int>(std::lround(std::clamp(du, -8.0, 8.0))), 0, w - 1);
          sv = std::clamp(v + static_cast<int>(std::lround(std::clamp(dv, -8.0, 8.0))), 0, h - 1);
        }
        const size_t sp = static_cast<size_t>(sv) * w + su;
        if (!Returns(m, in, su, sv, sp, min_cos)) continue;
        const double z = in.depth[sp];
        // Axial noise: the formula's total, less what the quantisation below adds.
        const double q = z * z / fb * step;  // the depth step of one disparity quantum at z
        const double cos_sp = std::clamp<double>(CosIncidence(in, su, sv, sp), 0.0, 1.0);
        const double sigma = KinectV1AxialSigma(z, cos_sp < 0.5 ? std::acos(cos_sp) : 0.0);
        const double added = std::sqrt(std::max(0.0, sigma * sigma - q * q / 12.0));
        const double noisy = z + added * axial(p);
        if (!(noisy > 0.0)) continue;
        const double levels = std::round(fb / noisy / step);
        if (!(levels > 0.0)) continue;
        out[p] = static_cast<float>(fb / (levels * step));
      }
    });
    return out;
  }

  if (m.kind == DepthModel::Kind::kAzureKinect) {
    // BlenderProc's order: shift (bilinear), noise, then holes from the noisy depth's 3 x 3 span
    // and from dark colour.
    std::vector<float> noisy(n, 0.0f);
    tbb::parallel_for(0, h, [&](int v) {
      PairedNormals axial(frame_seed, streams::kSensorAxial);
      for (int u = 0; u < w; ++u) {
        const size_t p = static_cast<size_t>(v) * w + u;
        double x = u, y = v;
        if (m.lateral_px > 0.0) {
          const Eigen::Vector2d shift =
              m.lateral_px * GaussianPair(frame_seed, streams::kSensorLateral, p);
          x += shift.x(), y += shift.y();
        }
        x = std::clamp(x, 0.0, w - 1.0), y = std::clamp(y, 0.0, h - 1.0);
        const int x0 = std::min(static_cast<int>(x), w - 1),
                  y0 = std::min(static_cast<int>(y), h - 1);
        const int x1 = std::min(x0 + 1, w - 1), y1 = std::min(y0 + 1, h - 1);
        const double fx = x - x0, fy = y - y0;
        const auto at = [&](int xx, int yy) {
          return static_cast<double>(in.depth[static_cast<size_t>(yy) * w + xx]);
        };
        double z = (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x1, y0)) +
                   fy * ((1 - fx) * at(x0, y1) + fx * at(x1, y1));
        if (!(z > 0.0)) continue;
        z += AzureKinectSigma(z) * axial(p);
        noisy[p] = static_cast<float>(std::max(z, 0.0));
      }
    });
    tbb::parallel_for(0, h, [&](int v) {
      for (int u = 0; u < w; ++u) {
        const size_t p = static_cast<size_t>(v) * w + u;
        if (!(noisy[p] > 0.0f) || !m.InRange(in.depth[p])) continue;
        if (m.jump_mm > 0.0 && Jump(noisy.data(), w, h, u, v, m.jump_mm)) continue;
        if (in.rgb != nullptr && m.dark_gray > 0) {
          const uint8_t* c = in.rgb + 3 * p;
          const int gray =
              static_cast<int>(std::lround(0.299 * c[0] + 0.587 * c[1] + 0.114 * c[2]));
          if (gray < m.dark_gray) continue;
        }
        out[p] = noisy[p];
      }
    });
    return out;
  }

  // Structured light: exact where camera and projector both see the point, small noise.
  tbb::parallel_for(0, h, [&](int v) {
    PairedNormals axial(frame_seed, streams::kSensorAxial);
    for (int u = 0; u < w; ++u) {
      const size_t p = static_cast<size_t>(v) * w + u;
      if (!Returns(m, in, u, v, p, min_cos)) continue;
      const double z = in.depth[p];
      const double sigma =
          StructuredLightSigma(m.noise_mm, z, in.signal != nullptr ? in.signal[p] : 1.0);
      const double noisy = z + sigma * axial(p);
      out[p] = static_cast<float>(std::max(noisy, 0.0));
    }
  });
  return out;
}

}  // namespace cadsynth
