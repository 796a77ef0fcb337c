#include "errfield/empirical_variogram.hpp"
#include "errfield/heterotopic_variogram.hpp"
#include "errfield/variogram_cloud.hpp"

#include "errfield/thread_count.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <string>

#if defined(_OPENMP)
#include <omp.h>
#endif

#include "errfield/csv_table.hpp"

namespace errfield {

std::string_view estimator_name(VariogramEstimator e) {
  switch (e) {
    case VariogramEstimator::Matheron: return "matheron";
    case VariogramEstimator::CressieHawkins: return "cressie";
    case VariogramEstimator::Dowd: return "dowd";
  }
  return "?";
}

VariogramEstimator estimator_from_name(std::string_view name) {
  if (name == "matheron") return VariogramEstimator::Matheron;
  if (name == "cressie" || name == "cressie-hawkins") return VariogramEstimator::CressieHawkins;
  if (name == "dowd") return VariogramEstimator::Dowd;
  throw ArgumentError("estimator: unknown name '" + std::string(name) +
                      "'; known: matheron, cressie, dowd");
}

std::string_view convention_name(BinConvention c) {
  switch (c) {
    case BinConvention::HalfOpen: return "paper";
    case BinConvention::Gstat: return "gstat";
  }
  return "?";
}

BinConvention convention_from_name(std::string_view name) {
  if (name == "paper" || name == "half-open") return BinConvention::HalfOpen;
  if (name == "gstat") return BinConvention::Gstat;
  throw ArgumentError("convention: unknown name '" + std::string(name) + "'; known: paper, gstat");
}

LagBins LagBins::gstat_default(const Eigen::MatrixXd& coordinates) {
  double diagonal2 = 0.0;
  if (coordinates.rows() > 0)
    diagonal2 = (coordinates.colwise().maxCoeff() - coordinates.colwise().minCoeff()).squaredNorm();
  // gstat's fraction is the constant 0.33333 (gl_fraction), not 1/3: its edges differ in the 6th digit.
  constexpr double kGstatFraction = 0.33333;
  const double cutoff = std::sqrt(diagonal2) * kGstatFraction;
  if (!(cutoff > 0.0) || !std::isfinite(cutoff))
    throw ArgumentError("lag bins: the locations span no distance (bounding-box diagonal " +
                        format_number(std::sqrt(diagonal2)) + "); give the bins explicitly");
  return uniform(0.0, cutoff, cutoff / 15.0);
}

LagBins LagBins::uniform(double lo, double max_lag, double width) {
  if (!std::isfinite(width) || !(width > 0.0))
    throw ArgumentError("lag bins: width = " + format_number(width) + "; expected a finite value > 0");
  if (!std::isfinite(lo) || !(lo >= 0.0))
    throw ArgumentError("lag bins: lower edge = " + format_number(lo) + "; expected a finite value >= 0");
  if (!std::isfinite(max_lag) || !(max_lag > lo))
    throw ArgumentError("lag bins: max_lag = " + format_number(max_lag) +
                        "; expected a finite value > the lower edge " + format_number(lo));
  const double q = (max_lag - lo) / width;
  double n = std::round(q);
  if (std::fabs(q - n) > 1e-9 * std::max(1.0, q)) n = std::ceil(q);
  if (n > 1e7)
    throw ArgumentError("lag bins: width = " + format_number(width) + " up to max_lag = " +
                        format_number(max_lag) + " gives " + format_number(n) +
                        " bins; expected at most 10^7 (use a larger width)");
  LagBins b;
  const std::size_t count = static_cast<std::size_t>(n);
  b.edges_.resize(count + 1);
  for (std::size_t k = 0; k <= count; ++k) b.edges_[k] = lo + static_cast<double>(k) * width;
  for (std::size_t k = 0; k < count; ++k)
    if (!(b.edges_[k + 1] > b.edges_[k]))
      throw ArgumentError("lag bins: width = " + format_number(width) +
                          " is too small to separate edges near " + format_number(b.edges_[k]));
  b.uniform_ = true;
  return b;
}

LagBins LagBins::from_edges(std::vector<double> edges) {
  if (edges.size() < 2)
    throw ArgumentError("lag bins: edges has " + std::to_string(edges.size()) +
                        " value(s); expected at least 2 (the bin edges e_0 < e_1 < ...)");
  for (std::size_t k = 0; k < edges.size(); ++k) {
    if (!std::isfinite(edges[k]))
      throw ArgumentError("lag bins: edges[" + std::to_string(k) + "] is not finite");
    if (k == 0 && edges[0] < 0.0)
      throw ArgumentError("lag bins: edges[0] = " + format_number(edges[0]) + "; expected >= 0");
    if (k > 0 && !(edges[k] > edges[k - 1]))
      throw ArgumentError("lag bins: edges[" + std::to_string(k) + "] = " + format_number(edges[k]) +
                          " is not greater than edges[" + std::to_string(k - 1) + "] = " +
                          format_number(edges[k - 1]) + "; edges must be strictly increasing");
  }
  LagBins b;
  b.edges_ = std::move(edges);
  // Equally spaced explicit edges get the fast lookup too (it is exact either way).
  const double w = b.edges_[1] - b.edges_[0];
  bool uniform = b.edges_.size() <= 100001;  // the lookup's guess stays far within kNearEdge
  for (std::size_t k = 1; k + 1 < b.edges_.size() && uniform; ++k)
    uniform = std::fabs((b.edges_[k + 1] - b.edges_[k]) - w) <= 1e-12 * w;
  b.uniform_ = uniform;
  return b;
}

void EmpiricalVariogramOptions::validate() const {
  if (!(pair_fraction > 0.0 && pair_fraction <= 1.0))
    throw ArgumentError("variogram options: pair_fraction = " + format_number(pair_fraction) +
                        "; expected 0 < pair_fraction <= 1");
  check_thread_count("variogram options: threads", threads);
  if (cross_variograms && estimator != VariogramEstimator::Matheron)
    throw ArgumentError("variogram options: cross_variograms with the " + std::string(estimator_name(estimator)) +
                        " estimator; cross-variograms are means of products of differences (Matheron): the robust "
                        "estimators transform |z_i - z_j| and have no signed cross counterpart");
}

double EmpiricalVariogram::gamma_of(std::size_t bin, int a, int b) const {
  const int K = components();
  if (bin >= bins.size() || a < 0 || b < 0 || a >= K || b >= K)
    throw ArgumentError("empirical variogram: gamma_of(bin " + std::to_string(bin) + ", " + std::to_string(a) + ", " +
                        std::to_string(b) + ") outside " + std::to_string(bins.size()) + " bins x " +
                        std::to_string(K) + " components");
  const auto k = static_cast<Eigen::Index>(bin);
  if (a == b) return component_gamma(k, a);
  if (cross_gamma.cols() != K * (K - 1) / 2)
    throw ArgumentError("empirical variogram: no cross-variograms (computed without cross_variograms)");
  return cross_gamma(k, cross_column(std::min(a, b), std::max(a, b), K));
}

namespace detail {

void check_variogram_accumulators(std::size_t bins, int components, const EmpiricalVariogramOptions& options) {
  const long double bytes = static_cast<long double>(kVariogramChunks) * static_cast<long double>(bins + 1) *
                            (2.0L + static_cast<long double>(components)) * 8.0L;
  if (bytes <= static_cast<long double>(options.max_accumulator_bytes)) return;
  const long double per_bin = static_cast<long double>(kVariogramChunks) * (2.0L + components) * 8.0L;
  const auto max_bins = static_cast<std::uint64_t>(static_cast<long double>(options.max_accumulator_bytes) / per_bin) - 1;
  char size[64];
  std::snprintf(size, sizeof size, "%.3g GB", static_cast<double>(bytes / 1e9L));
  throw ResourceError("empirical variogram: " + std::to_string(bins) + " lag bins x " + std::to_string(components) +
                      " component(s) need " + size + " of per-chunk sums, over the budget of " +
                      std::to_string(options.max_accumulator_bytes) +
                      " bytes (max_accumulator_bytes); use at most " + std::to_string(max_bins) +
                      " bins (a larger bin width, e.g. in --bins lo:max:width)");
}

std::vector<std::size_t> variogram_chunk_rows(std::size_t n) {
  std::vector<std::size_t> rows{1};
  if (n < 2) {
    rows.push_back(1);
    return rows;
  }
  // Rows 1..n-1; rows below r hold r(r-1)/2 pairs. Cut where the pair count passes c/C of the total.
  const double total = 0.5 * static_cast<double>(n) * static_cast<double>(n - 1);
  std::size_t r = 1;
  for (std::size_t c = 1; c < kVariogramChunks; ++c) {
    const double target = total * static_cast<double>(c) / static_cast<double>(kVariogramChunks);
    while (r < n && 0.5 * static_cast<double>(r) * static_cast<double>(r - 1) < target) ++r;
    rows.push_back(r);
  }
  rows.push_back(n);
  return rows;
}

void check_variogram_values(const Eigen::MatrixXd& values, std::size_t n_locations) {
  if (n_locations < 2)
    throw InputError("empirical variogram: " + std::to_string(n_locations) +
                     " location(s); need at least 2 to form a pair");
  if (static_cast<std::size_t>(values.rows()) != n_locations)
    throw ArgumentError("empirical variogram: " + std::to_string(values.rows()) + " values for " +
                        std::to_string(n_locations) + " locations; expected one value row per location");
  if (values.cols() < 1)
    throw ArgumentError("empirical variogram: values have 0 components; expected at least 1");
  for (Eigen::Index i = 0; i < values.rows(); ++i)
    for (Eigen::Index c = 0; c < values.cols(); ++c)
      if (!std::isfinite(values(i, c)))
        throw InputError("empirical variogram: value row " + std::to_string(i) + ", component " +
                         std::to_string(c) + " is " + format_number(values(i, c)) +
                         "; expected a finite number");
}

kernels::DirectionCone variogram_direction_cone(const VariogramDirection& direction,
                                                const double* coordinates, std::size_t n,
                                                int dimension) {
  constexpr double kRadPerDeg = std::numbers::pi / 180.0;
  kernels::DirectionCone c;
  c.coordinates = coordinates;
  c.n = n;
  c.dimension = dimension;
  if (direction.kind() == VariogramDirection::Kind::Gstat) {
    c.gstat = true;
    c.check_hor = direction.tol_hor_deg() < 90.0;
    c.hor_x = std::sin(direction.alpha_deg() * kRadPerDeg);
    c.hor_y = std::cos(direction.alpha_deg() * kRadPerDeg);
    c.cos_tol_hor = std::cos(direction.tol_hor_deg() * kRadPerDeg);
    c.check_ver = direction.tol_ver_deg() < 90.0;
    c.ver_xy = std::cos(direction.beta_deg() * kRadPerDeg);
    c.ver_z = std::sin(direction.beta_deg() * kRadPerDeg);
    c.cos_tol_ver = std::cos(direction.tol_ver_deg() * kRadPerDeg);
  } else {
    c.axis = direction.unit().data();  // owned by the options, which outlive the pair loop
    // 90 degrees or more: every pair (cos 90 deg rounds to 6e-17, which would drop the pairs
    // exactly at right angles to u).
    c.cos_tol = direction.tol_deg() < 90.0 ? std::cos(direction.tol_deg() * kRadPerDeg) : -1.0;
  }
  return c;
}

void throw_bad_coordinate(std::size_t row, int coordinate, double value) {
  throw InputError("empirical variogram: location row " + std::to_string(row) + ", coordinate " +
                   std::to_string(coordinate) + " is " + format_number(value) +
                   "; expected a finite number");
}

void throw_dimension_mismatch(std::size_t row, int dimension, int expected) {
  throw ArgumentError("empirical variogram: location row " + std::to_string(row) + " has " +
                      std::to_string(dimension) + " coordinates; location row 0 has " +
                      std::to_string(expected));
}

int variogram_team_size(int threads) {
#if defined(_OPENMP)
  return threads > 0 ? threads : std::max(1, omp_get_max_threads());
#else
  (void)threads;
  return 1;
#endif
}

int variogram_thread_index() {
#if defined(_OPENMP)
  return omp_get_thread_num();
#else
  return 0;
#endif
}

namespace {

// Cells (or columns) a little wider than bound / reach: a pair within the bound then differs by
// less than `reach` cells on the axis even after the rounding of (x - lo) / side (relative ~1e-16
// per cell index, far below the margin for the at most 2^28 cells allowed), so the kernel finds it.
constexpr double kSideMargin = 1e-6;

// One gridded axis: its cells of `side` over [lo, lo + extent] (`bound`: the cell list's pair bound).
struct GridAxis {
  int axis;
  double lo, extent, side, cells, bound;
};

double cells_for(double extent, double side) {
  return std::min(std::floor(extent / side) + 1.0, 1099511627776.0);  // 2^40: coarsened below
}

// The widest axis's cells doubled in size until there are at most `max_cells` in all; an axis
// left with fewer than `min_cells` is not gridded.
void coarsen(std::vector<GridAxis>& axes, double max_cells, double min_cells) {
  auto total = [&] {
    double t = 1.0;
    for (const GridAxis& x : axes) t *= x.cells;
    return t;
  };
  while (!axes.empty() && total() > max_cells) {
    auto widest = std::max_element(axes.begin(), axes.end(),
                                   [](const GridAxis& p, const GridAxis& q) { return p.cells < q.cells; });
    widest->side *= 2.0;
    widest->cells = cells_for(widest->extent, widest->side);
    if (widest->cells < min_cells) axes.erase(widest);
  }
}

// Most cells first (the first axis on ties).
void sort_by_cells(std::vector<GridAxis>& axes) {
  std::sort(axes.begin(), axes.end(), [](const GridAxis& p, const GridAxis& q) {
    return p.cells > q.cells || (p.cells == q.cells && p.axis < q.axis);
  });
}

// Expected share of the pairs in neighbouring cells within `reach` on gridded axes of c cells:
// ((2r + 1) c - r (r + 1)) / c^2 per axis (uniform points), times `start`.
double visited_share(const std::vector<GridAxis>& axes, std::size_t reach, double start) {
  double visited = start;
  const double r = static_cast<double>(reach);
  for (const GridAxis& x : axes)
    visited *= std::min(1.0, ((2.0 * r + 1.0) * x.cells - r * (r + 1.0)) / (x.cells * x.cells));
  return visited;
}

// Cells of half the bound: a pair within the cutoff is at most 2 cells apart on an axis, and
// the cells the kernel skips by their distance to the point (beyond the bound) take ~half of
// the 3-D neighbourhood away (measured: docs/variogram.md).
constexpr std::size_t kCellReach = 2;
constexpr double kMinCells = 2.0 * kCellReach + 1.0;
static_assert(kCellReach >= 1 && kCellReach <= kernels::kCellListMaxReach);

// The axes worth gridding for the cell list, most cells first, coarsened to ~2 cells per point.
std::vector<GridAxis> cell_list_axes(const double* axis_major, std::size_t n, int dimension,
                                     const std::vector<double>& axis_bound) {
  std::vector<GridAxis> axes;
  for (int a = 0; a < dimension; ++a) {
    const double b = axis_bound[static_cast<std::size_t>(a)];
    if (!(std::isfinite(b) && b > 0.0)) continue;
    const double* x = axis_major + static_cast<std::size_t>(a) * n;
    const auto [lo, hi] = std::minmax_element(x, x + n);
    const double extent = *hi - *lo;
    const double side = b * (1.0 + kSideMargin) / static_cast<double>(kCellReach);
    const double count = cells_for(extent, side);
    // With fewer cells every cell neighbours every other: gridding the axis saves nothing.
    if (count >= kMinCells) axes.push_back({a, *lo, extent, side, count, b});
  }
  sort_by_cells(axes);
  if (axes.size() > static_cast<std::size_t>(kernels::kCellListMaxAxes))
    axes.resize(static_cast<std::size_t>(kernels::kCellListMaxAxes));
  // At most ~2 cells per point (more cells are mostly empty and only cost their visits).
  coarsen(axes, std::min(2.0 * static_cast<double>(n), 268435456.0), kMinCells);
  return axes;
}

// The points sorted by cell (counting sort; ascending original index within a cell), with their
// coordinates in that order, and the kernel's view of them.
void fill_cell_list(const std::vector<GridAxis>& axes, const double* axis_major, std::size_t n, int dimension,
                    VariogramCells& cells) {
  kernels::CellList& g = cells.list;
  g = kernels::CellList{};
  g.n = n;
  g.dimension = dimension;
  g.axes = static_cast<int>(axes.size());
  std::size_t stride = 1;
  g.reach = kCellReach;
  for (std::size_t k = 0; k < axes.size(); ++k) {
    g.axis[k] = axes[k].axis;
    g.origin[k] = axes[k].lo;
    g.side[k] = axes[k].side;
    g.inv_bound[k] = 1.0 / axes[k].bound;
    g.cells_per_axis[k] = static_cast<std::size_t>(axes[k].cells);
    g.stride[k] = stride;
    stride *= g.cells_per_axis[k];
  }
  const std::size_t cell_count = stride;
  cells.cell_of.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    std::size_t cell = 0;
    for (std::size_t k = 0; k < axes.size(); ++k) {
      const double u = (axis_major[static_cast<std::size_t>(axes[k].axis) * n + i] - axes[k].lo) / axes[k].side;
      const std::size_t index = std::min(static_cast<std::size_t>(u), g.cells_per_axis[k] - 1);
      cell += index * g.stride[k];
    }
    cells.cell_of[i] = static_cast<std::uint32_t>(cell);
  }
  cells.cell_start.assign(cell_count + 1, 0);
  for (std::size_t i = 0; i < n; ++i) ++cells.cell_start[cells.cell_of[i] + 1];
  for (std::size_t c = 0; c < cell_count; ++c) cells.cell_start[c + 1] += cells.cell_start[c];
  cells.point.resize(n);
  cells.position.resize(n);
  {
    std::vector<std::uint32_t> next(cells.cell_start.begin(), cells.cell_start.end() - 1);
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t p = next[cells.cell_of[i]]++;
      cells.point[p] = static_cast<std::uint32_t>(i);
      cells.position[i] = p;
    }
  }
  const std::size_t D = static_cast<std::size_t>(dimension);
  cells.coordinates.resize(n * D);
  for (std::size_t a = 0; a < D; ++a)
    for (std::size_t p = 0; p < n; ++p) cells.coordinates[a * n + p] = axis_major[a * n + cells.point[p]];
  g.coordinates = cells.coordinates.data();
  g.point = cells.point.data();
  g.position = cells.position.data();
  g.cell_of = cells.cell_of.data();
  g.cell_start = cells.cell_start.data();
}

// Columns of half the cutoff (a pair within it is at most 2 columns apart), as the cell list's
// cells: the gap of a point to a column trims the run on the sort axis to the circle's chord.
constexpr std::size_t kColumnReach = 2;
constexpr double kMinColumns = 2.0 * kColumnReach + 1.0;
static_assert(kColumnReach >= 1 && kColumnReach <= kernels::kColumnMaxReach);

// The sort axis (the largest extent, first on ties) and the gridded ones: those with enough
// columns for some to be out of reach, most columns first, coarsened to one column per point.
struct ColumnAxes {
  GridAxis sort_axis;
  std::vector<GridAxis> grid;
  std::size_t reach = 1;
};

ColumnAxes column_axes(const double* axis_major, std::size_t n, int dimension, double cutoff) {
  std::vector<GridAxis> all;
  for (int a = 0; a < dimension; ++a) {
    const double* x = axis_major + static_cast<std::size_t>(a) * n;
    const auto [lo, hi] = std::minmax_element(x, x + n);
    const double side = cutoff * (1.0 + kSideMargin) / static_cast<double>(kColumnReach);
    all.push_back({a, *lo, *hi - *lo, side, cells_for(*hi - *lo, side), cutoff});
  }
  const auto sort_it = std::max_element(all.begin(), all.end(),
                                        [](const GridAxis& p, const GridAxis& q) { return p.extent < q.extent; });
  ColumnAxes c{*sort_it, {}, 1};
  for (const GridAxis& x : all)
    if (x.axis != c.sort_axis.axis && x.cells >= kMinColumns) c.grid.push_back(x);
  sort_by_cells(c.grid);
  // At most one column per point: emptier columns only cost their visits.
  coarsen(c.grid, static_cast<double>(n), kMinColumns);
  // Columns coarsened to a side >= the cutoff need a stencil of 1 column only: a pair within the
  // cutoff is at most floor(cutoff / side) + 1 columns apart.
  for (const GridAxis& x : c.grid)
    c.reach = std::max(c.reach, std::min(kColumnReach, static_cast<std::size_t>(std::floor(cutoff / x.side)) + 1));
  return c;
}

// The points sorted by column (counting sort), each column by the sort axis (index breaks ties:
// deterministic), with their coordinates and values in that order, and the kernel's view of them.
void fill_columns(const ColumnAxes& c, const double* axis_major, const double* values, std::size_t n, int dimension,
                  double cutoff, VariogramColumns& columns) {
  const std::vector<GridAxis>& grid = c.grid;
  kernels::SortedColumns& g = columns.list;
  g = kernels::SortedColumns{};
  g.dimension = dimension;
  g.sort_axis = c.sort_axis.axis;
  g.grid_axes = static_cast<int>(grid.size());
  g.reach = c.reach;
  g.cutoff = cutoff;
  for (std::size_t k = 0; k < grid.size(); ++k) {
    g.grid_axis[k] = grid[k].axis;
    g.origin[k] = grid[k].lo;
    g.side[k] = grid[k].side;
    g.columns_per_axis[k] = static_cast<std::size_t>(grid[k].cells);
  }
  const std::size_t column_count = g.columns_per_axis[0] * g.columns_per_axis[1];
  std::vector<std::uint32_t> column_of(n);
  for (std::size_t i = 0; i < n; ++i) {
    std::size_t column = 0, stride = 1;
    for (std::size_t k = 0; k < grid.size(); ++k) {
      const double v = (axis_major[static_cast<std::size_t>(grid[k].axis) * n + i] - grid[k].lo) / grid[k].side;
      column += std::min(static_cast<std::size_t>(v), g.columns_per_axis[k] - 1) * stride;
      stride *= g.columns_per_axis[k];
    }
    column_of[i] = static_cast<std::uint32_t>(column);
  }
  columns.column_start.assign(column_count + 1, 0);
  for (std::size_t i = 0; i < n; ++i) ++columns.column_start[column_of[i] + 1];
  for (std::size_t k = 0; k < column_count; ++k) columns.column_start[k + 1] += columns.column_start[k];
  std::vector<std::uint32_t> point(n);
  {
    std::vector<std::uint32_t> next(columns.column_start.begin(), columns.column_start.end() - 1);
    for (std::size_t i = 0; i < n; ++i) point[next[column_of[i]]++] = static_cast<std::uint32_t>(i);
  }
  const double* key = axis_major + static_cast<std::size_t>(c.sort_axis.axis) * n;
  for (std::size_t k = 0; k < column_count; ++k)
    std::sort(point.begin() + columns.column_start[k], point.begin() + columns.column_start[k + 1],
              [key](std::uint32_t p, std::uint32_t q) { return key[p] < key[q] || (key[p] == key[q] && p < q); });
  const std::size_t D = static_cast<std::size_t>(dimension);
  columns.coordinates.resize(n * D);
  columns.values.resize(n);
  for (std::size_t a = 0; a < D; ++a)
    for (std::size_t p = 0; p < n; ++p) columns.coordinates[a * n + p] = axis_major[a * n + point[p]];
  for (std::size_t p = 0; p < n; ++p) columns.values[p] = values[point[p]];
  g.coordinates = columns.coordinates.data();
  g.values = columns.values.data();
  g.column_start = columns.column_start.data();
  g.n = n;
}

}  // namespace

bool build_variogram_cells(const double* axis_major, std::size_t n, int dimension,
                           const std::vector<double>& axis_bound, bool force, VariogramCells& cells) {
  if (n < 2 || n >= std::numeric_limits<std::uint32_t>::max()) return false;
  if (!force && n < kCellListMinPoints) return false;
  const std::vector<GridAxis> axes = cell_list_axes(axis_major, n, dimension, axis_bound);
  if (axes.empty()) return false;
  // The expected share of the pairs in neighbouring cells, before the skipping.
  if (!force && visited_share(axes, kCellReach, 1.0) > kCellListMaxFraction) return false;
  fill_cell_list(axes, axis_major, n, dimension, cells);
  return true;
}

bool build_variogram_columns(const double* axis_major, const double* values, std::size_t n,
                             int dimension, double cutoff, bool force, double max_share,
                             VariogramColumns& columns) {
  if (dimension < 1 || dimension > 3) return false;
  if (n < 2 || n > kernels::kSimdMaxPoints) return false;
  if (!force && n < kCellListMinPoints) return false;
  if (!(std::isfinite(cutoff) && cutoff > 0.0)) return false;
  const ColumnAxes axes = column_axes(axis_major, n, dimension, cutoff);
  // Expected share of the pairs visited (uniform points): within the cutoff on the sort axis,
  // 2u - u^2 for u = cutoff / extent, times the gridded axes' share within reach.
  const double u = axes.sort_axis.extent > 0.0 ? std::min(1.0, cutoff / axes.sort_axis.extent) : 1.0;
  if (!force && visited_share(axes.grid, axes.reach, 2.0 * u - u * u) > max_share) return false;
  fill_columns(axes, axis_major, values, n, dimension, cutoff, columns);
  return true;
}

kernels::BinLayout variogram_bin_layout(const LagBins& bins, const EmpiricalVariogramOptions& o) {
  kernels::BinLayout layout;
  layout.edges = bins.edges().data();
  layout.bins = bins.size();
  layout.gstat = o.convention == BinConvention::Gstat;
  layout.uniform = bins.is_uniform();
  layout.inv_width = 1.0 / (bins.edges()[1] - bins.edges()[0]);
  return layout;
}

std::uint64_t variogram_keep_below(double fraction) {
  const long double x = std::ceil(static_cast<long double>(fraction) * 18446744073709551616.0L);
  if (x >= 18446744073709551615.0L) return std::numeric_limits<std::uint64_t>::max();
  return static_cast<std::uint64_t>(x);
}

std::vector<std::uint64_t> dowd_offsets(const std::vector<std::uint64_t>& count, std::size_t chunks,
                                        std::size_t bins, int components,
                                        const EmpiricalVariogramOptions& o) {
  const std::size_t B = bins + 1;
  std::uint64_t total = 0;
  for (std::size_t c = 0; c < chunks; ++c)
    for (std::size_t b = 0; b < bins; ++b) total += count[c * B + b];
  const long double values = static_cast<long double>(total) * components;
  if (values > static_cast<long double>(o.max_stored_differences)) {
    const double fraction = std::min(1.0, o.pair_fraction * static_cast<double>(o.max_stored_differences) /
                                              static_cast<double>(values));
    throw ResourceError("empirical variogram (Dowd): " + std::to_string(total) + " binned pairs x " +
                        std::to_string(components) + " component(s) = " +
                        format_number(static_cast<double>(values)) +
                        " stored differences (" + format_number(std::ceil(static_cast<double>(values) * 8e-6)) +
                        " MB) exceed max_stored_differences = " +
                        std::to_string(o.max_stored_differences) +
                        "; use pair_fraction (--subsample) <= " + format_number(fraction) +
                        ", a smaller max lag, or the Cressie-Hawkins estimator");
  }
  std::vector<std::uint64_t> offsets(chunks * B + 1, 0);
  std::uint64_t next = 0;
  for (std::size_t b = 0; b < bins; ++b)
    for (std::size_t c = 0; c < chunks; ++c) {
      offsets[c * B + b] = next;
      next += count[c * B + b];
    }
  offsets.back() = next;
  return offsets;
}

void finalize_dowd(EmpiricalVariogram& v, std::vector<double>& stored,
                   const std::vector<std::uint64_t>& offsets, std::size_t) {
  const std::size_t K = static_cast<std::size_t>(v.components());
  std::vector<double> tmp;
  for (std::size_t b = 0; b < v.bins.size(); ++b) {
    const std::uint64_t n = v.bins[b].pairs;
    if (n == 0) continue;
    const std::uint64_t base = offsets[b];  // chunk 0's first slot of bin b
    double total = 0.0;
    for (std::size_t c = 0; c < K; ++c) {
      tmp.resize(n);
      for (std::uint64_t p = 0; p < n; ++p) tmp[p] = stored[(base + p) * K + c];
      const std::size_t mid = n / 2;
      std::nth_element(tmp.begin(), tmp.begin() + static_cast<std::ptrdiff_t>(mid), tmp.end());
      double median = tmp[mid];
      if (n % 2 == 0)  // mean of the two middle values
        median = 0.5 * (median + *std::max_element(tmp.begin(), tmp.begin() + static_cast<std::ptrdiff_t>(mid)));
      const double g = 0.5 * 2.198 * median * median;
      v.component_gamma(static_cast<Eigen::Index>(b), static_cast<Eigen::Index>(c)) = g;
      total += g;
    }
    v.bins[b].gamma = total;
  }
}

EmpiricalVariogram finalize_variogram(const LagBins& bins, const EmpiricalVariogramOptions& o,
                                      int components, std::size_t chunks,
                                      const std::vector<std::uint64_t>& count,
                                      const std::vector<double>& lag,
                                      const std::vector<double>& stat) {
  const std::size_t B = bins.size();
  const std::size_t stride = B + 1;  // per-chunk arrays carry a discard slot at the end
  const std::size_t K = static_cast<std::size_t>(components);
  const std::size_t W = o.cross_variograms ? K + K * (K - 1) / 2 : K;  // sums per bin (kernels' width)
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EmpiricalVariogram out;
  out.estimator = o.estimator;
  out.convention = o.convention;
  out.pair_fraction = o.pair_fraction;
  out.bins.resize(B);
  out.component_gamma.resize(static_cast<Eigen::Index>(B), components);
  if (o.cross_variograms) out.cross_gamma.resize(static_cast<Eigen::Index>(B), static_cast<Eigen::Index>(W - K));
  std::vector<double> s(W);
  for (std::size_t b = 0; b < B; ++b) {
    std::uint64_t n = 0;
    double lag_sum = 0.0;
    std::fill(s.begin(), s.end(), 0.0);
    for (std::size_t c = 0; c < chunks; ++c) {  // fixed order: chunk 0, 1, ...
      n += count[c * stride + b];
      lag_sum += lag[c * stride + b];
      for (std::size_t k = 0; k < W; ++k) s[k] += stat[(c * stride + b) * W + k];
    }
    VariogramBin& bin = out.bins[b];
    bin.lag_lo = bins.lag_lo(b);
    bin.lag_hi = bins.lag_hi(b);
    bin.pairs = n;
    if (n == 0) {
      bin.lag_mean = bin.gamma = nan;
      for (std::size_t k = 0; k < K; ++k) out.component_gamma(static_cast<Eigen::Index>(b), static_cast<Eigen::Index>(k)) = nan;
      if (o.cross_variograms) out.cross_gamma.row(static_cast<Eigen::Index>(b)).setConstant(nan);
      continue;
    }
    const double nd = static_cast<double>(n);
    bin.lag_mean = lag_sum / nd;
    double total = 0.0;
    for (std::size_t k = 0; k < K; ++k) {
      double g;
      if (o.estimator == VariogramEstimator::Matheron) {
        g = s[k] / (2.0 * nd);
      } else {
        const double m = s[k] / nd;
        g = 0.5 * (m * m) * (m * m) / (0.457 + 0.494 / nd);
      }
      out.component_gamma(static_cast<Eigen::Index>(b), static_cast<Eigen::Index>(k)) = g;
      total += g;
    }
    bin.gamma = total;
    for (std::size_t k = K; k < W; ++k)  // cross-variograms: Matheron only (validate)
      out.cross_gamma(static_cast<Eigen::Index>(b), static_cast<Eigen::Index>(k - K)) = s[k] / (2.0 * nd);
  }
  return out;
}

}  // namespace detail

EmpiricalVariogram empirical_variogram(const Eigen::MatrixXd& coordinates,
                                       const Eigen::MatrixXd& values, const LagBins& bins,
                                       const EmpiricalVariogramOptions& options) {
  const Eigen::Index n = coordinates.rows();
  const Eigen::Index d = coordinates.cols();
  if (d < 1) throw ArgumentError("empirical variogram: coordinates have 0 columns; expected at least 1");
  auto run = [&]<class L>(L) {
    std::vector<L> loc(static_cast<std::size_t>(n));
    for (Eigen::Index i = 0; i < n; ++i) {
      if constexpr (std::is_same_v<L, double>) loc[static_cast<std::size_t>(i)] = coordinates(i, 0);
      else loc[static_cast<std::size_t>(i)] = coordinates.row(i).transpose();
    }
    return empirical_variogram<L, EuclideanMetric>(std::span<const L>(loc), values, EuclideanMetric{},
                                                   bins, options);
  };
  switch (d) {
    case 1: return run(double{});
    case 2: return run(Eigen::Vector2d{});
    case 3: return run(Eigen::Vector3d{});
    case 6: return run(Eigen::Matrix<double, 6, 1>{});
    default: return run(Eigen::VectorXd{});
  }
}

namespace {

// The rows (locations) where every one of `components` is measured.
std::vector<Eigen::Index> rows_measuring(const Eigen::MatrixXd& values, std::initializer_list<Eigen::Index> components) {
  std::vector<Eigen::Index> rows;
  for (Eigen::Index i = 0; i < values.rows(); ++i) {
    bool all = true;
    for (Eigen::Index c : components) all = all && !std::isnan(values(i, c));
    if (all) rows.push_back(i);
  }
  return rows;
}

}  // namespace

HeterotopicVariogram heterotopic_variogram(const Eigen::MatrixXd& coordinates, const Eigen::MatrixXd& values,
                                           const LagBins& bins, const EmpiricalVariogramOptions& options) {
  options.validate();
  for (Eigen::Index i = 0; i < values.rows(); ++i)
    for (Eigen::Index c = 0; c < values.cols(); ++c)
      if (std::isinf(values(i, c)))
        throw InputError("empirical variogram: value row " + std::to_string(i) + ", component " + std::to_string(c) +
                         " is " + format_number(values(i, c)) + "; expected a finite number (or NaN where not measured)");
  const Eigen::Index K = values.cols(), B = static_cast<Eigen::Index>(bins.size());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // The pairs of all locations: counts and lags of bins[k].
  EmpiricalVariogramOptions plain = options;
  plain.cross_variograms = false;
  EmpiricalVariogramOptions locations_only = plain;
  locations_only.estimator = VariogramEstimator::Matheron;
  HeterotopicVariogram out;
  out.variogram = empirical_variogram(coordinates, Eigen::MatrixXd::Zero(coordinates.rows(), 1), bins, locations_only);
  out.variogram.estimator = options.estimator;
  out.variogram.component_gamma.setConstant(B, K, nan);
  out.component_pairs.setZero(B, K);
  out.component_lag.setConstant(B, K, nan);
  // One variogram of the rows that measure `components`, into column `col` of gamma, pairs, lag.
  const auto run = [&](std::initializer_list<Eigen::Index> components, Eigen::MatrixXd& gamma, Eigen::MatrixXd& pairs,
                       Eigen::MatrixXd& lag, Eigen::Index col) {
    const std::vector<Eigen::Index> rows = rows_measuring(values, components);
    if (rows.size() < 2) return;  // no pair: counts 0, gamma and lag NaN
    Eigen::MatrixXd x(static_cast<Eigen::Index>(rows.size()), coordinates.cols());
    Eigen::MatrixXd z(static_cast<Eigen::Index>(rows.size()), static_cast<Eigen::Index>(components.size()));
    for (std::size_t r = 0; r < rows.size(); ++r) {
      x.row(static_cast<Eigen::Index>(r)) = coordinates.row(rows[r]);
      Eigen::Index k = 0;
      for (Eigen::Index c : components) z(static_cast<Eigen::Index>(r), k++) = values(rows[r], c);
    }
    EmpiricalVariogramOptions o = plain;
    o.cross_variograms = components.size() == 2;
    const EmpiricalVariogram v = empirical_variogram(x, z, bins, o);
    for (Eigen::Index b = 0; b < B; ++b) {
      gamma(b, col) = o.cross_variograms ? v.cross_gamma(b, 0) : v.component_gamma(b, 0);
      pairs(b, col) = static_cast<double>(v.bins[static_cast<std::size_t>(b)].pairs);
      lag(b, col) = v.bins[static_cast<std::size_t>(b)].lag_mean;
    }
  };
  for (Eigen::Index c = 0; c < K; ++c) run({c}, out.variogram.component_gamma, out.component_pairs, out.component_lag, c);
  for (Eigen::Index b = 0; b < B; ++b)
    out.variogram.bins[static_cast<std::size_t>(b)].gamma = out.variogram.component_gamma.row(b).sum();
  if (options.cross_variograms) {
    const Eigen::Index pairs_of_components = K * (K - 1) / 2;
    out.variogram.cross_gamma.setConstant(B, pairs_of_components, nan);
    out.cross_pairs.setZero(B, pairs_of_components);
    out.cross_lag.setConstant(B, pairs_of_components, nan);
    for (Eigen::Index a = 0; a < K; ++a)
      for (Eigen::Index c = a + 1; c < K; ++c)
        run({a, c}, out.variogram.cross_gamma, out.cross_pairs, out.cross_lag,
            EmpiricalVariogram::cross_column(static_cast<int>(a), static_cast<int>(c), static_cast<int>(K)));
  }
  return out;
}


#define ERRFIELD_VARIOGRAM_INSTANTIATE(L, M)                                                    \
  template EmpiricalVariogram empirical_variogram<L, M>(std::span<const L>,                     \
                                                        const Eigen::MatrixXd&, const M&,       \
                                                        const LagBins&,                         \
                                                        const EmpiricalVariogramOptions&);
#define ERRFIELD_VARIOGRAM_INSTANTIATE_METRICS(L)    \
  ERRFIELD_VARIOGRAM_INSTANTIATE(L, EuclideanMetric)  \
  ERRFIELD_VARIOGRAM_INSTANTIATE(L, JointSpaceMetric) \
  ERRFIELD_VARIOGRAM_INSTANTIATE(L, WeightedEuclideanMetric)
ERRFIELD_VARIOGRAM_INSTANTIATE_METRICS(double)
ERRFIELD_VARIOGRAM_INSTANTIATE_METRICS(Eigen::Vector2d)
ERRFIELD_VARIOGRAM_INSTANTIATE_METRICS(Eigen::Vector3d)
ERRFIELD_VARIOGRAM_INSTANTIATE_METRICS(detail::Location6d)
ERRFIELD_VARIOGRAM_INSTANTIATE_METRICS(Eigen::VectorXd)

// ---- variogram cloud and map (variogram_cloud.hpp) ----

namespace {

void check_cloud_inputs(const Eigen::MatrixXd& x, const Eigen::MatrixXd& z, const char* what) {
  detail::check_variogram_values(z, static_cast<std::size_t>(x.rows()));
  if (x.cols() < 1) throw ArgumentError(std::string(what) + ": locations have 0 coordinates; expected at least 1");
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    for (Eigen::Index c = 0; c < x.cols(); ++c)
      if (!std::isfinite(x(i, c))) detail::throw_bad_coordinate(static_cast<std::size_t>(i), static_cast<int>(c), x(i, c));
}

double half_squared_difference(const Eigen::MatrixXd& z, Eigen::Index i, Eigen::Index j) {
  double s = 0.0;
  for (Eigen::Index c = 0; c < z.cols(); ++c) {
    const double d = z(i, c) - z(j, c);
    s += d * d;
  }
  return 0.5 * s;
}

}  // namespace

VariogramCloud variogram_cloud(const Eigen::MatrixXd& x, const Eigen::MatrixXd& z, const VariogramCloudOptions& o) {
  if (!(o.cutoff > 0.0) || !std::isfinite(o.cutoff))
    throw ArgumentError("variogram cloud: cutoff = " + format_number(o.cutoff) + "; expected a finite value > 0");
  check_cloud_inputs(x, z, "variogram cloud");
  if (x.rows() > static_cast<Eigen::Index>(std::numeric_limits<std::uint32_t>::max()))
    throw ResourceError("variogram cloud: " + std::to_string(x.rows()) + " locations; at most 2^32 - 1");
  const int d = static_cast<int>(x.cols());
  o.direction.check_dimension(d);
  const kernels::DirectionCone cone = detail::variogram_direction_cone(o.direction, nullptr, 0, d);
  const bool directional = !o.direction.is_all() && kernels::cone_selects(cone);
  std::vector<double> s(static_cast<std::size_t>(d));
  // Visits the pairs (i > j) within the cutoff and the cone, in gstat's order; stops when f says so.
  const auto for_each_pair = [&](auto&& f) {
    for (Eigen::Index i = 1; i < x.rows(); ++i)
      for (Eigen::Index j = 0; j < i; ++j) {
        double h2 = 0.0;
        for (int a = 0; a < d; ++a) {
          s[static_cast<std::size_t>(a)] = x(i, a) - x(j, a);
          h2 += s[static_cast<std::size_t>(a)] * s[static_cast<std::size_t>(a)];
        }
        // Decided on the distance reported (not on h2 against cutoff^2, which rounds differently).
        const double h = std::sqrt(h2);
        if (!(h <= o.cutoff)) continue;
        if (directional && !kernels::direction_accepts(cone, s.data())) continue;
        if (!f(i, j, h)) return;
      }
  };
  // Count first, so that a cloud over the budget is refused before anything is stored.
  std::uint64_t count = 0;
  for_each_pair([&](Eigen::Index, Eigen::Index, double) { return ++count <= o.max_pairs; });
  if (count > o.max_pairs)
    throw ResourceError("variogram cloud: more than " + std::to_string(o.max_pairs) + " pairs within the cutoff " +
                        format_number(o.cutoff) + " (" + std::to_string(x.rows()) +
                        " locations); raise the budget (variogram --max-pairs) or give a shorter cutoff");
  VariogramCloud cloud;
  cloud.left.reserve(count);
  cloud.right.reserve(count);
  cloud.dist.reserve(count);
  cloud.gamma.reserve(count);
  for_each_pair([&](Eigen::Index i, Eigen::Index j, double h) {
    cloud.left.push_back(static_cast<std::uint32_t>(i));
    cloud.right.push_back(static_cast<std::uint32_t>(j));
    cloud.dist.push_back(h);
    cloud.gamma.push_back(half_squared_difference(z, i, j));
    return true;
  });
  return cloud;
}

VariogramMap variogram_map(const Eigen::MatrixXd& x, const Eigen::MatrixXd& z, const VariogramMapOptions& o) {
  if (!(o.cutoff > 0.0) || !std::isfinite(o.cutoff))
    throw ArgumentError("variogram map: cutoff = " + format_number(o.cutoff) + "; expected a finite value > 0");
  for (const double w : {o.width_x, o.width_y})
    if (!(w > 0.0) || !std::isfinite(w) || w > 2.0 * o.cutoff)
      throw ArgumentError("variogram map: cell width " + format_number(w) + "; expected a finite value in (0, 2 x cutoff = " +
                          format_number(2.0 * o.cutoff) + "]");
  if (x.cols() != 2)
    throw ArgumentError("variogram map: locations have " + std::to_string(x.cols()) +
                        " coordinates; a variogram map is of 2-D lag vectors (give 2 coordinates)");
  check_cloud_inputs(x, z, "variogram map");
  // R's length(seq(-cutoff, cutoff, by = width)), which sizes gstat's grid.
  const auto cells = [&](double w) { return static_cast<std::int64_t>(std::floor(2.0 * o.cutoff / w + 1e-10)) + 1; };
  const std::int64_t nx = cells(o.width_x), ny = cells(o.width_y);
  constexpr std::int64_t kMaxCells = 4'000'000;
  if (nx * ny > kMaxCells)
    throw ResourceError("variogram map: " + std::to_string(nx) + " x " + std::to_string(ny) + " cells; at most " +
                        std::to_string(kMaxCells) + " (wider cells or a shorter cutoff)");
  VariogramMap m;
  m.columns = static_cast<int>(nx);
  m.rows = static_cast<int>(ny);
  // gstat's grid: cell centres from -cutoff in steps of the width; left edge half a cell before
  // the first centre, top edge half a cell above the last.
  const double x_left = -o.cutoff - 0.5 * o.width_x;
  const double y_top = -o.cutoff + (static_cast<double>(ny) - 0.5) * o.width_y;
  for (std::int64_t c = 0; c < nx; ++c) m.lag_x.push_back(-o.cutoff + static_cast<double>(c) * o.width_x);
  for (std::int64_t r = 0; r < ny; ++r) m.lag_y.push_back(-o.cutoff + static_cast<double>(ny - 1 - r) * o.width_y);
  m.pairs.assign(static_cast<std::size_t>(nx * ny), 0);
  std::vector<double> sum(static_cast<std::size_t>(nx * ny), 0.0);
  const double x_right = x_left + static_cast<double>(nx) * o.width_x;
  const double y_bottom = y_top - static_cast<double>(ny) * o.width_y;
  const auto add = [&](double sx, double sy, double g) {
    if (sx < x_left || sx > x_right || sy > y_top || sy < y_bottom) return;
    auto c = static_cast<std::int64_t>(std::floor((sx - x_left) / o.width_x));
    auto r = static_cast<std::int64_t>(std::floor((y_top - sy) / o.width_y));
    c = std::min(c, nx - 1);  // on the right edge
    r = std::min(r, ny - 1);  // on the bottom edge
    const auto k = static_cast<std::size_t>(r * nx + c);
    ++m.pairs[k];
    sum[k] += g;
  };
  for (Eigen::Index i = 1; i < x.rows(); ++i)
    for (Eigen::Index j = 0; j < i; ++j) {
      const double sx = x(i, 0) - x(j, 0), sy = x(i, 1) - x(j, 1);
      const double g = half_squared_difference(z, i, j);
      add(sx, sy, g);
      add(-sx, -sy, g);
    }
  m.gamma.resize(sum.size());
  for (std::size_t k = 0; k < sum.size(); ++k)
    m.gamma[k] = m.pairs[k] ? sum[k] / static_cast<double>(m.pairs[k]) : std::numeric_limits<double>::quiet_NaN();
  return m;
}

}  // namespace errfield
