#pragma once
// The non-template core behind errfield::Kriging: data in Eigen matrices, one class, three back
// ends in their own files (dense.cpp, local.cpp, sparse.cpp). Formulas: docs/kriging.md.
//
// Notation used in every back end (N samples, p drift terms, C value components):
//   K  (N x N) covariance of the observations: C(h_ij), diagonal obs_var_ (C(0) of the signal plus
//      the noise of the sample's observation: measurement variance, and nugget/replicates when the
//      nugget is measurement error)
//   F  (N x p) drift at the samples, f0 (p) at a target; c0 (N) target-sample covariances
//   K = L L';  Q = L^-1 F;  G = Q'Q = F'K^-1F = Lg Lg';  y = L^-1 z
//   beta = G^-1 Q'y;  alpha = K^-1 (z - F beta) = L^-T (y - Q beta)
//   w = L^-1 c0;  r = f0 - Q'w
//   mean = f0'beta + c0'alpha (= f0'beta + w'(y - Q beta))
//   var  = c00 - w'w + r'G^-1 r = c00 - |w|^2 + |Lg^-1 r|^2
//   weights = L^-T (w + Q G^-1 r)
// Simple kriging is the case p = 0 on values with the known mean subtracted.

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "covariance_kernel.hpp"
#include "errfield/kriging.hpp"
#include "kriging/kd_tree.hpp"
#include "lower_triangular_solve.hpp"

namespace errfield::detail {

class CholmodFactor;

class KrigingEngine {
 public:
  KrigingEngine(Eigen::MatrixXd embedded, Eigen::MatrixXd raw, Eigen::MatrixXd values,
                Eigen::VectorXd measurement_variance, const VariogramModel& model,
                const KrigingOptions& options, Eigen::VectorXd replicates = {});
  ~KrigingEngine();
  KrigingEngine(const KrigingEngine&) = delete;
  KrigingEngine& operator=(const KrigingEngine&) = delete;

  const KrigingReport& report() const { return report_; }
  const KrigingOptions& options() const { return options_; }
  /// Non-empty `block_weights` (g weights summing to 1): block kriging. The columns come in
  /// consecutive groups of g points that discretize one block each (the same offsets for every
  /// block); each target is the block's weighted average: covariances and drift averaged over its
  /// points, the block-to-block covariance from the first group (translation invariant) without
  /// the nugget (micro-scale variation averages out over a block, as gstat has it). Dense and local.
  /// `with_weights`: the weights too for this call, as options().keep_weights gives them (dense and
  /// local back ends).
  KrigingOutput predict(const Eigen::MatrixXd& embedded, const Eigen::MatrixXd& raw,
                        const Eigen::VectorXd& block_weights = Eigen::VectorXd(), bool with_weights = false) const;
  KrigingOutput leave_one_out() const;
  /// Dense back end, no merged samples: the leave-one-out residuals v_i - sum_j w_ij v_j that the
  /// samples' leave-one-out weights give for other values (N x K, rows in the order the samples
  /// were given); linear in v (simple kriging's mean is not added: the operator on deviations).
  Eigen::MatrixXd leave_one_out_residuals_of(const Eigen::MatrixXd& values) const;
  KrigingOutput k_fold(int folds, std::uint64_t seed) const;

 private:
  // set-up
  void merge_duplicates();
  void set_observation_noise();
  void build_drift();
  void setup_dense();
  void setup_sparse();
  bool check_condition(double rcond);
  // drift row of one point (raw coordinates, D doubles) into out (p doubles)
  void drift_row(const double* raw_point, double* out) const;
  // "linear drift (order 1: 1 + 3 coordinate terms)" etc., for messages.
  std::string drift_description() const;
  // SingularDrift report message: the drift order and the sample geometry that makes it singular.
  std::string singular_drift_message(double rcond) const;
  // Names the first covariate that adds nothing to the drift terms before it at the samples;
  // empty when none does.
  std::string collinear_covariate_message() const;
  Eigen::MatrixXd drift_matrix(const Eigen::MatrixXd& raw) const;  // p x M
  // C(0) on the target side: the total sill (micro-scale nugget) or without nugget (signal)
  double target_variance() const;
  double target_zero_covariance() const { return target_variance(); }
  // back ends
  KrigingOutput predict_dense(const Eigen::MatrixXd& embedded, const Eigen::MatrixXd& raw,
                              const Eigen::VectorXd& block_weights, bool with_weights = false) const;
  KrigingOutput predict_local(const Eigen::MatrixXd& embedded, const Eigen::MatrixXd& raw,
                              bool leave_one_out, const Eigen::VectorXd& block_weights = Eigen::VectorXd(),
                              bool with_weights = false) const;
  // Block kriging: the weighted mean over the first group's pairs of points of their covariance
  // (the structured sill at coincident points), and the drift matrix averaged over each group
  // (p x M/g). Without weights: the target's point variance and the plain drift matrix.
  double block_variance(const Eigen::MatrixXd& embedded, const Eigen::VectorXd& block_weights) const;
  Eigen::MatrixXd block_drift_matrix(const Eigen::MatrixXd& raw, const Eigen::VectorXd& block_weights) const;
  KrigingOutput predict_sparse(const Eigen::MatrixXd& embedded, const Eigen::MatrixXd& raw) const;
  KrigingOutput loo_dense() const;
  // diag of P, the top-left block of the bordered system's inverse (Dubrule's 1 / variance),
  // computed once (n^3/3 flops: a fit asks for it three or four times per field)
  const Eigen::VectorXd& loo_precision_diagonal() const;
  Eigen::VectorXd compute_loo_precision_diagonal() const;
  KrigingOutput unusable_output() const;
  void add_simple_mean(Eigen::MatrixXd& mean) const;
  int thread_count() const;
  // Sparse back end's memory budget (dense_memory_budget_bytes), before assembly and before the
  // numeric factorization.
  void check_sparse_budget_before_assembly(double r2) const;
  ResourceError sparse_over_budget(const std::string& what) const;

  KrigingOptions options_;
  VariogramModel model_;
  kernels::CovarianceKernel kernel_;
  Eigen::MatrixXd points_;     // D x N embedded coordinates
  Eigen::MatrixXd raw_;        // (D + k) x N original coordinates (drift), then the k covariates
  Eigen::MatrixXd search_points_;  // D x N coordinates for search_tree_
  Eigen::MatrixXd values_;     // N x C, simple kriging: mean subtracted
  Eigen::MatrixXd observed_;   // N x C as given (after merging), for cross-validation
  Eigen::VectorXd meas_;       // N (zeros when none given; after merging: variance of the mean)
  Eigen::VectorXd replicates_; // N: observations averaged into each sample (1 unless merged)
  Eigen::VectorXd noise_;      // N: variance of the sample's observation error (see set_observation_noise)
  Eigen::VectorXd obs_var_;    // N: diagonal of K, C(0) of the signal + noise_
  std::vector<std::size_t> original_index_;  // merged sample -> index given by the caller
  Eigen::VectorXd simple_mean_;               // C
  int dimension_ = 0;
  int components_ = 0;
  int drift_terms_ = 0;
  int covariates_ = 0;  // k: external-drift covariates (rows D.. of raw_, last columns of f_)
  Eigen::VectorXd drift_center_, drift_scale_;
  Eigen::MatrixXd f_;  // N x p
  std::unique_ptr<PointTree> tree_;
  // Local back end with NeighbourMetric::Euclidean: neighbours by the raw coordinates (over raw_).
  std::unique_ptr<PointTree> search_tree_;
  KrigingReport report_;

  // dense and sparse: global solution
  Eigen::LLT<Eigen::MatrixXd> llt_;  // dense factor
  kernels::PackedLower packed_l_;    // dense: L packed for the variance kernel (refers to llt_)
  Eigen::MatrixXd q_;                // L^-1 F (dense: N x p; sparse: L^-1 P F)
  Eigen::LLT<Eigen::MatrixXd> g_llt_;
  Eigen::MatrixXd beta_;             // p x C
  Eigen::MatrixXd alpha_;            // N x C
  Eigen::MatrixXd kinv_f_;           // sparse: K^-1 F (N x p)
  std::unique_ptr<CholmodFactor> sparse_;
  mutable std::once_flag pdiag_once_;
  mutable Eigen::VectorXd pdiag_;
};

}  // namespace errfield::detail
