#include "errfield/regular_grid.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>

#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"

namespace errfield {
namespace {

constexpr const char* kAxisName[3] = {"x", "y", "z"};

std::string fmt(double v) { return format_number(v); }

std::string point_text(const Eigen::Vector3d& p) {
  std::string s = "(";
  s += fmt(p.x()) + ", " + fmt(p.y()) + ", " + fmt(p.z()) + ")";
  return s;
}

std::string list_values(const std::vector<double>& values, std::size_t max_items = 12) {
  std::string s;
  for (std::size_t i = 0; i < values.size() && i < max_items; ++i) s += (i ? ", " : "") + fmt(values[i]);
  if (values.size() > max_items) s += ", ... (" + std::to_string(values.size()) + " values)";
  return s;
}

// A throw helper that fills the file/line fields from the labels when they name a file, and
// starts the message with "g.csv:10: " for a row (compiler style) or "g.csv: " for the whole file.
[[noreturn]] void fail(const std::string& message, const RowLabels& labels, std::size_t row = SIZE_MAX) {
  const std::size_t line = row == SIZE_MAX ? 0 : labels.line(row);
  const std::string where = row != SIZE_MAX && labels.in_file(row) ? labels(row) : labels.source;
  const bool named = where.empty() || message.rfind(where, 0) == 0;
  const std::string prefix = named ? "" : where + ": ";
  throw InputError(prefix + message, labels.source, line);
}

double extent_of_planes(const std::vector<double>& planes) { return planes.back() - planes.front(); }

struct AxisLattice {
  double origin = 0.0;
  double step = 0.0;
  int count = 0;
};

// Planes of one axis: cluster the sorted coordinates, then check that the cluster centres sit on
// one evenly spaced lattice whose step is the smallest gap. Gaps that are whole multiples of the
// step are allowed here (they are whole missing planes, reported later as missing nodes).
AxisLattice detect_axis(std::vector<double> values, int axis, double relative_tolerance, std::size_t n_samples,
                        const RowLabels& labels) {
  std::sort(values.begin(), values.end());
  const double extent = values.back() - values.front();
  const std::string name = kAxisName[axis];
  if (!(extent > 0.0))
    fail("all " + std::to_string(values.size()) + " samples have " + name + " = " + fmt(values.front()) +
             "; a 3-D grid needs at least 2 distinct values per axis",
         labels);
  const double tol = relative_tolerance * extent;
  std::vector<double> planes;
  double sum = values.front();
  std::size_t in_cluster = 1;
  for (std::size_t i = 1; i < values.size(); ++i) {
    if (values[i] - values[i - 1] > tol) {
      planes.push_back(sum / static_cast<double>(in_cluster));
      sum = 0.0;
      in_cluster = 0;
    }
    sum += values[i];
    ++in_cluster;
  }
  planes.push_back(sum / static_cast<double>(in_cluster));

  double smallest_gap = extent;
  for (std::size_t i = 1; i < planes.size(); ++i) smallest_gap = std::min(smallest_gap, planes[i] - planes[i - 1]);
  const double steps_total = std::round(extent / smallest_gap);
  // A lattice far larger than the data cannot be a grid with a few missing nodes; it is noise in
  // the coordinates (values that should coincide but differ by more than the tolerance).
  if (steps_total + 1.0 > 4.0 * static_cast<double>(n_samples) + 64.0)
    fail("the " + name + " values are not evenly spaced: " + list_values(planes) + "; the smallest gap " +
             fmt(smallest_gap) + " would need " + fmt(steps_total + 1.0) + " planes over the extent " + fmt(extent) +
             " (if these values should coincide, raise the relative tolerance)",
         labels);
  // Every gap must be a whole multiple of the smallest one (each plane may be off by tol).
  double steps = 0.0;
  for (std::size_t i = 1; i < planes.size(); ++i) {
    const double gap = planes[i] - planes[i - 1];
    const double multiple = std::round(gap / smallest_gap);
    steps += multiple;
    if (std::abs(gap - multiple * smallest_gap) > 2.0 * tol * (1.0 + multiple))
      fail("uneven spacing on axis " + name + ": values " + list_values(planes) + "; the gap from " +
               fmt(planes[i - 1]) + " to " + fmt(planes[i]) + " is " + fmt(gap) +
               ", not a whole multiple of the smallest gap " + fmt(smallest_gap) + " (a regular grid has " + name +
               " = " + fmt(planes.front()) + " + i * step)",
           labels);
  }
  AxisLattice lattice;
  lattice.origin = planes.front();
  lattice.count = static_cast<int>(steps) + 1;
  lattice.step = extent_of_planes(planes) / steps;
  for (std::size_t i = 1; i < planes.size(); ++i) {
    const double index = std::round((planes[i] - lattice.origin) / lattice.step);
    const double ideal = lattice.origin + index * lattice.step;
    if (std::abs(planes[i] - ideal) > tol)
      fail("uneven spacing on axis " + name + ": values " + list_values(planes) + "; " + fmt(planes[i]) +
               " is " + fmt(planes[i] - ideal) + " off its lattice position " + fmt(ideal) + " (step " +
               fmt(lattice.step) + ")",
           labels);
  }
  return lattice;
}

}  // namespace

RegularGrid3::RegularGrid3(const Eigen::Vector3d& origin, const Eigen::Vector3d& step, const std::array<int, 3>& counts)
    : origin_(origin), step_(step), counts_(counts) {
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(origin_[a]))
      throw ArgumentError(std::string("RegularGrid3: origin ") + kAxisName[a] + " is " + fmt(origin_[a]) +
                          "; expected a finite number");
    if (!(step_[a] > 0.0) || !std::isfinite(step_[a]))
      throw ArgumentError(std::string("RegularGrid3: step ") + kAxisName[a] + " is " + fmt(step_[a]) +
                          "; expected a finite number > 0");
    if (counts_[a] < 2)
      throw ArgumentError(std::string("RegularGrid3: ") + std::to_string(counts_[a]) + " nodes on axis " +
                          kAxisName[a] + "; expected at least 2 (one cell)");
  }
}

Eigen::Vector3d RegularGrid3::upper() const {
  return origin_ + Eigen::Vector3d(step_.x() * (counts_[0] - 1), step_.y() * (counts_[1] - 1),
                                   step_.z() * (counts_[2] - 1));
}

std::size_t RegularGrid3::node_count() const noexcept {
  return static_cast<std::size_t>(counts_[0]) * static_cast<std::size_t>(counts_[1]) *
         static_cast<std::size_t>(counts_[2]);
}

std::size_t RegularGrid3::cell_count() const noexcept {
  return static_cast<std::size_t>(counts_[0] - 1) * static_cast<std::size_t>(counts_[1] - 1) *
         static_cast<std::size_t>(counts_[2] - 1);
}

std::array<int, 3> RegularGrid3::node_indices(std::size_t index) const noexcept {
  const auto nx = static_cast<std::size_t>(counts_[0]);
  const auto ny = static_cast<std::size_t>(counts_[1]);
  return {static_cast<int>(index % nx), static_cast<int>((index / nx) % ny), static_cast<int>(index / (nx * ny))};
}

Eigen::Vector3d RegularGrid3::node_position(int i, int j, int k) const {
  return origin_ + Eigen::Vector3d(step_.x() * i, step_.y() * j, step_.z() * k);
}

Eigen::Vector3d RegularGrid3::node_position(std::size_t index) const {
  const auto ijk = node_indices(index);
  return node_position(ijk[0], ijk[1], ijk[2]);
}

bool RegularGrid3::contains(const Eigen::Vector3d& p, double tolerance) const {
  const Eigen::Vector3d hi = upper();
  for (int a = 0; a < 3; ++a)
    if (!(p[a] >= origin_[a] - tolerance && p[a] <= hi[a] + tolerance)) return false;
  return true;
}

std::string RegularGrid3::describe() const {
  const Eigen::Vector3d hi = upper();
  std::string s;
  for (int a = 0; a < 3; ++a)
    s += std::string(a ? ", " : "") + kAxisName[a] + " [" + fmt(origin_[a]) + ", " + fmt(hi[a]) + "] step " +
         fmt(step_[a]) + " (" + std::to_string(counts_[a]) + " nodes)";
  return s;
}

void GridDetectionOptions::validate() const {
  if (!(relative_tolerance > 0.0 && relative_tolerance <= 1e-2))
    throw ArgumentError("GridDetectionOptions::relative_tolerance is " + fmt(relative_tolerance) +
                        "; expected a value in (0, 0.01]");
}

GridDetection detect_regular_grid(const Eigen::Ref<const Eigen::MatrixXd>& points, const RowLabels& labels,
                                  const GridDetectionOptions& options) {
  options.validate();
  if (points.cols() != 3)
    throw ArgumentError("detect_regular_grid: points have " + std::to_string(points.cols()) +
                        " columns; expected 3 (x, y, z)");
  const auto n = static_cast<std::size_t>(points.rows());
  for (std::size_t r = 0; r < n; ++r)
    for (int a = 0; a < 3; ++a)
      if (!std::isfinite(points(static_cast<Eigen::Index>(r), a)))
        fail(labels(r) + ": coordinate " + kAxisName[a] + " is " + fmt(points(static_cast<Eigen::Index>(r), a)) +
                 "; expected a finite number",
             labels, r);
  if (n < 8)
    fail(std::to_string(n) + " samples; a regular 3-D grid needs at least 8 (2 x 2 x 2 nodes)", labels);

  AxisLattice axes[3];
  for (int a = 0; a < 3; ++a) {
    std::vector<double> v(n);
    for (std::size_t r = 0; r < n; ++r) v[r] = points(static_cast<Eigen::Index>(r), a);
    axes[a] = detect_axis(std::move(v), a, options.relative_tolerance, n, labels);
  }
  RegularGrid3 grid(Eigen::Vector3d(axes[0].origin, axes[1].origin, axes[2].origin),
                    Eigen::Vector3d(axes[0].step, axes[1].step, axes[2].step),
                    {axes[0].count, axes[1].count, axes[2].count});

  constexpr std::size_t kNone = SIZE_MAX;
  std::vector<std::size_t> sample_of_node(grid.node_count(), kNone);
  for (std::size_t r = 0; r < n; ++r) {
    int ijk[3];
    for (int a = 0; a < 3; ++a) {
      const double t = std::round((points(static_cast<Eigen::Index>(r), a) - axes[a].origin) / axes[a].step);
      ijk[a] = std::clamp(static_cast<int>(t), 0, axes[a].count - 1);
    }
    const std::size_t node = grid.node_index(ijk[0], ijk[1], ijk[2]);
    if (sample_of_node[node] != kNone) {
      const std::size_t first = sample_of_node[node];
      const auto ri = static_cast<Eigen::Index>(r);
      const auto fi = static_cast<Eigen::Index>(first);
      fail("duplicate grid node (" + std::to_string(ijk[0]) + ", " + std::to_string(ijk[1]) + ", " +
               std::to_string(ijk[2]) + ") at " + point_text(grid.node_position(ijk[0], ijk[1], ijk[2])) + ": " +
               labels(first) + " " + point_text(points.row(fi).transpose()) + " and " + labels(r) + " " +
               point_text(points.row(ri).transpose()) + " are both on it",
           labels, r);
    }
    sample_of_node[node] = r;
  }

  std::vector<std::size_t> missing;
  for (std::size_t node = 0; node < sample_of_node.size(); ++node)
    if (sample_of_node[node] == kNone) missing.push_back(node);
  if (!missing.empty()) {
    auto node_text = [&](std::size_t node) {
      const auto ijk = grid.node_indices(node);
      std::string s = "(";
      s += std::to_string(ijk[0]) + ", " + std::to_string(ijk[1]) + ", " + std::to_string(ijk[2]) + ") at " +
           point_text(grid.node_position(node));
      return s;
    };
    std::string msg = "incomplete grid (" + grid.describe() + "; " + std::to_string(grid.node_count()) +
                      " nodes, " + std::to_string(n) + " samples): node " + node_text(missing.front()) +
                      " has no sample";
    if (missing.size() > 1) {
      msg += "; ";
      msg += std::to_string(missing.size()) + " nodes are missing in all, also";
      for (std::size_t m = 1; m < missing.size() && m < 6; ++m) {
        msg += m > 1 ? ", " : " ";
        msg += node_text(missing[m]);
      }
      if (missing.size() > 6) msg += ", ...";
    }
    fail(msg, labels);
  }
  return GridDetection{grid, std::move(sample_of_node)};
}

}  // namespace errfield
