#include "errfield/robot/calibration.hpp"
#include "errfield/robot/flange_points.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <Eigen/Dense>

#include "errfield/error.hpp"
#include "robot/calibration_problems.hpp"
#include "robot/calibration_solver.hpp"
#include "robot/rigid_fit.hpp"

// The public entry points of kinematic calibration. The measurement models live in
// calibration_problems.cpp, parameter selection in calibration_identifiability.cpp, the LM core
// and IGG3 weights in calibration_solver.cpp.

namespace errfield::robot {

using detail::CalibrationState;
using detail::DistanceProblem;
using detail::PositionProblem;

IkResult compensated_joints(const MdhModel& nominal, const MdhModel& identified, const Eigen::Isometry3d& target,
                            const JointVector& seed_deg, int iterations) {
  Eigen::Isometry3d command = target;
  IkResult r = inverse_kinematics(nominal, command, seed_deg);
  for (int it = 0; it < iterations && r.ok(); ++it) {
    const Eigen::Vector3d gap = forward_position(identified, r.q_deg) - target.translation();
    if (gap.norm() < 1e-7) break;
    command.translation() -= gap;
    r = inverse_kinematics(nominal, command, r.q_deg);
  }
  if (r.ok()) {
    r.position_residual_mm = (forward_position(identified, r.q_deg) - target.translation()).norm();
    if (r.position_residual_mm > 1e-4) r.status = IkStatus::max_iterations;
  }
  return r;
}

IkResult compensated_pose_joints(const MdhModel& nominal, const MdhModel& identified, const Eigen::Isometry3d& target,
                                 const JointVector& seed_deg, int iterations) {
  Eigen::Isometry3d command = target;
  IkResult r = inverse_kinematics(nominal, command, seed_deg);
  auto gaps = [&](const JointVector& q) {
    const Eigen::Isometry3d reached = forward_kinematics(identified, q);
    const Eigen::AngleAxisd turn(reached.linear() * target.linear().transpose());
    return std::make_pair(Eigen::Vector3d(reached.translation() - target.translation()), Eigen::Vector3d(turn.angle() * turn.axis()));
  };
  for (int it = 0; it < iterations && r.ok(); ++it) {
    const auto [position_gap, rotation_gap] = gaps(r.q_deg);
    if (position_gap.norm() < 1e-7 && rotation_gap.norm() < 1e-10) break;
    command.translation() -= position_gap;
    command.linear() = Eigen::AngleAxisd(-rotation_gap.norm(), rotation_gap.norm() > 0 ? Eigen::Vector3d(rotation_gap.normalized())
                                                                                       : Eigen::Vector3d::UnitX())
                           .toRotationMatrix() *
                       command.linear();
    r = inverse_kinematics(nominal, command, r.q_deg);
  }
  if (r.ok()) {
    const auto [position_gap, rotation_gap] = gaps(r.q_deg);
    r.position_residual_mm = position_gap.norm();
    r.orientation_residual_rad = rotation_gap.norm();
    if (r.position_residual_mm > 1e-4 || r.orientation_residual_rad > 1e-7) r.status = IkStatus::max_iterations;
  }
  return r;
}

double igg3_weight(double u, double k0, double k1) {
  if (u <= k0) return 1.0;
  if (u > k1) return 0.0;
  const double t = (k1 - u) / (k1 - k0);
  return (k0 / u) * t * t;
}

void CalibrationOptions::validate() const {
  if (!(redundancy_tolerance > 0 && redundancy_tolerance < 1))
    throw ArgumentError("CalibrationOptions::redundancy_tolerance = " + std::to_string(redundancy_tolerance) +
                        ", expected in (0, 1)");
  if (!(max_condition_number > 1))
    throw ArgumentError("CalibrationOptions::max_condition_number = " + std::to_string(max_condition_number) +
                        ", expected > 1");
  if (max_iterations < 1) throw ArgumentError("CalibrationOptions::max_iterations must be >= 1");
  if (!(cost_tolerance >= 0)) throw ArgumentError("CalibrationOptions::cost_tolerance must be >= 0");
  // Checked whether or not the weights are on: a bad k0/k1 is a mistake either way.
  if (!(robust.k0 > 0 && robust.k1 > robust.k0))
    throw ArgumentError("CalibrationOptions::robust: need 0 < k0 < k1, got k0 = " + std::to_string(robust.k0) +
                        ", k1 = " + std::to_string(robust.k1));
  if (robust.max_rounds < 1) throw ArgumentError("CalibrationOptions::robust.max_rounds must be >= 1");
  for (int c : candidates)
    if (c < 0 || c >= param::kCount)
      throw ArgumentError("CalibrationOptions::candidates: index " + std::to_string(c) + " outside [0, " +
                          std::to_string(param::kCount) + ")");
}

namespace {
// Consecutive axes are parallel when alpha is 0 or 180 deg (anti-parallel: URDF imports and arms
// whose joint 3 turns the other way have alpha = +-180); d and theta0 alone then cannot describe a
// small tilt between them, Hayati's beta can.
bool parallel_axes(double alpha_deg) {
  const double folded = std::fmod(std::abs(alpha_deg), 180.0);
  return folded < 1e-6 || 180.0 - folded < 1e-6;
}
}  // namespace

std::vector<int> default_candidates(const MdhModel& model, bool with_base) {
  std::vector<int> c;
  if (with_base)
    for (int k = 0; k < 6; ++k) c.push_back(param::kBaseTranslation + k);
  for (int k = 0; k < 3; ++k) c.push_back(param::kToolTranslation + k);
  for (int i = 0; i < kJointCount; ++i) {
    c.push_back(param::link_index(i, param::kAlpha));
    c.push_back(param::link_index(i, param::kA));
    c.push_back(param::link_index(i, param::kTheta0));
    c.push_back(param::link_index(i, param::kD));
    if (i > 0 && parallel_axes(model.link(i).alpha_deg)) c.push_back(param::link_index(i, param::kBeta));
  }
  return c;
}

namespace {

// The start of the further flange points, checked against the measurements that name them.
Eigen::VectorXd flange_point_start(const std::vector<PositionMeasurement>& data,
                                   const std::vector<Eigen::Vector3d>& start_mm) {
  for (std::size_t i = 0; i < data.size(); ++i)
    if (data[i].flange_point < 0 || data[i].flange_point > static_cast<int>(start_mm.size()))
      throw ArgumentError("calibration: measurement " + std::to_string(i) + " reads flange point " +
                          std::to_string(data[i].flange_point) + " but " + std::to_string(start_mm.size()) +
                          " further point(s) were given (0 is the tool point)");
  Eigen::VectorXd extra(3 * static_cast<Eigen::Index>(start_mm.size()));
  for (std::size_t k = 0; k < start_mm.size(); ++k) {
    if (!start_mm[k].allFinite())
      throw ArgumentError("calibration: flange point " + std::to_string(k + 1) + " starts at a non-finite position");
    extra.segment<3>(3 * static_cast<Eigen::Index>(k)) = start_mm[k];
  }
  return extra;
}

// The further points' coordinates go right after the tool translation (the front without one):
// kept before the link parameters, as the tool's are, so the last link's offsets that only shift
// every point together are the ones removed as redundant, never a point the data locate.
std::vector<int> with_flange_points(std::vector<int> candidates, std::size_t points) {
  auto at = candidates.begin();
  for (auto it = candidates.begin(); it != candidates.end(); ++it)
    if (*it >= param::kToolTranslation && *it < param::kToolTranslation + 3) at = it + 1;
  std::vector<int> extra;
  for (int k = 1; k <= static_cast<int>(points); ++k)
    for (int c = 0; c < 3; ++c) extra.push_back(flange_point_candidate(k, c));
  candidates.insert(at, extra.begin(), extra.end());
  return candidates;
}

}  // namespace

CalibrationResult register_tracker(const MdhModel& model, const std::vector<PositionMeasurement>& data,
                                   const CalibrationOptions& options) {
  return register_tracker(model, data, {}, options);
}

CalibrationResult register_tracker(const MdhModel& model, const std::vector<PositionMeasurement>& all,
                                   const std::vector<Eigen::Vector3d>& flange_points_start_mm,
                                   const CalibrationOptions& options) {
  const Eigen::VectorXd extra = flange_point_start(all, flange_points_start_mm);
  std::vector<PositionMeasurement> data;  // the tool point's readings: the closed-form start
  for (const PositionMeasurement& m : all)
    if (m.flange_point == 0) data.push_back(m);
  if (data.size() < 3)  // fewer than the closed-form start needs; the solver's guard names the count for more
    throw InputError("calibration: tracker registration from " + std::to_string(data.size()) +
                     " measured position(s); need at least 4 (9 parameters: base 6, reflector offset 3)");
  // Closed-form start: the rigid motion taking nominal robot-frame positions onto the measured ones.
  const MdhModel robot_frame = model.with_base(Eigen::Isometry3d::Identity());
  std::vector<Eigen::Vector3d> a(data.size()), b(data.size());
  for (std::size_t i = 0; i < data.size(); ++i) {
    a[i] = forward_position(robot_frame, data[i].q_deg);
    b[i] = data[i].measured_mm;
  }
  const Eigen::Isometry3d base = fit_rigid(a, b);
  const MdhModel start = model.with_base(base);
  std::vector<int> candidates;
  for (int k = 0; k < 6; ++k) candidates.push_back(param::kBaseTranslation + k);
  for (int k = 0; k < 3; ++k) candidates.push_back(param::kToolTranslation + k);
  PositionProblem problem(all);
  CalibrationResult r = detail::solve_calibration(problem, CalibrationState{start, extra},
                                                  with_flange_points(candidates, flange_points_start_mm.size()), options);
  // Report the base relative to the closed-form start? Users want the absolute transform; it is
  // in r.model.base(). The increments listed are relative to the closed-form start.
  return r;
}

CalibrationResult calibrate_positions(const MdhModel& model, const std::vector<PositionMeasurement>& data,
                                      const CalibrationOptions& options) {
  return calibrate_positions(model, data, {}, options);
}


CalibrationResult calibrate_positions(const MdhModel& model, const std::vector<PositionMeasurement>& data,
                                      const std::vector<Eigen::Vector3d>& flange_points_start_mm,
                                      const CalibrationOptions& options) {
  const Eigen::VectorXd extra = flange_point_start(data, flange_points_start_mm);
  PositionProblem problem(data);
  const std::vector<int> candidates = options.candidates.empty() ? default_candidates(model, true) : options.candidates;
  return detail::solve_calibration(problem, CalibrationState{model, extra},
                                   with_flange_points(candidates, flange_points_start_mm.size()), options);
}

Eigen::MatrixXd distance_identification_jacobian(const MdhModel& model, const std::vector<DistanceMeasurement>& data,
                                                const std::vector<Eigen::Vector3d>& fixed_bases_mm,
                                                const std::vector<int>& candidates) {
  const int fixed_count = static_cast<int>(fixed_bases_mm.size());
  for (int c : candidates)
    if (c < 0 || c >= param::kCount + 3 * fixed_count)
      throw ArgumentError("distance_identification_jacobian: candidate " + std::to_string(c) + " outside [0, " +
                          std::to_string(param::kCount + 3 * fixed_count) + ")");
  for (std::size_t i = 0; i < data.size(); ++i)
    if (data[i].fixed_base >= fixed_count)
      throw InputError("distance_identification_jacobian: measurement " + std::to_string(i) + " names fixed base point " +
                       std::to_string(data[i].fixed_base) + " of " + std::to_string(fixed_count));
  CalibrationState s{model, Eigen::VectorXd(3 * fixed_count)};
  for (int k = 0; k < fixed_count; ++k) s.extra.segment<3>(3 * k) = fixed_bases_mm[static_cast<std::size_t>(k)];
  Eigen::VectorXd r;
  Eigen::MatrixXd jac;
  DistanceProblem(data, fixed_count).evaluate(s, candidates, r, &jac);
  return jac;
}

CalibrationResult calibrate_distances(const MdhModel& model, const std::vector<DistanceMeasurement>& data,
                                      const CalibrationOptions& options) {
  return calibrate_distances(model, data, std::vector<Eigen::Vector3d>{}, options);
}

CalibrationResult calibrate_distances(const MdhModel& model, const std::vector<DistanceMeasurement>& data,
                                      const std::vector<Eigen::Vector3d>& fixed_bases_nominal_mm,
                                      const CalibrationOptions& options) {
  const int fixed_count = static_cast<int>(fixed_bases_nominal_mm.size());
  for (int k = 0; k < fixed_count; ++k)
    if (!fixed_bases_nominal_mm[static_cast<std::size_t>(k)].allFinite())
      throw InputError("calibrate_distances: fixed base point " + std::to_string(k) + " is not finite");
  for (std::size_t i = 0; i < data.size(); ++i)
    if (data[i].fixed_base >= fixed_count)
      throw InputError("calibrate_distances: measurement " + std::to_string(i) + " names fixed base point " +
                       std::to_string(data[i].fixed_base) + ", but " + std::to_string(fixed_count) +
                       " fixed base point(s) were given");
  std::vector<int> candidates = options.candidates.empty() ? default_candidates(model, false) : options.candidates;
  // The base is invisible to distances: drop it even if asked for, and say so.
  std::vector<int> kept;
  std::vector<RemovedParameter> dropped;
  // Fixed points first: they are what the user asked to identify, so the robot parameters that
  // duplicate them (the robot's placement in the world) are the ones reported redundant.
  for (int e = 0; e < 3 * fixed_count; ++e) kept.push_back(param::kCount + e);
  for (int c : candidates) {
    if (c >= param::kBaseTranslation && c < param::kToolTranslation)
      dropped.push_back({c, parameter_name(c), "base frame: distances are invariant under it"});
    else
      kept.push_back(c);
  }
  CalibrationState start{model, Eigen::VectorXd(3 * fixed_count)};
  for (int k = 0; k < fixed_count; ++k) start.extra.segment<3>(3 * k) = fixed_bases_nominal_mm[static_cast<std::size_t>(k)];
  DistanceProblem problem(data, fixed_count);
  CalibrationResult r = detail::solve_calibration(problem, start, kept, options);
  if (fixed_count == 0) {
    // Gauge: distances fix the model only up to a rigid motion of its world frame. Choose the one
    // that best aligns the identified model's positions with the initial model's at the measured
    // configurations, so the identified model keeps the robot's frame (compensation commands
    // targets in it). With fixed points the frame is the one the points were identified in.
    // Each measured configuration counts once: a base point shared by every pair is one pose, not
    // one per pair (it would otherwise pin the fit to itself).
    std::vector<JointVector> q;
    for (const auto& d : data) {
      q.push_back(d.q_a_deg);
      q.push_back(d.q_b_deg);
    }
    std::vector<Eigen::Vector3d> ident, init;
    for (const auto& qk : detail::distinct_configurations(q)) {
      ident.push_back(forward_position(r.model, qk));
      init.push_back(forward_position(model, qk));
    }
    r.model = r.model.with_base(fit_rigid(ident, init) * r.model.base());
  }
  r.removed.insert(r.removed.begin(), dropped.begin(), dropped.end());
  return r;
}

std::string CalibrationResult::report() const {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(4);
  s << "identified parameters (" << parameters.size() << "), increment +- 1-sigma standard error:\n";
  for (const auto& p : parameters) {
    s << "  " << p.name;
    for (std::size_t k = p.name.size(); k < 14; ++k) s << ' ';
    s << (p.increment >= 0 ? " +" : " ") << p.increment << " " << p.unit << "  +- " << p.standard_error << " "
      << p.unit;
    if (p.index < param::kBaseTranslation) s << "   (" << p.nominal << " -> " << p.nominal + p.increment << ")";
    s << "\n";
  }
  for (std::size_t k = 0; k < base_points.size(); ++k) {
    const BasePointEstimate& b = base_points[k];
    s << "fixed base point " << k << " (robot frame, mm):";
    for (int c = 0; c < 3; ++c) {
      s << "  " << "xyz"[c] << " " << b.position_mm[c];
      if (b.identified[c]) s << " +- " << b.standard_error_mm[c];
      else s << " (not identified, nominal)";
    }
    s << "   (nominal " << b.nominal_mm.x() << ", " << b.nominal_mm.y() << ", " << b.nominal_mm.z() << ")\n";
  }
  for (std::size_t k = 0; k < flange_points.size(); ++k) {
    const FlangePointEstimate& b = flange_points[k];
    s << "flange point " << k + 1 << " (flange frame, mm):";
    for (int c = 0; c < 3; ++c) {
      s << "  " << "xyz"[c] << " " << b.position_mm[c];
      if (b.identified[c]) s << " +- " << b.standard_error_mm[c];
      else s << " (not identified, start)";
    }
    s << "\n";
  }
  if (!removed.empty()) {
    s << "removed candidates (" << removed.size() << "):\n";
    for (const auto& r : removed) s << "  " << r.name << ": " << r.reason << "\n";
  }
  s.precision(1);
  s << "condition number of the identification Jacobian of the identified parameters (physically scaled: "
       "mm, and rad x reach "
    << reach_mm << " mm): " << condition_number << "\n";
  if (regularization > 0) {
    s.precision(6);
    s << "regularized toward nominal (distances): Tikhonov weight " << regularization
      << " mm^2 per physical mm^2 (0.1 x (largest singular value / max condition)^2, divided by 10 for each "
         "step an F test on the residuals asked for)\n";
  }
  s.precision(4);
  s << "residuals before: rms " << before.rms_mm << " mm, mean " << before.mean_abs_mm << " mm, max "
    << before.max_abs_mm << " mm (" << before.count << " measurements)\n";
  s << "residuals after:  rms " << after.rms_mm << " mm, mean " << after.mean_abs_mm << " mm, max " << after.max_abs_mm
    << " mm; " << rejected << " rejected by IGG3\n";
  s << "status: " << message << " (" << iterations << " LM iterations, " << rounds << " weighting rounds)\n";
  return s.str();
}

}  // namespace errfield::robot

// ---- several labelled points on the flange (flange_points.hpp) -------------------------------------

namespace errfield::robot {

LabelledFlangePoints assign_flange_points(const MdhModel& model, std::vector<PositionMeasurement>& data,
                                          const std::vector<std::string>& row_labels, const std::string& tool_label,
                                          const CalibrationOptions& options, const std::string& source) {
  if (row_labels.size() != data.size())
    throw ArgumentError("assign_flange_points: " + std::to_string(row_labels.size()) + " labels for " +
                        std::to_string(data.size()) + " readings");
  std::vector<std::string> labels;
  for (const std::string& l : row_labels)
    if (std::find(labels.begin(), labels.end(), l) == labels.end()) labels.push_back(l);
  std::vector<Eigen::Vector3d> located;
  std::vector<std::size_t> counts;
  for (const std::string& l : labels) {
    std::vector<PositionMeasurement> own;
    for (std::size_t i = 0; i < data.size(); ++i)
      if (row_labels[i] == l) own.push_back({data[i].q_deg, data[i].measured_mm, 0});
    if (own.size() < 4)
      throw InputError(source + ": reflector '" + l + "' has " + std::to_string(own.size()) +
                           " reading(s); each point on the flange needs at least 4 to be located (9 registration "
                           "parameters are shared, 3 are its own)",
                       source, 0, "reflector");
    located.push_back(register_tracker(model, own, options).model.tool().translation());
    counts.push_back(own.size());
  }
  std::size_t tool = 0;
  if (!tool_label.empty()) {
    const auto it = std::find(labels.begin(), labels.end(), tool_label);
    if (it == labels.end()) {
      std::string present;
      for (const std::string& l : labels) present += (present.empty() ? "'" : ", '") + l + "'";
      throw InputError(source + ": no reading of reflector '" + tool_label + "' (the tool point asked for); the data have " +
                           present,
                       source, 0, "reflector");
    }
    tool = static_cast<std::size_t>(it - labels.begin());
  } else {
    const Eigen::Vector3d t = model.tool().translation();
    for (std::size_t k = 1; k < labels.size(); ++k)
      if ((located[k] - t).norm() < (located[tool] - t).norm()) tool = k;
  }
  std::rotate(labels.begin(), labels.begin() + static_cast<std::ptrdiff_t>(tool), labels.begin() + static_cast<std::ptrdiff_t>(tool) + 1);
  std::rotate(located.begin(), located.begin() + static_cast<std::ptrdiff_t>(tool), located.begin() + static_cast<std::ptrdiff_t>(tool) + 1);
  std::rotate(counts.begin(), counts.begin() + static_cast<std::ptrdiff_t>(tool), counts.begin() + static_cast<std::ptrdiff_t>(tool) + 1);
  for (std::size_t i = 0; i < data.size(); ++i)
    data[i].flange_point = static_cast<int>(std::find(labels.begin(), labels.end(), row_labels[i]) - labels.begin());
  return {labels, located, counts};
}

}  // namespace errfield::robot
