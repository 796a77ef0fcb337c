#include "errfield/pseudo_cross_variogram.hpp"

#include <cmath>
#include <limits>
#include <string>

#include "errfield/error.hpp"
#include "errfield/number_format.hpp"
#include "pair_binning.hpp"

namespace errfield {
namespace {

void check_finite(const Eigen::MatrixXd& x, const Eigen::VectorXd& z, const char* which) {
  for (Eigen::Index r = 0; r < x.rows(); ++r) {
    for (Eigen::Index c = 0; c < x.cols(); ++c)
      if (!std::isfinite(x(r, c)))
        throw InputError(std::string("pseudo cross-variogram: variable ") + which + ", location " + std::to_string(r + 1) +
                             ", coordinate " + std::to_string(c + 1) + " = " + format_number(x(r, c)) + "; expected a finite number",
                         "", 0, "");
    if (!std::isfinite(z(r)))
      throw InputError(std::string("pseudo cross-variogram: variable ") + which + ", location " + std::to_string(r + 1) +
                           ": value " + format_number(z(r)) + "; expected a finite number",
                       "", 0, "");
  }
}

}  // namespace

PseudoCrossVariogram pseudo_cross_variogram(const Eigen::MatrixXd& xa, const Eigen::VectorXd& za, const Eigen::MatrixXd& xb,
                                            const Eigen::VectorXd& zb, const LagBins& bins, BinConvention convention) {
  if (xa.rows() != za.size() || xb.rows() != zb.size())
    throw ArgumentError("pseudo cross-variogram: " + std::to_string(xa.rows()) + " and " + std::to_string(xb.rows()) +
                        " locations but " + std::to_string(za.size()) + " and " + std::to_string(zb.size()) + " values");
  if (xa.cols() != xb.cols() || xa.cols() < 1)
    throw ArgumentError("pseudo cross-variogram: the two variables' locations have " + std::to_string(xa.cols()) + " and " +
                        std::to_string(xb.cols()) + " coordinates; expected the same number, at least 1");
  if (xa.rows() < 1 || xb.rows() < 1)
    throw ArgumentError("pseudo cross-variogram: a variable with no location");
  check_finite(xa, za, "A");
  check_finite(xb, zb, "B");
  kernels::BinLayout layout;
  layout.edges = bins.edges().data();
  layout.bins = bins.size();
  layout.gstat = convention == BinConvention::Gstat;
  layout.uniform = bins.is_uniform();
  layout.inv_width = 1.0 / (bins.edges()[1] - bins.edges()[0]);
  const std::size_t n_bins = bins.size();
  std::vector<double> sum(n_bins + 1, 0.0), lag(n_bins + 1, 0.0);
  std::vector<std::uint64_t> count(n_bins + 1, 0);  // slot n_bins: lag exactly 0
  const Eigen::Index d = xa.cols();
  for (Eigen::Index i = 0; i < xa.rows(); ++i)
    for (Eigen::Index j = 0; j < xb.rows(); ++j) {
      double h2 = 0.0;
      for (Eigen::Index c = 0; c < d; ++c) {
        const double s = xa(i, c) - xb(j, c);
        h2 += s * s;
      }
      const double h = std::sqrt(h2);
      std::size_t slot = n_bins;
      if (h != 0.0) {
        const std::ptrdiff_t k = kernels::find_bin(h, layout);
        if (k < 0) continue;
        slot = static_cast<std::size_t>(k);
      }
      const double diff = za(i) - zb(j);
      sum[slot] += diff * diff;
      lag[slot] += h;
      ++count[slot];
    }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto bin_of = [&](std::size_t slot, double lo, double hi) {
    VariogramBin b;
    b.lag_lo = lo;
    b.lag_hi = hi;
    b.pairs = count[slot];
    b.lag_mean = count[slot] ? lag[slot] / static_cast<double>(count[slot]) : nan;
    b.gamma = count[slot] ? sum[slot] / (2.0 * static_cast<double>(count[slot])) : nan;
    return b;
  };
  PseudoCrossVariogram out;
  for (std::size_t k = 0; k < n_bins; ++k) out.bins.push_back(bin_of(k, bins.lag_lo(k), bins.lag_hi(k)));
  out.zero_lag = bin_of(n_bins, 0.0, 0.0);
  return out;
}

}  // namespace errfield
