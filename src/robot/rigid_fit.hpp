#pragma once
// Internal: the best rigid motion between two point sets, shared by the simulator (absorbing the
// rigid part of the geometric error), calibration (initial base frame) and the pipeline's tracker
// registration (fit_registration).

#include <vector>

#include <Eigen/Geometry>

namespace errfield::robot {

/// Rigid motion T = (R, t) minimizing sum_k |R a_k + t - b_k|^2 (Kabsch / Horn, SVD of the
/// cross-covariance, reflection excluded). Precondition: a.size() == b.size() >= 3.
Eigen::Isometry3d fit_rigid(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b);

}  // namespace errfield::robot
