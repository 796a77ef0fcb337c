#pragma once
/// The flange's small rotation, seen through position errors at several points on it.
///
/// A flange moved by a small rigid motion (a translation t and a rotation w, |w| << 1 rad) moves a
/// point at x (robot frame, mm) by e = t + w × (x − c) for any fixed c. With three or more points
/// that do not lie on one line, (t, w) follow from their errors by least squares; only w is kept
/// here: it is the orientation error of the flange, and of every tool on it. What measures it:
/// three reflector nests on a plate, or a 6-DoF probe (whose orientation is turned into two
/// further points, probe_readings.hpp). What predicts it: a model with fields at three or more
/// points (CompensationModel::predict_rotation).
///
/// Units: mm in, rad out (rad per mm for the operator). Pure functions, thread-safe.

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace errfield::compensation {

/// Points whose spread off their best-fitting line is below this (mm: the second singular value of
/// their centred coordinates) do not determine the rotation about that line: the 0.01 mm noise of a
/// reading over a 10 mm lever is already 1 mrad.
inline constexpr double kMinPointSpreadOffLineMm = 10.0;

/// The rotation part of the least-squares rigid motion of K points: w = from_errors · [e_1; …; e_K].
struct FlangeRotationOperator {
  Eigen::Matrix<double, 3, Eigen::Dynamic> from_errors;  ///< 3 × 3K, rad per mm

  /// For points at `points_mm` (robot frame, mm); empty with fewer than three points or points that
  /// spread less than kMinPointSpreadOffLineMm off one line.
  static std::optional<FlangeRotationOperator> of(const std::vector<Eigen::Vector3d>& points_mm);

  /// w from the K points' errors (mm), in the order the points were given.
  Eigen::Vector3d rotation_rad(const std::vector<Eigen::Vector3d>& errors_mm) const;
  /// The covariance of w (rad²) when the points' errors are independent with per-axis variances
  /// `axis_variance_mm2` (mm², one per point).
  Eigen::Matrix3d covariance_rad2(const std::vector<Eigen::Vector3d>& axis_variance_mm2) const;
};

/// The covariance of the rotation a model's fields imply, as their leave-one-out shows it. Fields at
/// separate points combined as independent (FlangeRotationOperator::covariance_rad2) get neither the
/// size nor the shape right: what the points share (a reading's translation noise, the flange's
/// translation error) is no rotation, yet counts as one, and the orientation noise of a probe is
/// isotropic while the combination is not. So the shape and size are taken from the data: at the
/// training poses every field holds, the rotation their leave-one-out residuals imply, turned into
/// the flange frame (where the points' geometry is fixed), gives `flange_covariance_rad2`; how far a
/// pose is from the data enters through the independent combination's trace against its mean over
/// those poses. Predicted covariance at q: (tr C_ind(q) / mean_independent_trace_rad2) ·
/// R(q) flange_covariance_rad2 R(q)ᵀ, R(q) the flange's rotation ("rotation_calibration" in the
/// model file).
struct RotationCalibration {
  Eigen::Matrix3d flange_covariance_rad2 = Eigen::Matrix3d::Zero();
  double mean_independent_trace_rad2 = 0.0;
  std::size_t poses = 0;
  /// The covariance at a pose whose flange rotation is `flange_rotation` and whose independent
  /// combination is `independent_rad2`.
  Eigen::Matrix3d covariance_at(const Eigen::Matrix3d& flange_rotation, const Eigen::Matrix3d& independent_rad2) const;
};

/// A model's prediction of the flange's orientation error at one pose.
struct RotationPrediction {
  /// The predicted small rotation (robot frame, rad): the flange's true orientation is
  /// exp([w]×) times the calibrated model's.
  Eigen::Vector3d rotation_rad = Eigen::Vector3d::Zero();
  /// Covariance of a new measurement's rotation about the prediction (rad²): RotationCalibration's,
  /// or without one the fields' predictive variances at their points combined as independent.
  Eigen::Matrix3d covariance_rad2 = Eigen::Matrix3d::Zero();
  /// ok when every point's prediction is; otherwise the first point's status that is not.
  std::string status = "ok";
  /// The radius (rad) that holds a new measurement's rotation error with probability 0.95.
  double radius95_rad() const;
  /// |e|² over the covariance: e ᵀ C⁻¹ e (3 expected).
  double nees(const Eigen::Vector3d& error_rad) const;
};

}  // namespace errfield::compensation
