#pragma once
/// @file
/// The distance measurements of a table for calibrate_distances (calibration.hpp): each target's
/// dist_bK against base point K, where base points are either base rows (kind=base: robot
/// positions, each pair of bases once) or fixed points given by the caller (one per dist_bK
/// column; then the table has no base rows). Pairs less than 1 mm apart nominally are skipped (no
/// direction). Use it when your distances come as the columns of `errfield simulate`.

#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "errfield/robot/calibration.hpp"
#include "errfield/robot/mdh_model.hpp"

namespace errfield {
class CsvTable;
}

namespace errfield::robot {

struct DistanceTable {
  std::vector<DistanceMeasurement> data;
  std::size_t skipped = 0;  ///< pairs (points) less than 1 mm from their base
  std::string note;         ///< "3 pair(s) ... skipped\n" for the report, or empty
};

/// `q`: the table's q1..q6 (deg), one per row. `fixed`: fixed base points (robot frame, mm), one
/// per dist_bK column, or empty for base rows. Throws InputError/ArgumentError naming the table's
/// file:line and column for a missing kind column, a distance <= 0 or an implausible one
/// (input_checks.hpp), a base row mixed with fixed points.
DistanceTable distance_measurements_from_table(const CsvTable& table, const std::vector<JointVector>& q,
                                               const MdhModel& nominal, const std::vector<Eigen::Vector3d>& fixed);

}  // namespace errfield::robot
