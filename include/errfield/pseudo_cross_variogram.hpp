#pragma once
/// The pseudo cross-variogram of two variables measured at different locations (Myers 1991; Ver
/// Hoef & Cressie 1993): use it when two surveys are never co-located (two years of counts, a
/// primary and a secondary variable from different campaigns), where the classical
/// cross-variogram, a mean of products (A_i - A_j)(B_i - B_j) at pairs where both are measured,
/// has no pair at all.
///
/// For the pairs (i in A, j in B) whose lag h_ij = |x_i - x_j| (Euclidean) falls in bin k (N_k pairs):
///   gamma_AB,k = 1/(2 N_k) sum (z_A(x_i) - z_B(x_j))^2
/// over every i of A and every j of B (N_A N_B ordered pairs; it includes half the squared
/// difference of the means of z_A and z_B). R gstat's variogram(g, pseudo = TRUE) is this of the
/// residuals of each variable's own trend (for z ~ 1, z minus its mean: pass centred values; the
/// CLI's `variogram --pseudo` does), with its special estimate at lag exactly 0 (gstat's
/// ZERO_SPECIAL, the default for pseudo cross-variograms): pairs at distance 0 are counted in
/// `zero_lag`, not in the first bin. Bins follow `convention` (BinConvention::Gstat for gstat's). The
/// sums run in gstat's order (i over A, then j over B), so the result agrees with gstat's to the
/// last few bits. Cost O(N_A N_B D) time, O(bins) memory; single-threaded (fulmar's 595 x 729 pairs
/// take a few milliseconds).

#include <vector>

#include <Eigen/Core>

#include "errfield/empirical_variogram.hpp"

namespace errfield {

struct PseudoCrossVariogram {
  std::vector<VariogramBin> bins;  ///< one per bin of the LagBins; empty bin: pairs 0, lag_mean and gamma NaN
  /// The pairs at lag exactly 0 (a location of A that is also one of B): lag_lo = lag_hi = lag_mean = 0.
  VariogramBin zero_lag;
};

/// `coordinates_a` (N_A x D) with `values_a` (N_A), `coordinates_b` (N_B x D) with `values_b`
/// (N_B), D >= 1, N_A, N_B >= 1. Throws ArgumentError for mismatched sizes, InputError naming the
/// row for a non-finite coordinate or value.
PseudoCrossVariogram pseudo_cross_variogram(const Eigen::MatrixXd& coordinates_a, const Eigen::VectorXd& values_a,
                                            const Eigen::MatrixXd& coordinates_b, const Eigen::VectorXd& values_b,
                                            const LagBins& bins, BinConvention convention = BinConvention::Gstat);

}  // namespace errfield
