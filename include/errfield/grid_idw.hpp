#pragma once
/// Inverse-distance weighting on a regular 3-D grid: the paper's interpolation rule (SPEC §5,
/// eqs. 19-21). Use it when the error was measured at the nodes of a complete regular grid (the
/// paper's 125 mm cube) and is wanted at arbitrary targets inside it: each target is interpolated
/// from the 8 vertices of the cell that holds it,
///
///     d_j = |P - P_j|,   w_j = 1 / d_j^p,   value(P) = sum_j w_j v_j / sum_j w_j     (p = 1 in the paper)
///
/// and a target within `vertex_tolerance` of a vertex takes that vertex's value (exact at the
/// data). A target outside the grid is an error by default (OutsideGridError naming the target and
/// the grid bounds); with `clamp` it is interpolated from the nearest cell, using its true distances
/// to that cell's vertices. `predict_with_status` never throws for a target's position and
/// reports a status per target instead, for pipelines. Mathematics and conventions: docs/idw.md.
///
/// Generic over the Value (double, Eigen::Vector3d, any fixed-size Eigen vector); coordinates are
/// in the grid's unit (mm in task space). Immutable after construction; all methods are const
/// and thread-safe. Batch predictions run in parallel (OpenMP over targets) and give identical
/// results for any number of threads.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "errfield/concepts.hpp"
#include "errfield/detail/value_layout.hpp"
#include "errfield/error.hpp"
#include "errfield/regular_grid.hpp"
#include "errfield/row_labels.hpp"
#include "grid_idw_kernel.hpp"

namespace errfield {

struct GridIdwOptions {
  /// Power p of the weights 1/d^p; p >= 0 (p = 0 is the plain mean of the 8 vertices). The paper
  /// uses p = 1.
  double power = 1.0;
  /// false: a target outside the grid is an error (or status Outside). true: it is interpolated
  /// from the nearest cell (status Clamped).
  bool clamp = false;
  /// A target closer than vertex_tolerance x (smallest grid step) to a vertex takes that vertex's
  /// value. In [0, 0.01].
  double vertex_tolerance = 1e-9;
  /// A target at most boundary_tolerance x (step of an axis) outside the grid box still counts as
  /// inside (absorbs rounding in coordinates read from files). In [0, 0.01].
  double boundary_tolerance = 1e-9;
  /// OpenMP threads for batch predictions; 0 = OpenMP's default (OMP_NUM_THREADS or all cores).
  int threads = 0;
  /// Throws ArgumentError naming the field when out of domain.
  void validate() const;
};

/// Outcome of one target in GridIdw::predict_with_status.
enum class GridIdwStatus : std::uint8_t {
  Inside = kernels::kGridInside,    ///< inside the grid (within boundary_tolerance)
  Clamped = kernels::kGridClamped,  ///< outside, interpolated from the nearest cell (clamp = true)
  Outside = kernels::kGridOutside,  ///< outside with clamp = false, or a non-finite coordinate: NaN
};

/// A target lies outside the grid (and clamping is off). The message names the target, its
/// coordinates and the grid's bounds; file()/row() are set when the targets came from a file.
class OutsideGridError : public InputError {
 public:
  using InputError::InputError;
};

template <Value V>
class GridIdw {
 public:
  using ValueType = V;
  static constexpr int kComponents = ValueTraits<V>::kComponents;

  /// node_values[n] is the value at node n of `grid` (numbering in regular_grid.hpp). Throws
  /// ArgumentError if the count differs from grid.node_count() or an option is out of domain, and
  /// InputError if a value is not finite.
  GridIdw(const RegularGrid3& grid, std::span<const V> node_values, const GridIdwOptions& options = {});

  /// Recognises the grid in scattered samples (N x 3 points, any order; see detect_regular_grid,
  /// whose errors name missing, duplicate and unevenly spaced nodes) and builds the interpolator.
  static GridIdw from_samples(const Eigen::Ref<const Eigen::MatrixXd>& points, std::span<const V> values,
                              const GridIdwOptions& options = {}, const RowLabels& labels = {},
                              const GridDetectionOptions& detection = {});

  const RegularGrid3& grid() const noexcept { return grid_; }
  const GridIdwOptions& options() const noexcept { return options_; }
  /// Value at node n (n < grid().node_count()).
  V node_value(std::size_t n) const { return detail::value_from<V>(nodes_.data() + n * kComponents); }

  /// Value at one target. Throws OutsideGridError when the target is outside and clamp is off,
  /// or a coordinate is not finite.
  V operator()(const Eigen::Vector3d& target) const;

  /// Values at M targets (M x 3 matrix, one target per row, or a span of points). Throws
  /// OutsideGridError for the first target outside the grid (clamp off), naming it with `labels`.
  std::vector<V> predict(const Eigen::Ref<const Eigen::MatrixXd>& targets, const RowLabels& labels = {}) const;
  std::vector<V> predict(std::span<const Eigen::Vector3d> targets, const RowLabels& labels = {}) const;

  /// Non-throwing batch form for pipelines: out[t] and status[t] for each target; an Outside target
  /// gets NaN components. Throws ArgumentError only when out/status sizes differ from the number
  /// of targets (checked before any work).
  void predict_with_status(const Eigen::Ref<const Eigen::MatrixXd>& targets, std::span<V> out,
                           std::span<GridIdwStatus> status) const;
  void predict_with_status(std::span<const Eigen::Vector3d> targets, std::span<V> out,
                           std::span<GridIdwStatus> status) const;

 private:
  void run(const double* targets, std::ptrdiff_t target_stride, std::ptrdiff_t coord_stride, std::ptrdiff_t n,
           V* out, std::uint8_t* status) const;
  [[noreturn]] void throw_outside(const Eigen::Vector3d& target, std::size_t index, const RowLabels& labels) const;

  RegularGrid3 grid_;
  GridIdwOptions options_;
  std::vector<double> nodes_;  // node_count x kComponents
  kernels::GridIdwGeometry geometry_{};
  kernels::GridIdwParams params_{};
};

/// Message text for a target outside a grid (shared by GridIdw and the CLI).
std::string describe_outside_target(const Eigen::Vector3d& target, const std::string& name, const RegularGrid3& grid);

// ---- implementation ------------------------------------------------------------------------------

template <Value V>
GridIdw<V>::GridIdw(const RegularGrid3& grid, std::span<const V> node_values, const GridIdwOptions& options)
    : grid_(grid), options_(options) {
  options_.validate();
  if (node_values.size() != grid_.node_count())
    throw ArgumentError("GridIdw: " + std::to_string(node_values.size()) + " node values for a grid of " +
                        std::to_string(grid_.node_count()) + " nodes (" + grid_.describe() + ")");
  for (std::size_t n = 0; n < node_values.size(); ++n)
    if (!detail::value_is_finite(node_values[n])) {
      const auto ijk = grid_.node_indices(n);
      throw InputError("GridIdw: the value at node (" + std::to_string(ijk[0]) + ", " + std::to_string(ijk[1]) +
                       ", " + std::to_string(ijk[2]) + ") is not finite");
    }
  nodes_ = detail::flatten_values<V>(node_values);
  for (int a = 0; a < 3; ++a) {
    geometry_.origin[a] = grid_.origin()[a];
    geometry_.step[a] = grid_.step()[a];
    geometry_.inv_step[a] = 1.0 / grid_.step()[a];
    geometry_.count[a] = grid_.counts()[a];
  }
  const double vertex_tol = options_.vertex_tolerance * grid_.step().minCoeff();
  params_.power = options_.power;
  params_.vertex_tolerance_sq = vertex_tol * vertex_tol;
  params_.boundary_tolerance = options_.boundary_tolerance;
  params_.clamp = options_.clamp;
  params_.threads = options_.threads;
}

template <Value V>
GridIdw<V> GridIdw<V>::from_samples(const Eigen::Ref<const Eigen::MatrixXd>& points, std::span<const V> values,
                                    const GridIdwOptions& options, const RowLabels& labels,
                                    const GridDetectionOptions& detection) {
  options.validate();
  if (values.size() != static_cast<std::size_t>(points.rows()))
    throw ArgumentError("GridIdw::from_samples: " + std::to_string(points.rows()) + " points but " +
                        std::to_string(values.size()) + " values");
  for (std::size_t r = 0; r < values.size(); ++r)
    if (!detail::value_is_finite(values[r]))
      throw InputError(labels(r) + ": value is not finite", labels.source, labels.line(r));
  const GridDetection found = detect_regular_grid(points, labels, detection);
  std::vector<V> ordered;
  ordered.reserve(found.sample_of_node.size());
  for (std::size_t s : found.sample_of_node) ordered.push_back(values[s]);
  return GridIdw(found.grid, std::span<const V>(ordered), options);
}

template <Value V>
void GridIdw<V>::run(const double* targets, std::ptrdiff_t target_stride, std::ptrdiff_t coord_stride,
                     std::ptrdiff_t n, V* out, std::uint8_t* status) const {
  if constexpr (detail::kPackedValue<V>) {
    kernels::grid_idw<kComponents>(geometry_, params_, nodes_.data(), targets, target_stride, coord_stride, n,
                                   reinterpret_cast<double*>(out), status);
  } else {
    std::vector<double> flat(static_cast<std::size_t>(n) * kComponents);
    kernels::grid_idw<kComponents>(geometry_, params_, nodes_.data(), targets, target_stride, coord_stride, n,
                                   flat.data(), status);
    for (std::ptrdiff_t t = 0; t < n; ++t) out[t] = detail::value_from<V>(flat.data() + t * kComponents);
  }
}

template <Value V>
void GridIdw<V>::throw_outside(const Eigen::Vector3d& target, std::size_t index, const RowLabels& labels) const {
  // "T.csv:3: target (...) is outside ..." from a file, "target 2 (...) is outside ..." in memory
  const std::string name = labels.in_file(index) ? labels(index) + ": target" : labels(index);
  throw OutsideGridError(describe_outside_target(target, name, grid_), labels.source, labels.line(index));
}

template <Value V>
V GridIdw<V>::operator()(const Eigen::Vector3d& target) const {
  double out[kComponents];
  const double pos[3] = {target.x(), target.y(), target.z()};
  const auto s = kernels::grid_idw_single<kComponents>(geometry_, params_, nodes_.data(), pos, out);
  if (s == kernels::kGridOutside) throw OutsideGridError(describe_outside_target(target, "target", grid_));
  return detail::value_from<V>(out);
}

template <Value V>
std::vector<V> GridIdw<V>::predict(const Eigen::Ref<const Eigen::MatrixXd>& targets, const RowLabels& labels) const {
  if (targets.cols() != 3)
    throw ArgumentError("GridIdw::predict: targets have " + std::to_string(targets.cols()) +
                        " columns; expected 3 (x, y, z)");
  const std::ptrdiff_t n = targets.rows();
  std::vector<V> out(static_cast<std::size_t>(n), ValueTraits<V>::zero());
  std::vector<std::uint8_t> status(static_cast<std::size_t>(n));
  run(targets.data(), 1, targets.outerStride(), n, out.data(), status.data());
  for (std::ptrdiff_t t = 0; t < n; ++t)
    if (status[static_cast<std::size_t>(t)] == kernels::kGridOutside)
      throw_outside(targets.row(t).transpose(), static_cast<std::size_t>(t), labels);
  return out;
}

template <Value V>
std::vector<V> GridIdw<V>::predict(std::span<const Eigen::Vector3d> targets, const RowLabels& labels) const {
  static_assert(sizeof(Eigen::Vector3d) == 3 * sizeof(double));
  const auto n = static_cast<std::ptrdiff_t>(targets.size());
  std::vector<V> out(targets.size(), ValueTraits<V>::zero());
  std::vector<std::uint8_t> status(targets.size());
  run(reinterpret_cast<const double*>(targets.data()), 3, 1, n, out.data(), status.data());
  for (std::size_t t = 0; t < targets.size(); ++t)
    if (status[t] == kernels::kGridOutside) throw_outside(targets[t], t, labels);
  return out;
}

template <Value V>
void GridIdw<V>::predict_with_status(const Eigen::Ref<const Eigen::MatrixXd>& targets, std::span<V> out,
                                     std::span<GridIdwStatus> status) const {
  if (targets.cols() != 3 || out.size() != static_cast<std::size_t>(targets.rows()) || status.size() != out.size())
    throw ArgumentError("GridIdw::predict_with_status: targets are " + std::to_string(targets.rows()) + " x " +
                        std::to_string(targets.cols()) + " (expected M x 3), out has " + std::to_string(out.size()) +
                        " and status " + std::to_string(status.size()) + " entries (expected M)");
  run(targets.data(), 1, targets.outerStride(), targets.rows(), out.data(),
      reinterpret_cast<std::uint8_t*>(status.data()));
}

template <Value V>
void GridIdw<V>::predict_with_status(std::span<const Eigen::Vector3d> targets, std::span<V> out,
                                     std::span<GridIdwStatus> status) const {
  if (out.size() != targets.size() || status.size() != targets.size())
    throw ArgumentError("GridIdw::predict_with_status: " + std::to_string(targets.size()) + " targets, out has " +
                        std::to_string(out.size()) + " and status " + std::to_string(status.size()) + " entries");
  run(reinterpret_cast<const double*>(targets.data()), 3, 1, static_cast<std::ptrdiff_t>(targets.size()), out.data(),
      reinterpret_cast<std::uint8_t*>(status.data()));
}

extern template class GridIdw<double>;
extern template class GridIdw<Eigen::Vector3d>;

}  // namespace errfield
