#include "compensation/fitting/fit_checks.hpp"

#include "errfield/compensation/model/error_fields.hpp"

#include <cmath>

#include <nlohmann/json.hpp>

#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"
#include "errfield/robot/kinematics.hpp"

namespace errfield::compensation {

using namespace errfield::robot;

namespace {

double largest_deviation(const Eigen::MatrixXd& e) {
  if (e.rows() == 0) return 0.0;
  const Eigen::RowVectorXd mean = e.colwise().mean();
  double s = 0.0;
  for (Eigen::Index i = 0; i < e.rows(); ++i) s = std::max(s, (e.row(i) - mean).norm());
  return s;
}

}  // namespace

std::string fit_problem(const FitResult& fit) {
  if (!fit.cross_validation || !fit.cross_validation->factorization || !fit.model.field()) return {};
  const KrigingReport& f = *fit.cross_validation->factorization;
  std::string problem;
  if (f.status == KrigingStatus::IllConditioned || f.jitter > 0.0)
    problem = "its kriging system is ill-conditioned (condition number " + format_number(f.condition_number) +
              (f.jitter > 0.0 ? ", jitter " + format_number(f.jitter) + " needed" : std::string()) + ")";
  {
    const double spread = largest_deviation(fitted_errors(*fit.model.field()));
    if (fit.cross_validation->max_abs_mm > 3.0 * spread)
      problem += std::string(problem.empty() ? "" : " and ") + "its leave-one-out error reaches " +
                 format_number(fit.cross_validation->max_abs_mm) + " mm where the data deviate at most " +
                 format_number(spread) + " mm from their mean (a credible prediction stays within 3x that)";
  }
  return problem;
}

FitResult check_fitted_model(FitResult fit, const FitOptions& options,
                             const std::function<FitResult(const VariogramModel&)>& refit) {
  const std::string problem = fit_problem(fit);
  if (problem.empty()) return fit;
  const VariogramModel model = *fit.cross_validation->variogram;
  if (options.model)
    throw Error("fit: the variogram model " + model.to_string() + " gives a model that cannot be trusted: " + problem +
                "; nothing was written. Give the model a larger nugget, e.g. +nug(" +
                format_number(1e-2 * model.sill()) + ")");
  std::vector<ModelComponent> structure;
  for (const auto& c : model.components())
    if (c.kind != ModelKind::Nugget) structure.push_back(c);
  std::string tried;
  for (double fraction : {1e-4, 1e-3, 1e-2, 1e-1}) {
    std::vector<ModelComponent> with = structure;
    ModelComponent nug;
    nug.kind = ModelKind::Nugget;
    nug.sill = std::max(model.nugget(), fraction * model.sill());
    with.push_back(nug);
    const VariogramModel candidate(with);
    FitResult again = refit(candidate);
    const std::string left = fit_problem(again);
    if (left.empty()) {
      again.warnings.push_back("the estimated variogram model " + model.to_string() + " was rejected: " + problem +
                               "; refitted with " + candidate.to_string() + " (nugget " + format_number(fraction) +
                               " of the sill), which passes");
      return again;
    }
    tried += (tried.empty() ? "" : "; ") + candidate.to_string() + ": " + left;
  }
  throw Error("fit: the estimated variogram model " + model.to_string() + " gives a model that cannot be trusted: " +
              problem + "; refits with a nugget did not help (" + tried +
              "); nothing was written. Try --space task|joint or another --method");
}

MdhModel nominal_at_measured_point(const CompensationModel& model, const MdhModel& nominal) {
  if (model.working_tool()) return nominal_at_working_tool(model, nominal);
  const bool calibrated =
      model.method() == CompensationMethod::kinematic || model.method() == CompensationMethod::kinematic_kriging;
  if (!calibrated || (nominal.tool().translation() - model.measured_point_mm()).norm() <= kReflectorAtToolMm) return nominal;
  return nominal.with_tool_point(model.measured_point_mm());
}

MeasurementSet readings_at_measured_point(const CsvTable& table, const CompensationModel& model,
                                          const MdhModel& nominal_robot, const std::vector<Eigen::Vector3d>& fixed_bases) {
  const MdhModel at_point = nominal_at_measured_point(model, nominal_robot);
  MeasurementSet d = MeasurementSet::from_table(table, at_point, fixed_bases);
  const bool elsewhere = !at_point.tool().isApprox(nominal_at_working_tool(model, nominal_robot).tool(), 1e-12);
  if (table.has_column("x") && elsewhere) {
    for (std::size_t i = 0; i < d.q_deg.size(); ++i) d.nominal_mm[i] = forward_position(at_point, d.q_deg[i]);
    // Base rows come first in base_nominal_mm (fixed bases are used only without them).
    for (std::size_t k = 0; k < d.base_q_deg.size(); ++k) d.base_nominal_mm[k] = forward_position(at_point, d.base_q_deg[k]);
  }
  return d;
}

FitResult attach_artifacts(FitResult fit, const MdhModel& nominal, const MeasurementSet& d) {
  CompensationModel m = fit.model.with_data_joints(d.q_deg);
  const bool kinematic =
      m.method() == CompensationMethod::kinematic || m.method() == CompensationMethod::kinematic_kriging;
  if (kinematic) m = m.with_nominal_model(nominal);
  if (!fit.registration && !d.measured_mm.empty()) {
    // The model's own prediction of the training rows: the frame its errors live in.
    std::vector<Eigen::Vector3d> tracker, predicted;
    for (std::size_t i = 0; i < d.q_deg.size(); ++i) {
      const ErrorPrediction e = m.predict_error(d.q_deg[i]);
      if (!e.inside_region) continue;
      tracker.push_back(d.measured_mm[i]);
      predicted.push_back(forward_position(m.command_model(), d.q_deg[i]) + e.position_error_mm);
    }
    if (tracker.size() >= 3) {
      fit.registration = fit_registration(tracker, predicted);
      fit.notes.push_back("registration tracker -> robot fitted on the model's predictions of " +
                          std::to_string(tracker.size()) + " training points, residual RMS " +
                          format_number(fit.registration->residual_rms_mm) + " mm (stored in the model)");
    }
  }
  if (fit.registration) {
    if (fit.registration->points == 0) fit.registration->points = d.measured_mm.size();
    m = m.with_registration(fit.registration);
  }
  // The nominal robot's own registration on the same rows (what --method none stores): validate's
  // "before" uses it, so a calibrated model's frame never flatters or spoils the baseline.
  if (d.measured_mm.size() >= 3 && d.measured_mm.size() == d.q_deg.size()) {
    std::vector<Eigen::Vector3d> fk(d.q_deg.size());
    // At the reflector the readings are of (the calibration located it when the robot JSON's tool
    // is elsewhere, e.g. 0): at the flange centre the registration would absorb a lever of 100 mm.
    const MdhModel at_reflector = nominal_at_measured_point(m, nominal);
    for (std::size_t i = 0; i < fk.size(); ++i) fk[i] = forward_position(at_reflector, d.q_deg[i]);
    m = m.with_nominal_registration(fit_registration(d.measured_mm, fk));
  }
  fit.model = std::move(m);
  return fit;
}

std::optional<std::string> implausible_joint_functions(const JointErrorFunctions::Size& size) {
  if (size.largest_mrad <= kPlausibleJointErrorMrad && size.cancelling_mrad <= kPlausibleJointErrorMrad) return std::nullopt;
  const auto mrad = [](double v) { return format_number(std::round(v * 100.0) / 100.0); };
  return "the joint error functions reach " + mrad(size.largest_mrad) + " mrad at joint " +
         std::to_string(size.largest_joint + 1) +
         (size.cancelling_mrad > kPlausibleJointErrorMrad
              ? " and cancel: at joint " + std::to_string(size.cancelling_joint + 1) + " a polynomial part of " +
                    mrad(size.cancelling_polynomial_mrad) + " mrad against a gravity-load part of " +
                    mrad(size.cancelling_gravity_mrad) + " mrad"
              : std::string()) +
         "; beyond the " + format_number(kPlausibleJointErrorMrad) +
         " mrad a joint's transmission or load plausibly errs, they fit the measured point and may move any other "
         "point on the flange. Check the robot description (D-H parameters, joint offsets, joints in degrees), and "
         "compare on held-out readings (errfield validate) with --gravity-load off or --joint-functions 0";
}

}  // namespace errfield::compensation
