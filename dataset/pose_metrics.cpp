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

double MssdError(const std::vector<Eigen::Vector3f>& model_points,
                 const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& truth,
                 const std::vector<Eigen::Isometry3d>& symmetry_poses) {
  if (model_points.empty()) return 0.0;
  const std::vector<Eigen::Vector3d> est = Transformed(model_points, estimate);
  double best = std::numeric_limits<double>::infinity();
  const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();
  const std::vector<Eigen::Isometry3d> just_identity = {identity};
  for (const Eigen::Isometry3d& s : symmetry_poses.empty() ? just_identity : symmetry_poses) {
    const Eigen::Isometry3d moved = truth * s;
    double worst = 0;
    for (size_t i = 0; i < est.size() && worst < best; ++i)
      worst = std::max(worst, (est[i] - moved * model_points[i].cast<double>()).squaredNorm());
    best = std::min(best, worst);
  }
  return std::sqrt(best);
}

double AverageRecallMssd(const std::vector<double>& errors, const std::vector<double>& diameters) {
  if (errors.empty()) return 0.0;
  double sum = 0;
  for (int k = 1; k <= 10; ++k) {
    int hits = 0;
    for (size_t i = 0; i < errors.size(); ++i) hits += errors[i] < 0.05 * k * diameters[i];
    sum += static_cast<double>(hits) / errors.size();
  }
  return sum / 10;
}

}  // namespace cadsynth
