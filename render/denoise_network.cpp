// The denoiser network (render/denoise.h, DenoiseWithNetwork): features in, OpenCV's dnn module,
// radiance out. The ONNX model is linked into the library (render/models/denoiser_model.cpp).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <tbb/parallel_for.h>
#include <opencv2/core.hpp>
#include <opencv2/dnn.hpp>

#include "cad/core/error.h"
#include "render/denoise.h"

// The model's bytes (render/models/denoiser_model.cpp).
extern "C" const char cadsynth_denoiser_onnx[];
extern "C" const char cadsynth_denoiser_onnx_end[];

namespace cadsynth {

// (The library is built in unity batches, where denoise.cpp's anonymous namespace is this one:
// the names below are the network's own.)
namespace {

constexpr float kMaxRatio = 1e4f;  // L / s and sigma / s are at most this
constexpr int kChannels = 12;
constexpr int kDownsamplings = 3;  // the image is padded to a multiple of 2^3

// The upper median (element n / 2 of the sorted values); 1 where there are none.
float UpperMedian(std::vector<float> values) {
  if (values.empty()) return 1.0f;
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

// Networks ready to run: cv::dnn::Net::forward may not be called from two threads at once, and
// frames are denoised in parallel, so each call takes one from the pool (or reads a new one).
class NetPool {
 public:
  cv::dnn::Net Take() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!free_.empty()) {
        cv::dnn::Net net = free_.back();
        free_.pop_back();
        return net;
      }
    }
    const size_t size = static_cast<size_t>(cadsynth_denoiser_onnx_end - cadsynth_denoiser_onnx);
    cv::dnn::Net net = cv::dnn::readNetFromONNX(cadsynth_denoiser_onnx, size);
    net.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
    net.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
    return net;
  }
  void Give(cv::dnn::Net net) {
    std::lock_guard<std::mutex> lock(mutex_);
    free_.push_back(std::move(net));
  }

 private:
  std::mutex mutex_;
  std::vector<cv::dnn::Net> free_;
};

NetPool& Pool() {
  static NetPool pool;
  return pool;
}

}  // namespace

std::vector<float> DenoiseWithNetwork(const DenoiseInput& in) {
  const int w = in.width, h = in.height;
  if (w <= 0 || h <= 0) return {};
  const size_t n = static_cast<size_t>(w) * h;
  std::vector<float> out(in.radiance, in.radiance + 3 * n);

  // The lighting (radiance / albedo, render/denoise.h's Demodulate) and the frame's scales.
  std::vector<DemodulatedPixel> pixels(n);
  std::vector<float> lumas, depths;
  lumas.reserve(n);
  depths.reserve(n);
  for (size_t p = 0; p < n; ++p) {
    if (!(in.depth[p] > 0)) continue;
    pixels[p] = Demodulate(in, p);
    lumas.push_back(DenoiseLuma(pixels[p].light));
    depths.push_back(in.depth[p]);
  }
  if (lumas.empty()) return out;
  const float scale = std::max(1e-6f, UpperMedian(std::move(lumas)));
  const float z_median = UpperMedian(std::move(depths));

  // The features, NCHW, padded with zeros (what a pixel that sees nothing reads).
  const int step = 1 << kDownsamplings;
  const int hp = (h + step - 1) / step * step, wp = (w + step - 1) / step * step;
  const size_t plane = static_cast<size_t>(hp) * wp;
  const int shape[4] = {1, kChannels, hp, wp};
  cv::Mat blob(4, shape, CV_32F, cv::Scalar(0));
  float* x = blob.ptr<float>();
  tbb::parallel_for(0, h, [&](int v) {
    for (int u = 0; u < w; ++u) {
      const size_t p = static_cast<size_t>(v) * w + u;
      const size_t q = static_cast<size_t>(v) * wp + u;
      if (!(in.depth[p] > 0)) continue;
      const DemodulatedPixel& d = pixels[p];
      for (int c = 0; c < 3; ++c) {
        x[c * plane + q] = std::log1p(std::min(kMaxRatio, d.light[c] / scale));
        x[(3 + c) * plane + q] = std::clamp(in.albedo[3 * p + c], 0.0f, 1.0f);
        x[(6 + c) * plane + q] = in.normal[3 * p + c];
      }
      x[9 * plane + q] = std::log(in.depth[p] / z_median);
      x[10 * plane + q] = std::log1p(std::min(kMaxRatio, std::sqrt(d.variance) / scale));
      x[11 * plane + q] = 1.0f;
    }
  });

  NetPool& pool = Pool();
  cv::Mat y;
  try {
    cv::dnn::Net net = pool.Take();
    net.setInput(blob);
    // forward()'s Mat is the network's own output blob, not a copy: once the net is back in the
    // pool another frame's forward() overwrites it (seen as bands of garbage in a frame when
    // several were denoised at once). A copy is ours.
    y = net.forward().clone();
    pool.Give(net);
  } catch (const cv::Exception& e) {
    throw Error(std::string("the denoiser network (render/models/denoiser.onnx): ") + e.what());
  }
  if (!(y.dims == 4 && y.size[1] == 4 && y.size[2] == hp && y.size[3] == wp))
    throw Error(
        "the denoiser network (render/models/denoiser.onnx) gave an output of the wrong "
        "shape");
  const float* yp = y.ptr<float>();
  tbb::parallel_for(0, h, [&](int v) {
    for (int u = 0; u < w; ++u) {
      const size_t p = static_cast<size_t>(v) * w + u;
      const size_t q = static_cast<size_t>(v) * wp + u;
      if (!(in.depth[p] > 0)) continue;
      // Its own estimate, blended with the input's by the weight sigmoid(channel 3).
      const float alpha = 1.0f / (1.0f + std::exp(-yp[3 * plane + q]));
      for (int c = 0; c < 3; ++c) {
        const float own = std::expm1(std::clamp(yp[c * plane + q], 0.0f, std::log1p(kMaxRatio)));
        const float noisy = std::expm1(x[c * plane + q]);
        out[3 * p + c] = (alpha * own + (1.0f - alpha) * noisy) * scale * pixels[p].albedo[c];
      }
    }
  });
  return out;
}

}  // namespace cadsynth
