#pragma once
/// R gstat's lag bins for variogram(..., cutoff = C, width = W), as LagBins
/// (empirical_variogram.hpp): use them with BinConvention::Gstat to get gstat's variogram bin for bin.

#include "errfield/empirical_variogram.hpp"

namespace errfield {

/// Edges 0, W, 2W, ..., mW with m = floor(C / W), then C when C > mW: gstat's floor(C / W) + 1
/// bins, the last one cut at the cutoff (gstat counts no lag above C; its bin (C, C + W] when C is a
/// multiple of W is always empty and dropped). With BinConvention::Gstat: [0, W], (W, 2W], ...
/// Throws ArgumentError naming `cutoff` or `width` (finite, > 0), or beyond 10^7 bins.
LagBins gstat_cutoff_width_bins(double cutoff, double width);

}  // namespace errfield
