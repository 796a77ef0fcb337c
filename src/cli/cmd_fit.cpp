// `errfield fit`: a compensation model from measurements (step 3 of plan → measure → fit → compensate).
#include <iostream>

#include <nlohmann/json.hpp>

#include "cli/cli_support.hpp"
#include "cli/command_registry.hpp"
#include "cli/pipeline_cli.hpp"
#include "cli/robot_cli.hpp"
#include "errfield/atomic_file.hpp"
#include "errfield/error.hpp"
#include "errfield/robot/model_fitting.hpp"

namespace errfield::cli {
namespace {

struct FitArgs {
  std::string robot, data, method = "distance-idw", space = "task", out, model, kind = "ordinary";
  std::vector<std::string> base_points;
  double power = 1.0;
  std::size_t base = 0;
};

void run_fit(const FitArgs& a) {
  using namespace robot;
  const MdhModel model = load_robot_or_default(a.robot);
  FitOptions o;
  o.method = method_from_name(a.method);
  o.space = field_space_from_name(a.space);
  o.idw_power = a.power;
  o.base = a.base;
  if (!a.model.empty() && a.model != "auto") o.model = load_variogram_model(a.model);
  if (a.kind == "universal1" || a.kind == "universal2") {
    o.kind = KrigingKind::Universal;
    o.drift_order = a.kind == "universal1" ? 1 : 2;
  } else if (a.kind != "ordinary") {
    throw ArgumentError("--kind: '" + a.kind + "'; expected ordinary, universal1 or universal2");
  }
  std::vector<Eigen::Vector3d> fixed;
  for (const auto& b : a.base_points) {
    const auto v = parse_numbers(b, 3, "--base-point");
    fixed.emplace_back(v[0], v[1], v[2]);
  }
  const CsvTable table = CsvTable::read(a.data);
  const MeasurementSet data = MeasurementSet::from_table(table, model, fixed);
  warn_if_metres(table, model, "fit");
  // Dense kriging of a few thousand points takes tens of seconds: say which stage is running.
  o.on_stage = StageLog("fit", data.q_deg.size() >= 1000);
  const FitResult r = with_source(a.data, [&] { return fit_compensation_model(model, data, o); });
  write_file_atomically(a.out, r.model.to_json().dump(1) + "\n");
  std::cout << "fit: method " << a.method << " on " << data.q_deg.size() << " points of " << a.data << "\n";
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
  std::cout << "  model written to " << a.out << "\n";
  for (const auto& w : r.warnings) std::cerr << "errfield fit: warning: " << w << "\n";
}

void add_fit_command(CLI::App& app) {
  auto a = std::make_shared<FitArgs>();
  auto* cmd = app.add_subcommand(
      "fit",
      "Build a compensation model from measurements (the columns of 'errfield simulate': point, kind,\n"
      "q1..q6, x,y,z, mx,my,mz, dist_b0..). Methods: distance-idw (the paper's: 8-vertex IDW of distance\n"
      "errors on a complete grid, radial correction), position-idw (IDW of registered 3-D position errors),\n"
      "distance-kriging, vector-kriging (3-D errors from >= 3 base points' distances, else from positions),\n"
      "kinematic and kinematic+kriging (kinematic calibration on the distances to a base row, or to every\n"
      "--base-point, whose coordinates are then identified too). Prints a leave-one-out\n"
      "summary. Kriging models follow gstat's vgm: range is the scale parameter a.\n"
      "Example: errfield fit --data grid.csv --method distance-idw --out model.json");
  cmd->add_option("--robot", a->robot, "nominal robot JSON (default: built-in ER20-C10, no tool)");
  cmd->add_option("--data", a->data, "measurement CSV")->required();
  cmd->add_option("--method", a->method, "distance-idw | position-idw | distance-kriging | vector-kriging | kinematic | kinematic+kriging")
      ->capture_default_str();
  cmd->add_option("--space", a->space, "kriging in task (nominal positions, mm) or joint (deg) space")->capture_default_str();
  cmd->add_option("--power", a->power, "IDW power p (the paper: 1)")->capture_default_str();
  cmd->add_option("--model", a->model,
                  "kriging variogram model, e.g. \"gau(sill=0.05,range=400)+nug(0.001)\", or a model JSON file "
                  "(fit-variogram --out); default (auto): in joint space the REML fit of sph/exp/gau/mat(1.5,2.5) "
                  "+ nugget, isotropic or ARD, with the smallest AIC among well-conditioned ones; in task space the "
                  "best weighted fit to the empirical variogram");
  cmd->add_option("--kind", a->kind,
                  "kriging methods: ordinary (default), universal1 or universal2 (linear / quadratic drift in the "
                  "field's coordinates)")
      ->capture_default_str();
  cmd->add_option("--base", a->base, "index K of the base point whose distances dist_bK the distance methods use")
      ->capture_default_str();
  cmd->add_option("--base-point", a->base_points, "X,Y,Z of base point b0, b1, ... when the data have no base rows (fixed points)");
  cmd->add_option("--out", a->out, "model JSON (written atomically)")->required();
  cmd->callback([a] { run_fit(*a); });
}

Registration reg{"fit", 71, &add_fit_command};

}  // namespace
}  // namespace errfield::cli
