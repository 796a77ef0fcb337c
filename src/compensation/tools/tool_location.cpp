#include "errfield/compensation/tools/tool_location.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"
#include "errfield/compensation/model/kriging_fields.hpp"
#include "errfield/robot/kinematics.hpp"

namespace errfield::compensation {

using namespace errfield::robot;

void ToolLocationOptions::validate() const {
  if (!(distinct_orientation_deg > 0.0 && distinct_orientation_deg < 180.0))
    throw ArgumentError("ToolLocationOptions: distinct_orientation_deg must be in (0, 180), got " +
                        format_number(distinct_orientation_deg));
  if (min_orientations < 1) throw ArgumentError("ToolLocationOptions: min_orientations must be >= 1");
  if (!(not_rigid_factor > 0.0 && std::isfinite(not_rigid_factor)))
    throw ArgumentError("ToolLocationOptions: not_rigid_factor must be finite and > 0, got " + format_number(not_rigid_factor));
}

namespace {

/// Greedy clusters of rotations: a rotation further than `limit_rad` from every cluster's first
/// member starts a new one. Counts the clusters.
std::size_t distinct_orientations(const std::vector<Eigen::Matrix3d>& r, double limit_rad) {
  std::vector<Eigen::Matrix3d> seen;
  for (const Eigen::Matrix3d& m : r) {
    bool near = false;
    for (const Eigen::Matrix3d& s : seen)
      if (Eigen::AngleAxisd(s.transpose() * m).angle() <= limit_rad) {
        near = true;
        break;
      }
    if (!near) seen.push_back(m);
  }
  return seen.size();
}

Eigen::Matrix3d skew(const Eigen::Vector3d& w) {
  Eigen::Matrix3d s;
  s << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return s;
}

std::string mm(double v) { return format_number(std::round(v * 1e4) / 1e4); }

/// The readings' residual against `at_tool` (the model with the located point as working tool and no
/// correction), kriged over the joints with the model field's correlation (ToolPointCorrection);
/// sets the RMS before and the correction's leave-one-out RMS in `out`.
/// `flange_rotation` and `at_point` (at_tool's prediction there) are per reading of `used`.
std::shared_ptr<const ToolPointCorrection> correction_at_located_point(const CompensationModel& at_tool,
                                                                       const MeasurementSet& d,
                                                                       const std::vector<std::size_t>& used,
                                                                       const std::vector<Eigen::Matrix3d>& flange_rotation,
                                                                       const std::vector<ErrorPrediction>& at_point,
                                                                       ToolLocation& out) {
  const std::optional<VariogramModel> field_model =
      at_tool.field() ? joint_space_vector_field_model(*at_tool.field()) : std::nullopt;
  if (!field_model || used.size() < kMinToolPointCorrectionReadings) return nullptr;
  const Registration& reg = *at_tool.registration();
  const MdhModel scored = at_tool.scored_model();
  std::vector<JointVector> q;
  std::vector<Eigen::Matrix3d> rotation;
  std::vector<Eigen::Vector3d> residual;
  double ss = 0.0;
  for (std::size_t k = 0; k < used.size(); ++k) {
    const std::size_t i = used[k];
    const ErrorPrediction& e = at_point[k];
    if (!e.inside_region || !e.position_error_mm.allFinite()) continue;
    q.push_back(d.q_deg[i]);
    rotation.push_back(flange_rotation[k]);
    residual.push_back(reg.robot_from_tracker * d.measured_mm[i] -
                       (forward_position(scored, d.q_deg[i]) + e.position_error_mm));
    ss += residual.back().squaredNorm();
  }
  std::optional<ToolPointCorrection> c =
      ToolPointCorrection::fit(scored.tool().translation(), q, rotation, residual, *field_model);
  if (!c) return nullptr;
  out.uncorrected_rms_mm = std::sqrt(ss / static_cast<double>(q.size()));
  double loo = 0.0;
  const std::vector<Eigen::Vector3d> held_out = c->leave_one_out_residual_mm();  // of the readings kept
  for (const Eigen::Vector3d& r : held_out) loo += r.squaredNorm();
  out.correction_leave_one_out_rms_mm = std::sqrt(loo / static_cast<double>(held_out.size()));
  return std::make_shared<const ToolPointCorrection>(std::move(*c));
}

/// A reading given twice counts twice in the location and merges into one location in the
/// correction's kriging, which then has no leave-one-out to screen or scale it by (every reading
/// given twice scored 0.082 mm held out against 0.046 mm once, issue 47). Refuses a pose (joints)
/// that repeats an earlier one, naming both.
void refuse_repeated_poses(const MeasurementSet& d) {
  std::map<std::array<double, 6>, std::size_t> seen;
  for (std::size_t i = 0; i < d.q_deg.size(); ++i) {
    std::array<double, 6> key{};
    for (int k = 0; k < 6; ++k) key[static_cast<std::size_t>(k)] = d.q_deg[i][k];
    const auto [it, fresh] = seen.emplace(key, i);
    if (!fresh)
      throw InputError(d.source + ": reading '" + d.id[i] + "' repeats the joints of reading '" + d.id[it->second] +
                           "': each reading locates the point from another pose of the flange; remove the repeated "
                           "row (or average repeated readings of one pose into one row)",
                       d.source);
  }
}

/// Leave-one-out screen of the location's readings (the 3 x 3 blocks of the least squares `a` x = `b`):
/// reading k's residual with it left out, (I - H_kk)^-1 r_k, in units of the robust sd per
/// coordinate of the kept readings' residuals; over ToolPointCorrection::kOutlierLimit it is left out
/// of the location (and so of the correction), up to ToolPointCorrection::kOutlierRounds rounds.
/// Needs kMinScreenedReadings kept readings for a robust scale. Returns the kept indices into `a`.
std::vector<std::size_t> screened_readings(const std::vector<Eigen::Matrix3d>& a, const std::vector<Eigen::Vector3d>& b) {
  std::vector<std::size_t> kept(a.size());
  for (std::size_t k = 0; k < a.size(); ++k) kept[k] = k;
  for (int round = 0; round < ToolPointCorrection::kOutlierRounds && kept.size() >= kMinScreenedReadings; ++round) {
    Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
    Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
    for (std::size_t k : kept) {
      normal += a[k].transpose() * a[k];
      rhs += a[k].transpose() * b[k];
    }
    const Eigen::LDLT<Eigen::Matrix3d> solve(normal);
    const Eigen::Vector3d x = solve.solve(rhs);
    std::vector<double> squared, loo_squared;
    for (std::size_t k : kept) {
      const Eigen::Vector3d r = a[k] * x - b[k];
      const Eigen::Matrix3d h = a[k] * solve.solve(a[k].transpose());
      squared.push_back(r.squaredNorm());
      loo_squared.push_back(((Eigen::Matrix3d::Identity() - h).inverse() * r).squaredNorm());
    }
    std::vector<double> sorted = squared;
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
    // |r|^2 / s^2 is chi-square with 3 degrees of freedom, of median 2.366.
    const double s2 = sorted[sorted.size() / 2] / 2.366;
    if (!(s2 > 0.0)) break;
    std::vector<std::size_t> next;
    for (std::size_t j = 0; j < kept.size(); ++j)
      if (std::sqrt(loo_squared[j] / (3.0 * s2)) <= ToolPointCorrection::kOutlierLimit) next.push_back(kept[j]);
    if (next.size() == kept.size() || next.size() < kMinScreenedReadings) break;
    kept = std::move(next);
  }
  return kept;
}

/// The one-sided 95 % lower quantile of chi-square with `dof` degrees of freedom (Wilson-Hilferty;
/// 1.625 against the exact 1.635 at 6): dividing a sum of squares by it bounds the variance from
/// above with 95 % confidence.
double chi_square_lower_95(double dof) {
  const double c = 2.0 / (9.0 * dof);
  const double t = 1.0 - c - 1.6449 * std::sqrt(c);
  return dof * std::max(t, 1e-3) * std::max(t, 1e-3) * std::max(t, 1e-3);
}

/// One reading's equation of the point p on the flange: a p = b (robot frame), with the flange's
/// rotation and position at the pose and the model's error there taken out of b.
struct LocationEquations {
  std::vector<Eigen::Matrix3d> a, rotations;
  std::vector<Eigen::Vector3d> b;
  std::vector<std::size_t> used;  ///< the reading (row) of each equation

  void keep(const std::vector<std::size_t>& kept) {
    LocationEquations k;
    for (std::size_t i : kept) {
      k.a.push_back(a[i]);
      k.b.push_back(b[i]);
      k.rotations.push_back(rotations[i]);
      k.used.push_back(used[i]);
    }
    *this = std::move(k);
  }
};

LocationEquations location_equations(const CompensationModel& model, const MeasurementSet& d, ToolLocation& out) {
  const Registration& reg = *model.registration();
  const MdhModel& robot = model.command_model();
  // The flange origin as the model's point: the field's correction and the functions' displacement there.
  const MdhModel flange_model = robot.with_tool(Eigen::Isometry3d::Identity());
  LocationEquations eq;
  for (std::size_t i = 0; i < d.q_deg.size(); ++i) {
    const JointVector& q = d.q_deg[i];
    const Eigen::Isometry3d flange = forward_kinematics(robot, q, EndFrame::flange);
    Eigen::Vector3d shift = Eigen::Vector3d::Zero();
    Eigen::Matrix3d turn = Eigen::Matrix3d::Identity();
    if (model.field()) {
      const ErrorPrediction e = model.predict_error_at(q, flange_model);
      if (!e.inside_region || !e.credible || !e.position_error_mm.allFinite()) {
        ++out.left_out;
        continue;
      }
      shift = e.position_error_mm;
      if (const auto& f = model.joint_error_functions()) {
        const Eigen::Matrix<double, 6, 1> dq_rad = 1e-3 * f->angle_error_mrad(q, &robot);
        turn += skew(geometric_jacobian(robot, q, EndFrame::flange).bottomRows<3>() * dq_rad);
      }
    }
    eq.a.push_back(turn * flange.linear());
    eq.b.push_back(reg.robot_from_tracker * d.measured_mm[i] - flange.translation() - shift);
    eq.rotations.push_back(flange.linear());
    eq.used.push_back(i);
  }
  return eq;
}

/// The point by least squares over the equations: its position, residuals and standard deviation
/// (in `out`); returns the residual sum of squares.
double solve_location(const LocationEquations& eq, const CompensationModel& model, ToolLocation& out) {
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < eq.a.size(); ++k) {
    normal += eq.a[k].transpose() * eq.a[k];
    rhs += eq.a[k].transpose() * eq.b[k];
  }
  const Eigen::LDLT<Eigen::Matrix3d> solve(normal);
  out.tool_mm = solve.solve(rhs);
  double ss = 0.0;
  for (std::size_t k = 0; k < eq.a.size(); ++k) {
    out.residual_mm.push_back(eq.a[k] * out.tool_mm - eq.b[k]);
    ss += out.residual_mm.back().squaredNorm();
  }
  const double n = static_cast<double>(eq.a.size());
  out.residual_rms_mm = std::sqrt(ss / n);
  // Residual variance per coordinate with 3 parameters fitted from 3n numbers.
  const double s2 = eq.a.size() > 1 ? ss / (3.0 * n - 3.0) : 0.0;
  out.sd_mm = (s2 * solve.solve(Eigen::Matrix3d::Identity())).diagonal().cwiseSqrt();
  out.lever_mm = (out.tool_mm - model.measured_point_mm()).norm();
  return ss;
}

/// What the model states at the located point, summed over the readings used.
struct StatedAtPoint {
  double variance_sum = 0.0;  ///< predictive variance (mm²)
  double stated_sum = 0.0;    ///< the same without the orientation term (mm²)
  double lever_ss = 0.0;      ///< E|w x L|² per unit rotation variance, summed (mm²)
  std::size_t count = 0;      ///< readings with a finite variance
  std::vector<ErrorPrediction> predictions;  ///< per reading used
};

StatedAtPoint stated_at_point(const CompensationModel& model, const CompensationModel& at_tool, const MeasurementSet& d,
                              const LocationEquations& eq, const ToolLocation& out) {
  const MdhModel& robot = model.command_model();
  StatedAtPoint s;
  for (std::size_t i : eq.used) {
    const ErrorPrediction& e = s.predictions.emplace_back(at_tool.predict_error(d.q_deg[i]));
    const double v = e.predictive_variance_mm2();
    if (std::isfinite(v)) {
      s.variance_sum += v;
      s.stated_sum += v - (std::isfinite(e.orientation_variance_mm2) ? e.orientation_variance_mm2 : 0.0);
      ++s.count;
    }
    const Eigen::Vector3d lever =
        forward_kinematics(robot, d.q_deg[i], EndFrame::flange).linear() * (out.tool_mm - model.measured_point_mm());
    s.lever_ss += 2.0 * lever.squaredNorm();
  }
  return s;
}

/// Along the lever no turn of the flange moves the point (w x L is perpendicular to L), so there the
/// residual is what the model states without its orientation term. The orientation term widens the
/// rigidity check enough that readings of another unit of the same robot model passed it (0.655 mm
/// held out, 0 % coverage, issue 47); along the lever they stand out.
void refuse_another_unit(const CompensationModel& model, const LocationEquations& eq, const StatedAtPoint& stated,
                         const ToolLocation& out, const ToolLocationOptions& options, const std::string& src) {
  const double n = static_cast<double>(eq.a.size());
  double along_ss = 0.0;
  for (std::size_t k = 0; k < eq.a.size(); ++k) {
    const Eigen::Vector3d u = (eq.rotations[k] * (out.tool_mm - model.measured_point_mm())).normalized();
    along_ss += std::pow(out.residual_mm[k].dot(u), 2);
  }
  const double along_rms = std::sqrt(along_ss / (n - 1.0));  // one of the n numbers spent on the point
  // Per axis: the model's stated variance there, but no less than what its own training readings
  // left per axis after the fit (the registration residual). A stated 0.005 mm, under the tracker's
  // noise, refused readings of the same SIMULATED robot that left 0.019 mm along the lever; another
  // unit left 0.655 mm.
  const double fit_rms_per_axis = model.registration() ? model.registration()->residual_rms_mm / std::sqrt(3.0) : 0.0;
  const double stated_rms = std::max(std::sqrt(stated.stated_sum / (3.0 * n)), fit_rms_per_axis);
  if (along_rms > options.not_rigid_factor * stated_rms)
    throw InputError(src + ": the " + std::to_string(out.readings) + " readings are not of this robot's flange as the "
                         "model knows it: along the lever from the model's reflector, where no turn of the flange "
                         "moves the point, they leave " + mm(along_rms) + " mm RMS, more than " +
                         format_number(options.not_rigid_factor) + " x the " + mm(stated_rms) +
                         " mm per axis the model states there (readings of another unit of the robot, another "
                         "registration, or two points mixed)",
                     src);
}

}  // namespace

ToolLocation locate_tool(const CompensationModel& model, const MeasurementSet& d, const ToolLocationOptions& options) {
  options.validate();
  const std::string& src = d.source;
  if (d.measured_mm.empty())
    throw InputError(src + ": no tracker readings (columns mx,my,mz): locate-tool needs readings of the point", src);
  if (!model.registration())
    throw InputError(src + ": the model holds no tracker registration (fit or calibrate it from data with mx,my,mz), "
                           "so readings cannot be put in the robot frame", src);
  const Registration& reg = *model.registration();
  const MdhModel& robot = model.command_model();
  refuse_repeated_poses(d);
  ToolLocation out;
  out.field_used = model.field() != nullptr;
  LocationEquations eq = location_equations(model, d, out);
  out.readings = eq.used.size();
  out.orientations = distinct_orientations(eq.rotations, options.distinct_orientation_deg * M_PI / 180.0);
  if (out.orientations < options.min_orientations)
    throw InputError(src + ": " + std::to_string(out.readings) + " reading(s)" +
                         (out.left_out ? " (" + std::to_string(out.left_out) + " more outside the model's region)" : "") +
                         " in " + std::to_string(out.orientations) + " distinct flange orientation(s) (closer than " +
                         format_number(options.distinct_orientation_deg) + " deg count as one); at least " +
                         std::to_string(options.min_orientations) +
                         " are needed to locate the point: with fewer, the model's error at those poses cannot be told "
                         "from the point's offset. Measure the point at more orientations of the flange",
                     src);
  // A gross reading (a bumped nest, a beam break) is left out of the location, not only of the
  // correction kriged after it.
  if (const std::vector<std::size_t> kept = screened_readings(eq.a, eq.b); kept.size() < eq.a.size()) {
    out.gross = eq.a.size() - kept.size();
    eq.keep(kept);
    out.readings = eq.used.size();
  }
  const double ss = solve_location(eq, model, out);
  const double n = static_cast<double>(eq.a.size());

  // What the model's own errors explain at the located point.
  Eigen::Isometry3d tool = robot.tool();
  tool.translation() = out.tool_mm;
  // An earlier located point's correction is of its readings: not this point's.
  const CompensationModel at_tool = model.with_working_tool(tool).with_tool_point_correction(nullptr);
  const StatedAtPoint stated = stated_at_point(model, at_tool, d, eq, out);
  const bool every_variance = stated.count == eq.used.size();
  // The orientation residual at this lever, as fit measures it at other points (MeasuredOrientation):
  // what the readings leave beyond the stated variance (their sum of squares taken per degree of
  // freedom: 3n numbers, 3 spent on the point), over E|w x L|^2 = 2 sigma^2 |L|^2.
  if (out.field_used && every_variance && eq.a.size() > 1 && out.lever_mm > kReflectorAtToolMm && stated.lever_ss > 0.0) {
    // From a few readings that estimate is itself uncertain (3n - 3 degrees of freedom: 6 from 3
    // readings), and the point's own location error, a constant offset in the flange frame, moves
    // every later prediction there too: their 95 % radius held 72 % of held-out readings from 3
    // readings (issue 47). So the sum of squares is taken at its one-sided 95 % upper bound, and
    // the location's variance (the trace of its covariance) is added, both read as w x L.
    const double dof = 3.0 * n - 3.0;
    const double upper_ss = ss * (3.0 * n) / chi_square_lower_95(dof);
    const double location_variance = out.sd_mm.squaredNorm() * n;  // summed over the n readings
    out.orientation = MeasuredOrientation{
        std::sqrt(std::max(0.0, upper_ss + location_variance - stated.stated_sum) / stated.lever_ss), eq.used.size(), false};
  }
  if (every_variance && stated.count > 0) {
    out.expected_rms_mm = std::sqrt(stated.variance_sum / static_cast<double>(stated.count));
    out.expected_basis = "the model's predictive variance at the point";
  } else {
    out.expected_rms_mm = reg.residual_rms_mm;
    out.expected_basis = "the model's registration residual";
  }
  if (out.field_used)
    out.correction = correction_at_located_point(at_tool, d, eq.used, eq.rotations, stated.predictions, out);
  if (out.residual_rms_mm > options.not_rigid_factor * out.expected_rms_mm)
    throw InputError(src + ": the " + std::to_string(out.readings) + " readings are not one point rigidly attached to "
                         "the flange: located at (" + mm(out.tool_mm.x()) + ", " + mm(out.tool_mm.y()) + ", " +
                         mm(out.tool_mm.z()) + ") mm they leave a residual RMS of " + mm(out.residual_rms_mm) +
                         " mm, more than " + format_number(options.not_rigid_factor) + " x the " +
                         mm(out.expected_rms_mm) + " mm that " + out.expected_basis +
                         " explains (readings of two points mixed, a moved nest, or another robot's)",
                     src);
  // (A model with fields at several points predicts the flange origin by their rigid motion, turn
  // included, so there the lever from its reflector is no longer free of the turn: one-point models.)
  // (Calibrated models only: a field alone, in task space, states its kriging variance at the reflector's
  // position whatever the wrist's orientation, and readings at 30 deg of other orientations of the same
  // SIMULATED robot left 22x that along the lever: the field's limit, not another unit.)
  const bool calibrated =
      model.method() == CompensationMethod::kinematic || model.method() == CompensationMethod::kinematic_kriging;
  if (calibrated && model.fielded_points().size() == 1 && every_variance && eq.a.size() > 1 &&
      out.lever_mm > kReflectorAtToolMm && stated.stated_sum > 0.0)
    refuse_another_unit(model, eq, stated, out, options, src);
  return out;
}

CompensationModel with_located_tool(const CompensationModel& model, const ToolLocation& t) {
  CompensationModel located = model.with_located_working_tool(model.command_model().with_tool_point(t.tool_mm).tool())
                                  .with_tool_point_correction(t.correction);
  // Calibrated models also aim it when read by a version that knows no working tool.
  const bool calibrated =
      model.method() == CompensationMethod::kinematic || model.method() == CompensationMethod::kinematic_kriging;
  if (calibrated) located = located.with_tool_point(t.tool_mm, model.reflector_mm() ? model.reflector_mm() : model.measured_point_mm());
  // The readings at the point measured the orientation residual at its lever: it replaces the guess
  // (and a smaller one measured at other points, which may not hold at this lever).
  auto effective = [](const MeasuredOrientation& m) {
    return m.add_floor ? std::hypot(m.sigma_rad, kOrientationPriorFloorRad) : m.sigma_rad;
  };
  if (t.orientation && (!model.measured_orientation() || effective(*t.orientation) > effective(*model.measured_orientation())))
    located = located.with_measured_orientation(t.orientation);
  return located;
}

}  // namespace errfield::compensation
