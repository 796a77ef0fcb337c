#pragma once
/// Plausibility checks on robot data read from files, for warnings (not errors): measured
/// positions that look like metres where millimetres are expected, and joint angles outside the
/// model's limits (often radians where degrees are expected, or a wrong joint order). Use them
/// where a command or pipeline reads positions or joint angles; print the returned text to the
/// user and carry on, since the data may be right after all.

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "errfield/robot/mdh_model.hpp"
#include "errfield/row_labels.hpp"

namespace errfield::robot {

/// Reach scale of a model: sum over links of |a| + |d| (mm). 2478 mm for the ER20-C10.
double reach_scale_mm(const MdhModel& model);

/// A warning when every position (rows of `positions_mm`, columns x, y, z in the model's world
/// frame) lies within reach_scale_mm(model) / 100 of both the world origin and the robot base
/// (25 mm for the ER20-C10): no real robot measures all its poses there, while metres read as
/// millimetres land exactly there. Returns nothing when the data look like millimetres, when
/// there are no rows, or when the model's reach is below 100 mm. `what` names the data (file and
/// columns).
std::optional<std::string> metres_instead_of_mm(const Eigen::MatrixXd& positions_mm, const MdhModel& model,
                                                const std::string& what);

/// A warning when the model's reach scale is above 0 but below 100 mm: MD-H lengths (a_mm,
/// d_mm) given in metres. `what` names the source (robot JSON file).
std::optional<std::string> lengths_in_metres(const MdhModel& model, const std::string& what);

/// A warning when every distance (mm) is below reach_scale_mm(model) / 100 in magnitude (25 mm for
/// the ER20-C10) while some is not 0: distances between robot positions across a workspace in
/// metres read as millimetres. Nothing for no distances or a reach below 100 mm. `what` names
/// the data (file and column).
std::optional<std::string> distances_in_metres(const std::vector<double>& distances_mm, const MdhModel& model,
                                               const std::string& what);

/// Why a measured distance (mm) cannot be right, or nothing: it must be > 0 and within
/// reach_scale_mm(model) / 10 of the nominal distance (250 mm for the ER20-C10; positioning
/// errors are millimetres). Distances of 1e300 "calibrated" to a robot with 1e300 mm links, and a
/// negative dist_b0 became a 1 m correction marked ok. The caller adds file, line and column.
/// `near_nominal` false checks only > 0: for a column that distances_in_metres warns about (a
/// warning, not an error, by the bad-input catalogue), whose errors are then all about -d.
std::optional<std::string> implausible_distance(double measured_mm, double nominal_mm, const MdhModel& model,
                                                bool near_nominal = true);

/// Why tracker positions (N x 3, mm) cannot be measurements of the robot at the nominal positions
/// (N x 3), or nothing: when the nominal positions spread over more than 1 mm and the measured
/// ones over less than a thousandth of that, the tracker did not follow the reflector (a frozen
/// reading), and any fit to them is made up.
std::optional<std::string> tracker_frozen(const Eigen::MatrixXd& measured_mm, const Eigen::MatrixXd& nominal_mm);

/// A warning naming the first row (via `labels`), joint and value outside the model's joint
/// limits, and how many rows are; nothing when all are within. `slack_deg` widens the limits.
std::optional<std::string> joints_outside_limits(const std::vector<JointVector>& q_deg, const MdhModel& model,
                                                 const RowLabels& labels, double slack_deg = 1e-9);

}  // namespace errfield::robot
