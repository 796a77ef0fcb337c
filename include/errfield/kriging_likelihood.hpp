#pragma once
/// Estimating the kriging model's parameters by maximum likelihood (ML) or restricted maximum
/// likelihood (REML) of a Gaussian field, instead of fitting an empirical variogram. Use it when
/// the samples are few or irregular (a binned variogram is then noisy); REML corrects the bias of
/// ML in the sill when a mean or drift is estimated.
///
/// With K(theta) the covariance of the observations (the model's C(h), total sill on the
/// diagonal), F the drift (ordinary: a column of ones; universal: the polynomial drift) and
/// beta_hat = (F'K^-1F)^-1 F'K^-1 z, the negative log-likelihoods are
///   ML:   0.5 [ log det K + (z - F beta)'K^-1(z - F beta) + N log 2 pi ]
///   REML: 0.5 [ log det K + log det F'K^-1F + (z - F beta)'K^-1(z - F beta) + (N - p) log 2 pi ]
/// (simple kriging: F empty, z minus the known mean). Scalar values only. Dense: O(N^3) per
/// evaluation, so meant for N up to a few thousand. Coordinates are Euclidean (scale them first
/// for a weighted metric).

#include <string>
#include <vector>

#include <Eigen/Core>

#include "errfield/kriging.hpp"
#include "errfield/variogram_model.hpp"

namespace errfield {

struct LikelihoodFitOptions {
  bool restricted = true;                   ///< REML (true) or ML (false)
  KrigingKind kind = KrigingKind::Ordinary; ///< which mean the likelihood profiles out
  int drift_order = 1;                      ///< Universal: 0, 1 or 2
  double simple_mean = 0.0;                 ///< Simple: the known mean
  bool fit_nugget = true;                   ///< estimate a nugget (else none)
  int max_evaluations = 3000;
  double relative_tolerance = 1e-9;
  /// Throws ArgumentError naming the field.
  void validate() const;
};

struct LikelihoodFitResult {
  VariogramModel model;                    ///< the estimate (structure components, then the nugget)
  double negative_log_likelihood = 0.0;    ///< at the estimate (ML or REML as asked)
  int evaluations = 0;
  bool converged = false;                  ///< NLopt met a tolerance (not the evaluation limit)
  std::string message;                     ///< NLopt's outcome in words
};

/// The (restricted) negative log-likelihood above for `model` at samples given as the rows of
/// `coordinates` (N x D) with scalar `values` (N). Returns +infinity when K or F'K^-1F is not
/// positive definite. Throws ArgumentError for mismatched sizes or an unbounded model.
double negative_log_likelihood(const Eigen::MatrixXd& coordinates, const Eigen::VectorXd& values,
                               const VariogramModel& model, const LikelihoodFitOptions& options);

/// Maximizes the (restricted) likelihood over the partial sills and ranges of `structure` (kinds
/// and Matérn nu fixed; non-zero parameters are the starting point, else data-based defaults) and
/// a nugget, with NLopt's BOBYQA on log-parameters. Throws ArgumentError / InputError for bad
/// input; the optimizer's outcome is in the result.
LikelihoodFitResult fit_likelihood(const Eigen::MatrixXd& coordinates, const Eigen::VectorXd& values,
                                   const std::vector<ModelComponent>& structure,
                                   const LikelihoodFitOptions& options = {});

}  // namespace errfield
