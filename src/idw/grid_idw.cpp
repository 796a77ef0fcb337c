#include "errfield/grid_idw.hpp"

#include "errfield/thread_count.hpp"

#include <cmath>

#include "errfield/csv_table.hpp"

namespace errfield {

void GridIdwOptions::validate() const {
  if (!(power >= 0.0) || !std::isfinite(power))
    throw ArgumentError("GridIdwOptions::power is " + format_number(power) + "; expected a finite value >= 0");
  if (!(vertex_tolerance >= 0.0 && vertex_tolerance <= 1e-2))
    throw ArgumentError("GridIdwOptions::vertex_tolerance is " + format_number(vertex_tolerance) +
                        "; expected a value in [0, 0.01] (a fraction of the grid step)");
  if (!(boundary_tolerance >= 0.0 && boundary_tolerance <= 1e-2))
    throw ArgumentError("GridIdwOptions::boundary_tolerance is " + format_number(boundary_tolerance) +
                        "; expected a value in [0, 0.01] (a fraction of the grid step)");
  check_thread_count("GridIdwOptions::threads", threads);
}

std::string describe_outside_target(const Eigen::Vector3d& target, const std::string& name, const RegularGrid3& grid) {
  const Eigen::Vector3d lo = grid.lower(), hi = grid.upper();
  std::string where;
  constexpr const char* kAxis[3] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(target[a])) {
      where += std::string(where.empty() ? "" : ", ") + kAxis[a] + " is not finite";
    } else if (target[a] < lo[a]) {
      where += std::string(where.empty() ? "" : ", ") + kAxis[a] + " " + format_number(lo[a] - target[a]) +
               " below";
    } else if (target[a] > hi[a]) {
      where += std::string(where.empty() ? "" : ", ") + kAxis[a] + " " + format_number(target[a] - hi[a]) +
               " above";
    }
  }
  return name + " (" + format_number(target.x()) + ", " + format_number(target.y()) + ", " +
         format_number(target.z()) + ") is outside the grid [" + format_number(lo.x()) + ", " +
         format_number(hi.x()) + "] x [" + format_number(lo.y()) + ", " + format_number(hi.y()) + "] x [" +
         format_number(lo.z()) + ", " + format_number(hi.z()) + "] (" + where +
         "); clamping (GridIdwOptions::clamp, CLI --clamp) would use the nearest cell instead";
}

template class GridIdw<double>;
template class GridIdw<Eigen::Vector3d>;

}  // namespace errfield
