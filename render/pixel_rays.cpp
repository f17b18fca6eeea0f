#include "render/pixel_rays.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <tbb/parallel_for.h>

namespace cadsynth {

PixelRays::PixelRays(const Intrinsics& k) : k_(k), distorted_(k.distortion.active()) {
  if (!distorted_) {
    Tabulate(0.5, 0.5, 4, &xs_, &ys_);
    return;
  }
  fold_ = k.distortion.FoldRadius();
  const size_t w = static_cast<size_t>(k.width);
  table_.assign(w * k.height, Eigen::Vector2f::Zero());
  ok_.assign(w * k.height, 0);
  // Row by row, each pixel's Newton iteration starting from its left neighbour's ray (the first
  // from the pinhole's): a row's values do not depend on which thread computes it.
  tbb::parallel_for(0, k.height, [&](int v) {
    Eigen::Vector2d guess((0.5 - k.cx) / k.fx, (v + 0.5 - k.cy) / k.fy);
    bool have = false;
    for (int u = 0; u < k.width; ++u) {
      const Eigen::Vector2d pinhole((u + 0.5 - k.cx) / k.fx, (v + 0.5 - k.cy) / k.fy);
      Eigen::Vector2d xy;
      bool ok = k.distortion.Undistort(pinhole, have ? guess : pinhole, &xy);
      if (!ok && have) ok = k.distortion.Undistort(pinhole, pinhole, &xy);
      const size_t p = static_cast<size_t>(v) * w + u;
      if (ok) {
        table_[p] = xy.cast<float>();
        ok_[p] = 1;
        guess = xy;
      }
      have = ok;
    }
  });
}

bool PixelRays::At(int u, int v, float du, float dv, Eigen::Vector2f* xy) const {
  if (!distorted_) {
    *xy = Eigen::Vector2f(static_cast<float>((u + du - k_.cx) / k_.fx),
                          static_cast<float>((v + dv - k_.cy) / k_.fy));
    return true;
  }
  Eigen::Vector2f centre;
  const bool have = Centre(u, v, &centre);
  if (du == 0.5f && dv == 0.5f) {
    *xy = centre;
    return have;
  }
  const Eigen::Vector2d pinhole((u + du - k_.cx) / k_.fx, (v + dv - k_.cy) / k_.fy);
  Eigen::Vector2d out;
  if (!k_.distortion.Undistort(pinhole, have ? Eigen::Vector2d(centre.cast<double>()) : pinhole,
                               &out))
    return false;
  *xy = out.cast<float>();
  return true;
}

bool PixelRays::Anywhere(int u, int v, Eigen::Vector2f* xy) const {
  if (u >= 0 && v >= 0 && u < k_.width && v < k_.height) return Centre(u, v, xy);
  const Eigen::Vector2d pinhole((u + 0.5 - k_.cx) / k_.fx, (v + 0.5 - k_.cy) / k_.fy);
  if (!distorted_) {
    *xy = pinhole.cast<float>();
    return true;
  }
  Eigen::Vector2d out;
  if (!k_.distortion.Undistort(pinhole, pinhole, &out)) return false;
  *xy = out.cast<float>();
  return true;
}

void PixelRays::Tabulate(double du, double dv, int pad, std::vector<float>* xs,
                         std::vector<float>* ys) const {
  xs->resize(static_cast<size_t>(k_.width + pad));
  ys->resize(static_cast<size_t>(k_.height + pad));
  for (size_t u = 0; u < xs->size(); ++u) (*xs)[u] = static_cast<float>((u + du - k_.cx) / k_.fx);
  for (size_t v = 0; v < ys->size(); ++v) (*ys)[v] = static_cast<float>((v + dv - k_.cy) / k_.fy);
}

void PixelRays::RectOfPlane(double x0, double y0, double x1, double y1, const int bounds[4],
                            int out[4]) const {
  const auto clamp = [](double x, int lo, int hi) {
    return static_cast<int>(std::clamp(x, static_cast<double>(lo), static_cast<double>(hi)));
  };
  double umin = std::numeric_limits<double>::infinity(), vmin = umin;
  double umax = -umin, vmax = -umin;
  const auto add = [&](const Eigen::Vector2d& xy) {
    const Eigen::Vector2d d = k_.distortion.Distort(xy);
    const double u = k_.fx * d.x() + k_.cx, v = k_.fy * d.y() + k_.cy;
    umin = std::min(umin, u), umax = std::max(umax, u);
    vmin = std::min(vmin, v), vmax = std::max(vmax, v);
  };
  // Only the part of the rectangle inside the fold radius is imaged; the distortion maps that
  // part one-to-one, so its image is bounded by the image of its border: the rectangle's edges
  // inside the fold, and the fold circle's arcs inside the rectangle.
  const double r = fold_ * (1.0 - 1e-9);
  if (std::isfinite(r)) {
    x0 = std::max(x0, -r), y0 = std::max(y0, -r), x1 = std::min(x1, r), y1 = std::min(y1, r);
  } else {
    // No fold: every ray within 89.94 degrees of the axis (|x|, |y| <= 1000) is imaged.
    const double big = 1e3;
    x0 = std::max(x0, -big), y0 = std::max(y0, -big), x1 = std::min(x1, big),
    y1 = std::min(y1, big);
  }
  if (!(x0 <= x1 && y0 <= y1)) {
    out[0] = out[2] = bounds[0], out[1] = out[3] = bounds[1];
    return;
  }
  // A sample every pixel or two of the pinhole's image of the longer edge (and of the fold
  // circle, when the rectangle reaches past it): the distorted border between samples strays
  // from their box by far less than the margin.
  const auto count = [](double pixels) {
    return static_cast<int>(std::clamp(0.5 * pixels + 8.0, 8.0, 65536.0));
  };
  const int edge_samples = count(std::max(k_.fx * (x1 - x0), k_.fy * (y1 - y0)));
  for (int i = 0; i <= edge_samples; ++i) {
    const double t = static_cast<double>(i) / edge_samples;
    for (const Eigen::Vector2d& p :
         {Eigen::Vector2d(x0 + t * (x1 - x0), y0), Eigen::Vector2d(x0 + t * (x1 - x0), y1),
          Eigen::Vector2d(x0, y0 + t * (y1 - y0)), Eigen::Vector2d(x1, y0 + t * (y1 - y0))}) {
      if (p.norm() <= r) add(p);
    }
  }
  const double far_corner =
      std::max(std::hypot(x0, y0),
               std::max(std::hypot(x0, y1), std::max(std::hypot(x1, y0), std::hypot(x1, y1))));
  if (std::isfinite(r) && far_corner > r) {
    const int circle_samples = count(2.0 * M_PI * r * std::max(k_.fx, k_.fy));
    for (int i = 0; i < circle_samples; ++i) {
      const double a = 2.0 * M_PI * i / circle_samples;
      const Eigen::Vector2d p(r * std::cos(a), r * std::sin(a));
      if (p.x() >= x0 && p.x() <= x1 && p.y() >= y0 && p.y() <= y1) add(p);
    }
  }
  if (!std::isfinite(umin)) {
    out[0] = out[2] = bounds[0], out[1] = out[3] = bounds[1];
    return;
  }
  // Pixel centres at +0.5: pixel u is inside when umin <= u + 0.5 <= umax; two pixels more.
  constexpr double margin = 2.0;
  out[0] = clamp(std::floor(umin - 0.5) - margin, bounds[0], bounds[2]);
  out[2] = clamp(std::ceil(umax - 0.5) + margin + 1, bounds[0], bounds[2]);
  out[1] = clamp(std::floor(vmin - 0.5) - margin, bounds[1], bounds[3]);
  out[3] = clamp(std::ceil(vmax - 0.5) + margin + 1, bounds[1], bounds[3]);
}

}  // namespace cadsynth
