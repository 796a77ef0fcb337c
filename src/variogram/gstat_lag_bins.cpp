#include "errfield/gstat_lag_bins.hpp"

#include <cmath>
#include <vector>

#include "errfield/error.hpp"
#include "errfield/number_format.hpp"

namespace errfield {

LagBins gstat_cutoff_width_bins(double cutoff, double width) {
  if (!std::isfinite(cutoff) || !(cutoff > 0.0))
    throw ArgumentError("lag bins: cutoff = " + format_number(cutoff) + "; expected a finite value > 0");
  if (!std::isfinite(width) || !(width > 0.0))
    throw ArgumentError("lag bins: width = " + format_number(width) + "; expected a finite value > 0");
  const double m = std::floor(cutoff / width);  // gstat: floor(cutoff / width) + 1 bins, the last cut at the cutoff
  if (m > 1e7)
    throw ArgumentError("lag bins: width = " + format_number(width) + " up to the cutoff " + format_number(cutoff) + " gives " +
                        format_number(m) + " bins; expected at most 10^7 (use a larger width)");
  std::vector<double> edges;
  for (double k = 0.0; k <= m; k += 1.0) edges.push_back(k * width);
  if (cutoff > edges.back()) edges.push_back(cutoff);
  return LagBins::from_edges(std::move(edges));
}

}  // namespace errfield
