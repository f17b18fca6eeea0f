#include "render/sensor.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include <tbb/parallel_for.h>

#include "cad/random.h"

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
  } else {
    return true;
  }
  *why = out.str();
  return false;
}

double KinectV1AxialSigma(double z_mm) {
  const double d = z_mm / 1000.0 - 0.4;
  return 1.2 + 1.9 * d * d;
}

double AzureKinectSigma(double z_mm) { return 0.5 + std::max(z_mm - 500.0, 0.0) / 1000.0; }

namespace {

// Two independent standard normal numbers from two uniform draws (Box-Muller).
Eigen::Vector2d GaussianPair(uint64_t seed, const RandomStream& stream, uint64_t index) {
  const double u1 = UniformDraw(seed, stream, 2 * index);
  const double u2 = UniformDraw(seed, stream, 2 * index + 1);
  const double r = std::sqrt(-2.0 * std::log(1.0 - u1));
  return Eigen::Vector2d(r * std::cos(2.0 * M_PI * u2), r * std::sin(2.0 * M_PI * u2));
}

// One standard normal number: the first of the pair.
double Gaussian(uint64_t seed, const RandomStream& stream, uint64_t index) {
  return GaussianPair(seed, stream, index).x();
}

// cos of the angle between the surface and the camera ray of pixel (u, v).
float CosIncidence(const DepthSensorInput& in, int u, int v, size_t p) {
  if (in.normals == nullptr) return 1.0f;
  const Intrinsics& k = in.intrinsics;
  const Eigen::Vector3f ray(static_cast<float>((u + 0.5 - k.cx) / k.fx),
                            static_cast<float>((v + 0.5 - k.cy) / k.fy), 1.0f);
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
bool Returns(const DepthModel& m, const DepthSensorInput& in, int u, int v, size_t p) {
  const int w = in.intrinsics.width, h = in.intrinsics.height;
  if (!(in.depth[p] > 0.0f)) return false;
  if (in.projector_seen != nullptr && !in.projector_seen[p]) return false;
  const float signal = in.signal != nullptr ? in.signal[p] : 1.0f;
  if (signal < m.min_signal) return false;
  if (m.max_signal > 0.0 && signal > m.max_signal) return false;
  if (m.max_incidence_rad > 0.0 &&
      CosIncidence(in, u, v, p) < static_cast<float>(std::cos(m.max_incidence_rad)))
    return false;
  if (m.jump_mm > 0.0 && Jump(in.depth, w, h, u, v, m.jump_mm)) return false;
  return true;
}

}  // namespace

std::vector<float> SimulateDepth(const DepthModel& m, const DepthSensorInput& in, uint64_t view) {
  const int w = in.intrinsics.width, h = in.intrinsics.height;
  const size_t n = static_cast<size_t>(w) * h;
  if (m.kind == DepthModel::Kind::kIdeal) return std::vector<float>(in.depth, in.depth + n);
  std::vector<float> out(n, 0.0f);
  // One seed per frame: draws are indexed by pixel (and axis), never by thread or order.
  const auto frame_seed =
      static_cast<uint64_t>(UniformDraw(m.seed, streams::kSensorFrame, view) * 9007199254740992.0);

  if (m.kind == DepthModel::Kind::kKinectV1) {
    const double fb = m.focal_px * std::abs(m.baseline_mm);
    const double step = m.disparity_step_px;
    tbb::parallel_for(0, h, [&](int v) {
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
        if (!Returns(m, in, su, sv, sp)) continue;
        const double z = in.depth[sp];
        // Axial noise: the formula's total, less what the quantisation below adds.
        const double q = z * z / fb * step;  // the depth step of one disparity quantum at z
        const double sigma = KinectV1AxialSigma(z);
        const double added = std::sqrt(std::max(0.0, sigma * sigma - q * q / 12.0));
        const double noisy = z + added * Gaussian(frame_seed, streams::kSensorAxial, p);
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
        z += AzureKinectSigma(z) * Gaussian(frame_seed, streams::kSensorAxial, p);
        noisy[p] = static_cast<float>(std::max(z, 0.0));
      }
    });
    tbb::parallel_for(0, h, [&](int v) {
      for (int u = 0; u < w; ++u) {
        const size_t p = static_cast<size_t>(v) * w + u;
        if (!(noisy[p] > 0.0f)) continue;
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
    for (int u = 0; u < w; ++u) {
      const size_t p = static_cast<size_t>(v) * w + u;
      if (!Returns(m, in, u, v, p)) continue;
      const double z = in.depth[p];
      const double sigma = m.noise_mm * (z / 1000.0) * (z / 1000.0);
      const double noisy = z + sigma * Gaussian(frame_seed, streams::kSensorAxial, p);
      out[p] = static_cast<float>(std::max(noisy, 0.0));
    }
  });
  return out;
}

}  // namespace cadsynth
