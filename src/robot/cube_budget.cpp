#include "errfield/robot/cube_budget.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
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

std::size_t max_cube_points() {
  const char* env = std::getenv("ERRFIELD_MAX_CUBE_POINTS");
  if (!env) return kMaxCubePoints;
  char* end = nullptr;
  errno = 0;
  const unsigned long long v = std::strtoull(env, &end, 10);
  if (end == env || *end != '\0' || errno == ERANGE || v == 0 || env[0] == '-')
    throw ArgumentError(std::string("ERRFIELD_MAX_CUBE_POINTS='") + env + "': expected a positive integer");
  return static_cast<std::size_t>(v);
}

void check_cube_budget(double size_mm, double step_mm, bool cell_samples, const std::string& option) {
  if (!(step_mm > 0) || !std::isfinite(step_mm) || !(size_mm > 0) || !std::isfinite(size_mm)) return;
  const double cells = std::round(size_mm / step_mm);
  const double points = cube_points(cells, cell_samples);
  const double limit = static_cast<double>(max_cube_points());
  if (points <= limit) return;
  double max_cells = std::floor(std::cbrt(limit)) - 1;
  while (max_cells > 1 && cube_points(max_cells, cell_samples) > limit) --max_cells;
  max_cells = std::max(max_cells, 1.0);
  throw ResourceError(option + " " + format_number(step_mm) + ": a " + format_number(size_mm) + " mm cube in steps of " +
                      format_number(step_mm) + " mm has " + approx(cells) + " cells per side, " + approx(points) +
                      (cell_samples ? " grid points and cell samples" : " grid points") + " (about " +
                      gigabytes(points) + " GB of memory); the limit is " + approx(limit) +
                      " points per job (about " + gigabytes(limit) + " GB). Use at most " + approx(max_cells) + " cells per side (" + option + " >= " +
                      significant(size_mm / max_cells) + " mm) or split the cube");
}

void check_point_budget(double count, const std::string& option) {
  const double limit = static_cast<double>(max_cube_points());
  if (!(count > limit)) return;
  throw ResourceError(option + ": " + approx(count) + " points (about " + gigabytes(count) +
                      " GB of memory); the limit is " + approx(limit) +
                      " points per job (about " + gigabytes(limit) + " GB). Split the job");
}

}  // namespace errfield::robot
