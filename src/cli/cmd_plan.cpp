// `errfield plan`: the measurement plan (step 1 of plan → measure → fit → compensate).
#include <iostream>
#include <optional>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "cli/cli_support.hpp"
#include "cli/command_registry.hpp"
#include "cli/interpolation_methods.hpp"
#include "cli/pipeline_cli.hpp"
#include "cli/robot_cli.hpp"
#include "errfield/empirical_variogram.hpp"
#include "errfield/error.hpp"
#include "errfield/robot/cube_budget.hpp"
#include "errfield/compensation/planning/measurement_plan.hpp"
#include "errfield/compensation/pipeline.hpp"
#include "errfield/compensation/planning/pose_selection.hpp"
#include "errfield/json_file.hpp"
#include "errfield/robot/input_checks.hpp"
#include "errfield/robot/pose.hpp"
#include "errfield/variogram_fit.hpp"

namespace errfield::cli {
namespace {

struct PlanArgs {
  std::string robot, cube, step = "125", orientation = "180,0,0", out, samples_out, variogram, variogram_model;
  std::vector<std::string> bases;
  double gamma_max = 0.01;
  std::uint64_t seed = 1;
  // Choosing from a pool of candidate poses (issue 21).
  std::string candidates, model, data, summary_out;
  std::size_t count = 0;
  double target_rms = 0.0;
  std::string local_scale = "on";
  double spacing_floor = 0.7;
};

std::string three_digits(double v) {
  std::ostringstream s;
  s.precision(3);
  s << v;
  return s.str();
}

// Grid options refused, and --count and --target-rms checked, before anything is read.
void check_candidate_options(const PlanArgs& a, CLI::App* cmd) {
  for (const char* grid_only : {"--cube", "--base-point", "--samples-out", "--variogram", "--variogram-model"})
    if (cmd->count(grid_only))
      throw ArgumentError(std::string(grid_only) + " plans a grid; --candidates chooses from a pool: give one or the other");
  if (a.count == 0) throw ArgumentError("--count: how many poses to choose from --candidates (at least 1)");
  if (cmd->count("--target-rms") && !(a.target_rms > 0.0 && std::isfinite(a.target_rms)))
    throw ArgumentError("--target-rms: " + format_number(a.target_rms) + "; expected a finite RMS > 0 (mm)");
  if (cmd->count("--target-rms") && a.model.empty())
    throw ArgumentError("--target-rms needs --model: the predicted RMS comes from a fitted model's field");
  refuse_same_output({{"--out", &a.out}, {"--summary-out", &a.summary_out}});
}

// The robot that judges the pool: --robot, else the model's nominal (or command) robot, else the built-in.
robot::MdhModel plan_robot(const PlanArgs& a, const std::optional<compensation::CompensationModel>& model) {
  using namespace robot;
  using namespace compensation;
  const MdhModel robot = !a.robot.empty() || !model ? load_robot_or_default(a.robot)
                         : model->has_nominal_model() ? model->nominal_model() : model->command_model();
  // A --robot beside a model must be the robot the model was fitted on: its joint limits and FK
  // judge the pool ("93.7 mm now -> 0.0455 after 5 poses" came from another robot's model).
  if (model && !a.robot.empty())
    if (const auto why = differs_beyond_calibration(model->nominal_model(), robot))
      throw ArgumentError("--robot " + a.robot + " is not the robot of --model " + a.model + " ('" +
                          model->nominal_model().name() + "'): " + *why + "; leave --robot out (the model's robot is used)");
  return robot;
}

// The pool's rows still to choose from, and the poses measured so far.
struct OpenPool {
  std::vector<std::size_t> rows;
  std::vector<robot::JointVector> open, measured;
};

OpenPool open_pool(const PlanArgs& a, const CsvTable& pool, const robot::MdhModel& robot,
                   const robot::RobotOrigin& origin) {
  using namespace robot;
  using namespace compensation;
  const std::vector<JointVector> pool_q = read_joint_columns(pool);
  if (const auto w = joints_outside_limits(pool_q, robot, row_labels_of(pool, "row")))
    throw InputError(a.candidates + ": " + *w + "; check units (degrees), joint order and --robot", a.candidates);
  // A pool or data that carry positions (x,y,z or mx,my,mz) must be this robot's (the check of
  // fit, validate, predict and compensate): another robot's pool was planned in silence.
  check_table_fits_robot(pool, robot, origin);
  // Measured so far: conditioned on, and never chosen again (matched by `point`, and by joints in
  // select_poses: data without a point column had 39 measured poses chosen again).
  OpenPool p;
  std::set<std::string> measured_points;
  if (!a.data.empty()) {
    const CsvTable d = CsvTable::read(a.data);
    p.measured = read_joint_columns(d);
    check_table_fits_robot(d, robot, origin);
    if (d.has_column("point") && pool.has_column("point"))
      for (std::size_t i = 0; i < d.row_count(); ++i) measured_points.emplace(d.cell(i, d.column_index("point")));
  }
  for (std::size_t i = 0; i < pool.row_count(); ++i) {
    if (!measured_points.empty() && measured_points.count(std::string(pool.cell(i, pool.column_index("point"))))) continue;
    p.rows.push_back(i);
    p.open.push_back(pool_q[i]);
  }
  if (p.open.size() < a.count)
    throw InputError(a.candidates + ": " + std::to_string(p.open.size()) + " candidate poses not yet measured, --count " +
                         std::to_string(a.count),
                     a.candidates);
  return p;
}

// Pool rows left out as repeats: said, naming the first few (a warning: the choice is still right).
void warn_left_out(const PlanArgs& a, const CsvTable& pool, const OpenPool& p, const compensation::PoseSelection& sel) {
  const RowLabels labels = row_labels_of(pool, "row");
  auto name_rows = [&](const std::vector<std::size_t>& ks) {
    std::string s;
    for (std::size_t n = 0; n < ks.size() && n < 5; ++n) s += (n ? ", " : "") + labels(p.rows[ks[n]]);
    return s + (ks.size() > 5 ? ", ..." : "");
  };
  if (!sel.repeated.empty())
    std::cerr << "errfield plan: warning: " << sel.repeated.size() << " pool row(s) repeat the joints of an earlier row and "
              << "were left out (" << name_rows(sel.repeated) << ")\n";
  if (!sel.already_measured.empty())
    std::cerr << "errfield plan: warning: " << sel.already_measured.size() << " pool row(s) have the joints of a pose in "
              << a.data << " and were left out as measured (" << name_rows(sel.already_measured) << ")\n";
}

std::string rms_range(const compensation::PoseSelection& sel, std::size_t k) {
  return three_digits(sel.predicted_rms_low_mm[k]) + "-" + three_digits(sel.predicted_rms_high_mm[k]);
}

// --target-rms: how many more poses reach it, said only as far as the prediction's range allows.
void say_poses_for_target(const PlanArgs& a, const compensation::PoseSelection& sel, double target_rms,
                          nlohmann::json& summary, std::ostringstream& text) {
  summary["target_rms_mm"] = target_rms;
  auto count_or_null = [](const std::optional<std::size_t>& n) { return n ? nlohmann::json(*n) : nlohmann::json(nullptr); };
  summary["poses_for_target"] = count_or_null(sel.poses_for_target);
  summary["poses_for_target_range"] = {count_or_null(sel.poses_for_target_low), count_or_null(sel.poses_for_target_high)};
  const std::string target = "  target " + format_number(target_rms) + " mm: ";
  const std::size_t horizon = sel.predicted_rms_mm.size() - 1;
  if (sel.poses_for_target_high && *sel.poses_for_target_high == 0) {
    text << target << "reached (predicted, the whole 90 % range) with the poses measured so far\n";
  } else if (sel.poses_for_target_low && *sel.poses_for_target_low == 0) {
    // The range covers the target now: a number of poses would be the noise of the estimate.
    text << target << "within the prediction's 90 % range now (" << rms_range(sel, 0)
         << " mm): no count is given; measure the batch and validate on held-out poses to tell\n";
  } else if (sel.poses_for_target_low) {
    text << target << "about " << (sel.poses_for_target ? std::to_string(*sel.poses_for_target) : std::string("?"))
         << " more poses chosen this way (90 % range " << *sel.poses_for_target_low << " to "
         << (sel.poses_for_target_high ? std::to_string(*sel.poses_for_target_high)
                                       : "beyond " + std::to_string(horizon) + " (not reached within this pool)")
         << "; " << (sel.poses_for_target && *sel.poses_for_target <= a.count ? "within" : "beyond") << " this batch)\n";
  } else {
    text << target << "not reached within " << horizon << " more poses of this pool, even at the low end of the "
         << "prediction's range (predicted " << three_digits(sel.predicted_rms_mm.back()) << " mm, "
         << rms_range(sel, horizon) << ", at the end): a finer model, a larger pool or less measurement noise is needed\n";
  }
}

// With a model: the predicted RMS now and after the batch, with its range (stopping rule).
void say_predicted_rms(const PlanArgs& a, const compensation::PoseSelection& sel,
                       const compensation::PoseSelectionOptions& o, const compensation::CompensationModel& model,
                       nlohmann::json& summary, std::ostringstream& text) {
  const std::size_t at_end = std::min(a.count, sel.predicted_rms_mm.size() - 1);
  const double now = sel.predicted_rms_mm.front(), after = sel.predicted_rms_mm[at_end];
  text << "  predicted 3-D RMS of a new reading over the pool: " << three_digits(now) << " mm (90 % range "
       << rms_range(sel, 0) << ") with the " << sel.conditioned_on << " poses measured, " << three_digits(after)
       << " mm (" << rms_range(sel, at_end) << ") after these " << a.count
       << " (the field's own variance with its nugget"
       << (model.joint_error_functions() ? ", plus what the field's correction leaves of the joint error functions' estimation variance" : "")
       << "; calibration and registration uncertainty not included)\n";
  if (sel.leave_one_out_scores > 0)
    text << "  the range: the level of the prediction is the mean of the model's " << sel.leave_one_out_scores
         << " leave-one-out scores (z^2), known to +/-" << format_number(std::round(1000.0 * sel.predicted_mse_relative_se) / 10.0)
         << " % in the mean square (one standard error)\n";
  summary["predicted_rms_mm"] = {{"now", now},
                                 {"after", after},
                                 {"by_pose", sel.predicted_rms_mm},
                                 {"now_range", {sel.predicted_rms_low_mm.front(), sel.predicted_rms_high_mm.front()}},
                                 {"after_range", {sel.predicted_rms_low_mm[at_end], sel.predicted_rms_high_mm[at_end]}},
                                 {"mse_relative_se", sel.predicted_mse_relative_se},
                                 {"leave_one_out_scores", sel.leave_one_out_scores}};
  if (o.target_rms_mm) say_poses_for_target(a, sel, *o.target_rms_mm, summary, text);
}

/// `plan --candidates`: the next poses to measure from a pool, with the predicted RMS (stopping rule).
void run_plan_from_candidates(const PlanArgs& a, CLI::App* cmd) {
  using namespace robot;
  using namespace compensation;
  check_candidate_options(a, cmd);
  std::optional<CompensationModel> model;
  if (!a.model.empty()) {
    const nlohmann::json j = read_json_file(a.model, "model file");
    model.emplace(with_json_source(a.model, [&] { return CompensationModel::from_json(j, a.model); }));
  }
  const MdhModel robot = plan_robot(a, model);
  const RobotOrigin origin{!a.robot.empty() || model.has_value(),
                           !a.robot.empty() ? "--robot " + a.robot
                           : model         ? "the nominal robot of " + a.model
                                           : std::string("the built-in ER20-C10 (no --robot)")};
  const CsvTable pool = CsvTable::read(a.candidates);
  const OpenPool p = open_pool(a, pool, robot, origin);
  PoseSelectionOptions o;
  o.count = a.count;
  if (a.local_scale != "on" && a.local_scale != "off")
    throw ArgumentError("--local-scale: expected on or off, got '" + a.local_scale + "'");
  o.local_scale = a.local_scale == "on";
  if (cmd->count("--target-rms")) o.target_rms_mm = a.target_rms;
  o.spacing_floor = a.spacing_floor;
  PoseSelection sel;
  naming_options([&] { sel = select_poses(p.open, p.measured, model ? &*model : nullptr, o); },
                 {{"PoseSelectionOptions::count", "--count"}, {"PoseSelectionOptions::target_rms_mm", "--target-rms"},
                  {"PoseSelectionOptions::spacing_floor", "--spacing-floor"}});
  warn_left_out(a, pool, p, sel);
  OutputTable out;
  std::vector<std::size_t> picked;
  for (std::size_t k : sel.chosen) picked.push_back(p.rows[k]);
  out.add_all_columns(pool, picked);
  nlohmann::json summary = {{"candidates", pool.row_count()}, {"measured", p.measured.size()},
                            {"chosen", sel.chosen.size()}, {"design", sel.design}};
  std::ostringstream text;
  text << "plan: " << sel.chosen.size() << " of " << p.open.size() << " candidate poses chosen, in measuring order ("
       << sel.design << ")\n";
  if (!sel.predicted_rms_mm.empty()) say_predicted_rms(a, sel, o, *model, summary, text);
  AtomicFileSet outputs;
  outputs.add(a.out, out.to_csv());
  if (!a.summary_out.empty()) outputs.add(a.summary_out, summary.dump(2) + "\n");
  text << "  written to " << a.out << "\n";
  commit_after_standard_output(outputs, text.str());
}

/// Best of sph/exp/gau/pow (free nugget, N_j weights) fitted to an `errfield variogram` CSV.
VariogramModel model_from_variogram_csv(const std::string& path) {
  const CsvTable t = CsvTable::read(path);
  std::vector<double> lag, gamma;
  std::vector<std::uint64_t> pairs;
  const auto p = t.numeric_column("pairs");
  const std::size_t lag_col = t.column_index("lag_mean"), gamma_col = t.column_index("gamma");
  for (std::size_t r = 0; r < t.row_count(); ++r) {
    if (p[r] <= 0) continue;  // empty bins have empty lag_mean/gamma cells
    lag.push_back(std::stod(std::string(t.cell(r, lag_col))));
    gamma.push_back(std::stod(std::string(t.cell(r, gamma_col))));
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

void run_plan(const PlanArgs& a, CLI::App* cmd) {
  if (!a.candidates.empty()) return run_plan_from_candidates(a, cmd);
  for (const char* pool_only : {"--count", "--model", "--data", "--target-rms", "--summary-out"})
    if (cmd->count(pool_only)) throw ArgumentError(std::string(pool_only) + " is for choosing from --candidates");
  if (a.cube.empty()) throw ArgumentError("--cube X0,Y0,Z0,SIZE (a grid plan) or --candidates POOL.csv --count K is required");
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
  std::size_t grid = 0, bases = 0;
  for (const auto* p : main_rows) (p->kind == "grid" ? grid : bases)++;
  std::ostringstream text;
  text << "plan: " << grid << " grid points (step " << o.step_mm << " mm) and " << bases
       << " base point(s), all reachable at the orientation; written to " << a.out << "\n";
  if (!a.samples_out.empty())
    text << "  " << sample_rows.size() << " validation samples (one per cell) written to " << a.samples_out << "\n";
  commit_after_standard_output(outputs, text.str());
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
      "           --base-point 750,-250,350 --out plan.csv --samples-out samples.csv\n"
      "Or choose the next poses from a pool of candidates (columns point, q1..q6 deg; all columns kept):\n"
      "without --model, maximin in joint space (the first batch); with --model (errfield fit,\n"
      "kinematic+kriging or vector-kriging) and --data (the poses measured so far), the poses that most\n"
      "reduce the field's predicted error over the pool, and the predicted 3-D RMS now and after them,\n"
      "with its 90 % range (from the spread of the model's leave-one-out scores);\n"
      "--target-rms MM says how many more poses the prediction needs to reach MM, and the range of counts\n"
      "its range gives (no count while the range covers MM now).\n"
      "Example (pool.csv: SIMULATED poses already measured, README's example inputs):\n"
      "  errfield plan --robot kr16 --candidates pool.csv --count 40 --out batch1.csv\n"
      "  errfield fit --robot kr16 --data batch1.csv --out m1.json\n"
      "  errfield plan --candidates pool.csv --count 40 --model m1.json --data batch1.csv \\\n"
      "    --target-rms 0.09 --out batch2.csv");
  cmd->add_option("--robot", a->robot,
                  "robot JSON or built-in name (er20-c10, kr16, ur5e, ur5, ur10; default: built-in ER20-C10, no tool)");
  cmd->add_option("--cube", a->cube, "X0,Y0,Z0,SIZE: lower corner and side (mm); a grid plan");
  cmd->add_option("--step", a->step, "grid step (mm, divides SIZE) or auto")->capture_default_str();
  cmd->add_option("--orientation", a->orientation, "RX,RY,RZ tool orientation (deg, fixed axes XYZ)")->capture_default_str();
  cmd->add_option("--base-point", a->bases, "X,Y,Z of a base point (robot position, mm), repeatable");
  cmd->add_option("--variogram", a->variogram, "--step auto: CSV of 'errfield variogram' (task-space lags, mm)");
  cmd->add_option("--variogram-model", a->variogram_model, "--step auto: model text, e.g. \"gau(sill=0.5,range=900)\"");
  cmd->add_option("--gamma-max", a->gamma_max, "--step auto: largest semivariance allowed at the cell diagonal (mm²)")
      ->capture_default_str();
  cmd->add_option("--samples-out", a->samples_out, "also write one random validation point per cell here");
  cmd->add_option("--seed", a->seed, "seed of the validation samples")->check(kUnsignedInteger)->capture_default_str();
  cmd->add_option("--candidates", a->candidates,
                  "pool of candidate poses (CSV: point, q1..q6 deg, any other columns carried through): choose "
                  "--count of them instead of a grid");
  cmd->add_option("--count", a->count,
                  "--candidates: how many poses to choose (in measuring order); a pool row repeating an earlier "
                  "one's joints counts once");
  cmd->add_option("--model", a->model,
                  "--candidates: a model of errfield fit (kinematic+kriging or vector-kriging): choose the poses that "
                  "most reduce its predicted error, and predict the RMS; without it, maximin in joint space");
  cmd->add_option("--data", a->data,
                  "--candidates: the poses measured so far (CSV with point, q1..q6): never chosen again (matched by "
                  "point, and by joints), and the choice is conditioned on them");
  cmd->add_option("--target-rms", a->target_rms,
                  "--candidates with --model: the 3-D RMS wanted (mm); says whether the prediction reaches it and "
                  "roughly how many more poses it needs, with the range of counts the prediction's 90 % range gives");
  cmd->add_option("--local-scale", a->local_scale,
                  "--candidates with --model: on (default) weights the choice and the prediction by where the model's "
                  "leave-one-out errors exceeded its variance (docs/robot.md, 'Which poses to measure'); off: the "
                  "model's variance as it is")
      ->capture_default_str();
  cmd->add_option("--spacing-floor", a->spacing_floor,
                  "--candidates with --model: choose only among pool poses at least this fraction (0..1) of the "
                  "farthest pose's distance (joints scaled by their spread) from all measured or chosen: a hedge "
                  "against a model fitted on few poses (0.7: measured, docs/robot.md 'Which poses to measure'); 0 = "
                  "variance reduction alone")
      ->capture_default_str();
  cmd->add_option("--summary-out", a->summary_out,
                  "--candidates: also write the design and predicted RMS (now, after, per pose) as JSON");
  cmd->add_option("--out", a->out,
                  "plan CSV: point,kind,x,y,z,rx,ry,rz,q1..q6 (a grid), or the chosen pool rows with all their "
                  "columns (--candidates); written atomically")
      ->required();
  cmd->callback([a, cmd] { run_plan(*a, cmd); });
}

Registration register_plan{"plan", 70, &add_plan_command};

}  // namespace
}  // namespace errfield::cli
