#include "errfield/robot/input_checks.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"
#include "errfield/robot/builtin_robots.hpp"
#include "errfield/robot/kinematics.hpp"
#include "robot/rigid_fit.hpp"

namespace errfield::robot {

double reach_scale_mm(const MdhModel& model) {
  double s = 0.0;
  for (const auto& l : model.links()) s += std::abs(l.a_mm) + std::abs(l.d_mm);
  return s;
}

std::optional<std::string> differs_beyond_calibration(const MdhModel& nominal, const MdhModel& other) {
  auto text = [](double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6g", v);
    return std::string(buf);
  };
  for (int i = 0; i < kJointCount; ++i) {
    const MdhLink &n = nominal.link(i), &o = other.link(i);
    const std::string at = "links[" + std::to_string(i) + "].";
    const std::pair<const char*, std::pair<double, double>> lengths[] = {{"a_mm", {n.a_mm, o.a_mm}}, {"d_mm", {n.d_mm, o.d_mm}}};
    for (const auto& [name, v] : lengths)
      if (!(std::abs(v.first - v.second) <= kMaxCalibrationLengthChangeMm))
        return at + name + " is " + text(v.second) + " against " + text(v.first) + " (more than " +
               text(kMaxCalibrationLengthChangeMm) + " mm apart)";
    const std::pair<const char*, std::pair<double, double>> angles[] = {
        {"alpha_deg", {n.alpha_deg, o.alpha_deg}}, {"theta0_deg", {n.theta0_deg, o.theta0_deg}}, {"beta_deg", {n.beta_deg, o.beta_deg}}};
    for (const auto& [name, v] : angles) {
      const double turn = std::remainder(v.first - v.second, 360.0);
      if (!(std::abs(turn) <= kMaxCalibrationAngleChangeDeg))
        return at + name + " is " + text(v.second) + " against " + text(v.first) + " (more than " +
               text(kMaxCalibrationAngleChangeDeg) + " degrees apart)";
    }
  }
  return std::nullopt;
}

std::optional<std::string> metres_instead_of_mm(const Eigen::MatrixXd& positions_mm, const MdhModel& model,
                                                const std::string& what) {
  const double reach = reach_scale_mm(model);
  if (positions_mm.rows() == 0 || positions_mm.cols() != 3 || reach < 100.0) return std::nullopt;
  const double limit = reach / 100.0;
  const Eigen::Vector3d base = model.base().translation();
  double max_world = 0.0, max_base = 0.0;
  for (Eigen::Index i = 0; i < positions_mm.rows(); ++i) {
    const Eigen::Vector3d p = positions_mm.row(i).transpose();
    max_world = std::max(max_world, p.norm());
    max_base = std::max(max_base, (p - base).norm());
  }
  if (max_world >= limit && max_base >= limit) return std::nullopt;
  return what + ": every position is within " + format_number(std::round(limit * 10) / 10) + " mm of the " +
         (max_world < limit ? "origin" : "robot base") + " (largest distance " +
         format_number(std::round(std::min(max_world, max_base) * 1000) / 1000) + ") for a robot of reach ~" + format_number(std::round(reach)) +
         " mm: are these metres? errfield expects millimetres (multiply by 1000)";
}

std::optional<std::string> lengths_in_metres(const MdhModel& model, const std::string& what) {
  const double reach = reach_scale_mm(model);
  if (!(reach > 0.0) || reach >= 100.0) return std::nullopt;
  return what + ": the links' lengths add up to " + format_number(std::round(reach * 1000) / 1000) +
         " mm (sum of |a_mm| + |d_mm|): are they in metres? errfield expects millimetres (multiply by 1000)";
}

std::optional<std::string> distances_in_metres(const std::vector<double>& distances_mm, const MdhModel& model,
                                               const std::string& what) {
  const double reach = reach_scale_mm(model);
  if (distances_mm.empty() || reach < 100.0) return std::nullopt;
  const double limit = reach / 100.0;
  double largest = 0.0;
  for (double d : distances_mm) largest = std::max(largest, std::abs(d));
  if (largest >= limit || largest == 0.0) return std::nullopt;
  return what + ": every distance is below " + format_number(std::round(limit * 10) / 10) + " mm (largest " +
         format_number(std::round(largest * 1000) / 1000) + ") for a robot of reach ~" + format_number(std::round(reach)) +
         " mm: are these metres? errfield expects millimetres (multiply by 1000)";
}

std::optional<int> joint_outside_limits(const JointVector& q_deg, const MdhModel& model, double slack_deg) {
  for (int j = 0; j < kJointCount; ++j) {
    const MdhLink& l = model.link(j);
    if (!(q_deg[j] >= l.q_min_deg - slack_deg && q_deg[j] <= l.q_max_deg + slack_deg)) return j;
  }
  return std::nullopt;
}

std::optional<std::string> joints_outside_limits(const std::vector<JointVector>& q_deg, const MdhModel& model,
                                                 const RowLabels& labels, double slack_deg) {
  const JointVector lo = model.q_min_deg(), hi = model.q_max_deg();
  std::size_t count = 0, first = 0;
  int first_joint = 0;
  for (std::size_t i = 0; i < q_deg.size(); ++i) {
    if (const auto j = joint_outside_limits(q_deg[i], model, slack_deg)) {
      if (count == 0) {
        first = i;
        first_joint = *j;
      }
      ++count;
    }
  }
  if (count == 0) return std::nullopt;
  const double v = q_deg[first][first_joint];
  return labels(first) + ": q" + std::to_string(first_joint + 1) + " = " + format_number(v) +
         " deg is outside the joint limits [" + format_number(lo[first_joint]) + ", " + format_number(hi[first_joint]) +
         "] of " + model.name() + (count > 1 ? " (" + std::to_string(count) + " rows are outside in all)" : "") +
         "; check units (degrees) and joint order";
}

namespace {

std::string mm(double v) { return format_number(std::round(v * 1000.0) / 1000.0); }
std::string xyz_text(const Eigen::Vector3d& p) { return "(" + mm(p.x()) + ", " + mm(p.y()) + ", " + mm(p.z()) + ")"; }

bool has_xyz(const CsvTable& t, const std::string& prefix) {
  return t.has_column(prefix + "x") && t.has_column(prefix + "y") && t.has_column(prefix + "z");
}

std::vector<Eigen::Vector3d> xyz_rows(const CsvTable& t, const std::string& prefix) {
  const Eigen::MatrixXd m = t.numeric_columns({prefix + "x", prefix + "y", prefix + "z"});
  std::vector<Eigen::Vector3d> out(static_cast<std::size_t>(m.rows()));
  for (Eigen::Index i = 0; i < m.rows(); ++i) out[static_cast<std::size_t>(i)] = m.row(i).transpose();
  return out;
}

std::string line_of(const CsvTable& t, std::size_t row) { return t.source() + ":" + std::to_string(t.line_of_row(row)); }

}  // namespace

void check_nominal_positions(const CsvTable& t, const MdhModel& model, bool robot_given, double tolerance_mm) {
  if (!has_xyz(t, "") || t.row_count() == 0) return;
  const std::vector<Eigen::Vector3d> xyz = xyz_rows(t, "");
  if (has_xyz(t, "m")) {
    // Nominal columns that hold the measurements make every error 0: refuse whatever the FK says
    // (a tracker registered to the robot frame agrees with the FK to a few mm).
    const std::vector<Eigen::Vector3d> m = xyz_rows(t, "m");
    double largest = 0.0;
    for (std::size_t i = 0; i < xyz.size(); ++i) largest = std::max(largest, (xyz[i] - m[i]).norm());
    if (largest <= 1e-6)
      throw InputError(t.source() + ": columns x,y,z equal the tracker readings mx,my,mz in every row (largest "
                           "difference " + format_number(largest) + " mm): the nominal columns must hold where the "
                           "robot was commanded (FK of q1..q6, robot base frame), not measurements, or every error "
                           "is 0. Drop x,y,z (errfield computes them from q1..q6 and --robot)",
                       t.source(), 0, "x");
  }
  const Eigen::MatrixXd qm = t.numeric_columns({"q1", "q2", "q3", "q4", "q5", "q6"});
  const std::size_t n = xyz.size();
  std::vector<Eigen::Vector3d> fk(n);
  std::vector<Eigen::Matrix3d> rot(n);
  std::size_t worst = 0;
  double worst_mm = -1.0, worst_metres = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Isometry3d pose = forward_kinematics(model, qm.row(static_cast<Eigen::Index>(i)).transpose());
    fk[i] = pose.translation();
    rot[i] = pose.linear();
    const double e = (xyz[i] - fk[i]).norm();
    if (!(e <= worst_mm)) {
      worst_mm = e;
      worst = i;
    }
    worst_metres = std::max(worst_metres, (1000.0 * xyz[i] - fk[i]).norm());
  }
  if (worst_mm <= tolerance_mm) return;
  std::string cause;
  // A constant offset in the tool frame: x,y,z = p_i + R_i t, least squares t = mean(R_i^T e_i).
  Eigen::Vector3d tool = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < n; ++i) tool += rot[i].transpose() * (xyz[i] - fk[i]);
  tool /= static_cast<double>(n);
  double tool_residual = 0.0, rigid_residual = 0.0;
  for (std::size_t i = 0; i < n; ++i) tool_residual = std::max(tool_residual, (fk[i] + rot[i] * tool - xyz[i]).norm());
  Eigen::Isometry3d frame = Eigen::Isometry3d::Identity();
  if (n >= 3) {
    frame = fit_rigid(fk, xyz);
    for (std::size_t i = 0; i < n; ++i) rigid_residual = std::max(rigid_residual, (frame * fk[i] - xyz[i]).norm());
  }
  if (worst_metres <= tolerance_mm) {
    cause = "x,y,z look like metres (times 1000 they agree with the FK to " + mm(worst_metres) +
            " mm): errfield expects millimetres";
  } else if (tool_residual <= tolerance_mm) {
    cause = "x,y,z are the FK plus a constant offset " + xyz_text(tool) + " mm in the tool frame (to " +
            mm(tool_residual) + " mm): a tool or reflector that the robot description lacks (add it as \"tool\" in the "
            "robot JSON" + (robot_given ? "" : " and give it with --robot") + ")";
  } else if (n >= 3 && rigid_residual <= tolerance_mm) {
    const PoseXyzRpy f = to_xyz_rpy(frame);
    cause = "x,y,z are the FK in another frame (a rigid motion x " + mm(f.x_mm) + " y " + mm(f.y_mm) + " z " +
            mm(f.z_mm) + " mm, rx " + mm(f.rx_deg) + " ry " + mm(f.ry_deg) + " rz " + mm(f.rz_deg) +
            " deg fits to " + mm(rigid_residual) + " mm): the robot description's \"base\" differs";
  } else if (!robot_given) {
    cause = "no --robot was given, so the built-in ER20-C10 (no tool) was used: give the robot the data come "
            "from (--robot R.json, or a built-in name: " + builtin_robot_names() + ")";
  } else {
    cause = "they are not the FK of robot '" + model.name() +
            "': a wrong --robot, or joints in another convention (zero offsets, signs, order)";
  }
  throw InputError(line_of(t, worst) + ": columns x,y,z " + xyz_text(xyz[worst]) + " are " + mm(worst_mm) +
                       " mm from the robot's FK " + xyz_text(fk[worst]) + " of q1..q6 (limit " +
                       format_number(tolerance_mm) + " mm); likely cause: " + cause +
                       ". If --robot is a calibrated model and x,y,z the controller's nominal positions, drop the "
                       "x,y,z columns (errfield computes them from q1..q6)",
                   t.source(), t.line_of_row(worst), "x");
}

void check_registration_residual(double rms_mm, std::size_t points, const std::string& source, const std::string& what,
                                 double limit_mm, bool fits_reflector_offset) {
  if (rms_mm <= limit_mm) return;
  throw InputError(source + ": " + what + " on " + std::to_string(points) + " points leaves RMS " + mm(rms_mm) +
                       " mm, beyond the limit " + format_number(limit_mm) +
                       " mm: the tracker readings and the nominal positions differ by more than a rigid motion" +
                       (fits_reflector_offset ? std::string(" and a reflector offset") : std::string()) +
                       ". Likely causes: " +
                       (fits_reflector_offset
                            ? std::string("")
                            : std::string("a tool or reflector offset missing from --robot (a rigid registration "
                                          "cannot absorb an offset that turns with the flange; 'errfield calibrate "
                                          "--model position' identifies it with the registration), ")) +
                       "a wrong --robot (or none given: the built-in ER20-C10), mx,my,mz in metres, or readings not in "
                       "the rows of their joints",
                   source);
}

namespace {

/// The residual RMS (mm) of register_tracker on at most 60 evenly spread rows: enough to tell a
/// fitting hypothesis (below the limit) from a wrong one (hundreds of mm), fast on any data size.
double registration_rms(const MdhModel& model, const std::vector<PositionMeasurement>& data) {
  std::vector<PositionMeasurement> few;
  const std::size_t step = std::max<std::size_t>(1, data.size() / 60);
  for (std::size_t i = 0; i < data.size(); i += step) few.push_back(data[i]);
  try {
    return register_tracker(model, few).after.rms_mm;
  } catch (const Error&) {
    return std::numeric_limits<double>::infinity();
  }
}

std::string likely_registration_cause(const MdhModel& model, const std::vector<PositionMeasurement>& data,
                                      const RobotOrigin& origin, double limit_mm) {
  const std::string robot = "'" + model.name() + "'" + (origin.given ? " (" + (origin.what.empty() ? std::string("--robot") : origin.what) + ")" : "");
  // Radians read as degrees: every joint within +-2 pi.
  bool small = true;
  for (const auto& d : data) small = small && d.q_deg.cwiseAbs().maxCoeff() <= 2.0 * std::numbers::pi + 1e-9;
  if (small) {
    std::vector<PositionMeasurement> deg = data;
    for (auto& d : deg) d.q_deg *= 180.0 / std::numbers::pi;
    const double rms = registration_rms(model, deg);
    if (rms <= limit_mm)
      return "the joints q1..q6 are in radians (times 180/pi they register to " + mm(rms) +
             " mm): errfield expects degrees";
  }
  std::vector<PositionMeasurement> scaled = data;
  for (auto& d : scaled) d.measured_mm *= 1000.0;
  if (const double rms = registration_rms(model, scaled); rms <= limit_mm)
    return "the tracker readings mx,my,mz are in metres (times 1000 they register to " + mm(rms) +
           " mm): errfield expects millimetres";
  for (const BuiltinRobot& b : builtin_robots()) {
    if (b.model.name() == model.name()) continue;
    if (const double rms = registration_rms(b.model, data); rms <= limit_mm)
      return "the data are of another robot: they register to the built-in " + b.name + " to " + mm(rms) +
             " mm, not to robot " + robot + (origin.given ? std::string() : "; no --robot was given, so the built-in "
             "ER20-C10 was used") + ": give the robot the data come from (--robot " + b.name + " or its JSON)";
  }
  if (!origin.given)
    return "no --robot was given, so the built-in ER20-C10 (no tool) was used: give the robot the data come from "
           "(--robot R.json, or a built-in name: " + builtin_robot_names() + ")";
  return "the data are not of robot " + robot + ": a wrong robot, joints in another convention (zero offsets, "
         "signs, order), or readings not in the rows of their joints";
}

}  // namespace

std::optional<CalibrationResult> check_tracker_registration(const MdhModel& model,
                                                            const std::vector<PositionMeasurement>& data,
                                                            const std::string& source, const RobotOrigin& origin,
                                                            double limit_mm, const CalibrationOptions& options) {
  if (data.size() < 6) return std::nullopt;
  CalibrationResult reg = register_tracker(model, data, options);
  if (reg.after.rms_mm <= limit_mm) return reg;
  throw InputError(source + ": registration tracker -> robot '" + model.name() + "' (with a reflector offset) on " +
                       std::to_string(data.size()) + " points leaves RMS " + mm(reg.after.rms_mm) +
                       " mm, beyond the limit " + format_number(limit_mm) +
                       " mm (--max-registration-rms): the readings are not this robot's positions at these joints. "
                       "Likely cause: " + likely_registration_cause(model, data, origin, limit_mm),
                   source);
}

void check_distance_columns(const CsvTable& t, const MdhModel* robot, const std::vector<Eigen::Vector3d>& fixed_bases) {
  const bool has_kind = t.has_column("kind");
  const std::size_t kind_col = has_kind ? t.column_index("kind") : 0;
  std::vector<std::size_t> base_rows;
  for (std::size_t i = 0; has_kind && i < t.row_count(); ++i)
    if (t.cell(i, kind_col) == "base") base_rows.push_back(i);
  // Nominal positions of the rows and the base points, to recognise a row that is a base point.
  std::vector<Eigen::Vector3d> nominal, bases;
  const bool has_q = t.has_column("q1") && t.has_column("q2") && t.has_column("q3") && t.has_column("q4") &&
                     t.has_column("q5") && t.has_column("q6");
  if (robot && (has_xyz(t, "") || has_q)) {
    if (has_xyz(t, "")) {
      nominal = xyz_rows(t, "");
    } else {
      const Eigen::MatrixXd q = t.numeric_columns({"q1", "q2", "q3", "q4", "q5", "q6"});
      for (Eigen::Index i = 0; i < q.rows(); ++i) nominal.push_back(forward_position(*robot, q.row(i).transpose()));
    }
    for (std::size_t r : base_rows) bases.push_back(nominal[r]);
    if (bases.empty()) bases = fixed_bases;
  }
  for (std::size_t k = 0; t.has_column("dist_b" + std::to_string(k)); ++k) {
    const std::string col = "dist_b" + std::to_string(k);
    const std::vector<double> d = t.numeric_column(col);
    for (std::size_t i = 0; i < d.size(); ++i) {
      const bool own_base = k < base_rows.size() && base_rows[k] == i;
      const bool at_base = k < bases.size() && i < nominal.size() && (nominal[i] - bases[k]).norm() <= kAtBasePointMm;
      if (d[i] > 0 || (own_base && d[i] >= 0) || (at_base && d[i] == 0.0)) continue;
      throw InputError(line_of(t, i) + ": column '" + col + "': " + format_number(d[i]) + " mm; expected a distance > 0 " +
                           (own_base ? "" : "from base point b" + std::to_string(k) + " ") +
                           "(a tracker distance is never negative, and 0 only at the base point itself)",
                       t.source(), t.line_of_row(i), col);
    }
  }
}

void check_error_vectors_from_distances(bool robot_position_bases, bool has_positions, const std::string& source) {
  if (!robot_position_bases || has_positions) return;
  throw InputError(source + ": 3-D errors from distances need base points whose positions are known: these base "
                       "points are robot positions (kind=base rows), whose own error enters every distance "
                       "(dL = n.(dP - dP0)), so taking them as error-free biases every error vector. Measure tracker "
                       "positions (mx,my,mz), or use fixed base points (no base rows, --base-point X,Y,Z), or a "
                       "method that accounts for the base's error (distance-kriging, kinematic)",
                   source, 0, "dist_b0");
}

std::optional<std::string> implausible_distance(double measured_mm, double nominal_mm, const MdhModel& model,
                                                bool near_nominal) {
  if (!(measured_mm > 0.0))
    return format_number(measured_mm) + " mm; expected a distance > 0 (the nominal distance is " +
           format_number(std::round(nominal_mm * 1000) / 1000) + " mm)";
  const double limit = reach_scale_mm(model) / 10.0;
  if (!near_nominal || std::abs(measured_mm - nominal_mm) <= limit) return std::nullopt;
  return format_number(measured_mm) + " mm, but the nominal distance is " +
         format_number(std::round(nominal_mm * 1000) / 1000) + " mm: an error of " +
         format_number(std::round((measured_mm - nominal_mm) * 1000) / 1000) + " mm, more than a tenth of " +
         model.name() + "'s size (" + format_number(std::round(limit)) +
         " mm); check the column, its units (mm) and the base point";
}

std::optional<std::string> tracker_frozen(const Eigen::MatrixXd& measured_mm, const Eigen::MatrixXd& nominal_mm) {
  if (measured_mm.rows() < 2 || measured_mm.rows() != nominal_mm.rows() || measured_mm.cols() != 3 ||
      nominal_mm.cols() != 3)
    return std::nullopt;
  const auto spread = [](const Eigen::MatrixXd& p) {
    const Eigen::RowVector3d c = p.colwise().mean();
    return (p.rowwise() - c).rowwise().norm().maxCoeff();
  };
  const double nominal = spread(nominal_mm), measured = spread(measured_mm);
  if (!(nominal > 1.0) || measured > nominal * 1e-6) return std::nullopt;
  return "the " + std::to_string(measured_mm.rows()) + " measured positions (mx,my,mz) lie within " +
         format_number(measured) + " mm of their mean while the nominal positions spread over " +
         format_number(std::round(nominal)) +
         " mm: the tracker did not follow the reflector (a frozen reading?); nothing can be fitted to them";
}

}  // namespace errfield::robot
