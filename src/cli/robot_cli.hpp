#pragma once
// Helpers shared by the robot subcommands (fk, ik, simulate, calibrate): loading the robot,
// reading joint and pose columns with messages that name the file, row and column.

#include <optional>
#include <string>
#include <vector>

#include "cli/cli_support.hpp"
#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"
#include "errfield/robot/mdh_model.hpp"

namespace errfield::cli {

/// The robot of `--robot PATH|NAME`: a built-in robot by name (robot/builtin_robots.hpp: er20-c10,
/// kr16, ur5e) unless a file of that name exists, else a robot JSON; the built-in nominal ER20-C10
/// (no tool) when empty. Warns on stderr when the file's lengths look like metres
/// (robot/input_checks.hpp).
robot::MdhModel load_robot_or_default(const std::string& path);

/// Columns q1..q6 (degrees) of a table, one JointVector per row.
std::vector<robot::JointVector> read_joint_columns(const CsvTable& table, const std::string& prefix = "q");

/// True if every column q1..q6 (with `prefix`) is present.
bool has_joint_columns(const CsvTable& table, const std::string& prefix = "q");

/// Names "q1".."q6" with a prefix.
std::vector<std::string> joint_column_names(const std::string& prefix = "q");

/// Warnings (to stderr, prefixed "errfield <command>: warning: ") when the position triples
/// x,y,z and mx,my,mz or the distance columns dist_b0, dist_b1, ... that `table` has look like
/// metres where millimetres are expected (robot/input_checks.hpp). Each names the file and the
/// columns. Reads only columns that are present; call it after the command has parsed them.
/// `groups` selects what to check (bits of MetresCheck).
enum MetresCheck : unsigned { kNominalXyz = 1, kMeasuredXyz = 2, kDistances = 4, kAllUnits = 7 };
void warn_if_metres(const CsvTable& table, const robot::MdhModel& model, const std::string& command,
                    unsigned groups = kAllUnits);

/// Rotation-matrix column names r11, r12, ..., r33 (row-major).
const std::vector<std::string>& rotation_column_names();

}  // namespace errfield::cli
