#pragma once
/// Direct and cross empirical variograms of heterotopic data: several value components, some not
/// measured at some locations (NaN there; an empty cell of `errfield variogram --value A,B`). Use
/// it before cokriging a secondary variable measured at fewer (or other) locations than the
/// primary.
///
/// Each direct variogram is over the pairs whose two ends both measure its component; each
/// cross-variogram (options.cross_variograms, Matheron) over the pairs where both components are
/// measured at both ends, the classical cross-variogram of collocated data (gstat's variogram() of
/// a multivariable object whose variables share their locations). Each is one pass of
/// empirical_variogram (empirical_variogram.hpp) over the rows that have its components, so the
/// conventions, bins, options and cost are that function's, once per variogram (K + K(K-1)/2 passes
/// and one over all locations). With pair_fraction < 1 the kept pairs are drawn per pass.

#include <Eigen/Core>

#include "errfield/empirical_variogram.hpp"

namespace errfield {

struct HeterotopicVariogram {
  /// component_gamma and cross_gamma as for complete data, each over its own pairs; bins[k] counts
  /// the pairs of all locations (pairs, lag_mean) and its gamma is the sum of the components' own.
  EmpiricalVariogram variogram;
  /// Pair count and mean lag of each direct variogram (bins x K) and each cross-variogram
  /// (bins x K(K-1)/2, EmpiricalVariogram::cross_column order); an empty bin has 0 pairs and NaN lag.
  Eigen::MatrixXd component_pairs, component_lag, cross_pairs, cross_lag;
};

/// Locations as the rows of an N x D matrix, values N x K with NaN where not measured (K >= 1).
/// Throws as empirical_variogram does, and InputError for an infinite value (naming row and
/// component). A component with fewer than 2 measured locations has no pair: gamma NaN.
HeterotopicVariogram heterotopic_variogram(const Eigen::MatrixXd& coordinates, const Eigen::MatrixXd& values,
                                           const LagBins& bins, const EmpiricalVariogramOptions& options = {});

}  // namespace errfield
