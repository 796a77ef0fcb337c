#pragma once
/// Where to measure next: choosing sampling locations from a pool of candidates, for any error field
/// (a robot's joint space, a machine tool's work volume, a CMM's table). Two designs:
///
///  - `select_maximin`: no model yet. Greedy farthest-point (maximin) selection in coordinates scaled
///    per axis (by default each axis by its standard deviation over the pool, so that no unit
///    dominates): each pick is the candidate farthest from everything measured or picked so far. It
///    covers the pool evenly, which serves a first model fit and a kinematic calibration alike.
///  - `select_by_variance_reduction`: with a fitted covariance model. Greedy integrated variance
///    reduction: each pick is the candidate whose measurement (with its nugget) most reduces the
///    summed predictive variance over a reference set (the pool, or a deterministic subset of it),
///    under the Gaussian-process model the kriging uses; the unknown mean is a constant with a
///    large prior variance (ordinary kriging in the limit). The posterior is updated after each
///    pick without the pick's value, so a whole batch is chosen before anything is measured.
///    It also predicts the mean squared prediction error over the reference set before and after
///    each pick: the stopping rule's number (`predicted_mse`).
///
/// Both are deterministic (ties go to the lower candidate index), independent of the thread count.
/// Cost of the variance reduction: O(M·(R + C)·M) to condition on M measured locations, then per
/// pick O(R·C) over R references and C candidates; memory R·C doubles (80 MB at 1,000 × 10,000).
/// A linear term of p coefficients and K components adds O(C·M·p·K) to condition and O(C·p·K²
/// + p³) per pick, memory 3·K·C·p doubles.

#include <cstddef>
#include <functional>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "errfield/variogram_model.hpp"

namespace errfield {

struct MaximinOptions {
  std::size_t count = 0;  ///< how many to pick (at most the number of candidates)
  /// Per-axis scale of the coordinates; empty = each axis' standard deviation over the candidates
  /// (an axis without spread gets 1).
  std::vector<double> axis_scale;
};

/// Indices into the rows of `candidates` (one location per row), in picking order. `measured`
/// (one location per row, same columns; may be empty) counts as already picked. Throws
/// ArgumentError on a column mismatch, a non-finite coordinate or a non-positive scale.
std::vector<std::size_t> select_maximin(const Eigen::MatrixXd& candidates, const Eigen::MatrixXd& measured,
                                        const MaximinOptions& options);

struct VarianceReductionOptions {
  std::size_t count = 0;  ///< how many to pick
  /// Picks beyond `count` only to predict how the error would fall with more measurements (they
  /// are reported in predicted_mse, not in chosen); 0 = none.
  std::size_t lookahead = 0;
  /// Ends the look-ahead early: after the first look-ahead pick (or at once after the last of
  /// `count`) whose predicted_mse this returns true for. Empty: all `lookahead` picks.
  std::function<bool(double predicted_mse)> lookahead_done;
  /// The reference set over which variance is integrated: every candidate when there are at most
  /// this many, else a deterministic, evenly spread subset of this size (maximin order).
  std::size_t max_references = 1000;
  /// Prior variance of the unknown constant mean, as a multiple of the model's sill: large enough
  /// that the variances are those of ordinary kriging to a few percent, small enough to keep the
  /// systems well conditioned.
  double mean_variance_factor = 100.0;
  /// Per-candidate multiplier of the predictive variance (>= 0; empty = 1 everywhere): where the
  /// model is known to under- or over-state the error (local_error_scale), the variance reduction
  /// is weighted, and predicted_mse scaled, by it - a field whose errors grow at the workspace
  /// edges is sampled more there.
  std::vector<double> variance_scale;
  /// Candidate rows picked first, in this order, before the greedy choice (count includes them):
  /// locations the caller needs whatever their variance reduction (e.g. those that extend the
  /// region a model answers for). Distinct, and at most `count`.
  std::vector<std::size_t> first_picks;
  /// The measured locations count in predicted_mse too, each with its leave-one-out variance (when
  /// they were drawn from the same pool as the candidates: the prediction is then over the whole
  /// pool). Their variance multipliers in `measured_scale` (empty = 1), as variance_scale.
  bool measured_in_prediction = false;
  std::vector<double> measured_scale;
  /// A linear term beside the field (e.g. a regression fitted to the data before the field was,
  /// with coefficients beta): a reading at candidate c is D_c beta + field + noise, with D_c the
  /// candidate's `components` x p rows of `candidate_rows` (rows [components·c, components·(c+1))),
  /// and `measured_rows` the same rows at the measured locations. `covariance` is beta's covariance
  /// given the measured readings (p x p). The field's kriging takes back the part of the term's
  /// error that nearby readings share: what is left at c is D~_c = D_c - k(c,S) K_S^-1 D_S over the
  /// set S measured or picked (universal kriging's drift term), and the term adds tr(D~_c A D~_c')
  /// to c's predictive variance, per component. A pick b informs beta by D~_b with its field
  /// variance plus the noise (A <- A - A D~_b' (S_b + D~_b A D~_b')^-1 D~_b A). The choice adds
  /// the resulting fall of the term's mean variance tr(A Q~) / components, Q~ the mean of
  /// D~_c' D~_c over the candidates (the pick's effect on the other candidates' D~ counts in
  /// predicted_mse, not in the choice); predicted_mse adds the term's variance at every location it
  /// averages over, a member's with its rows as they were when it joined (a pick's D~ given the
  /// members before it, a measured location's given the other measured ones: what later picks
  /// would take back of it is not counted). beta's covariance is updated in square-root form, so it
  /// stays positive semi-definite however ill-conditioned. Empty `covariance`: no term. At most 8
  /// components.
  struct LinearTerm {
    Eigen::MatrixXd covariance;
    Eigen::MatrixXd candidate_rows;
    Eigen::MatrixXd measured_rows;
    int components = 1;
  };
  LinearTerm linear_term;
  /// A hedge against a model fitted on few readings, in [0, 1): a greedy pick is only among the
  /// candidates whose distance to the nearest measured or picked location (each axis scaled by its
  /// standard deviation over the candidates, as select_maximin) is at least this fraction of the
  /// largest such distance. 0: variance reduction alone. first_picks are exempt.
  double spacing_floor = 0.0;
};

/// Candidate rows that extend the box of `measured` (one location per row; per axis [min - margin,
/// max + margin]) to the candidates' own extent: while some candidate lies outside the box, the one
/// farthest beyond it on one axis and side (axes in order, lower side first) is picked and the box
/// grown by it. At most `limit` rows, in picking order. For a model that refuses locations outside
/// the box of its samples, these are the measurements without which part of the pool stays refused.
/// Empty `measured`: nothing (there is no box yet).
std::vector<std::size_t> box_extending_picks(const Eigen::MatrixXd& candidates, const Eigen::MatrixXd& measured,
                                             double margin, std::size_t limit);

struct VarianceReductionPlan {
  std::vector<std::size_t> chosen;  ///< candidate rows, in picking order (`count` of them)
  /// Mean over every candidate (and, with measured_in_prediction, measured location) of the
  /// predictive variance of a new measurement (field + nugget, times its variance scale), per
  /// component: [0] with the measured locations only, [k] after the first k picks (count +
  /// lookahead entries after [0], fewer if the candidates ran out). A picked candidate and a
  /// measured location count with their leave-one-out variance given every other member: what a
  /// new location near them would see. The references serve the choice only.
  std::vector<double> predicted_mse;
  /// The lookahead picks' rows (after `chosen`), for "how many more would it take".
  std::vector<std::size_t> lookahead_rows;
  std::size_t references = 0;
};

/// Greedy integrated-variance-reduction batch (see above). `model` must be bounded (a covariance
/// exists) and its anisotropy, if any, of the locations' dimension; the nugget components of
/// `model` are the measurement noise (added to every measurement, and to a new one in
/// predicted_mse). `measured` may be empty. Throws ArgumentError on bad shapes, an unbounded model,
/// or non-finite coordinates.
/// How much larger the errors of `values` (N x K, rows at `samples`) are than the model says,
/// locally, at each row of `query`: the leave-one-out squared residual of each sample divided by
/// its leave-one-out predictive variance (nugget included; averaged over the K components), then
/// averaged over the `neighbours` samples nearest each query point in the model's (anisotropy-
/// mapped) coordinates, and clamped to [0.1, 10]. 1 where the model is right on average. Same
/// covariance conventions as select_by_variance_reduction (the mean as a constant of large variance).
std::vector<double> local_error_scale(const Eigen::MatrixXd& samples, const Eigen::MatrixXd& values,
                                      const VariogramModel& model, const Eigen::MatrixXd& query,
                                      std::size_t neighbours = 10, double mean_variance_factor = 100.0);

/// Each sample's leave-one-out squared residual over its leave-one-out predictive variance (nugget
/// included), averaged over the K components of `values` (N x K): z² per sample, 1 on average where
/// the model is right. What local_error_scale averages locally; their mean and spread say how well
/// a model's variance level is known (the stopping rule's uncertainty, pose_selection.hpp). Empty
/// for fewer than 3 samples, a model without structured variance or a covariance that does not
/// factor. Same conventions and errors as local_error_scale. O(N³).
std::vector<double> leave_one_out_squared_z(const Eigen::MatrixXd& samples, const Eigen::MatrixXd& values,
                                            const VariogramModel& model, double mean_variance_factor = 100.0);

/// local_error_scale from the samples' z² computed already (leave_one_out_squared_z; empty: 1
/// everywhere), without factoring the samples' covariance again. ArgumentError when `squared_z`
/// is neither empty nor one per sample.
std::vector<double> local_error_scale(const Eigen::MatrixXd& samples, const std::vector<double>& squared_z,
                                      const VariogramModel& model, const Eigen::MatrixXd& query,
                                      std::size_t neighbours = 10);

VarianceReductionPlan select_by_variance_reduction(const Eigen::MatrixXd& candidates, const Eigen::MatrixXd& measured,
                                                   const VariogramModel& model,
                                                   const VarianceReductionOptions& options);

}  // namespace errfield
