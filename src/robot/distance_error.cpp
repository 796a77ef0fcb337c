#include "errfield/robot/distance_error.hpp"

#include <cmath>
#include <limits>

#include <Eigen/Dense>

#include "errfield/error.hpp"

namespace errfield::robot {

double distance_error(const BasePoint& base, const Eigen::Vector3d& nominal_mm, const Eigen::Vector3d& actual_mm) {
  return (actual_mm - base.actual()).norm() - (nominal_mm - base.nominal()).norm();
}

double distance_error(const Eigen::Vector3d& nominal_i, const Eigen::Vector3d& actual_i,
                      const Eigen::Vector3d& nominal_j, const Eigen::Vector3d& actual_j) {
  return (actual_j - actual_i).norm() - (nominal_j - nominal_i).norm();
}

Eigen::Vector3d unit_direction(const Eigen::Vector3d& from_mm, const Eigen::Vector3d& to_mm) {
  const Eigen::Vector3d d = to_mm - from_mm;
  const double len = d.norm();
  if (!(len > 0)) throw ArgumentError("unit_direction: the two points coincide; the direction is undefined");
  return d / len;
}

double linearized_distance_error(const BasePoint& base, const Eigen::Vector3d& nominal_mm,
                                 const Eigen::Vector3d& position_error_mm) {
  return unit_direction(base.nominal(), nominal_mm).dot(position_error_mm - base.error());
}

Eigen::Vector3d project_distance_error(double distance_error_mm, const Eigen::Vector3d& base_nominal_mm,
                                       const Eigen::Vector3d& target_nominal_mm) {
  return distance_error_mm * unit_direction(base_nominal_mm, target_nominal_mm);
}

PositionErrorRecovery recover_position_error(std::span<const Eigen::Vector3d> bases_mm,
                                             std::span<const double> distance_errors_mm,
                                             const Eigen::Vector3d& nominal_mm, bool exact) {
  if (bases_mm.size() != distance_errors_mm.size())
    throw ArgumentError("recover_position_error: " + std::to_string(bases_mm.size()) + " base points but " +
                        std::to_string(distance_errors_mm.size()) + " distance errors");
  PositionErrorRecovery out;
  const auto k = static_cast<Eigen::Index>(bases_mm.size());
  if (k < 3) {
    out.message = "need distances to at least 3 base points, got " + std::to_string(k);
    out.condition_number = std::numeric_limits<double>::infinity();
    return out;
  }
  Eigen::MatrixX3d n(k, 3);
  Eigen::VectorXd dl(k), nominal_len(k);
  for (Eigen::Index i = 0; i < k; ++i) {
    const Eigen::Vector3d d = nominal_mm - bases_mm[static_cast<std::size_t>(i)];
    nominal_len[i] = d.norm();
    if (nominal_len[i] < 1.0) {
      out.message = "base point " + std::to_string(i) + " is " + std::to_string(nominal_len[i]) +
                    " mm from the point; its direction is undefined";
      out.condition_number = std::numeric_limits<double>::infinity();
      return out;
    }
    n.row(i) = d.transpose() / nominal_len[i];
    dl[i] = distance_errors_mm[static_cast<std::size_t>(i)];
  }
  // Dynamic column type: Eigen asserts on thin U/V for a fixed number of columns (MatrixX3d).
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(Eigen::MatrixXd(n), Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Eigen::Vector3d s = svd.singularValues();
  out.condition_number = s[2] > 1e-12 * s[0] ? s[0] / s[2] : std::numeric_limits<double>::infinity();
  if (!std::isfinite(out.condition_number)) {
    out.message = "base points and the point are (nearly) coplanar or collinear: the direction matrix has rank < 3";
    return out;
  }
  out.dilution = std::sqrt((1.0 / s.array().square()).sum());
  Eigen::Vector3d dp = svd.solve(dl);
  if (exact) {
    // Gauss–Newton on f_k(dP) = |P + dP − B_k| − |P − B_k| − dL_k; Jacobian rows are the unit
    // vectors from B_k to P + dP. Starts at the linear solution, so 2–3 steps reach 1e-12 mm.
    for (int it = 0; it < 20; ++it) {
      Eigen::MatrixX3d jac(k, 3);
      Eigen::VectorXd f(k);
      for (Eigen::Index i = 0; i < k; ++i) {
        const Eigen::Vector3d d = nominal_mm + dp - bases_mm[static_cast<std::size_t>(i)];
        const double len = d.norm();
        jac.row(i) = d.transpose() / len;
        f[i] = len - nominal_len[i] - dl[i];
      }
      const Eigen::Vector3d step = jac.colPivHouseholderQr().solve(-f);
      dp += step;
      if (step.norm() < 1e-13) break;
    }
    Eigen::VectorXd f(k);
    for (Eigen::Index i = 0; i < k; ++i)
      f[i] = (nominal_mm + dp - bases_mm[static_cast<std::size_t>(i)]).norm() - nominal_len[i] - dl[i];
    out.residual_rms_mm = std::sqrt(f.squaredNorm() / static_cast<double>(k));
  } else {
    out.residual_rms_mm = std::sqrt((n * dp - dl).squaredNorm() / static_cast<double>(k));
  }
  out.position_error_mm = dp;
  out.ok = true;
  return out;
}

}  // namespace errfield::robot
