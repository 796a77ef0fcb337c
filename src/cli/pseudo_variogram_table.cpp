#include "cli/pseudo_variogram_table.hpp"

#include <cmath>

#include "errfield/pseudo_cross_variogram.hpp"

namespace errfield::cli {
namespace {

/// The rows (coordinates, values) where column c is measured.
struct Measured {
  Eigen::MatrixXd x;
  Eigen::VectorXd z;
};

Measured measured(const Eigen::MatrixXd& x, const Eigen::MatrixXd& z, Eigen::Index c) {
  Eigen::Index n = 0;
  for (Eigen::Index r = 0; r < z.rows(); ++r) n += std::isnan(z(r, c)) ? 0 : 1;
  Measured m{Eigen::MatrixXd(n, x.cols()), Eigen::VectorXd(n)};
  for (Eigen::Index r = 0, k = 0; r < z.rows(); ++r)
    if (!std::isnan(z(r, c))) {
      m.x.row(k) = x.row(r);
      m.z(k++) = z(r, c);
    }
  return m;
}

}  // namespace

OutputTable pseudo_variogram_table(const Eigen::MatrixXd& x, const Eigen::MatrixXd& z, const std::vector<std::string>& names,
                                   const std::optional<LagBins>& shared_bins, BinConvention convention, std::string& note) {
  std::vector<std::string> id, lo, hi, mean, gamma, pairs;
  const auto cell = [](double v) { return std::isnan(v) ? std::string() : format_number(v); };
  const auto add = [&](const std::string& name, const VariogramBin& b) {
    id.push_back(name);
    lo.push_back(format_number(b.lag_lo));
    hi.push_back(format_number(b.lag_hi));
    mean.push_back(cell(b.lag_mean));
    gamma.push_back(cell(b.gamma));
    pairs.push_back(std::to_string(b.pairs));
  };
  std::vector<Measured> columns;
  for (Eigen::Index c = 0; c < z.cols(); ++c) {
    columns.push_back(measured(x, z, c));
    if (columns.back().z.size() < 2)
      throw InputError("--pseudo: column '" + names[static_cast<std::size_t>(c)] + "' is measured at " +
                       std::to_string(columns.back().z.size()) + " row(s); each --value column needs at least 2 for its variogram");
  }
  const auto bins_of = [&](const Measured& m) { return shared_bins ? *shared_bins : LagBins::gstat_default(m.x); };
  EmpiricalVariogramOptions options;
  options.convention = convention;
  for (std::size_t c = 0; c < names.size(); ++c) {
    const EmpiricalVariogram v = empirical_variogram(columns[c].x, columns[c].z, bins_of(columns[c]), options);
    for (const VariogramBin& b : v.bins) add(names[c], b);
  }
  for (std::size_t a = 0; a < names.size(); ++a)
    for (std::size_t b = a + 1; b < names.size(); ++b) {
      const std::string name = names[a] + "." + names[b];
      // gstat computes the cross-variogram of A and B with B (the later variable) first: its bins by
      // default and the order of its sums.
      // gstat pairs the residuals of each variable's own trend (z ~ 1: z minus its mean; sem.c's
      // make_residuals_lm), so a difference between the two means does not enter the pseudo
      // cross-variogram.
      const Eigen::VectorXd ra = columns[a].z.array() - columns[a].z.mean();
      const Eigen::VectorXd rb = columns[b].z.array() - columns[b].z.mean();
      const PseudoCrossVariogram p = pseudo_cross_variogram(columns[b].x, rb, columns[a].x, ra, bins_of(columns[b]), convention);
      if (p.zero_lag.pairs > 0) {
        add(name, p.zero_lag);
        note += "variogram --pseudo: " + std::to_string(p.zero_lag.pairs) + " pair(s) of " + name +
                " at lag 0 (locations measuring both), in their own row lag_lo = lag_hi = 0 (gstat's zero estimate)\n";
      }
      for (const VariogramBin& bin : p.bins) add(name, bin);
    }
  OutputTable out;
  out.add_column("id", id);
  out.add_column("lag_lo", lo);
  out.add_column("lag_hi", hi);
  out.add_column("lag_mean", mean);
  out.add_column("gamma", gamma);
  out.add_column("pairs", pairs);
  return out;
}

}  // namespace errfield::cli
