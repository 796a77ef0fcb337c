#pragma once
/// A regular (axis-aligned, evenly spaced) 3-D grid of nodes: the cubic sampling grid of the
/// paper (SPEC §5: a 500 mm cube with a 125 mm step, 5 x 5 x 5 nodes). Use `RegularGrid3` to
/// describe such a grid and to number its nodes and cells; use `detect_regular_grid` to recognise
/// one in scattered sample coordinates (a CSV of measured grid points in any order), with a
/// precise error when the samples do not form a complete grid.
///
/// Numbering: node (i, j, k), 0 <= i < nx, ..., has index i + nx (j + ny k) (x fastest) and
/// position origin + (i step_x, j step_y, k step_z). Cell (i, j, k), 0 <= i < nx - 1, ..., is the
/// box between nodes (i, j, k) and (i+1, j+1, k+1). Coordinates are in the unit of the data
/// (mm for task space).

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "errfield/row_labels.hpp"

namespace errfield {

/// Immutable description of a regular grid. Cheap to copy; thread-safe.
class RegularGrid3 {
 public:
  /// origin: position of node (0,0,0); step: spacing per axis (> 0, finite); counts: nodes per
  /// axis (>= 2 each, so that the grid has at least one cell). Throws ArgumentError otherwise.
  RegularGrid3(const Eigen::Vector3d& origin, const Eigen::Vector3d& step, const std::array<int, 3>& counts);

  const Eigen::Vector3d& origin() const noexcept { return origin_; }
  const Eigen::Vector3d& step() const noexcept { return step_; }
  const std::array<int, 3>& counts() const noexcept { return counts_; }
  /// Lowest corner (= origin) and highest corner (origin + (counts - 1) * step).
  Eigen::Vector3d lower() const { return origin_; }
  Eigen::Vector3d upper() const;

  std::size_t node_count() const noexcept;
  std::size_t cell_count() const noexcept;
  /// Index of node (i, j, k); precondition 0 <= i < nx etc.
  std::size_t node_index(int i, int j, int k) const noexcept {
    return static_cast<std::size_t>(i) +
           static_cast<std::size_t>(counts_[0]) *
               (static_cast<std::size_t>(j) + static_cast<std::size_t>(counts_[1]) * static_cast<std::size_t>(k));
  }
  /// (i, j, k) of a node index; precondition index < node_count().
  std::array<int, 3> node_indices(std::size_t index) const noexcept;
  Eigen::Vector3d node_position(int i, int j, int k) const;
  Eigen::Vector3d node_position(std::size_t index) const;

  /// Whether p lies in the closed box [lower, upper], widened by `tolerance` (same unit) per side.
  bool contains(const Eigen::Vector3d& p, double tolerance = 0.0) const;

  /// "x [0, 500] step 125 (5 nodes), y [...], z [...]" for messages.
  std::string describe() const;

 private:
  Eigen::Vector3d origin_;
  Eigen::Vector3d step_;
  std::array<int, 3> counts_;
};

/// Numerical policy of detect_regular_grid.
struct GridDetectionOptions {
  /// Two coordinates on one axis closer than relative_tolerance x (extent of that axis) are the
  /// same grid plane, and a plane may sit that far from its ideal lattice position. Must be in
  /// (0, 1e-2]. The default accepts coordinates written with ~7 significant digits.
  double relative_tolerance = 1e-6;
  /// Throws ArgumentError naming the field when out of domain.
  void validate() const;
};

/// A grid recognised in scattered samples, and where each of its nodes came from.
struct GridDetection {
  RegularGrid3 grid;
  /// sample_of_node[n]: row of the input that is node n (every node has exactly one).
  std::vector<std::size_t> sample_of_node;
};

/// Recognises a complete regular grid in `points` (N x 3: x, y, z per row, any order).
///
/// Throws InputError (with file and line when `labels` names a file) when
///  - a coordinate is not finite, or fewer than 8 points are given;
///  - an axis has a single value (a 3-D grid needs >= 2 planes per axis);
///  - the planes of an axis are not evenly spaced (the message names the axis, its values and the
///    first gap that breaks the lattice);
///  - two samples fall on the same node (names both rows and the node);
///  - a node has no sample (names its indices and coordinates, the number of missing nodes and
///    the first few others).
/// Throws ArgumentError if `points` does not have 3 columns. O(N log N).
GridDetection detect_regular_grid(const Eigen::Ref<const Eigen::MatrixXd>& points, const RowLabels& labels = {},
                                  const GridDetectionOptions& options = {});

}  // namespace errfield
