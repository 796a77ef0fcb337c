// `errfield plan`: the measurement plan (step 1 of plan → measure → fit → compensate).
#include <iostream>

#include "cli/cli_support.hpp"
#include "cli/command_registry.hpp"
#include "cli/pipeline_cli.hpp"
#include "cli/robot_cli.hpp"
#include "errfield/empirical_variogram.hpp"
#include "errfield/error.hpp"
#include "errfield/robot/cube_budget.hpp"
#include "errfield/compensation/measurement_plan.hpp"
#include "errfield/robot/pose.hpp"
#include "errfield/variogram_fit.hpp"

namespace errfield::cli {
namespace {

struct PlanArgs {
  std::string robot, cube, step = "125", orientation = "180,0,0", out, samples_out, variogram, variogram_model;
  std::vector<std::string> bases;
  double gamma_max = 0.01;
  std::uint64_t seed = 1;
};

/// Best of sph/exp/gau/pow (free nugget, N_j weights) fitted to an `errfield variogram` CSV.
VariogramModel model_from_variogram_csv(const std::string& path) {
  const CsvTable t = CsvTable::read(path);
  std::vector<double> lag, gamma;
  std::vector<std::uint64_t> pairs;
  const auto p = t.numeric_column("pairs");
  const std::size_t lag_col = t.column_index("lag_mean"), gamma_col = t.column_index("gamma");
  for (std::size_t r = 0; r < t.row_count(); ++r) {
    if (p[r] <= 0) continue;  // empty bins have empty lag_mean/gamma cells
    lag.push_back(std::stod(t.row(r)[lag_col]));
    gamma.push_back(std::stod(t.row(r)[gamma_col]));
    pairs.push_back(static_cast<std::uint64_t>(p[r]));
  }
  VariogramFitOptions fo;
  fo.weighting = FitWeighting::Nj;
  VariogramModel best;
  double best_sse = INFINITY;
  for (ModelKind kind : {ModelKind::Spherical, ModelKind::Exponential, ModelKind::Gaussian, ModelKind::Power}) {
    ModelComponent c;
    c.kind = kind;
    const auto fit = fit_variogram(lag, gamma, pairs, {c}, fo);
    if (fit.status != FitStatus::Failed && fit.weighted_sse < best_sse) best = fit.model, best_sse = fit.weighted_sse;
  }
  if (!std::isfinite(best_sse)) throw InputError(path + ": could not fit a variogram model to its bins", path);
  return best;
}

void run_plan(const PlanArgs& a) {
  refuse_same_output({{"--out", &a.out}, {"--samples-out", &a.samples_out}});
  using namespace robot;
  using namespace compensation;
  const MdhModel robot = load_robot_or_default(a.robot);
  PlanOptions o;
  const auto cube = parse_numbers(a.cube, 4, "--cube");
  o.min_corner_mm = Eigen::Vector3d(cube[0], cube[1], cube[2]);
  o.size_mm = cube[3];
  const auto rpy = parse_numbers(a.orientation, 3, "--orientation");
  o.orientation = rotation_from_rpy_deg(rpy[0], rpy[1], rpy[2]);
  for (const auto& b : a.bases) {
    const auto v = parse_numbers(b, 3, "--base-point");
    o.base_points_mm.emplace_back(v[0], v[1], v[2]);
  }
  o.sample_per_cell = !a.samples_out.empty();
  o.seed = a.seed;
  if (a.step == "auto") {
    if (a.variogram.empty() == a.variogram_model.empty())
      throw ArgumentError("--step auto needs exactly one of --variogram CSV or --variogram-model TEXT (lags in mm)");
    const VariogramModel m = a.variogram_model.empty() ? model_from_variogram_csv(a.variogram)
                                                       : load_variogram_model(a.variogram_model);
    if (!m.anisotropy().isotropic())
      throw ArgumentError("--variogram-model: the step recommendation uses one range; '" + m.to_string() +
                          "' is anisotropic (give an isotropic model)");
    StepRecommendation rec;
    naming_options([&] { rec = recommend_grid_step(m, o.size_mm, a.gamma_max); },
                   {{"recommend_grid_step: gamma_max", "--gamma-max"}});
    std::cout << "plan: variogram model " << m.to_string() << "\n  recommended " << rec.reason << "\n";
    o.step_mm = rec.step_mm;
  } else {
    o.step_mm = parse_numbers(a.step, 1, "--step")[0];
  }
  check_cube_budget(o.size_mm, o.step_mm, o.sample_per_cell, "--step");
  std::vector<PlannedPoint> points;
  naming_options([&] { points = plan_measurements(robot, o); },
                 {{"plan: step", "--step"}, {"plan: cube size", "--cube SIZE"}, {"plan: cube corner", "--cube corner"}});
  auto table = [&](const std::vector<const PlannedPoint*>& rows) {
    OutputTable t;
    std::vector<std::string> id, kind;
    std::vector<std::vector<double>> v(12);
    for (const auto* p : rows) {
      id.push_back(p->id);
      kind.push_back(p->kind);
      for (int k = 0; k < 3; ++k) v[static_cast<std::size_t>(k)].push_back(p->position_mm[k]);
      for (int k = 0; k < 3; ++k) v[static_cast<std::size_t>(3 + k)].push_back(rpy[static_cast<std::size_t>(k)]);
      for (int k = 0; k < 6; ++k) v[static_cast<std::size_t>(6 + k)].push_back(p->q_deg[k]);
    }
    t.add_column("point", id);
    t.add_column("kind", kind);
    const char* names[] = {"x", "y", "z", "rx", "ry", "rz", "q1", "q2", "q3", "q4", "q5", "q6"};
    for (std::size_t c = 0; c < 12; ++c) t.add_numeric_column(names[c], v[c]);
    return t.to_csv();
  };
  std::vector<const PlannedPoint*> main_rows, sample_rows;
  for (const auto& p : points) (p.kind == "sample" ? sample_rows : main_rows).push_back(&p);
  AtomicFileSet outputs;  // --out and --samples-out all or none
  outputs.add(a.out, table(main_rows));
  if (!a.samples_out.empty()) outputs.add(a.samples_out, table(sample_rows));
  outputs.commit();
  std::size_t grid = 0, bases = 0;
  for (const auto* p : main_rows) (p->kind == "grid" ? grid : bases)++;
  std::cout << "plan: " << grid << " grid points (step " << o.step_mm << " mm) and " << bases
            << " base point(s), all reachable at the orientation; written to " << a.out << "\n";
  if (!a.samples_out.empty())
    std::cout << "  " << sample_rows.size() << " validation samples (one per cell) written to " << a.samples_out << "\n";
}

void add_plan_command(CLI::App& app) {
  auto a = std::make_shared<PlanArgs>();
  auto* cmd = app.add_subcommand(
      "plan",
      "Measurement plan: grid points of a cube at a constant tool orientation with their IK joints, the\n"
      "base point(s) (kind=base rows first), optionally one random validation sample per cell. Refuses\n"
      "unreachable points with a list. --step auto recommends a step from a variogram: the largest step\n"
      "dividing the cube whose cell diagonal keeps gamma <= --gamma-max (the paper's reasoning).\n"
      "Example: errfield plan --robot robot.json --cube 750,-250,350,500 --step 125 --orientation 180,0,0 \\\n"
      "           --base-point 750,-250,350 --out plan.csv --samples-out samples.csv");
  cmd->add_option("--robot", a->robot, "robot JSON or built-in name (er20-c10, kr16, ur5e; default: built-in ER20-C10, no tool)");
  cmd->add_option("--cube", a->cube, "X0,Y0,Z0,SIZE: lower corner and side (mm)")->required();
  cmd->add_option("--step", a->step, "grid step (mm, divides SIZE) or auto")->capture_default_str();
  cmd->add_option("--orientation", a->orientation, "RX,RY,RZ tool orientation (deg, fixed axes XYZ)")->capture_default_str();
  cmd->add_option("--base-point", a->bases, "X,Y,Z of a base point (robot position, mm), repeatable");
  cmd->add_option("--variogram", a->variogram, "--step auto: CSV of 'errfield variogram' (task-space lags, mm)");
  cmd->add_option("--variogram-model", a->variogram_model, "--step auto: model text, e.g. \"gau(sill=0.5,range=900)\"");
  cmd->add_option("--gamma-max", a->gamma_max, "--step auto: largest semivariance allowed at the cell diagonal (mm²)")
      ->capture_default_str();
  cmd->add_option("--samples-out", a->samples_out, "also write one random validation point per cell here");
  cmd->add_option("--seed", a->seed, "seed of the validation samples")->check(kUnsignedInteger)->capture_default_str();
  cmd->add_option("--out", a->out, "plan CSV: point,kind,x,y,z,rx,ry,rz,q1..q6 (written atomically)")->required();
  cmd->callback([a] { run_plan(*a); });
}

Registration register_plan{"plan", 70, &add_plan_command};

}  // namespace
}  // namespace errfield::cli
