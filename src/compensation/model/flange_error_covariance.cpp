#include "errfield/compensation/model/flange_error_covariance.hpp"

#include <Eigen/Eigenvalues>

namespace errfield::compensation {

Eigen::Matrix3d FlangeErrorCovariance::covariance_at(const Eigen::Matrix3d& flange_rotation,
                                                     const Eigen::MatrixXd& combination,
                                                     double field_variance_mm2) const {
  const Eigen::Index k = field_covariance_mm2.rows() / 3;
  // C B: each 3 x 3 block of the combination times the flange's rotation (flange -> robot frame).
  Eigen::MatrixXd cb(3, 3 * k);
  for (Eigen::Index j = 0; j < k; ++j) cb.middleCols<3>(3 * j) = combination.middleCols<3>(3 * j) * flange_rotation;
  const double scale = field_variance_mm2 / mean_field_variance_mm2;
  return scale * cb * field_covariance_mm2 * cb.transpose();
}

std::optional<FlangeErrorCovariance> FlangeErrorCovariance::of(const std::vector<Eigen::VectorXd>& flange_residual_mm,
                                                              const std::vector<double>& field_variance_mm2,
                                                              const Eigen::VectorXd& noise_variance_per_axis_mm2) {
  if (flange_residual_mm.size() < kMinimumPoses || field_variance_mm2.size() != flange_residual_mm.size())
    return std::nullopt;
  const Eigen::Index n = flange_residual_mm.front().size();
  if (n == 0 || n % 3 != 0 || noise_variance_per_axis_mm2.size() != n / 3) return std::nullopt;
  FlangeErrorCovariance out;
  Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(n, n);
  double variance = 0.0;
  for (std::size_t i = 0; i < flange_residual_mm.size(); ++i) {
    if (flange_residual_mm[i].size() != n) return std::nullopt;
    sum.noalias() += flange_residual_mm[i] * flange_residual_mm[i].transpose();
    variance += field_variance_mm2[i];
  }
  out.poses = flange_residual_mm.size();
  sum /= static_cast<double>(out.poses);
  for (Eigen::Index j = 0; j < n / 3; ++j) sum.block<3, 3>(3 * j, 3 * j).diagonal().array() -= noise_variance_per_axis_mm2[j];
  // Taking the noise off can leave small negative eigenvalues (a point noisier than its nugget
  // says, or a handful of poses): the nearest positive semi-definite matrix.
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(0.5 * (sum + sum.transpose()));
  out.field_covariance_mm2 =
      eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() * eig.eigenvectors().transpose();
  out.mean_field_variance_mm2 = variance / static_cast<double>(out.poses);
  if (!(out.mean_field_variance_mm2 > 0.0) || !out.field_covariance_mm2.allFinite()) return std::nullopt;
  return out;
}

}  // namespace errfield::compensation
