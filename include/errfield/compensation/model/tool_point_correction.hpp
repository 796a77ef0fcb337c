#pragma once
/// What a located point's own readings add to a model's prediction at that point: the kriged
/// residual of those readings (`errfield locate-tool`, "tool_point_correction" in the model file).
///
/// Why. A model measured at one point, or at two, cannot see every turn of the flange: with one point
/// none, with two the rotation about their line. At a point elsewhere on the flange that rotation w(q)
/// moves the error by w(q) x L, which the model can only state as a variance (the orientation term,
/// docs/robot.md "Tool points and orientation"). The readings locate-tool located the point from see
/// it: at their poses the model's prediction there misses by w(q) x L plus the reading noise. w varies
/// smoothly over the joints, so those misses are kriged over joint space and added where the point is
/// predicted. On SIMULATED KR 16 readings at three nests (seed 3, 40 readings of the located point,
/// 200 held-out poses) a two-point model's 0.0560 mm at the third point became 0.048 mm, and a
/// one-point model's 0.166 mm at a point 150 mm away 0.08 mm (docs/robot.md has the study).
///
/// The model. In the flange frame (where the lever L is fixed, so each axis is one quantity over the
/// poses) each axis k of the residual is a zero-mean field with covariance s_k ρ_m(q, q') and the
/// reading noise n added on the diagonal: ρ_m the correlation of the model's own field (its
/// structures and anisotropy over the joints, every range times m), or an isotropic gau over the
/// joints. Which ρ (kRangeMultipliers, kIsotropicRangesDeg), n (one for the three axes) and the s_k
/// by maximum likelihood: for each ρ and n the profile over each s_k is one-dimensional, solved on
/// the eigenvalues of ρ. (n is estimated, not the field's nugget: a
/// field may hold its noise in a structure of very short range instead, as REML chose on SIMULATED
/// UR5e readings, nugget 4e-11 mm².) Prediction is simple kriging with mean 0: far from the readings the
/// correction goes to zero (the model's own prediction) and its variance to s_k, the size of the
/// residual the readings showed. The kriging variance is scaled so the readings' leave-one-out
/// holds (variance_factor). Its kriging variance replaces the orientation term at the point
/// (what the term guessed, the readings measured).
///
/// Frames and units: joints in degrees, flange frame and robot frame, mm and mm². Immutable after
/// construction; predict is thread-safe.

#include <array>
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json_fwd.hpp>

#include "errfield/robot/mdh_model.hpp"
#include "errfield/variogram_model.hpp"

namespace errfield::compensation {

/// Fewest readings of a point a correction is kriged from: with fewer, the likelihood of a range and
/// three sills is too flat to tell a residual field from noise.
inline constexpr std::size_t kMinToolPointCorrectionReadings = 20;

/// The multipliers of the model field's ranges the correction's likelihood chooses among (a
/// rotation of the flange varies over the joints more slowly than the position error at one point:
/// on the simulations above the likelihood chose 1.5 to 4).
inline constexpr std::array<double, 7> kRangeMultipliers = {0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 4.0};
/// The ranges (deg) of the isotropic gau correlations it chooses among as well.
inline constexpr std::array<double, 5> kIsotropicRangesDeg = {15.0, 30.0, 60.0, 120.0, 240.0};

/// The correction's prediction at one pose (robot frame).
struct ToolPointCorrectionPrediction {
  Eigen::Vector3d error_mm = Eigen::Vector3d::Zero();           ///< added to the model's prediction
  Eigen::Vector3d axis_variance_mm2 = Eigen::Vector3d::Zero();  ///< its kriging variance per axis (noise excluded)
};

class ToolPointCorrection {
 public:
  /// Kriges `residual_mm` (robot frame: reading − the model's prediction at the point, one per
  /// reading) at joints `q_deg`, whose flange rotations (robot from flange) are `flange_rotation`.
  /// `field_model` is the model's own field's variogram (per component; its structures give the
  /// correlation). Gross readings are left out first (excluded_readings). None with fewer than
  /// kMinToolPointCorrectionReadings readings, a field model
  /// without a bounded structure, residuals that are all zero, or non-finite input.
  static std::optional<ToolPointCorrection> fit(const Eigen::Vector3d& point_mm, const std::vector<robot::JointVector>& q_deg,
                                                const std::vector<Eigen::Matrix3d>& flange_rotation,
                                                const std::vector<Eigen::Vector3d>& residual_mm,
                                                const VariogramModel& field_model);

  /// At joints `q_deg` with flange rotation `flange_rotation`.
  ToolPointCorrectionPrediction predict(const robot::JointVector& q_deg, const Eigen::Matrix3d& flange_rotation) const;
  /// The same for several poses at once (one kriging call per axis).
  std::vector<ToolPointCorrectionPrediction> predict(const std::vector<robot::JointVector>& q_deg,
                                                     const std::vector<Eigen::Matrix3d>& flange_rotation) const;

  /// The leave-one-out residual of every reading (flange frame, mm): its value less the correction
  /// kriged from the other readings. What locate-tool reports the correction's gain with.
  std::vector<Eigen::Vector3d> leave_one_out_residual_mm() const;
  /// Readings left out as gross (fit's screen: leave-one-out residual over kOutlierLimit robust sd).
  std::size_t excluded_readings() const noexcept { return excluded_readings_; }
  /// The screen's limit (robust sd, as fit's --outlier-limit default) and its rounds.
  static constexpr double kOutlierLimit = 5.0;
  static constexpr int kOutlierRounds = 3;

  const Eigen::Vector3d& point_mm() const noexcept { return point_mm_; }
  std::size_t readings() const noexcept { return q_deg_.size(); }
  /// ρ: the correlation the likelihood chose (unit sill, no nugget).
  const VariogramModel& correlation() const noexcept { return correlation_; }
  /// s_k per flange axis (mm²).
  const Eigen::Vector3d& sill_mm2() const noexcept { return sill_mm2_; }
  /// n, per axis (mm²).
  double noise_mm2() const noexcept { return noise_mm2_; }
  /// What the kriging variance is multiplied by: the factor that maximizes the readings'
  /// leave-one-out log score with variance f v_i + n (v_i the kriging variance of reading i from the
  /// others). The maximum-likelihood sill of 20–40 readings with a long range was up to twice what
  /// their leave-one-out showed (SIMULATED, docs/robot.md).
  double variance_factor() const noexcept { return variance_factor_; }
  /// The bounds of variance_factor. The leave-one-out only raises the kriging's own statement: its
  /// readings are training poses, where the model's fields are in-sample and its prediction at the
  /// point misses by less than at a new pose. Let it lower the variance too (to 0.25) and the
  /// located points whose factor fell below 1 held 91-93.5 % of their held-out readings (four of 24
  /// SIMULATED cases; docs/robot.md). Above: a wide bound; too small a variance is the danger.
  static constexpr double kMinVarianceFactor = 1.0, kMaxVarianceFactor = 20.0;

  /// {"point_mm", "correlation" (the model text of ρ: unit sill), "sill_mm2" [3], "noise_mm2",
  /// "variance_factor", "joints_deg" [N][6], "residual_flange_mm" [N][3]}.
  nlohmann::json to_json() const;
  /// Reads to_json's form; throws InputError naming `source` and the member for anything malformed
  /// (sizes, non-finite numbers, a negative sill, a correlation that is not one).
  static ToolPointCorrection from_json(const nlohmann::json& j, const std::string& source);

 private:
  struct Kriged;
  ToolPointCorrection(Eigen::Vector3d point_mm, std::vector<robot::JointVector> q_deg,
                      std::vector<Eigen::Vector3d> residual_flange_mm, VariogramModel correlation,
                      Eigen::Vector3d sill_mm2, double noise_mm2);
  Eigen::Vector3d point_mm_;
  std::vector<robot::JointVector> q_deg_;
  std::vector<Eigen::Vector3d> residual_flange_mm_;
  VariogramModel correlation_;  ///< ρ: unit total sill, no nugget
  Eigen::Vector3d sill_mm2_;
  double noise_mm2_ = 0.0;
  double variance_factor_ = 1.0;
  std::size_t excluded_readings_ = 0;
  /// Kriging and the variance factor for the given readings (no screen).
  static std::optional<ToolPointCorrection> fit_once(const Eigen::Vector3d& point_mm,
                                                     const std::vector<robot::JointVector>& q_deg,
                                                     const std::vector<Eigen::Vector3d>& flange,
                                                     const VariogramModel& field_model);
  /// Per reading: its leave-one-out residual (flange frame) and the kriging variance of that
  /// prediction per axis (noise excluded, unscaled; 0 on an axis without a field); empty when
  /// readings were merged. What the three below are computed from.
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> leave_one_out_by_axis() const;
  /// leave_one_out_by_axis with the variance as predict states it (times variance_factor, plus n).
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> held_out_residuals() const;
  /// variance_factor from the readings' leave-one-out.
  double leave_one_out_variance_factor() const;
  std::shared_ptr<const Kriged> kriged_;  ///< the three simple krigings (shared: copies are cheap)
};

}  // namespace errfield::compensation
