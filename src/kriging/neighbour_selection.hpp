#pragma once
// Which samples enter one target's system in the local back ends of kriging (local.cpp) and
// cokriging (cokriging.cpp): the k nearest within the radius, or, with no neighbour count, all
// within the radius. One set of buffers per thread, grown but never shrunk, so that warm targets
// allocate nothing.

#include <algorithm>
#include <cstddef>
#include <utility>
#include <vector>

#include "kriging/kd_tree.hpp"

namespace errfield::detail {

/// One thread's search buffers and its result, `chosen`. A local back end's workspace derives from
/// it so that the system it builds reads the sample indices as `ws.chosen`.
struct NeighbourBuffers {
  std::vector<std::size_t> index;  ///< k-nearest hits; its size is the count asked of the tree
  std::vector<double> d2;          ///< their squared distances
  std::vector<std::pair<std::size_t, double>> hits;  ///< radius hits
  std::vector<std::size_t> chosen;                   ///< the selected sample indices

  /// Sizes the k-nearest buffers for `k_query` hits per target (0 for a radius search).
  void size_for(std::size_t k_query) {
    index.resize(k_query);
    d2.resize(k_query);
  }
};

/// Fills `buf.chosen` with the samples for the target at `query` (a column of the tree's space).
/// With k_max > 0: the first k_max of the `buf.index.size()` nearest that are not `self` and lie at
/// squared distance < r2, nearest first (ask for k_max + 1 when `self` is one of the samples).
/// With k_max == 0: every sample but `self` at squared distance < r2, in increasing index order,
/// so that the system (and its rounding) does not depend on the tree's internal order.
/// `self` is the sample to leave out (leave-one-out), or any index >= N for none.
inline void select_neighbours(const PointTree& tree, const double* query, std::size_t k_max, double r2,
                              std::size_t self, NeighbourBuffers& buf) {
  buf.chosen.clear();
  if (k_max > 0) {
    const std::size_t found = tree.nearest(query, buf.index.size(), buf.index.data(), buf.d2.data());
    for (std::size_t a = 0; a < found && buf.chosen.size() < k_max; ++a)
      if (buf.index[a] != self && buf.d2[a] < r2) buf.chosen.push_back(buf.index[a]);
  } else {
    tree.within(query, r2, buf.hits);
    for (const auto& h : buf.hits)
      if (h.first != self) buf.chosen.push_back(h.first);
    std::sort(buf.chosen.begin(), buf.chosen.end());
  }
}

}  // namespace errfield::detail
