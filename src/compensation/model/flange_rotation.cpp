#include "errfield/compensation/model/flange_rotation.hpp"

#include <cmath>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

#include "errfield/compensation/model/error_ball.hpp"

namespace errfield::compensation {

std::optional<FlangeRotationOperator> FlangeRotationOperator::of(const std::vector<Eigen::Vector3d>& points_mm) {
  const Eigen::Index k = static_cast<Eigen::Index>(points_mm.size());
  if (k < 3) return std::nullopt;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : points_mm) centre += p;
  centre /= static_cast<double>(k);
  Eigen::MatrixXd centred(k, 3);
  for (Eigen::Index j = 0; j < k; ++j) centred.row(j) = (points_mm[static_cast<std::size_t>(j)] - centre).transpose();
  const Eigen::JacobiSVD<Eigen::MatrixXd> spread(centred);
  if (spread.singularValues()[1] < kMinPointSpreadOffLineMm) return std::nullopt;
  // e_j = t + w × d_j = [I, −[d_j]×] (t, w) with d_j = x_j − c; the normal equations of all K
  // points, solved for both and the rotation kept (the spread check above makes them regular).
  Eigen::MatrixXd a(3 * k, 6);
  for (Eigen::Index j = 0; j < k; ++j) {
    const Eigen::Vector3d d = points_mm[static_cast<std::size_t>(j)] - centre;
    Eigen::Matrix3d cross;
    cross << 0, -d.z(), d.y(), d.z(), 0, -d.x(), -d.y(), d.x(), 0;
    a.block<3, 3>(3 * j, 0).setIdentity();
    a.block<3, 3>(3 * j, 3) = -cross;
  }
  const Eigen::MatrixXd normal = a.transpose() * a;
  FlangeRotationOperator out;
  out.from_errors = normal.ldlt().solve(a.transpose()).bottomRows<3>();
  return out;
}

Eigen::Vector3d FlangeRotationOperator::rotation_rad(const std::vector<Eigen::Vector3d>& errors_mm) const {
  Eigen::Vector3d w = Eigen::Vector3d::Zero();
  for (std::size_t j = 0; j < errors_mm.size(); ++j) w += from_errors.middleCols<3>(3 * static_cast<Eigen::Index>(j)) * errors_mm[j];
  return w;
}

Eigen::Matrix3d FlangeRotationOperator::covariance_rad2(const std::vector<Eigen::Vector3d>& axis_variance_mm2) const {
  Eigen::Matrix3d c = Eigen::Matrix3d::Zero();
  for (std::size_t j = 0; j < axis_variance_mm2.size(); ++j) {
    const Eigen::Matrix3d b = from_errors.middleCols<3>(3 * static_cast<Eigen::Index>(j));
    c += b * axis_variance_mm2[j].asDiagonal() * b.transpose();
  }
  return c;
}

Eigen::Matrix3d RotationCalibration::covariance_at(const Eigen::Matrix3d& flange_rotation,
                                                   const Eigen::Matrix3d& independent_rad2) const {
  const double distance_from_data = independent_rad2.trace() / mean_independent_trace_rad2;
  return distance_from_data * flange_rotation * flange_covariance_rad2 * flange_rotation.transpose();
}

double RotationPrediction::radius95_rad() const {
  // |e| is unchanged by a rotation of the axes: the covariance's eigenvalues are independent
  // per-axis variances of the same radius.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(covariance_rad2, Eigen::EigenvaluesOnly);
  const Eigen::Vector3d lambda = eig.eigenvalues().cwiseMax(0.0);
  if (!lambda.allFinite() || lambda.maxCoeff() <= 0.0) return std::nan("");
  return radius_with_probability(0.95, lambda);
}

double RotationPrediction::nees(const Eigen::Vector3d& error_rad) const {
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(covariance_rad2);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return std::nan("");
  return error_rad.dot(ldlt.solve(error_rad));
}

}  // namespace errfield::compensation
