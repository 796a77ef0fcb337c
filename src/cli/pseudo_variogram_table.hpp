#pragma once
// `errfield variogram --pseudo`: the direct variogram of each --value column over the rows that
// measure it and the pseudo cross-variogram of each pair (pseudo_cross_variogram.hpp), one block of
// rows per variogram, as R gstat's variogram(g, pseudo = TRUE) data frame.

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "cli/cli_support.hpp"
#include "errfield/empirical_variogram.hpp"

namespace errfield::cli {

/// x: N x D coordinates; z: N x K values, NaN where a column is not measured (K >= 2). Without
/// `shared_bins`, each variogram gets gstat's default bins of its own: a direct variogram those of
/// its column's locations, the pseudo cross-variogram of A before B those of B's (gstat's choice).
/// The pseudo cross-variograms pair each column's residuals from its mean (gstat's residuals of
/// z ~ 1), as gstat does. Columns id (A, or A.B as gstat names them), lag_lo, lag_hi, lag_mean, gamma, pairs; a pseudo
/// cross-variogram's pairs at lag exactly 0 (gstat's special zero estimate) in a row lag_lo = lag_hi
/// = 0 first in its block. `note` gets one line per variogram with pairs at lag 0.
OutputTable pseudo_variogram_table(const Eigen::MatrixXd& x, const Eigen::MatrixXd& z, const std::vector<std::string>& names,
                                   const std::optional<LagBins>& shared_bins, BinConvention convention, std::string& note);

}  // namespace errfield::cli
