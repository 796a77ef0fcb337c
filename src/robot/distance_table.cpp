// Distance measurements (pairs of joints and a measured distance) from the columns of a
// measurement table, as `errfield calibrate --model distance` and the Python module read them.

#include "errfield/robot/distance_table.hpp"

#include <algorithm>

#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"
#include "errfield/robot/input_checks.hpp"
#include "errfield/robot/kinematics.hpp"

namespace errfield::robot {

DistanceTable distance_measurements_from_table(const CsvTable& table, const std::vector<JointVector>& q,
                                               const MdhModel& nominal, const std::vector<Eigen::Vector3d>& fixed) {
  const std::string& source = table.source();
  DistanceTable out;
  auto& data = out.data;
  auto& skipped = out.skipped;
  if (!fixed.empty()) {
    // Fixed base points (not robot positions): identified with the robot, from their nominals.
    std::size_t columns = 0;
    while (table.has_column("dist_b" + std::to_string(columns))) ++columns;
    if (columns != fixed.size())
      throw ArgumentError("--base-point: " + std::to_string(fixed.size()) + " given, but " + source + " has " +
                          std::to_string(columns) + " distance column(s) (dist_b0, dist_b1, ...); give one --base-point "
                          "X,Y,Z per dist_bK column, in order");
    const bool has_kind = table.has_column("kind");
    const std::size_t kind_col = has_kind ? table.column_index("kind") : 0;
    for (std::size_t k = 0; k < fixed.size(); ++k) {
      const std::string col = "dist_b" + std::to_string(k);
      const std::vector<double> d = table.numeric_column(col);
      const bool in_metres = distances_in_metres(d, nominal, {}).has_value();  // warned about, not refused
      for (std::size_t i = 0; i < table.row_count(); ++i) {
        const std::string kind(has_kind ? table.cell(i, kind_col) : std::string_view("target"));
        if (kind == "base")
          throw ArgumentError("--base-point: " + source + ":" + std::to_string(table.line_of_row(i)) +
                              " is a base row (kind=base), a robot-position base point; give base points either as "
                              "base rows or with --base-point (fixed points), not both");
        if (kind != "target")
          throw InputError(source + ":" + std::to_string(table.line_of_row(i)) + ": column 'kind': '" + kind +
                               "'; expected base or target",
                           source, table.line_of_row(i), "kind");
        if ((forward_position(nominal, q[i]) - fixed[k]).norm() < 1.0) {  // the tool at the point itself
          ++skipped;
          continue;
        }
        if (!(d[i] > 0))
          throw InputError(source + ":" + std::to_string(table.line_of_row(i)) + ": column '" + col + "': " +
                               format_number(d[i]) + "; expected a distance > 0 to fixed base point " +
                               std::to_string(k),
                           source, table.line_of_row(i), col);
        if (const auto why = implausible_distance(d[i], (forward_position(nominal, q[i]) - fixed[k]).norm(), nominal,
                                                  !in_metres))
          throw InputError(source + ":" + std::to_string(table.line_of_row(i)) + ": column '" + col + "': " + *why,
                           source, table.line_of_row(i), col);
        data.push_back({q[i], JointVector::Zero(), d[i], static_cast<int>(k)});
      }
    }
    if (skipped) out.note = std::to_string(skipped) + " point(s) less than 1 mm from their fixed base point skipped\n";
    return out;
  }
  if (!table.has_column("kind"))
    throw InputError(source + ": the distance model needs a 'kind' column (base|target) to find the base points",
                     source, 1, "kind");
  const std::size_t kind_col = table.column_index("kind");
  std::vector<std::size_t> base_rows;
  for (std::size_t i = 0; i < table.row_count(); ++i) {
    const std::string k(table.cell(i, kind_col));
    if (k == "base") base_rows.push_back(i);
    else if (k != "target")
      throw InputError(source + ":" + std::to_string(table.line_of_row(i)) + ": column 'kind': '" + k +
                           "'; expected base or target",
                       source, table.line_of_row(i), "kind");
  }
  if (base_rows.empty()) throw InputError(source + ": no row with kind 'base'", source, 0, "kind");
  for (std::size_t k = 0; k < base_rows.size(); ++k) {
    const std::string col = "dist_b" + std::to_string(k);
    const std::vector<double> d = table.numeric_column(col);
    const bool in_metres = distances_in_metres(d, nominal, {}).has_value();  // warned about, not refused
    for (std::size_t i = 0; i < table.row_count(); ++i) {
      const auto it = std::find(base_rows.begin(), base_rows.end(), i);
      if (it != base_rows.end() && static_cast<std::size_t>(it - base_rows.begin()) <= k) continue;  // each base pair once
      // A pair at (nominally) the same place carries no distance information, only noise along
      // an undefined direction: skip it (e.g. the grid point that is the base point itself).
      if ((forward_position(nominal, q[i]) - forward_position(nominal, q[base_rows[k]])).norm() < 1.0) {
        ++skipped;
        continue;
      }
      if (d[i] <= 0)
        throw InputError(source + ":" + std::to_string(table.line_of_row(i)) + ": column '" + col + "': " +
                             format_number(d[i]) + "; expected a distance > 0 for a point other than the base",
                         source, table.line_of_row(i), col);
      const double nominal_d = (forward_position(nominal, q[i]) - forward_position(nominal, q[base_rows[k]])).norm();
      if (const auto why = implausible_distance(d[i], nominal_d, nominal, !in_metres))
        throw InputError(source + ":" + std::to_string(table.line_of_row(i)) + ": column '" + col + "': " + *why,
                         source, table.line_of_row(i), col);
      data.push_back({q[i], q[base_rows[k]], d[i]});
    }
  }
  if (skipped) out.note = std::to_string(skipped) + " pair(s) less than 1 mm apart (a point at its base point) skipped\n";
  return out;
}

}  // namespace errfield::robot
