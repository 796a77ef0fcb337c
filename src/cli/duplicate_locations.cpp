#include "cli/duplicate_locations.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <vector>

#include <iostream>

#include "errfield/error.hpp"

namespace errfield::cli {

DuplicateHandling duplicate_handling_from(const std::string& text, const std::string& option, bool keep_allowed) {
  if (text == "average") return DuplicateHandling::Average;
  if (text == "first") return DuplicateHandling::First;
  if (text == "refuse") return DuplicateHandling::Refuse;
  if (text == "keep" && keep_allowed) return DuplicateHandling::Keep;
  throw ArgumentError(option + ": '" + text + "'; expected " + (keep_allowed ? "keep, " : "") + "average, first or refuse");
}

MergedSamples merge_duplicate_locations(const Eigen::MatrixXd& x, const Eigen::MatrixXd& z, DuplicateHandling handling,
                                        const CsvTable& table, const std::string& option) {
  if (handling == DuplicateHandling::Keep) return {x, z, 0};
  const auto n = static_cast<std::size_t>(x.rows());
  // Rows sorted by their coordinates (then by row): equal locations are neighbours, the first row first.
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    for (Eigen::Index c = 0; c < x.cols(); ++c)
      if (x(static_cast<Eigen::Index>(a), c) != x(static_cast<Eigen::Index>(b), c))
        return x(static_cast<Eigen::Index>(a), c) < x(static_cast<Eigen::Index>(b), c);
    return a < b;
  });
  std::vector<std::size_t> group(n);  // the first row at each row's location
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t r = order[k];
    const bool same = k > 0 && x.row(static_cast<Eigen::Index>(r)) == x.row(static_cast<Eigen::Index>(order[k - 1]));
    group[r] = same ? group[order[k - 1]] : r;
    if (same && handling == DuplicateHandling::Refuse)
      throw InputError(table.source() + ":" + std::to_string(table.line_of_row(r)) + ": this sample and " + table.source() +
                           ":" + std::to_string(table.line_of_row(group[r])) +
                           " are at the same location; give " + option +
                           " average (one sample there, the mean of their values, as gstat users do before krige) or " +
                           option + " first (the earlier row's values)",
                       table.source(), table.line_of_row(r));
  }
  std::vector<std::size_t> slot(n, n), firsts;
  for (std::size_t r = 0; r < n; ++r)
    if (group[r] == r) {
      slot[r] = firsts.size();
      firsts.push_back(r);
    }
  const auto m = static_cast<Eigen::Index>(firsts.size());
  MergedSamples out{Eigen::MatrixXd(m, x.cols()), Eigen::MatrixXd::Zero(m, z.cols()), n - firsts.size()};
  Eigen::MatrixXd count = Eigen::MatrixXd::Zero(m, z.cols());
  for (Eigen::Index g = 0; g < m; ++g) out.x.row(g) = x.row(static_cast<Eigen::Index>(firsts[static_cast<std::size_t>(g)]));
  for (std::size_t r = 0; r < n; ++r) {
    const auto g = static_cast<Eigen::Index>(slot[group[r]]);
    for (Eigen::Index c = 0; c < z.cols(); ++c) {
      const double v = z(static_cast<Eigen::Index>(r), c);
      if (std::isnan(v)) continue;
      if (handling == DuplicateHandling::First && count(g, c) > 0.0) continue;
      out.z(g, c) += v;
      count(g, c) += 1.0;
    }
  }
  out.z = (count.array() > 0.0).select(out.z.array() / count.array(), std::numeric_limits<double>::quiet_NaN());
  return out;
}

void apply_duplicates_option(const std::string& text, const std::string& command, bool covariates_given, const CsvTable& table,
                             Eigen::MatrixXd& x, Eigen::MatrixXd& z) {
  const DuplicateHandling handling = duplicate_handling_from(text, "--duplicates", true);
  if (handling == DuplicateHandling::Keep) return;
  if (covariates_given && handling != DuplicateHandling::Refuse)
    throw ArgumentError("--duplicates " + text + " with --covariates: merge the duplicated rows of " + table.source() +
                        " first (the covariates are read per row)");
  MergedSamples merged = merge_duplicate_locations(x, z, handling, table, "--duplicates");
  if (merged.merged == 0) return;
  std::cerr << command << ": " << merged.merged << " row(s) at the location of an earlier row merged into it (--duplicates "
            << text << "): " << merged.x.rows() << " locations\n";
  x = std::move(merged.x);
  z = std::move(merged.z);
}

}  // namespace errfield::cli
