#pragma once
// The gradient path of fit_likelihood (kriging_likelihood.hpp): one structure + nugget, isotropic
// or ARD, the sill profiled out, L-BFGS on log ranges and log(nugget / sill) with analytic
// gradients. Formulas: docs/kriging.md, "Likelihood fits".

#include <vector>

#include <Eigen/Core>

#include "errfield/kriging_likelihood.hpp"

namespace errfield::detail {

/// Whether the structure has a correlation with a closed-form derivative here.
bool profiled_fit_supported(const ModelComponent& structure);

/// x: N x D coordinates, z: N x C values (simple kriging: mean already subtracted), f: N x p drift.
/// Precondition: profiled_fit_supported(structure), inputs checked by the caller.
LikelihoodFitResult fit_profiled_likelihood(const Eigen::MatrixXd& x, const Eigen::MatrixXd& z, const Eigen::MatrixXd& f,
                                            const ModelComponent& structure, const LikelihoodFitOptions& options);

/// The profiled negative log-likelihood the fit minimizes, at theta = (log ranges: one, or one per
/// coordinate when `ard`; then log(nugget / sill) when `fit_nugget`), with its analytic gradient
/// when `gradient` is not null and the profiled sill in `sigma2`. For tests of the gradient.
double profiled_negative_log_likelihood(const Eigen::MatrixXd& x, const Eigen::MatrixXd& z, const Eigen::MatrixXd& f,
                                        const ModelComponent& structure, bool ard, bool fit_nugget, bool restricted,
                                        const std::vector<double>& theta, std::vector<double>* gradient,
                                        double* sigma2 = nullptr);

}  // namespace errfield::detail
