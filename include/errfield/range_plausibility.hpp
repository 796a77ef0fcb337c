#pragma once
/// Whether a fitted range means anything for the samples it was fitted to: a range below the
/// closest sample spacing is a nugget the samples cannot resolve, one far beyond the samples'
/// extent is a trend, not a range. Use it after a likelihood fit (fit_likelihood) or an
/// automatic model choice (choose_likelihood_model uses it) to refuse or warn before kriging
/// with a degenerate model (issue 49: a stripe of range 2.5e8 along x and 92 along y chosen for the
/// fulmar indicator; a free REML range 620 x the extent on oxford, "converged").

#include <string>
#include <vector>

#include <Eigen/Core>

#include "errfield/variogram_model.hpp"

namespace errfield {

/// Smallest distance between two distinct sample locations (the rows of `coordinates`);
/// +infinity with fewer than 2 distinct locations. A sweep along the first coordinate: O(N log N)
/// for spread-out data.
double smallest_sample_spacing(const Eigen::MatrixXd& coordinates);

/// The ranges of `model` that the samples cannot support, one sentence each (empty: none), for
/// samples spanning `extent` (max - min per coordinate) whose closest distinct locations are
/// `spacing` apart: a structure whose practical range (where its covariance falls to 5 % of its
/// sill; along each coordinate with an ARD anisotropy) is below the spacing (it acts as a nugget)
/// or beyond `factor` x the extent (along that coordinate; isotropic: the diagonal), named a trend
/// with what to do about it. Give spacing 0 or factor infinity to check one side only.
std::vector<std::string> implausible_ranges(const VariogramModel& model, const Eigen::RowVectorXd& extent, double spacing,
                                            double factor = 10.0);

/// The shape of `model`'s ranges for samples spanning `extent`, one sentence per problem (empty:
/// none): every range beyond `factor` x its coordinate's extent (a trend, not a range), or an
/// anisotropy ratio (longest / shortest range) beyond `ratio`, where a range beyond the factor
/// counts as factor x its extent: flat along one coordinate is an answer, flat along it with a
/// range along another far below the extent is a stripe per sample line. ARD ranges are compared
/// per coordinate, an isotropic range against the diagonal.
std::vector<std::string> implausible_range_shape(const VariogramModel& model, const Eigen::RowVectorXd& extent,
                                                 double factor = 10.0, double ratio = 100.0);

}  // namespace errfield
