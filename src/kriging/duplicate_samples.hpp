#pragma once
// The duplicate-sample check of kriging's and cokriging's engines: two samples at (near) the same
// location make the kriging matrix singular, so the engines find the first such pair and name it
// by file and line, the later row first like every row error ("S.csv:9: ... S.csv:5 ...").

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"
#include "errfield/row_labels.hpp"
#include "kriging/kd_tree.hpp"

namespace errfield::detail {

/// Two samples (column indices, first < later) at lag `lag` in the tree's space.
struct DuplicatePair {
  std::size_t first;
  std::size_t later;
  double lag;
};

/// The pair found first, scanning samples in index order, whose lag is <= `tolerance`, or none.
/// `tree` is built over `points` (D x N). O(N log N).
inline std::optional<DuplicatePair> first_duplicate(const PointTree& tree, const Eigen::MatrixXd& points,
                                                    double tolerance) {
  const auto n = static_cast<std::size_t>(points.cols());
  if (n < 2) return std::nullopt;
  const double tol2 = tolerance * tolerance;
  std::size_t idx[2];
  double d2[2];
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t found = tree.nearest(points.col(static_cast<Eigen::Index>(i)).data(), 2, idx, d2);
    for (std::size_t k = 0; k < found; ++k) {
      if (idx[k] == i || d2[k] > tol2) continue;
      return DuplicatePair{std::min(i, idx[k]), std::max(i, idx[k]), std::sqrt(d2[k])};
    }
  }
  return std::nullopt;
}

/// Throws the InputError for `pair`: "<later>: <who>: this sample and <first> are duplicates (lag
/// <lag><after_lag>" when `labels` has a line per sample (n samples), else "<who>: samples <first>
/// and <later> are duplicates (lag <lag><after_lag>". `after_lag` closes the parenthesis and says
/// what to do.
[[noreturn]] inline void throw_duplicate(const DuplicatePair& pair, const RowLabels& labels, std::size_t n,
                                         const std::string& who, const std::string& after_lag) {
  const bool labelled = labels.lines.size() == n;
  const std::string which =
      labelled ? labels(pair.later) + ": " + who + ": this sample and " + labels(pair.first)
               : who + ": samples " + std::to_string(pair.first) + " and " + std::to_string(pair.later);
  throw InputError(which + " are duplicates (lag " + format_number(pair.lag) + after_lag,
                   labelled ? labels.source : std::string(), labelled ? labels.line(pair.later) : 0);
}

}  // namespace errfield::detail
