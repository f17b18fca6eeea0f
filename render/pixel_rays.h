// The camera rays of an image's pixels (internal to render/): the one place that turns pixels into
// rays, for the labels' rays, the colour samples and the amodal canvas alike. A pinhole camera's
// x(u) and y(v) are tabulated apart; a camera with lens distortion has (x, y) tabulated per pixel
// centre (Intrinsics::Unproject), and other points of a pixel start Newton's method from it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "render/camera.h"

namespace cadsynth {

class PixelRays {
 public:
  // Builds the tables (in parallel with distortion; the same values on any thread count).
  explicit PixelRays(const Intrinsics& k);

  const Intrinsics& intrinsics() const { return k_; }
  bool distorted() const { return distorted_; }

  // The ray (x, y, 1) through the centre of pixel (u, v) of the image; false if it has none.
  bool Centre(int u, int v, Eigen::Vector2f* xy) const {
    if (!distorted_) {
      *xy = Eigen::Vector2f(xs_[static_cast<size_t>(u)], ys_[static_cast<size_t>(v)]);
      return true;
    }
    const size_t p = static_cast<size_t>(v) * k_.width + u;
    *xy = table_[p];
    return ok_[p] != 0;
  }
  // The ray through image point (u + du, v + dv), for pixel (u, v) of the image and du, dv in
  // [0, 1]; Centre's at du = dv = 0.5.
  // (u + du is summed in single precision, as the path tracer always has.)
  bool At(int u, int v, float du, float dv, Eigen::Vector2f* xy) const;
  // The ray through the centre of pixel (u, v) anywhere on the plane (the amodal canvas); Centre's
  // inside the image.
  bool Anywhere(int u, int v, Eigen::Vector2f* xy) const;
  // A pinhole camera's x(u) = (u + du - cx) / fx for u in [0, width + pad), y(v) likewise.
  void Tabulate(double du, double dv, int pad, std::vector<float>* xs,
                std::vector<float>* ys) const;

  // A distorted camera's pixels [u0, u1) x [v0, v1) whose rays can pass through the rectangle
  // [x0, x1] x [y0, y1] of the plane z = 1, clamped to `bounds` (u0, v0, u1, v1): the box around
  // the distorted border of the rectangle's part inside the fold radius (sampled finely, with two
  // pixels of margin). Empty (u0 = u1) when none can. (A pinhole's: renderer.cpp's ProjectedRect.)
  void RectOfPlane(double x0, double y0, double x1, double y1, const int bounds[4],
                   int out[4]) const;

 private:
  Intrinsics k_;
  bool distorted_ = false;
  double fold_ = 0.0;
  std::vector<float> xs_, ys_;          // pinhole
  std::vector<Eigen::Vector2f> table_;  // distorted: per pixel centre
  std::vector<uint8_t> ok_;
};

}  // namespace cadsynth
