#pragma once
/// Residuals of an ordinary least-squares trend in covariates: z - F beta_hat with
/// F = [1, cov_1, ..., cov_k] and beta_hat = argmin |z - F beta|^2, per value column.
///
/// This is what R gstat's `variogram(z ~ cov1 + cov2, data)` takes the variogram of (its
/// residuals come from an OLS fit, not a generalized least-squares one), so the residual variogram
/// for kriging with external drift is empirical_variogram(coords, ols_trend_residuals(z, cov), ...).
/// The OLS trend ignores the spatial correlation: the residual variogram is a biased estimate of
/// the residual process' variogram (too low at long lags); the likelihood fit with covariates
/// (LikelihoodFitOptions::covariates) has no such bias. See docs/kriging.md.

#include <string>
#include <vector>

#include <Eigen/Core>

#include "errfield/row_labels.hpp"

namespace errfield {

/// values: N x C; covariates: N x k (k >= 0; k = 0 leaves z minus its mean), column j named
/// names[j] in messages (may be empty). Throws ArgumentError for mismatched sizes, InputError
/// naming the row (`labels`) and the covariate for a non-finite value, and InputError naming the
/// covariate that is constant or a linear combination of the ones before it (F rank-deficient).
Eigen::MatrixXd ols_trend_residuals(const Eigen::MatrixXd& values, const Eigen::MatrixXd& covariates,
                                    const std::vector<std::string>& names = {}, const RowLabels& labels = {});

}  // namespace errfield
