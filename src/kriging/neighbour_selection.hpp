#pragma once
// Which samples enter one target's system in the local back ends of kriging (local.cpp) and
// cokriging (cokriging.cpp): the k nearest within the radius, or, with no neighbour count, all
// within the radius. One set of buffers per thread, grown but never shrunk, so that warm targets
// allocate nothing.
//
// The radius is inclusive, as gstat's maxdist (its search keeps dist2 <= maxdist^2) and errfield's
// IDW: a sample at exactly the radius is a neighbour. nanoflann's searches are strict (<) and
// prune with rounded box distances, so the tree is asked for a slightly wider ball and the squared
// distance it computed (the same sum of squares gstat forms) decides. Ties are broken by sample
// index, so that the selection does not depend on the tree's internal order.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <utility>
#include <vector>

#include "kriging/kd_tree.hpp"

namespace errfield::detail {

/// One thread's search buffers and its result, `chosen`. A local back end's workspace derives from
/// it so that the system it builds reads the sample indices as `ws.chosen`.
struct NeighbourBuffers {
  std::vector<std::size_t> index;  ///< k-nearest hits; one more than the count asked (to see ties)
  std::vector<double> d2;          ///< their squared distances
  std::vector<std::pair<std::size_t, double>> hits;  ///< radius hits
  std::vector<std::pair<double, std::size_t>> ranked;  ///< candidates as (squared distance, index)
  std::vector<std::size_t> chosen;                   ///< the selected sample indices

  /// Sizes the k-nearest buffers for `k_query` hits per target (0 for a radius search).
  void size_for(std::size_t k_query) {
    index.resize(k_query > 0 ? k_query + 1 : 0);
    d2.resize(index.size());
  }
};

/// A squared radius for nanoflann's strict search that still returns every point whose computed
/// squared distance is <= r2 (the relative margin covers the rounding of its box distances).
inline double widened_for_search(double r2) {
  return std::max(r2 * (1.0 + 1e-12), std::numeric_limits<double>::min());
}

/// What a target's neighbourhood is (KrigingOptions' neighbors, radius, min_neighbours, octant_max).
struct NeighbourRule {
  std::size_t k_max = 0;                                  ///< nearest count; 0 = all within the radius
  double r2 = std::numeric_limits<double>::infinity();   ///< squared radius, inclusive
  std::size_t min_count = 0;                              ///< fewer candidates: no prediction (gstat's nmin)
  std::size_t octant_max = 0;                             ///< at most this many per quadrant/octant (gstat's omax)

  /// From the options' fields; the radius is squared here once.
  static NeighbourRule from(std::size_t neighbors, double radius, std::size_t min_neighbours, std::size_t octant_max) {
    return {neighbors, std::isfinite(radius) ? radius * radius : std::numeric_limits<double>::infinity(),
            min_neighbours, octant_max};
  }
};

/// The quadrant (2-D), octant (3-D) or half (1-D) of the target at `query` that the sample at `p`
/// lies in, as gstat numbers them (its which_octant): offset d = p - query; a sample on a dividing
/// axis is put in one quadrant by a rule that turns around the target, so that four samples at
/// equal distances along the axes land in four quadrants.
inline int octant_of(const double* p, const double* query, int dimension) {
  const double dx = p[0] - query[0];
  if (dimension == 1) return dx > 0.0 ? 1 : 0;
  const double dy = p[1] - query[1];
  const int x = dy < 0.0 ? (dx > 0.0) : (dx >= 0.0);
  const int y = dx < 0.0 ? (dy >= 0.0) : (dy > 0.0);
  const int z = dimension >= 3 && p[2] - query[2] < 0.0 ? 1 : 0;
  return x | (y << 1) | (z << 2);
}

/// Fills `buf.chosen` with the samples for the target at `query` (a column of the tree's space).
/// Candidates: with rule.k_max > 0 the k_max nearest that are not `self` and lie at squared distance
/// <= rule.r2, equal distances by increasing index (`buf` sized by size_for(k_max + 1) when `self`
/// is one of the samples, else size_for(k_max)); with k_max == 0 every sample but `self` at squared
/// distance <= r2. Fewer than rule.min_count candidates: `chosen` is left empty and false returned.
/// With rule.octant_max > 0 only the octant_max nearest candidates of each quadrant/octant
/// (octant_of) are kept, as gstat's omax after its nmax/maxdist search. `chosen` is nearest first
/// (k_max > 0) or in increasing index order (k_max == 0), so that the system (and its rounding)
/// does not depend on the tree's internal order. `self` is the sample to leave out (leave-one-out),
/// or any index >= N for none.
inline bool select_neighbours(const PointTree& tree, const double* query, const NeighbourRule& rule, std::size_t self,
                              NeighbourBuffers& buf) {
  buf.chosen.clear();
  auto& ranked = buf.ranked;
  ranked.clear();
  const std::size_t k_max = rule.k_max;
  if (k_max == 0) {
    tree.within(query, widened_for_search(rule.r2), buf.hits);
    for (const auto& h : buf.hits)
      if (h.first != self && h.second <= rule.r2) ranked.emplace_back(h.second, h.first);
  } else {
    const std::size_t found = tree.nearest(query, buf.index.size(), buf.index.data(), buf.d2.data());
    for (std::size_t a = 0; a < found; ++a)
      if (buf.index[a] != self && buf.d2[a] <= rule.r2) ranked.emplace_back(buf.d2[a], buf.index[a]);
    if (ranked.size() > k_max && ranked[k_max - 1].first == ranked[k_max].first) {
      // The k-th and the next are equally far: which of the equidistant samples the tree returned
      // is its internal order. Take all of them and keep the lowest indices.
      const double tie = ranked[k_max - 1].first;
      ranked.clear();
      tree.within(query, widened_for_search(tie), buf.hits);
      for (const auto& h : buf.hits)
        if (h.first != self && h.second <= tie) ranked.emplace_back(h.second, h.first);
    }
    const std::size_t keep = std::min(k_max, ranked.size());
    std::partial_sort(ranked.begin(), ranked.begin() + static_cast<std::ptrdiff_t>(keep), ranked.end());
    ranked.resize(keep);
  }
  if (ranked.size() < rule.min_count) return false;
  if (rule.octant_max > 0) {
    if (k_max == 0) std::sort(ranked.begin(), ranked.end());
    const int dimension = tree.dimension();
    std::size_t per_octant[8] = {};
    std::size_t kept = 0;
    for (const auto& r : ranked) {
      const int o = octant_of(tree.point(r.second), query, dimension);
      if (per_octant[o] < rule.octant_max) {
        ++per_octant[o];
        ranked[kept++] = r;
      }
    }
    ranked.resize(kept);
  }
  for (const auto& r : ranked) buf.chosen.push_back(r.second);
  if (k_max == 0) std::sort(buf.chosen.begin(), buf.chosen.end());
  return true;
}

}  // namespace errfield::detail
