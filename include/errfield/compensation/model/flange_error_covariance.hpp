#pragma once
/// How alike a model's errors are at the points on the flange it holds fields at, as their
/// leave-one-out shows it: what a point predicted from their combination needs for its variance.
///
/// A model with fields at several points predicts any other point p from the small rigid motion of
/// the flange their predictions imply: e(p) = C(p) [e_1; ...; e_K] (CompensationModel::
/// predict_error_at). The error of that prediction is C(p) times the fields' errors at their points,
/// whose covariance no field states: they are fitted apart, yet their errors at one pose are alike
/// (what moves the flange moves every point on it). Taken as fully correlated (the sum of their
/// standard deviations, an upper bound), the 95 % radius at a located point held 100 % of held-out
/// readings with a mean NEES of 2.0 (SIMULATED KR 16, reflectors r1 and r2, r3 located; seed 1). So
/// the covariance is taken from the data: at every training pose that every field holds, the fields'
/// leave-one-out residuals, turned into the flange frame (where the points' geometry is fixed) and
/// stacked; their mean outer product less each point's reading noise on its own diagonal block (a
/// new reading at p has its own noise once, added apart) is `field_covariance_mm2`. At a pose:
///
///   scale · C B Σ Bᵀ Cᵀ,   B = diag(R, ..., R), R the flange's rotation there,
///
/// scale = the fields' stated variances there (noise excluded, summed) over their mean at the
/// training poses: far from the data it grows as they do ("flange_error_covariance" in the model).
///
/// Units: mm², rotations dimensionless. Pure functions, thread-safe.

#include <cstddef>
#include <optional>
#include <vector>

#include <Eigen/Core>

namespace errfield::compensation {

struct FlangeErrorCovariance {
  /// 3K x 3K (K fielded points, the model's own point first), flange frame, mm²; symmetric positive
  /// semi-definite.
  Eigen::MatrixXd field_covariance_mm2;
  /// Mean over the training poses of the fields' stated leave-one-out variance less their noise,
  /// summed over points and axes (mm²).
  double mean_field_variance_mm2 = 0.0;
  std::size_t poses = 0;

  /// The points the covariance is for.
  std::size_t point_count() const { return static_cast<std::size_t>(field_covariance_mm2.rows() / 3); }
  /// The covariance (robot frame, mm²) of combination · (the fields' errors) at a pose whose flange
  /// rotation is `flange_rotation` and whose fields state `field_variance_mm2` (noise excluded,
  /// summed over points and axes). `combination` is 3 x 3K (robot frame).
  Eigen::Matrix3d covariance_at(const Eigen::Matrix3d& flange_rotation, const Eigen::MatrixXd& combination,
                                double field_variance_mm2) const;
  /// From the stacked flange-frame residuals (3K each, one per pose), the summed field variances at
  /// those poses and each point's noise variance per axis (K): empty with fewer than
  /// kMinimumPoses poses or no field variance.
  static std::optional<FlangeErrorCovariance> of(const std::vector<Eigen::VectorXd>& flange_residual_mm,
                                                 const std::vector<double>& field_variance_mm2,
                                                 const Eigen::VectorXd& noise_variance_per_axis_mm2);
  /// Fewer poses than this leave a 3K x 3K covariance too uncertain to claim a 95 % region from.
  static constexpr std::size_t kMinimumPoses = 30;
};

}  // namespace errfield::compensation
