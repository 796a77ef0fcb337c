#pragma once
/// Position and distance error models of a robot (SPEC section 3, eqs. 5–11) and the
/// scalar-to-vector projection used for compensation (section 6, eqs. 22–23).
///
/// Use these to turn measurements into error values for the estimators: a laser tracker gives
/// positions (→ position_error, needs a registered frame) or distances to a base point
/// (→ distance_error, frame-free). With distances to several base points, recover_position_error
/// gets the full 3-D error vector back without any frame registration.
/// All positions in mm in one frame (the robot's world frame); functions are pure and thread-safe.

#include <span>
#include <string>

#include <Eigen/Core>

namespace errfield::robot {

/// Position error dP = P' − P, actual minus nominal (eq. 5), mm.
inline Eigen::Vector3d position_error(const Eigen::Vector3d& actual_mm, const Eigen::Vector3d& nominal_mm) {
  return actual_mm - nominal_mm;
}

/// The reference of a distance measurement (the paper's base point P0). Either a fixed point that
/// carries no error (eq. 11: a tracker nest, a fixture), or itself a robot position whose own
/// error enters (`dL = n·(dP − dP0)`).
class BasePoint {
 public:
  /// A fixed point at `position_mm`: nominal and actual coincide.
  static BasePoint fixed(const Eigen::Vector3d& position_mm) { return BasePoint(position_mm, position_mm, true); }
  /// A robot position: commanded to `nominal_mm`, actually at `actual_mm`.
  static BasePoint robot_position(const Eigen::Vector3d& nominal_mm, const Eigen::Vector3d& actual_mm) {
    return BasePoint(nominal_mm, actual_mm, false);
  }
  const Eigen::Vector3d& nominal() const noexcept { return nominal_; }
  const Eigen::Vector3d& actual() const noexcept { return actual_; }
  /// dP0 = actual − nominal (zero for a fixed point).
  Eigen::Vector3d error() const { return actual_ - nominal_; }
  bool is_fixed() const noexcept { return fixed_; }

 private:
  BasePoint(const Eigen::Vector3d& n, const Eigen::Vector3d& a, bool fixed) : nominal_(n), actual_(a), fixed_(fixed) {}
  Eigen::Vector3d nominal_, actual_;
  bool fixed_;
};

/// Exact distance error `|P'_j − P'_0| − |P_j − P_0|` (eq. 6: L_A − L_T), mm.
double distance_error(const BasePoint& base, const Eigen::Vector3d& nominal_mm, const Eigen::Vector3d& actual_mm);

/// Exact distance error between two robot positions i and j: `|P'_j − P'_i| − |P_j − P_i|`, mm.
double distance_error(const Eigen::Vector3d& nominal_i, const Eigen::Vector3d& actual_i,
                      const Eigen::Vector3d& nominal_j, const Eigen::Vector3d& actual_j);

/// Unit vector n = (P_j − P_0)/|P_j − P_0| between nominal positions (eq. 8; eq. 22's m when the
/// first point is the base point). Precondition: the points differ (|P_j − P_0| > 0).
Eigen::Vector3d unit_direction(const Eigen::Vector3d& from_mm, const Eigen::Vector3d& to_mm);

/// Linearized distance error `n · (dP_j − dP_0)` (eq. 10; eq. 11 for a fixed base, dP_0 = 0), mm.
/// Differs from the exact form by O(|dP|² / |P_j − P_0|).
double linearized_distance_error(const BasePoint& base, const Eigen::Vector3d& nominal_mm,
                                 const Eigen::Vector3d& position_error_mm);

/// Projection of a scalar distance error to a 3-D correction (eqs. 22–23):
/// `dP = dL · m`, `m = (P_n − P0)/|P_n − P0|`, all nominal positions, mm.
Eigen::Vector3d project_distance_error(double distance_error_mm, const Eigen::Vector3d& base_nominal_mm,
                                       const Eigen::Vector3d& target_nominal_mm);

/// Result of recovering the full error vector from distances to several base points.
struct PositionErrorRecovery {
  Eigen::Vector3d position_error_mm = Eigen::Vector3d::Zero();  ///< dP estimate.
  /// Condition number of the 3 × K direction matrix (ratio of its singular values); infinite if
  /// rank < 3. Below ~10 the geometry is good; above ~100 a direction is barely observed.
  double condition_number = 0.0;
  /// Error amplification: sqrt(trace((NᵀN)⁻¹)); the dP standard error is this times the distance
  /// noise (per-distance sigma), for independent noise.
  double dilution = 0.0;
  double residual_rms_mm = 0.0;  ///< RMS of the fitted distance equations (0 for exactly 3 bases).
  bool ok = false;                ///< False when fewer than 3 bases or rank < 3.
  std::string message;            ///< Why not ok.
};

/// Recovers dP of one point from its distance errors to K >= 3 fixed base points (SPEC section 8:
/// registration-free, includes the tangential part the radial projection cannot correct).
/// `exact = true` solves the exact equations `|P + dP − B_k| − |P − B_k| = dL_k` by Gauss–Newton
/// from the linear solution (differs from the linear one by O(|dP|²/L)); `false` solves the
/// linearized ones `n_k · dP = dL_k` by least squares. The bases are fixed points (no error).
/// For bases that are robot positions with a known error dP0_k, pass `dL_k + n_k·dP0_k` (the
/// linear model); with unknown base errors dP is determined only together with them, across many
/// points and up to a rigid motion (distances are invariant under it). A base closer than 1 mm to
/// the point makes its direction undefined and the result not ok.
PositionErrorRecovery recover_position_error(std::span<const Eigen::Vector3d> bases_mm,
                                             std::span<const double> distance_errors_mm,
                                             const Eigen::Vector3d& nominal_mm, bool exact = true);

}  // namespace errfield::robot
