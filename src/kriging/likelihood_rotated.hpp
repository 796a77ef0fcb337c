#pragma once
// The rotated-anisotropy path of fit_likelihood (kriging_likelihood.hpp): gstat's anis in 2-D/3-D,
// angles by a derivative-free profile search around the ARD fit of rotated coordinates.

#include <Eigen/Core>

#include "errfield/kriging_likelihood.hpp"

namespace errfield::detail {

/// x: N x D coordinates (D = 2 or 3, else ArgumentError), z: N x C values, f: N x p drift.
/// Precondition: profiled_fit_supported(structure), inputs checked by the caller.
LikelihoodFitResult fit_rotated_likelihood(const Eigen::MatrixXd& x, const Eigen::MatrixXd& z,
                                           const Eigen::MatrixXd& f, const ModelComponent& structure,
                                           const LikelihoodFitOptions& options);

}  // namespace errfield::detail
