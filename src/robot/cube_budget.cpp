#include "errfield/robot/cube_budget.hpp"

#include <cmath>
#include <cstdio>

#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"

namespace errfield::robot {
namespace {

double cube_points(double cells_per_side, bool cell_samples) {
  const double nodes = std::pow(std::floor(cells_per_side) + 1.0, 3);
  return cell_samples ? nodes + std::pow(std::floor(cells_per_side), 3) : nodes;
}

std::string approx(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, v < 1e7 ? "%.0f" : "%.3g", v);
  return buf;
}

std::string significant(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

std::string gigabytes(double points) {  // ~2.2 KB per point, measured on simulate (docs/reliability.md)
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", points * 2.2e3 / 1e9);
  return buf;
}

}  // namespace

void check_cube_budget(double size_mm, double step_mm, bool cell_samples, const std::string& option) {
  if (!(step_mm > 0) || !std::isfinite(step_mm) || !(size_mm > 0) || !std::isfinite(size_mm)) return;
  const double cells = std::round(size_mm / step_mm);
  const double points = cube_points(cells, cell_samples);
  if (points <= static_cast<double>(kMaxCubePoints)) return;
  double max_cells = std::floor(std::cbrt(static_cast<double>(kMaxCubePoints))) - 1;
  while (max_cells > 1 && cube_points(max_cells, cell_samples) > static_cast<double>(kMaxCubePoints)) --max_cells;
  throw ResourceError(option + " " + format_number(step_mm) + ": a " + format_number(size_mm) + " mm cube in steps of " +
                      format_number(step_mm) + " mm has " + approx(cells) + " cells per side, " + approx(points) +
                      (cell_samples ? " grid points and cell samples" : " grid points") + " (about " +
                      gigabytes(points) + " GB of memory); the limit is " + approx(kMaxCubePoints) +
                      " points per job (about 2 GB). Use at most " + approx(max_cells) + " cells per side (" + option + " >= " +
                      significant(size_mm / max_cells) + " mm) or split the cube");
}

void check_point_budget(double count, const std::string& option) {
  if (!(count > static_cast<double>(kMaxCubePoints))) return;
  throw ResourceError(option + ": " + approx(count) + " points (about " + gigabytes(count) +
                      " GB of memory); the limit is " + approx(kMaxCubePoints) +
                      " points per job (about 2 GB). Split the job");
}

}  // namespace errfield::robot
