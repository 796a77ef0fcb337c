#include "compensation/fitting/kinematic_fit.hpp"

#include "errfield/number_format.hpp"

#include <numbers>
#include <sstream>

#include "errfield/error.hpp"
#include "errfield/robot/flange_points.hpp"
#include "errfield/robot/input_checks.hpp"

namespace errfield::compensation {

using namespace errfield::robot;

CalibrationData calibration_data_from_name(std::string_view name) {
  if (name == "position") return CalibrationData::position;
  if (name == "distance") return CalibrationData::distance;
  throw ArgumentError("--calibration: expected 'position' or 'distance', got '" + std::string(name) + "'");
}

namespace detail {

namespace {

// 5 significant digits: notes are read by people; the numbers that matter are in the model JSON.
std::string short_number(double v) { return format_significant(v, 5); }

std::string summary(const CalibrationResult& cal, std::size_t count, const std::string& what, bool robust) {
  return "calibration on " + std::to_string(count) + " " + what + ": residual RMS " + short_number(cal.before.rms_mm) +
         " -> " + short_number(cal.after.rms_mm) + " mm, " + std::to_string(cal.parameters.size()) +
         " parameters identified, " + std::to_string(cal.removed.size()) + " removed, condition number " +
         short_number(cal.condition_number) + " (physically scaled)" +
         // From distances the weak directions are regularized, not removed: say so beside a large condition number.
         (cal.regularization > 0 ? ", regularized toward nominal (Tikhonov weight " + short_number(cal.regularization) + ")"
                                 : std::string()) +
         ", robust weights " +
         (robust ? "igg3 (" + std::to_string(cal.rejected) + " rejected)" : std::string("none")) + "; " + cal.message;
}

/// The calibration's leverage (calibration_leverage.hpp) over its readings `pm`, each at its point
/// `point_of_reading_mm` (empty: the model's tool), with its robust weights. The noise variance is
/// the residual's per component, at least (1 um)²: a fit of exact data leaves rounding, and no
/// tracker reads better.
std::optional<CalibrationLeverage> leverage_of(const MdhModel& model, const std::vector<PositionMeasurement>& pm,
                                               const CalibrationResult& cal,
                                               const std::vector<Eigen::Vector3d>& point_of_reading_mm) {
  std::vector<JointVector> q;
  for (const PositionMeasurement& m : pm) q.push_back(m.q_deg);
  const double noise_variance = std::max(cal.after.rms_mm * cal.after.rms_mm / 3.0, 1e-6);
  return CalibrationLeverage::of(model, q, noise_variance, point_of_reading_mm,
                                 cal.weights.size() == q.size() ? cal.weights : std::vector<double>{});
}

std::string flange_point_text(const Eigen::Vector3d& v) {
  return "(" + short_number(v.x()) + ", " + short_number(v.y()) + ", " + short_number(v.z()) + ")";
}

// The reflector is the point measured; the robot JSON's tool is the point to compensate. Close
// together they are one point (the data locate it better than the JSON); apart, compensate aims
// the JSON's tool on the calibrated flange, which the data only see through the reflector.
void tool_and_reflector(KinematicFit& out, const MdhModel& robot, const Eigen::Vector3d& reflector,
                        const MeasurementSet& d, const FitOptions& o) {
  const Eigen::Vector3d tool = robot.tool().translation();
  const double apart = (reflector - tool).norm();
  out.reflector_mm = reflector;
  const std::string where = "the reflector found from the data is at " + flange_point_text(reflector) +
                            " mm in the flange frame, " + short_number(apart) +
                            " mm from the robot JSON's tool point " + flange_point_text(tool) + " mm";
  if (apart <= kReflectorAtToolMm) {
    out.tool_point_mm = reflector;
    out.notes.push_back(where + ": taken as the same point (within " + short_number(kReflectorAtToolMm) +
                        " mm); compensate aims it as identified");
    return;
  }
  if (apart > kReflectorFarMm && !o.reflector_far_ok)
    throw InputError(d.source + ": " + where + " (limit " + short_number(kReflectorFarMm) +
                         " mm): the robot JSON's tool cannot be the point measured. Give --robot the tool that "
                         "carries the reflector (or measure at the tool point); if the reflector really sits that far "
                         "from the tool point (a second nest), say so with --reflector-far-ok",
                     d.source, 0, "mx");
  out.tool_point_mm = tool;
  // What the lever costs: an orientation error of the calibrated flange moves the tool point by
  // apart x angle more than the reflector, and the data see only the reflector.
  const double per_hundredth_deg = apart * 0.01 * std::numbers::pi / 180.0;
  out.warnings.push_back(where + ": compensate aims the tool point on the calibrated flange, measured only through "
                         "the reflector; every 0.01 deg of flange orientation error the calibration leaves moves "
                         "the tool point " + short_number(per_hundredth_deg) +
                         " mm more than it moves the reflector, and an error in the tool's own offset is not seen "
                         "at all. Measure at the tool point for its accuracy");
  out.notes.push_back(where + ": compensate aims the robot JSON's tool point on the calibrated flange");
}

// Registration (tracker ← robot base and the reflector offset, MD-H fixed), then the full model in
// the tracker frame; the result is expressed back in the robot's world frame (the nominal
// model's base frame), and the registration maps tracker readings into it.
KinematicFit from_positions(const MdhModel& robot, const MeasurementSet& d, const FitOptions& o) {
  if (d.measured_mm.empty())
    throw InputError(d.source + ": --calibration position needs measured positions (columns mx,my,mz, tracker frame)",
                     d.source, 0, "mx");
  std::vector<PositionMeasurement> pm;
  for (std::size_t i = 0; i < d.q_deg.size(); ++i) pm.push_back({d.q_deg[i], d.measured_mm[i]});
  if (o.on_stage) o.on_stage("registration and kinematic calibration on " + std::to_string(pm.size()) + " positions");
  const CalibrationResult reg = register_tracker(robot, pm, o.calibration);
  const CalibrationResult cal = calibrate_positions(reg.model, pm, o.calibration);
  // reg.model.base() is tracker ← robot chain; the nominal base is world ← robot chain.
  const Eigen::Isometry3d world_from_tracker = robot.base() * reg.model.base().inverse();
  KinematicFit out{cal.model.with_base(world_from_tracker * cal.model.base()), Registration{}, {}, {}};
  out.registration->robot_from_tracker = world_from_tracker;
  out.registration->residual_rms_mm = cal.after.rms_mm;
  const Eigen::Vector3d reflector = reg.model.tool().translation();
  out.notes.push_back("registration tracker -> robot with the reflector offset (" + short_number(reflector.x()) + ", " +
                      short_number(reflector.y()) + ", " + short_number(reflector.z()) +
                      ") mm in the flange: residual RMS " + short_number(reg.after.rms_mm) + " mm");
  out.notes.push_back(summary(cal, pm.size(), "positions (tracker frame)", o.calibration.robust.enabled));
  if (!reg.converged) out.warnings.push_back("the tracker registration did not converge: " + reg.message);
  if (!cal.converged) out.warnings.push_back("the kinematic calibration did not converge: " + cal.message);
  tool_and_reflector(out, robot, cal.model.tool().translation(), d, o);
  out.leverage = leverage_of(out.model, pm, cal, {});
  return out;
}

// Readings of several points on the flange (a `reflector` column): one registration, one MD-H table,
// the tool point (the label nearest the robot JSON's tool, or FitOptions::tool_reflector) and each
// further label's offset, all in one fit, so the points together determine the flange's orientation.
// The robot JSON's tool stays the point compensated; the rows of the model's own label are what the
// joint functions and the field take.
KinematicFit from_several_points(const MdhModel& robot, const MeasurementSet& d, const FitOptions& o) {
  std::vector<PositionMeasurement> pm;
  for (std::size_t i = 0; i < d.q_deg.size(); ++i) pm.push_back({d.q_deg[i], d.measured_mm[i], 0});
  if (o.on_stage)
    o.on_stage("registration and kinematic calibration on " + std::to_string(pm.size()) + " readings of " +
               std::to_string(d.reflector_labels().size()) + " points on the flange");
  const LabelledFlangePoints points = assign_flange_points(robot, pm, d.reflector, o.tool_reflector, o.calibration, d.source);
  const CalibrationResult reg = register_tracker(robot, pm, points.further_points_mm(), o.calibration);
  std::vector<Eigen::Vector3d> located;
  for (const FlangePointEstimate& p : reg.flange_points) located.push_back(p.position_mm);
  const CalibrationResult cal = calibrate_positions(reg.model, pm, located, o.calibration);
  const Eigen::Isometry3d world_from_tracker = robot.base() * reg.model.base().inverse();
  KinematicFit out{cal.model.with_base(world_from_tracker * cal.model.base()), Registration{}, {}, {}, {}, {}, {}, {}, {}, {}};
  out.registration->robot_from_tracker = world_from_tracker;
  out.registration->residual_rms_mm = cal.after.rms_mm;
  for (std::size_t i = 0; i < pm.size(); ++i) {
    const int k = pm[i].flange_point;
    if (k == 0) out.own_point_rows.push_back(i);
    out.flange_point_of_row_mm.push_back(k == 0 ? Eigen::Vector3d(cal.model.tool().translation())
                                                : cal.flange_points[static_cast<std::size_t>(k - 1)].position_mm);
  }
  std::string where;
  for (std::size_t k = 0; k < points.labels.size(); ++k) {
    const Eigen::Vector3d p = k == 0 ? Eigen::Vector3d(cal.model.tool().translation()) : cal.flange_points[k - 1].position_mm;
    out.located_points.emplace_back(points.labels[k], p);
    where += (k ? "; '" : "'") + points.labels[k] + "' " + flange_point_text(p) + " (" +
             std::to_string(points.readings[k]) + " readings" + (k == 0 ? ", the model's own point" : "") + ")";
  }
  out.notes.push_back("points on the flange located with the robot (flange frame, mm): " + where);
  out.notes.push_back(summary(cal, pm.size(), "readings of " + std::to_string(points.labels.size()) +
                                                  " points on the flange (tracker frame)",
                              o.calibration.robust.enabled));
  out.notes.push_back("the joint error functions and the field are fitted to the readings of '" + points.labels[0] +
                      "' (" + std::to_string(out.own_point_rows.size()) +
                      " rows); the other points determine the flange's orientation in the calibration");
  if (!reg.converged) out.warnings.push_back("the tracker registration did not converge: " + reg.message);
  if (!cal.converged) out.warnings.push_back("the kinematic calibration did not converge: " + cal.message);
  // The robot JSON's tool is the working point (the "far from the tool" check is for one unlabelled
  // reflector, where a far one means a wrong tool).
  FitOptions far_ok = o;
  far_ok.reflector_far_ok = true;
  tool_and_reflector(out, robot, cal.model.tool().translation(), d, far_ok);
  out.leverage = leverage_of(out.model, pm, cal, out.flange_point_of_row_mm);
  return out;
}

KinematicFit from_distances(const MdhModel& robot, const MeasurementSet& d, const FitOptions& o) {
  const bool fixed_bases = d.base_q_deg.empty();  // --base-point: points in the cell, not robot positions
  if (o.base >= d.distance_mm.size() || o.base >= d.base_nominal_mm.size() ||
      (!fixed_bases && o.base >= d.base_q_deg.size()))
    throw InputError(d.source + ": kinematic calibration from distances needs distances dist_b" +
                         std::to_string(o.base) +
                         " to a base point: a robot position (a kind=base row with its joints) or fixed points given "
                         "with --base-point" +
                         (d.measured_mm.empty() ? std::string() : "; or calibrate from the positions (--calibration position)"),
                     d.source, 0, "dist_b" + std::to_string(o.base));
  std::vector<DistanceMeasurement> dm;
  if (fixed_bases) {
    // Every fixed point's distances: their coordinates are identified with the robot.
    // A row at the point itself (the paper's P0 as a grid vertex, distance 0) has no direction:
    // skipped, as the robot-position bases' own rows are below.
    for (std::size_t k = 0; k < d.distance_mm.size(); ++k)
      for (std::size_t i = 0; i < d.q_deg.size(); ++i)
        if ((d.nominal_mm[i] - d.base_nominal_mm[k]).norm() > kAtBasePointMm)
          dm.push_back({d.q_deg[i], JointVector::Zero(), d.distance_mm[k][i], static_cast<int>(k)});
  } else {
    for (std::size_t i = 0; i < d.q_deg.size(); ++i)
      if ((d.nominal_mm[i] - d.base_nominal_mm[o.base]).norm() > 1.0)
        dm.push_back({d.base_q_deg[o.base], d.q_deg[i], d.distance_mm[o.base][i]});
  }
  if (o.on_stage) o.on_stage("kinematic calibration on " + std::to_string(dm.size()) + " distances");
  const CalibrationResult cal = fixed_bases ? calibrate_distances(robot, dm, d.base_nominal_mm, o.calibration)
                                            : calibrate_distances(robot, dm, o.calibration);
  KinematicFit out{cal.model, std::nullopt, {}, {}};
  out.notes.push_back(summary(cal, dm.size(), "distances", o.calibration.robust.enabled));
  for (std::size_t k = 0; k < cal.base_points.size(); ++k) {
    const BasePointEstimate& b = cal.base_points[k];
    out.notes.push_back("fixed base point b" + std::to_string(k) + " identified at (" + short_number(b.position_mm.x()) +
                        ", " + short_number(b.position_mm.y()) + ", " + short_number(b.position_mm.z()) +
                        ") mm, nominal (" + short_number(b.nominal_mm.x()) + ", " + short_number(b.nominal_mm.y()) +
                        ", " + short_number(b.nominal_mm.z()) + ") mm");
  }
  if (!cal.converged) out.warnings.push_back("the kinematic calibration did not converge: " + cal.message);
  return out;
}

}  // namespace

KinematicFit fit_kinematic(const MdhModel& robot, const MeasurementSet& d, const FitOptions& o) {
  CalibrationData how = o.calibration_data;
  if (how == CalibrationData::automatic) how = d.measured_mm.empty() ? CalibrationData::distance : CalibrationData::position;
  if (d.reflector_labels().size() > 1) {
    if (how != CalibrationData::position || d.measured_mm.empty())
      throw InputError(d.source + ": readings of several points on the flange (column 'reflector') calibrate from "
                           "positions (mx,my,mz), not from distances",
                       d.source, 0, "reflector");
    return from_several_points(robot, d, o);
  }
  return how == CalibrationData::position ? from_positions(robot, d, o) : from_distances(robot, d, o);
}

}  // namespace detail
}  // namespace errfield::compensation
