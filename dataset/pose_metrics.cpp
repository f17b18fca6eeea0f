#include "dataset/pose_metrics.h"

#include <algorithm>
#include <limits>

namespace cadsynth {
namespace {

std::vector<Eigen::Vector3d> Transformed(const std::vector<Eigen::Vector3f>& points,
                                         const Eigen::Isometry3d& pose) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(points.size());
  for (const Eigen::Vector3f& p : points) out.push_back(pose * p.cast<double>());
  return out;
}

}  // namespace

double AddError(const std::vector<Eigen::Vector3f>& model_points, const Eigen::Isometry3d& estimate,
                const Eigen::Isometry3d& truth) {
  if (model_points.empty()) return 0.0;
  double sum = 0.0;
  for (const Eigen::Vector3f& p : model_points) {
    const Eigen::Vector3d q = p.cast<double>();
    sum += (estimate * q - truth * q).norm();
  }
  return sum / static_cast<double>(model_points.size());
}

double AddSError(const std::vector<Eigen::Vector3f>& model_points,
                 const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& truth) {
  if (model_points.empty()) return 0.0;
  const std::vector<Eigen::Vector3d> est = Transformed(model_points, estimate);
  const std::vector<Eigen::Vector3d> gt = Transformed(model_points, truth);
  double sum = 0.0;
  for (const Eigen::Vector3d& g : gt) {
    double best = std::numeric_limits<double>::infinity();
    for (const Eigen::Vector3d& e : est) best = std::min(best, (g - e).squaredNorm());
    sum += std::sqrt(best);
  }
  return sum / static_cast<double>(gt.size());
}

double AccuracyAuc(const std::vector<double>& errors, double max_threshold) {
  if (errors.empty() || !(max_threshold > 0)) return 0.0;
  double area = 0.0;
  for (double e : errors) {
    if (e < max_threshold) area += max_threshold - std::max(e, 0.0);
  }
  return area / (static_cast<double>(errors.size()) * max_threshold);
}

double ShareBelow(const std::vector<double>& errors, double threshold) {
  if (errors.empty()) return 0.0;
  const auto hits =
      std::count_if(errors.begin(), errors.end(), [&](double e) { return e < threshold; });
  return static_cast<double>(hits) / static_cast<double>(errors.size());
}

}  // namespace cadsynth
