#pragma once
/// Plausibility checks on robot data read from files.
///
/// Warnings (the data may be right after all; print the text and carry on): measured positions
/// that look like metres where millimetres are expected, and joint angles outside the model's
/// limits (often radians where degrees are expected, or a wrong joint order).
///
/// Errors (`check_*`: throw InputError with file:line and the likely cause; the CLI exits 2): data
/// that cannot be what the command takes them for - nominal x,y,z that are not the robot's FK,
/// a tracker registration that leaves more than a rigid motion can explain, distances <= 0, and
/// robot-position base points taken as error-free. docs/robot.md ("Checks on the input") lists them
/// with their limits.

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "errfield/csv_table.hpp"
#include "errfield/robot/calibration.hpp"
#include "errfield/robot/mdh_model.hpp"
#include "errfield/row_labels.hpp"

namespace errfield::robot {

/// Reach scale of a model: sum over links of |a| + |d| (mm). 2478 mm for the ER20-C10.
double reach_scale_mm(const MdhModel& model);

/// How far a calibration may move an MD-H parameter from the nominal robot's and still be a
/// calibration of that robot: lengths (a, d) by kMaxCalibrationLengthChangeMm, angles (alpha,
/// theta0, beta) by kMaxCalibrationAngleChangeDeg. Real corrections are millimetres and tenths of a
/// degree; another robot's table differs by hundreds of millimetres or by 90 degrees.
inline constexpr double kMaxCalibrationLengthChangeMm = 50.0;
inline constexpr double kMaxCalibrationAngleChangeDeg = 10.0;

/// Why `other` is not a calibration of (or the same robot as) `nominal`, naming the first link
/// parameter that differs beyond the limits above (base and tool are free: a registration and a
/// tool or reflector), or nothing. A model whose command_model was swapped for another robot's
/// (a UR5e inside a KR16 model) gave 126/126 rows ok, 1,066 mm off.
std::optional<std::string> differs_beyond_calibration(const MdhModel& nominal, const MdhModel& other);

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

/// The first joint (0-based) of `q_deg` outside the model's joint limits widened by `slack_deg`
/// (a NaN is outside), or nothing. The one test behind joints_outside_limits and the status
/// outside-limits of predict, compensate and validate.
std::optional<int> joint_outside_limits(const JointVector& q_deg, const MdhModel& model, double slack_deg = 1e-9);

/// A warning naming the first row (via `labels`), joint and value outside the model's joint
/// limits, and how many rows are; nothing when all are within. `slack_deg` widens the limits.
std::optional<std::string> joints_outside_limits(const std::vector<JointVector>& q_deg, const MdhModel& model,
                                                 const RowLabels& labels, double slack_deg = 1e-9);

/// How far (mm) a row's nominal x,y,z may lie from the FK of its joints: joints recorded to two
/// decimals move a 2 m arm's tool by ~0.2 mm, a wrong robot or a missing tool by tens of mm.
inline constexpr double kNominalFkToleranceMm = 5.0;

/// Throws InputError when `table` has x,y,z and some row's x,y,z lies more than `tolerance_mm`
/// from forward_position(model, q1..q6), naming the worst row (file:line), both positions and
/// the likely cause, tested in this order: x,y,z in metres; the FK with a constant tool offset
/// (a tool or reflector missing from the robot; the offset is given); the FK in another frame (a
/// base transform missing); else a wrong robot - "no --robot given, the built-in ER20-C10 was
/// used" when `robot_given` is false. Also throws when x,y,z equal the tracker readings mx,my,mz
/// in every row (nominal columns holding measurements: every error would be 0), whatever the FK
/// says. Nothing happens for a table without x,y,z.
void check_nominal_positions(const CsvTable& table, const MdhModel& model, bool robot_given,
                             double tolerance_mm = kNominalFkToleranceMm);

/// Registration tracker -> robot residual (RMS over the points, mm) beyond which a rigid motion
/// cannot be what separates the readings from the nominal positions: an uncalibrated arm's error
/// left after a rigid fit is ~0.1-3 mm; a tool or reflector offset that turns with the flange, a
/// wrong robot or rows out of order leave tens of mm.
inline constexpr double kRegistrationRmsLimitMm = 5.0;

/// Throws InputError (naming `source`, the residual, the limit and the likely causes) when
/// `rms_mm` exceeds `limit_mm`. `what` says which registration ("registration tracker -> robot");
/// `fits_reflector_offset`: the registration fitted a reflector offset too (then a missing tool is
/// not the cause).
void check_registration_residual(double rms_mm, std::size_t points, const std::string& source,
                                 const std::string& what, double limit_mm = kRegistrationRmsLimitMm,
                                 bool fits_reflector_offset = false);

/// Where the robot a command checks the data against came from, for the message's likely cause.
struct RobotOrigin {
  bool given = false;  ///< false: no --robot, the built-in ER20-C10 was used
  std::string what;    ///< e.g. "--robot kr16", "the model's nominal robot (m.json)"; "" = "--robot"
};

/// The one data-fit-the-robot check of fit, calibrate, validate, predict and compensate (docs/robot.md
/// "Checks on the input"): registers the tracker readings `data` to `model` with a reflector offset
/// (register_tracker: 6 frame + 3 offset parameters, so a tool or reflector the robot JSON lacks does
/// not count) and throws InputError when the RMS residual exceeds `limit_mm`, naming `source`, the
/// residual, the limit and the likely cause, tried in this order on a subsample: joints in radians,
/// readings in metres, data of another built-in robot, no --robot given (the built-in ER20-C10 was
/// used), else a wrong robot or readings not in the rows of their joints. Returns the registration
/// (options as given, e.g. robust weights), or nothing for fewer than 6 readings (too few to tell).
std::optional<CalibrationResult> check_tracker_registration(const MdhModel& model,
                                                            const std::vector<PositionMeasurement>& data,
                                                            const std::string& source, const RobotOrigin& origin,
                                                            double limit_mm = kRegistrationRmsLimitMm,
                                                            const CalibrationOptions& options = {});

/// How close (mm) a row's nominal position must be to a base point to be that point (the paper's
/// layout: P0 is grid vertex 0, its distance to itself exactly 0).
inline constexpr double kAtBasePointMm = 1.0;

/// Throws InputError naming file:line and column when a distance column dist_b0, dist_b1, ... holds
/// a value <= 0, except exactly 0 where the row is base point K itself: the K-th base row
/// (kind=base) of dist_bK, or - when `robot` is given - a row whose nominal position (x,y,z, else
/// the FK of q1..q6) lies within kAtBasePointMm of base point K (the K-th base row's, else
/// `fixed_bases`[K]). Non-finite cells are refused by CsvTable already.
void check_distance_columns(const CsvTable& table, const MdhModel* robot = nullptr,
                            const std::vector<Eigen::Vector3d>& fixed_bases = {});

/// Throws InputError when 3-D errors would be recovered from distances to robot-position base
/// points (`robot_position_bases`: base rows with joints) and no tracker positions are available:
/// the robot's own error at each base enters every distance (dL = n·(dP − dP0)), so taking the
/// bases as error-free gives errors biased by the bases' errors.
void check_error_vectors_from_distances(bool robot_position_bases, bool has_positions, const std::string& source);

}  // namespace errfield::robot
