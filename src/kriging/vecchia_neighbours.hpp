#pragma once
// The ordering and conditioning sets of the Vecchia likelihood (kriging_likelihood.hpp,
// LikelihoodMethod::Vecchia): which samples each sample's density is conditioned on.

#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "errfield/kriging_likelihood.hpp"

namespace errfield::detail {

/// Position i of the ordering is sample order[i]; it is conditioned on the samples
/// sets[offsets[i] .. offsets[i + 1]) (sample indices, nearest first), all at earlier positions:
/// its min(i, m) nearest predecessors.
struct VecchiaNeighbours {
  std::vector<Eigen::Index> order;
  std::vector<std::size_t> offsets;
  std::vector<Eigen::Index> sets;
  std::size_t largest_set() const;
};

/// `points`: D x N, already in the metric the neighbours are sought in (ranges applied). m >= 1.
/// Deterministic: the same sets whatever the number of OpenMP threads.
VecchiaNeighbours find_vecchia_neighbours(const Eigen::MatrixXd& points, int m, VecchiaOrdering ordering);

/// Bytes the Vecchia evaluation of N samples with m neighbours, C value columns, p drift columns
/// and `parameters` covariance parameters keeps (neighbour sets, per-sample terms, a kd-tree).
double vecchia_memory_bytes(std::size_t n, int m, std::size_t columns, std::size_t parameters);

}  // namespace errfield::detail
