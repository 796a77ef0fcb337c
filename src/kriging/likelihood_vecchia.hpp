#pragma once
// The Vecchia approximation of the Gaussian (restricted) negative log-likelihood
// (kriging_likelihood.hpp, LikelihoodMethod::Vecchia). Formulas: docs/kriging.md, "Vecchia likelihood".

#include <vector>

#include <Eigen/Core>

#include "errfield/kriging_likelihood.hpp"
#include "kriging/correlation_derivative.hpp"
#include "kriging/vecchia_neighbours.hpp"

namespace errfield::detail {

/// The profiled negative log-likelihood of likelihood_profile.hpp under the Vecchia approximation:
/// u: D x N coordinates divided by the ranges, correlation R(u) + g I with g = nugget / sill,
/// z: N x C values, f: N x p drift. With `gradient` (size ranges + nugget): d nll / d log range
/// (one per row of u when `ard`, else one) and d nll / d log g (when `fit_nugget`). The profiled
/// sill in `sigma2`. Returns +infinity when a conditional variance is not positive. Per-sample terms
/// run on the OpenMP threads and are summed in a fixed order: the result does not depend on their
/// number.
double vecchia_profiled_nll(const Eigen::MatrixXd& u, const Eigen::MatrixXd& z, const Eigen::MatrixXd& f,
                            const VecchiaNeighbours& neighbours, const Correlation& correlation, double g, bool ard,
                            bool fit_nugget, bool restricted, double* gradient, double* sigma2);

/// The (restricted) negative log-likelihood of any bounded `model` under the Vecchia
/// approximation; points: D x N, already mapped by the model's anisotropy. +infinity when a
/// conditional variance is not positive.
double vecchia_model_nll(const Eigen::MatrixXd& points, const Eigen::MatrixXd& z, const Eigen::MatrixXd& f,
                         const VariogramModel& model, bool restricted, const VecchiaNeighbours& neighbours);

}  // namespace errfield::detail
