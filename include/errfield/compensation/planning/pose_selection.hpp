#pragma once
/// Which poses to measure next, from a pool of candidate joint vectors (issue 21): the robot side of
/// sampling_design.hpp. Tracker time is the cost of a compensation, and which poses are measured
/// matters as much as how many.
///
///  - Without a model (the first batch): maximin in joint space, each joint scaled by its spread
///    over the pool, so the batch covers the joint space the model will live in and spreads the
///    postures a kinematic calibration needs.
///  - With a fitted model whose field is vector kriging (`kinematic+kriging`, the default, or
///    `vector-kriging`): the poses that most reduce the field's predictive variance over the pool
///    (integrated variance reduction under the fitted variogram, conditioned on the poses already
///    measured), and the 3-D RMS error a new reading will have, predicted over the pool, now and
///    after each further pose: the stopping rule. The prediction is the field's: it leaves out the
///    calibration's and the registration's own uncertainty (small beside the field's with a few
///    hundred poses; docs/robot.md says what held-out data showed).

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "errfield/compensation/model/compensation.hpp"
#include "errfield/robot/mdh_model.hpp"

namespace errfield::compensation {

/// The standard normal quantile of the prediction's 90 % range (PoseSelection::predicted_rms_low_mm).
inline constexpr double kPredictionRangeZ = 1.645;

struct PoseSelectionOptions {
  std::size_t count = 0;  ///< poses to choose
  /// With a model: keep choosing (beyond count, for the prediction only) until the predicted 3-D RMS
  /// reaches this (mm), at most max_lookahead more poses. Empty: predict for `count` only.
  std::optional<double> target_rms_mm;
  std::size_t max_lookahead = 600;
  std::size_t max_references = 1000;  ///< see VarianceReductionOptions
  /// With a model: weight by where the model's leave-one-out errors exceeded its variance
  /// (local_error_scale in sampling_design.hpp).
  bool local_scale = true;
  /// With a model: first take the pool poses beyond the box of the poses measured so far (the
  /// region the model answers for, widened by its margin), the farthest per axis and side, so that
  /// no part of the pool stays refused by the next fit (box_extending_picks in sampling_design.hpp).
  bool extend_region = true;
  /// With a model: the greedy choice is only among pool poses at least this fraction of the
  /// farthest one's distance from everything measured or chosen (VarianceReductionOptions::
  /// spacing_floor); 0 = variance reduction alone. 0.7 by held-out RMS on six SIMULATED KR 16
  /// draws (docs/robot.md, "Which poses to measure"): a model fitted on 40-80 poses misplaces its
  /// picks, and the floor keeps them spread.
  double spacing_floor = 0.7;
  /// Throws ArgumentError naming the field.
  void validate() const;
};

struct PoseSelection {
  std::vector<std::size_t> chosen;  ///< indices into the candidates, in measuring order
  std::string design;               ///< for people: which design and why
  /// Model-based only: predicted 3-D RMS (mm) of a new reading over the pool and the measured poses
  /// (these and the chosen ones with their leave-one-out variance: VarianceReductionPlan), [0] with the poses
  /// measured so far, [k] after the first k chosen (and lookahead) poses; with joint error functions
  /// in the model, what the field's correction leaves of their estimation variance is included
  /// (VarianceReductionOptions::LinearTerm). With target_rms_mm, it ends where it reaches the target.
  std::vector<double> predicted_rms_mm;
  /// With target_rms_mm: how many poses (counted from now) the prediction needs to reach it; empty
  /// when not reached within count + max_lookahead poses of this pool.
  std::optional<std::size_t> poses_for_target;
  /// The prediction's uncertainty: the relative standard error of its mean squared error, that of
  /// the mean of the model's `leave_one_out_scores` z² (their standard deviation / mean / sqrt(N)),
  /// which set the prediction's level; 0 without them. The RMS's relative error is about half.
  double predicted_mse_relative_se = 0.0;
  std::size_t leave_one_out_scores = 0;
  /// predicted_rms_mm at the ends of its 90 % range (mean squared error times 1 -/+ 1.645 relative
  /// standard errors), entry by entry.
  std::vector<double> predicted_rms_low_mm, predicted_rms_high_mm;
  /// With target_rms_mm: poses_for_target by predicted_rms_low_mm (the fewest the prediction's
  /// range allows) and by predicted_rms_high_mm (the most; empty when the high end does not reach
  /// the target within count + max_lookahead poses). Advice between batches moves within this.
  std::optional<std::size_t> poses_for_target_low, poses_for_target_high;
  std::size_t conditioned_on = 0;  ///< measured poses the model-based choice was conditioned on
  std::size_t region_extending = 0;  ///< model-based: how many of `chosen` (the first) extend the region
  /// Candidates never chosen because their joints equal (exactly, as read) an earlier candidate's
  /// (`repeated`) or a measured pose's (`already_measured`): a pool with one pose five times had it
  /// chosen five times, and a pool holding the poses of measured data without a point label had 39
  /// measured poses chosen again. Indices into the candidates, ascending.
  std::vector<std::size_t> repeated, already_measured;
};

/// Chooses `options.count` of `candidates` (joints, deg), each distinct pose at most once. `measured`
/// are the poses measured so far: conditioned on, kept away from, and never chosen (a candidate
/// whose joints equal a measured pose's is left out; PoseSelection::already_measured). `model` may
/// be null (maximin); with a model, its field must be vector kriging (ArgumentError naming the
/// method otherwise; a `kinematic` model has no field to plan for) and the field's own training
/// poses are conditioned on too. ArgumentError naming PoseSelectionOptions::count when fewer
/// distinct candidates are left than `count` (never fewer chosen in silence).
PoseSelection select_poses(const std::vector<robot::JointVector>& candidates,
                           const std::vector<robot::JointVector>& measured, const CompensationModel* model,
                           const PoseSelectionOptions& options);

}  // namespace errfield::compensation
