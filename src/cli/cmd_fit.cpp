// `errfield fit`: a compensation model from measurements (step 3 of plan → measure → fit → compensate).
#include <cmath>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>

#include <nlohmann/json.hpp>

#include "cli/cli_support.hpp"
#include "cli/command_registry.hpp"
#include "cli/pipeline_cli.hpp"
#include "cli/robot_cli.hpp"
#include "errfield/atomic_file.hpp"
#include "errfield/error.hpp"
#include "errfield/compensation/model/kriging_fields.hpp"
#include "errfield/compensation/tools/probe_readings.hpp"
#include "errfield/compensation/fitting/model_fitting.hpp"
#include "errfield/compensation/pipeline.hpp"
#include "errfield/robot/input_checks.hpp"

namespace errfield::cli {
namespace {

std::string default_prior_text() {
  const compensation::JointFunctionPrior p;
  return format_number(p.polynomial_sd_mrad) + "," + format_number(p.gravity_sd_mrad);
}

/// "off", "SD" (both groups) or "POLY_SD,GRAVITY_SD" (mrad, > 0; "inf" leaves a group to the ridge).
compensation::JointFunctionPrior parse_joint_function_prior(const std::string& text) {
  compensation::JointFunctionPrior p;
  if (text == "off") {
    p.polynomial_sd_mrad = p.gravity_sd_mrad = std::numeric_limits<double>::infinity();
    return p;
  }
  std::vector<double> v;
  std::size_t start = 0;
  while (start <= text.size() && v.size() < 3) {
    const std::size_t comma = std::min(text.find(',', start), text.size());
    const std::string item = text.substr(start, comma - start);
    std::size_t used = 0;
    double x = NAN;
    try {
      x = item == "inf" ? std::numeric_limits<double>::infinity() : std::stod(item, &used);
      if (item == "inf") used = item.size();
    } catch (const std::exception&) {
      used = 0;
    }
    if (item.empty() || used != item.size() || std::isnan(x))
      throw ArgumentError("--joint-function-prior '" + text + "': '" + item + "' is not a number (mrad) or inf");
    v.push_back(x);
    start = comma + 1;
  }
  if (v.empty() || v.size() > 2)
    throw ArgumentError("--joint-function-prior '" + text + "': expected off, SD or POLY_SD,GRAVITY_SD (mrad)");
  p.polynomial_sd_mrad = v[0];
  p.gravity_sd_mrad = v.size() > 1 ? v[1] : v[0];
  for (double sd : {p.polynomial_sd_mrad, p.gravity_sd_mrad})
    if (!(sd > 0.0))
      throw ArgumentError("--joint-function-prior '" + text + "': a prior sd must be > 0 mrad (inf: no prior for that group)");
  return p;
}

// The work of a fit with a kriging field grows faster than its readings: the default fit's CPU was
// 4.75 s at 687 poses and 146 s at 5,000 (docs/benchmarks.md, "Model choice of the robot fit"), about
// N^1.7. Beyond kLongFitReadings the fit says so before it starts; beyond --max-fit-readings it is
// refused (exit 3) before any work, with the estimate (docs/robot.md, "How long a fit takes").
constexpr std::size_t kLongFitReadings = 2000;
// The gross-outlier screen fits again after each of up to three rounds that leave readings out: four
// fits in all (real UR10 series A, 3,000 poses: 295 s of CPU in four, 10 readings left out).
constexpr int kMostFitsOfTheOutlierScreen = 4;
constexpr std::size_t kDefaultMaxFitReadings = 20000;

double estimated_fit_cpu_seconds(std::size_t readings) {
  return 146.0 * std::pow(static_cast<double>(readings) / 5000.0, 1.7);
}

std::string cpu_time_text(double seconds) {
  if (seconds < 120.0) return format_number(std::round(seconds)) + " s";
  if (seconds < 7200.0) return format_number(std::round(seconds / 60.0)) + " min";
  return format_number(std::round(seconds / 360.0) / 10.0) + " h";
}

/// The budget of a fit with a kriging field (see kLongFitReadings): the count of readings is known
/// up front, the minutes are not, so the count is what is limited.
void check_fit_budget(const std::string& method, const CsvTable& table, const std::string& data, std::size_t max_readings) {
  // auto fits a field when the data have tracker positions (kinematic+kriging), else none.
  const bool field = method.find("kriging") != std::string::npos || (method == "auto" && table.has_column("mx"));
  const std::size_t n = table.row_count();
  if (!field || (n <= kLongFitReadings && n <= max_readings)) return;
  const std::string what = std::to_string(n) + " readings in " + data +
                           (table.has_column("reflector") ? " (a probe row or pose counts once per point on the flange)" : "");
  const double per_fit = estimated_fit_cpu_seconds(n);
  const std::string estimate = "roughly " + cpu_time_text(per_fit) +
                               " of CPU for the kriging field's model choice and fit at this size (146 s measured at 5,000 "
                               "poses, growing as about N^1.7), and up to " + std::to_string(kMostFitsOfTheOutlierScreen) +
                               " fits in all (~" + cpu_time_text(kMostFitsOfTheOutlierScreen * per_fit) +
                               ") when the gross-outlier screen leaves readings out (docs/robot.md, \"How long a fit takes\")";
  if (n > max_readings)
    throw ResourceError("fit: " + what + ", more than --max-fit-readings " + std::to_string(max_readings) + ": " + estimate +
                        ". Fit a subset of the poses (the field's accuracy levels off long before: docs/robot.md), a "
                        "method without a field (--method kinematic), or raise --max-fit-readings");
  std::cerr << "errfield fit: note: " << what << ": " << estimate << "; stderr says which stage runs\n";
}

struct FitArgs {
  std::string robot, data, method = "auto", space = "auto", out, model, calibration, robust, kind = "ordinary",
      variance_calibration = "auto";
  double max_condition = 1e3, outlier_limit = 5.0;
  std::vector<std::string> base_points;
  double power = 1.0, max_registration_rms = robot::kRegistrationRmsLimitMm;
  std::optional<double> region_margin;
  std::size_t base = 0;
  bool reflector_far_ok = false;
  std::string tool_reflector;
  std::string joint_functions = "auto";
  std::string gravity_load = compensation::FitOptions{}.gravity_load ? "on" : "off";
  std::string joint_function_prior = default_prior_text();
  double gls_guard = compensation::FitOptions{}.gls_guard_ratio;
  std::size_t max_fit_readings = kDefaultMaxFitReadings;
};

/// --joint-functions: 'auto' (the degree from the number of poses) or a degree 0..20.
int joint_function_degree_of(const std::string& text) {
  if (text == "auto") return compensation::kJointFunctionDegreeByPoses;
  std::size_t used = 0;
  int degree = -1;
  try {
    degree = std::stoi(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || text.empty() || degree < 0 || degree > 20)
    throw ArgumentError("--joint-functions: '" + text + "'; expected auto or a degree 0 (none) to 20");
  return degree;
}

void run_fit(const FitArgs& a) {
  using namespace robot;
  using namespace compensation;
  const MdhModel model = load_robot_or_default(a.robot);
  FitOptions o = fit_options_from_text({a.method, a.space, a.power, a.model, a.kind, a.base, a.region_margin,
                                              a.calibration, a.robust, a.max_condition, a.outlier_limit,
                                              a.variance_calibration});
  o.joint_function_degree = joint_function_degree_of(a.joint_functions);
  o.gravity_load = a.gravity_load == "on";
  o.joint_function_prior = parse_joint_function_prior(a.joint_function_prior);
  o.gls_guard_ratio = a.gls_guard;
  std::vector<Eigen::Vector3d> fixed;
  for (const auto& b : a.base_points) {
    const auto v = parse_numbers(b, 3, "--base-point");
    fixed.emplace_back(v[0], v[1], v[2]);
  }
  // A 6-DoF probe's rows become three points on the flange (probe_readings.hpp).
  const CsvTable table = compensation::expand_probe_readings(CsvTable::read(a.data));
  check_fit_budget(a.method, table, a.data, a.max_fit_readings);
  FitTableOptions fo;
  fo.fit = o;
  fo.fit.reflector_far_ok = a.reflector_far_ok;
  fo.fit.tool_reflector = a.tool_reflector;
  fo.fixed_bases = fixed;
  fo.robot_given = !a.robot.empty();
  fo.max_registration_rms_mm = a.max_registration_rms;
  // Dense kriging of a few thousand points takes tens of seconds: say which stage is running.
  fo.fit.on_stage = StageLog("fit", table.row_count() >= 1000);
  fo.on_measurements_read = [&] { warn_if_metres(table, model, "fit"); };
  const TableFit fit = with_source(a.data, [&] { return fit_table(model, table, fo); });
  const FitResult& r = fit.result;
  std::cout << "fit: method " << method_name(r.model.method()) << " on " << fit.points << " points of " << a.data << "\n";
  if (r.model.field()) std::cout << "  field: " << r.model.field()->describe() << "\n";
  for (const auto& n : r.notes) std::cout << "  " << n << "\n";
  if (r.cross_validation) {
    const auto& cv = *r.cross_validation;
    std::cout << "  cross-validation (" << cv.method << "), " << cv.samples << " points:\n"
              << "    mean |e| " << cv.mean_abs_mm << " mm, RMS " << cv.rms_mm << " mm, max |e| " << cv.max_abs_mm
              << " mm";
    if (cv.mean_squared_z) std::cout << ", mean z^2 " << *cv.mean_squared_z << " (~1 when the variance is right)";
    std::cout << "\n";
  }
  if (r.registration)
    std::cout << "  registration tracker -> robot stored in the model (residual RMS "
              << format_number(r.registration->residual_rms_mm) << " mm on " << r.registration->points << " points)\n";
  std::cout << "  model written to " << a.out << "\n";
  require_standard_output();  // before the write: a run that fails leaves the previous model
  write_file_atomically(a.out, r.model.to_json().dump(1) + "\n");
  for (const auto& w : r.warnings) std::cerr << "errfield fit: warning: " << w << "\n";
}

void add_fit_method_options(CLI::App* cmd, const std::shared_ptr<FitArgs>& a) {
  cmd->add_option("--robot", a->robot,
                  "nominal robot JSON or built-in name (er20-c10, kr16, ur5e, ur5, ur10); default: built-in ER20-C10, no tool. "
                  "x,y,z that are not its FK (within 5 mm) are refused with the likely cause");
  cmd->add_option("--data", a->data, "measurement CSV")->required();
  cmd->add_option("--method", a->method, "auto | distance-idw | position-idw | distance-kriging | vector-kriging | kinematic | kinematic+kriging; "
                  "auto: kinematic+kriging when the data have mx,my,mz, else kinematic (from distances)")
      ->capture_default_str();
  cmd->add_option("--space", a->space, "kriging methods: the field's coordinates, task (nominal positions, mm) or joint (deg); auto = joint, "
                  "more accurate on every held-out set in docs/robot.md")->capture_default_str();
  cmd->add_option("--power", a->power, "IDW power p (the paper: 1)")->capture_default_str();
  cmd->add_option("--model", a->model,
                  "kriging variogram model, e.g. \"gau(sill=0.05,range=400)+nug(0.001)\", or a model JSON file "
                  "(fit-variogram --out), or a family whose parameters are estimated: sph, exp, gau, mat, "
                  "mat(2.5), wen, with @iso or @ard to fix the anisotropy; default (auto): the REML fit of "
                  "sph/exp/gau/mat(1.5,2.5) + nugget, isotropic or ARD (over q1..q6 in joint space, x,y,z in task "
                  "space), with the smallest AIC among well-conditioned ones (ranked on up to " +
                      std::to_string(compensation::kFieldChoiceSubsample) + " points, the best " +
                      std::to_string(compensation::kFieldChoiceConfirmed) +
                      " refitted on all; beyond 3000 points by the Vecchia likelihood)");
  cmd->add_option("--kind", a->kind,
                  "kriging methods: ordinary (default), universal1 or universal2 (linear / quadratic drift in the "
                  "field's coordinates)")
      ->capture_default_str();
}

void add_base_and_limit_options(CLI::App* cmd, const std::shared_ptr<FitArgs>& a) {
  cmd->add_option("--base", a->base, "index K of the base point whose distances dist_bK the distance methods use")
      ->check(kUnsignedInteger)
      ->capture_default_str();
  cmd->add_option("--base-point", a->base_points, "X,Y,Z of base point b0, b1, ... when the data have no base rows (fixed points)");
  cmd->add_option("--max-fit-readings", a->max_fit_readings,
                  "methods with a kriging field (auto included): refuse (exit 3, before any work) data of more readings "
                  "than this (a probe row or pose counts once per point on the flange); the field's CPU time grows as "
                  "about N^1.7, 146 s at 5,000 poses, per fit (the gross-outlier screen may fit up to four times; "
                  "docs/robot.md, 'How long a fit takes'); above " +
                      std::to_string(kLongFitReadings) + " readings fit says its estimate before it starts")
      ->check(kUnsignedInteger)
      ->capture_default_str();
  cmd->add_option("--max-registration-rms", a->max_registration_rms,
                  "refuse (exit 2) when the tracker -> robot registration leaves a larger RMS (mm): a tool/reflector "
                  "offset missing from --robot, a wrong robot (docs/robot.md)")
      ->capture_default_str();
  cmd->add_option("--region-margin", a->region_margin,
                  "kriging: predict this far beyond the samples' box (mm in task space, deg per joint in joint space); "
                  "default 5 deg in joint space (measured, docs/robot.md), 0 mm in task space")
      ->check(CLI::NonNegativeNumber);
}

void add_calibration_options(CLI::App* cmd, const std::shared_ptr<FitArgs>& a) {
  cmd->add_option("--calibration", a->calibration,
                  "kinematic methods: calibrate from 'position' (tracker positions mx,my,mz; the default when the "
                  "data have them) or 'distance' (dist_bK to a base point)");
  cmd->add_option("--robust", a->robust,
                  "kinematic methods: 'none' (plain least squares, the default) or 'igg3' (IGG3 reweighting against "
                  "gross outliers); docs/robot.md says which data decided the default");
  cmd->add_option("--max-condition", a->max_condition,
                  "kinematic methods: remove weakly identifiable parameters until the physically scaled Jacobian's "
                  "condition number is below this (from positions); from distances, regularize directions weaker "
                  "than largest/this toward nominal")
      ->capture_default_str();
  cmd->add_option("--outlier-limit", a->outlier_limit,
                  "kinematic methods from positions: refit without gross outliers (a lost reflector, a wrong row; all "
                  "listed in a warning and the model file): a row is dropped whose reading is beyond this many robust "
                  "sigmas from what its neighbours in the kinematic+kriging field predict (leave-one-out against the "
                  "predictive sigma, nugget included), so rows where the robot departs smoothly from its kinematic "
                  "model are kept; --method kinematic judges with a joint-space field fitted to the same rows when "
                  "--model gives its variogram, and screens nothing without; 0 keeps every row; "
                  "docs/robot.md says which data decided the default")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--variance-calibration", a->variance_calibration,
                  "kriging methods: auto (when the variogram is estimated, not given by --model), loo or none: scale "
                  "the variogram's sill and nugget so that on the training data's leave-one-out the mean z^2 is at "
                  "most 1 and at least 95 % fall in the 95 % region; the predicted errors are unchanged, var_mm2 "
                  "and r95_mm hold on held-out readings (docs/robot.md, 'Predictive uncertainty'); stored in the "
                  "model file")
      ->capture_default_str();
}

void add_joint_function_options(CLI::App* cmd, const std::shared_ptr<FitArgs>& a) {
  cmd->add_option("--joint-functions", a->joint_functions,
                  "kinematic+kriging: DEGREE of per-joint angle-error functions (Legendre polynomials of each joint's "
                  "angle over its measured range, no constant: that is the joint offset) fitted to the calibration's "
                  "residuals before the field krigs what they leave; they model errors that depend on one joint's "
                  "angle (growing toward the end of its travel, gear transmission, gain), which the kinematic model "
                  "cannot express and the field learns only near its samples; 0 = none; auto = " +
                      std::to_string(compensation::kJointFunctionDegreeManyPoses) + " from " +
                      std::to_string(compensation::kJointFunctionManyPoses) + " poses, else " +
                      std::to_string(compensation::kJointFunctionDegreeFewPoses) +
                      " (real robots' joint errors vary faster than the simulator's; docs/robot.md and "
                      "docs/realdata.md say which data decided)")
      ->capture_default_str();
  cmd->add_option("--gravity-load", a->gravity_load,
                  "kinematic+kriging with --joint-functions: on also fits each joint's deflection under the weight of "
                  "the arm beyond it (a coefficient per joint and loaded point: the frame origins beyond the joint and "
                  "the tool point, times its gravity lever about the joint's axis, gravity along -z of the robot's "
                  "world frame: a robot on a wall or ceiling needs that rotation in its JSON's base), which depends on "
                  "several joints at once, so no function of one angle expresses it; "
                  "off = the one-joint functions only; docs/robot.md says which data decided the default")
      ->check(CLI::IsMember({"on", "off"}))
      ->capture_default_str();
  cmd->add_option("--joint-function-prior", a->joint_function_prior,
                  "kinematic+kriging with --joint-functions: POLY_SD[,GRAVITY_SD] (mrad), the physical prior's "
                  "standard deviation of each Legendre coefficient and of each gravity term (its RMS deflection), or "
                  "off: fitted freely, combinations of angle errors that barely move the measured point (they turn the "
                  "flange about it) grow to tens of mrad and move every other point on the flange; docs/robot.md "
                  "('Tool points and orientation') says which data decided the default")
      ->capture_default_str();
  cmd->add_option("--gls-guard", a->gls_guard,
                  "kinematic+kriging with --joint-functions: RATIO; the functions are refitted by generalized least "
                  "squares under the field's covariance, and a positive RATIO drops that refit when it leaves the "
                  "field more than RATIO x the ordinary fit's RMS; 0 (default) always keeps it; docs/realdata.md says "
                  "which data decided the default")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
}

void add_reflector_and_output_options(CLI::App* cmd, const std::shared_ptr<FitArgs>& a) {
  cmd->add_flag("--reflector-far-ok", a->reflector_far_ok,
                "kinematic methods from positions: accept a reflector found more than 50 mm from --robot's tool "
                "point (a second nest, a tool-less robot JSON on purpose); compensate still aims the tool point "
                "(docs/robot.md)");
  cmd->add_option("--tool-reflector", a->tool_reflector,
                  "data with a 'reflector' column (several points on the flange, e.g. simulate --reflectors): the "
                  "label whose readings are the model's own point (the joint error functions and the field are "
                  "fitted to them; the others are located and determine the flange's orientation in the "
                  "calibration). Default: the label the data locate nearest --robot's tool point");
  cmd->add_option("--out", a->out, "model JSON (written atomically)")->required();
}

void add_fit_command(CLI::App& app) {
  auto a = std::make_shared<FitArgs>();
  auto* cmd = app.add_subcommand(
      "fit",
      "Build a compensation model from measurements (the columns of 'errfield simulate': point, kind,\n"
      "q1..q6, x,y,z, mx,my,mz, dist_b0..). Methods: distance-idw (the paper's: 8-vertex IDW of distance\n"
      "errors on a complete grid, radial correction), position-idw (IDW of registered 3-D position errors),\n"
      "distance-kriging, vector-kriging (3-D errors from >= 3 base points' distances, else from positions),\n"
      "kinematic and kinematic+kriging (kinematic calibration from the tracker positions mx,my,mz when the\n"
      "data have them: registration with the reflector offset, then the model; or from the distances to a\n"
      "base row, or to every --base-point, whose coordinates are then identified too). Prints a leave-one-out\n"
      "summary. Kriging models follow gstat's vgm: range is the scale parameter a.\n"
      "Default (auto): kinematic+kriging in joint space when the data have tracker positions, kinematic from\n"
      "distances otherwise: the most accurate on held-out points of the data in docs/robot.md.\n"
      "Example: errfield fit --robot robot.json --data measured.csv --out model.json\n"
      "Example: errfield fit --robot robot.json --data grid.csv --method distance-idw --out model.json   # the paper's method");
  add_fit_method_options(cmd, a);
  add_base_and_limit_options(cmd, a);
  add_calibration_options(cmd, a);
  add_joint_function_options(cmd, a);
  add_reflector_and_output_options(cmd, a);
  cmd->callback([a] { run_fit(*a); });
}

Registration register_fit{"fit", 71, &add_fit_command};

}  // namespace
}  // namespace errfield::cli
