// Pose-error metrics of the 6D-pose literature on model point clouds (all lengths in mm).
//
// ADD (Hinterstoisser et al. 2012): the mean distance between each model point under the
// estimated pose and the same point under the true pose. ADD-S: the mean distance from each
// point under the true pose to the closest point under the estimated pose, used for symmetric
// parts, where several poses look the same.
#pragma once

#include <vector>

#include <Eigen/Geometry>

namespace cadsynth {

double AddError(const std::vector<Eigen::Vector3f>& model_points, const Eigen::Isometry3d& estimate,
                const Eigen::Isometry3d& truth);

// Exact nearest neighbours (brute force over the cloud; 3,000 points take a few ms).
double AddSError(const std::vector<Eigen::Vector3f>& model_points,
                 const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& truth);

// BOP's Maximum Symmetry-aware Surface Distance (Hodan et al. 2020): the smallest, over the
// object's symmetry poses S (the identity among them; BopModelInfo::symmetry_poses), of the
// largest distance between a model point under the estimate and under truth * S.
double MssdError(const std::vector<Eigen::Vector3f>& model_points,
                 const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& truth,
                 const std::vector<Eigen::Isometry3d>& symmetry_poses);

// BOP's recall averaged over the MSSD thresholds 0.05, 0.10, ..., 0.50 of the diameter (an error
// counts below a threshold when strictly less; a missed object is an infinite error).
double AverageRecallMssd(const std::vector<double>& errors, const std::vector<double>& diameters);

// The area under the accuracy-threshold curve for thresholds 0..max_threshold, divided by
// max_threshold (PoseCNN / PVN3D report it with max_threshold = 0.1 m). Accuracy at t is the share
// of errors <= t; a missed object is an infinite error. Computed exactly for the step curve:
// sum over errors e < max of (max - e), divided by (count x max). Empty input gives 0.
double AccuracyAuc(const std::vector<double>& errors, double max_threshold);

// The share of errors below `threshold` (e.g. 10% of the object's diameter, the paper's Table II).
double ShareBelow(const std::vector<double>& errors, double threshold);

}  // namespace cadsynth
