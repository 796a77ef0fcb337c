#pragma once
/// The variogram before binning: the **cloud** (every pair of samples with its distance and
/// semivariance) and the **map** (semivariances averaged over cells of the lag *vector*). Use the
/// cloud to find the pairs behind an odd bin (an outlier shows as a band of high gamma at every
/// lag) and the map, on 2-D data, to see anisotropy before choosing directions (anisotropy.hpp,
/// variogram_direction.hpp). Both follow R gstat's variogram(..., cloud = TRUE) and
/// variogram(..., map = TRUE, cutoff, width); docs/geostatistics.md, "Variogram cloud and map".
///
/// gamma of a pair is 0.5 |z_i - z_j|^2 (summed over the value columns for a vector value, as the
/// binned variogram). Both are O(N^2) pair loops without a distance matrix; the cloud stores what
/// it returns, 24 bytes a pair, and refuses (ResourceError) before storing when the pairs within
/// the cutoff would exceed max_pairs.

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "errfield/variogram_direction.hpp"

namespace errfield {

struct VariogramCloudOptions {
  /// Pairs at a distance <= cutoff (gstat's rule, a pair exactly at the cutoff included); > 0.
  double cutoff = 0.0;
  /// The pairs of one direction only (gstat's alpha/tol.hor, beta/tol.ver); default every pair.
  VariogramDirection direction;
  /// Budget of stored pairs: more within the cutoff is a ResourceError naming the count and the
  /// cutoff that would fit (default 1,000,000: 24 MB, a CSV of some 40 MB).
  std::uint64_t max_pairs = 1'000'000;
};

/// One row per pair (i, j) with i > j, ordered by i then j (gstat's order); indices are 0-based
/// rows of the input (gstat's left/right are these plus one).
struct VariogramCloud {
  std::vector<std::uint32_t> left, right;
  std::vector<double> dist, gamma;
  std::size_t size() const noexcept { return dist.size(); }
};

/// coordinates N x D (any D >= 1; D of 2 or 3 for a gstat direction), values N x C, all finite.
/// Throws ArgumentError for bad options or shapes, InputError for a non-finite number (naming the
/// row), ResourceError over the budget.
VariogramCloud variogram_cloud(const Eigen::MatrixXd& coordinates, const Eigen::MatrixXd& values,
                               const VariogramCloudOptions& options);

/// Cells of width width_x by width_y centred on -cutoff + k * width for k = 0 .. n - 1, with
/// n = floor(2 cutoff / width + 1e-10) + 1 per axis (R's length(seq(-cutoff, cutoff, by = width));
/// gstat has one width for both axes). Every pair counts twice, at its lag vector s = x_i - x_j
/// and at -s, so the map is symmetric through the origin; a lag falls in the cell of column
/// floor((s_x - x_left) / width_x) and row floor((y_top - s_y) / width_y) (x_left the grid's left
/// edge, y_top its top edge; a lag on the right or bottom edge goes to the last cell, one outside
/// the grid to none) - gstat's rule, so that a lag exactly half-way between two cell centres goes
/// to the larger one in x and the smaller one in y, as in gstat.
struct VariogramMapOptions {
  double cutoff = 0.0;   ///< > 0
  double width_x = 0.0;  ///< > 0, at most 2 cutoff
  double width_y = 0.0;  ///< > 0, at most 2 cutoff
};

/// Cells row-major from the top row (largest lag y) down, x increasing within a row: gstat's order.
struct VariogramMap {
  int columns = 0, rows = 0;
  std::vector<double> lag_x;  ///< columns: cell centres in x
  std::vector<double> lag_y;  ///< rows: cell centres in y, decreasing
  std::vector<std::uint64_t> pairs;  ///< rows x columns: lag vectors in the cell (each pair twice, +s and -s)
  std::vector<double> gamma;         ///< rows x columns: mean of 0.5 |z_i - z_j|^2; NaN where pairs is 0
};

/// coordinates N x 2, values N x C, finite. Throws ArgumentError for other shapes or options,
/// InputError for a non-finite number, ResourceError beyond 4,000,000 cells.
VariogramMap variogram_map(const Eigen::MatrixXd& coordinates, const Eigen::MatrixXd& values,
                           const VariogramMapOptions& options);

}  // namespace errfield
