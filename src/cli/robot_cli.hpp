#pragma once
// Helpers shared by the robot subcommands (fk, ik, simulate, calibrate): loading the robot,
// reading joint and pose columns with messages that name the file, row and column.

#include <optional>
#include <string>
#include <vector>

#include "errfield/csv_table.hpp"
#include "errfield/robot/mdh_model.hpp"

namespace errfield::cli {

/// The robot of `--robot PATH`, or the built-in nominal ER20-C10 (no tool) when the path is empty.
robot::MdhModel load_robot_or_default(const std::string& path);

/// Columns q1..q6 (degrees) of a table, one JointVector per row.
std::vector<robot::JointVector> read_joint_columns(const CsvTable& table, const std::string& prefix = "q");

/// True if every column q1..q6 (with `prefix`) is present.
bool has_joint_columns(const CsvTable& table, const std::string& prefix = "q");

/// Names "q1".."q6" with a prefix.
std::vector<std::string> joint_column_names(const std::string& prefix = "q");

/// Rotation-matrix column names r11, r12, ..., r33 (row-major).
const std::vector<std::string>& rotation_column_names();

}  // namespace errfield::cli
