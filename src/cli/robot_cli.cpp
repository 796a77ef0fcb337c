#include "cli/robot_cli.hpp"

#include <iostream>

#include <filesystem>

#include "errfield/robot/builtin_robots.hpp"
#include "errfield/robot/input_checks.hpp"

namespace errfield::cli {

robot::MdhModel load_robot_or_default(const std::string& path) {
  if (path.empty()) return robot::MdhModel::er20_c10();
  if (const robot::BuiltinRobot* b = robot::builtin_robot_unless_file(path)) return b->model;
  if (path == "list")
    throw ArgumentError("--robot list: the built-in robots are " + robot::builtin_robot_names() +
                        " (errfield robots describes them)");
  if (!std::filesystem::exists(path))
    throw InputError("--robot '" + path + "': no such file and not a built-in robot (" + robot::builtin_robot_names() +
                         "; errfield robots lists them)",
                     path);
  robot::MdhModel m = robot::MdhModel::load(path);
  if (const auto w = robot::lengths_in_metres(m, path)) std::cerr << "errfield: warning: " << *w << "\n";
  return m;
}

std::vector<std::string> joint_column_names(const std::string& prefix) {
  std::vector<std::string> names;
  for (int i = 1; i <= robot::kJointCount; ++i) names.push_back(prefix + std::to_string(i));
  return names;
}

bool has_joint_columns(const CsvTable& table, const std::string& prefix) {
  for (const auto& n : joint_column_names(prefix))
    if (!table.has_column(n)) return false;
  return true;
}

std::vector<robot::JointVector> read_joint_columns(const CsvTable& table, const std::string& prefix) {
  const Eigen::MatrixXd m = table.numeric_columns(joint_column_names(prefix));
  std::vector<robot::JointVector> q(static_cast<std::size_t>(m.rows()));
  for (Eigen::Index r = 0; r < m.rows(); ++r) q[static_cast<std::size_t>(r)] = m.row(r).transpose();
  return q;
}

void warn_if_metres(const CsvTable& table, const robot::MdhModel& model, const std::string& command,
                    unsigned groups) {
  for (const std::string prefix : {"", "m"}) {
    if (!(groups & (prefix.empty() ? kNominalXyz : kMeasuredXyz))) continue;
    const std::vector<std::string> cols{prefix + "x", prefix + "y", prefix + "z"};
    if (!table.has_column(cols[0]) || !table.has_column(cols[1]) || !table.has_column(cols[2])) continue;
    if (const auto w = robot::metres_instead_of_mm(table.numeric_columns(cols), model,
                                                   table.source() + " columns " + cols[0] + "," + cols[1] + "," + cols[2]))
      std::cerr << "errfield " << command << ": warning: " << *w << "\n";
  }
  for (std::size_t k = 0; (groups & kDistances) && table.has_column("dist_b" + std::to_string(k)); ++k) {
    const std::string col = "dist_b" + std::to_string(k);
    if (const auto w = robot::distances_in_metres(table.numeric_column(col), model, table.source() + " column " + col))
      std::cerr << "errfield " << command << ": warning: " << *w << "\n";
  }
}

const std::vector<std::string>& rotation_column_names() {
  static const std::vector<std::string> names{"r11", "r12", "r13", "r21", "r22", "r23", "r31", "r32", "r33"};
  return names;
}

}  // namespace errfield::cli
