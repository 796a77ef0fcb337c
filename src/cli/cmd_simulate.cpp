// `errfield simulate`: measurement files from the simulated robot and laser tracker, in the
// columns `errfield calibrate` (and the pipeline's `fit`) read. Every file says it is SIMULATED.

#include <cmath>
#include <iostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "cli/cli_support.hpp"
#include "cli/command_registry.hpp"
#include "cli/robot_cli.hpp"
#include "errfield/error.hpp"
#include "errfield/robot/cube_budget.hpp"
#include "errfield/robot/simulator.hpp"

namespace errfield::cli {
namespace {

struct SimulateArgs {
  std::string config, robot, joints, cube, orientation = "180,0,0", sample = "grid", out, truth_out, config_out,
      robot_out;
  std::vector<std::string> bases, fixed_bases;
  double step = 125.0;
  long long seed = -1;
  std::string measure = "both";
  bool truth_columns = false;
};

double parse_number(const std::string& text, const std::string& what) {
  try {
    std::size_t used = 0;
    const double v = std::stod(text, &used);
    if (used != text.size() || !std::isfinite(v)) throw std::invalid_argument("trailing");
    return v;
  } catch (const std::exception&) {
    throw ArgumentError(what + ": '" + text + "' is not a number");
  }
}

Eigen::Vector3d parse_vec3(const std::string& text, const std::string& what) {
  const auto items = split_list(text, what);
  if (items.size() != 3) throw ArgumentError(what + ": expected X,Y,Z, got '" + text + "'");
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) {
    try {
      std::size_t used = 0;
      v[i] = std::stod(items[static_cast<std::size_t>(i)], &used);
      if (used != items[static_cast<std::size_t>(i)].size()) throw std::invalid_argument("trailing");
    } catch (const std::exception&) {
      throw ArgumentError(what + ": '" + items[static_cast<std::size_t>(i)] + "' is not a number");
    }
  }
  return v;
}

void run_simulate(const SimulateArgs& a) {
  refuse_same_output({{"--out", &a.out}, {"--truth-out", &a.truth_out}, {"--config-out", &a.config_out},
                      {"--robot-out", &a.robot_out}});
  using namespace robot;
  SimulatorConfig config = a.config.empty() ? SimulatorConfig::paper_default() : SimulatorConfig::load(a.config);
  if (!a.robot.empty()) config.nominal = load_robot_or_default(a.robot);
  if (a.seed >= 0) config.seed = static_cast<std::uint64_t>(a.seed);
  if (a.measure != "positions" && a.measure != "distances" && a.measure != "both")
    throw ArgumentError("--measure: expected positions, distances or both, got '" + a.measure + "'");
  const bool want_positions = a.measure != "distances", want_distances = a.measure != "positions";
  const SimulatedRobot robot(config);
  SimulationRng rng(config.seed);

  MeasurementCube cube = paper_cube();
  if (!a.cube.empty()) {
    const auto items = split_list(a.cube, "--cube");
    if (items.size() != 4) throw ArgumentError("--cube: expected X0,Y0,Z0,SIZE (mm), got '" + a.cube + "'");
    cube.min_corner_mm = parse_vec3(items[0] + "," + items[1] + "," + items[2], "--cube");
    cube.size_mm = parse_number(items[3], "--cube SIZE");
    if (!(cube.size_mm > 0)) throw ArgumentError("--cube: SIZE must be > 0, got '" + items[3] + "'");
  }
  const Eigen::Vector3d rpy = parse_vec3(a.orientation, "--orientation");
  cube.orientation = rotation_from_rpy_deg(rpy.x(), rpy.y(), rpy.z());

  // Targets: joints from a file, or cube points solved by IK on the nominal model.
  struct Row {
    std::string id, kind;
    JointVector q;
  };
  std::vector<Row> rows;
  IkResult seed = cube_seed(config.nominal, cube);
  auto solve = [&](const Eigen::Vector3d& p, const std::string& id) {
    if (!seed.ok())
      throw ArgumentError("the cube centre " + std::to_string(cube.center().x()) + "," +
                          std::to_string(cube.center().y()) + "," + std::to_string(cube.center().z()) +
                          " is not reachable at the requested orientation (" + to_string(seed.status) + ")");
    const IkResult r = solve_cube_pose(config.nominal, cube, p, seed.q_deg);
    if (!r.ok()) {
      std::ostringstream s;
      s << "point " << id << " (" << p.transpose() << ") is not reachable at the requested orientation: "
        << to_string(r.status) << ", residual " << r.position_residual_mm << " mm";
      throw ArgumentError(s.str());
    }
    return r.q_deg;
  };
  if (!a.fixed_bases.empty() && !a.bases.empty())
    throw ArgumentError("--base and --fixed-base: give base points either as robot positions (--base) or as fixed "
                        "points (--fixed-base), not both");
  // Fixed base points: points in the cell (e.g. tracker nests), not carried by the robot; the
  // tracker measures each once (one reading shared by all its distances), no base rows.
  std::vector<Eigen::Vector3d> fixed;
  for (const auto& b : a.fixed_bases) fixed.push_back(parse_vec3(b, "--fixed-base"));
  std::vector<Eigen::Vector3d> base_nominal;
  if (a.bases.empty() && fixed.empty()) base_nominal.push_back(paper_base_point_nominal());
  for (const auto& b : a.bases) base_nominal.push_back(parse_vec3(b, "--base"));
  for (std::size_t k = 0; k < base_nominal.size(); ++k)
    rows.push_back({"b" + std::to_string(k), "base", solve(base_nominal[k], "b" + std::to_string(k))});
  if (!a.joints.empty()) {
    const CsvTable table = CsvTable::read(a.joints);
    const auto q = read_joint_columns(table);
    for (std::size_t i = 0; i < q.size(); ++i) {
      if (!config.nominal.within_limits(q[i]))
        throw InputError(a.joints + ":" + std::to_string(table.line_of_row(i)) + ": joints outside the robot's limits",
                         a.joints, table.line_of_row(i), "q1");
      rows.push_back({"p" + std::to_string(i), "target", q[i]});
    }
  } else {
    std::vector<Eigen::Vector3d> pts;
    if (a.sample == "grid" || a.sample == "cells") check_cube_budget(cube.size_mm, a.step, false, "--step");
    if (a.sample == "grid") {
      naming_options([&] { pts = cube.grid(a.step); }, {{"MeasurementCube::grid: step", "--step"}});
    } else if (a.sample == "cells") {
      naming_options([&] { pts = cube.random_per_cell(a.step, rng); },
                     {{"MeasurementCube::random_per_cell: step", "--step"}});
    } else if (a.sample.rfind("random:", 0) == 0) {
      const double nd = parse_number(a.sample.substr(7), "--sample random:N");
      check_point_budget(nd, "--sample " + a.sample);  // before the cast: 1e12 must not wrap
      const int n = static_cast<int>(nd);
      if (n < 1 || n != nd) throw ArgumentError("--sample random:N needs N >= 1, got '" + a.sample + "'");
      for (int i = 0; i < n; ++i)
        pts.push_back(cube.min_corner_mm + cube.size_mm * Eigen::Vector3d(rng.uniform01(), rng.uniform01(), rng.uniform01()));
    } else {
      throw ArgumentError("--sample: expected grid, cells or random:N, got '" + a.sample + "'");
    }
    for (std::size_t i = 0; i < pts.size(); ++i) rows.push_back({"p" + std::to_string(i), "target", solve(pts[i], "p" + std::to_string(i))});
  }

  // Visit every row once (bases first, as the paper's reference is measured before the targets):
  // fresh repeatability noise per move, one tracker reading per visit.
  const std::size_t n = rows.size();
  std::vector<Eigen::Vector3d> nominal(n), truth(n), measured(n);
  for (std::size_t i = 0; i < n; ++i) {
    nominal[i] = forward_position(config.nominal, rows[i].q);
    const Eigen::Vector3d reached = robot.move(rows[i].q, rng);
    truth[i] = reached;
    measured[i] = robot.measure(reached, rng);
  }
  std::vector<Eigen::Vector3d> fixed_measured;
  for (const auto& f : fixed) fixed_measured.push_back(robot.measure(f, rng));
  OutputTable out;
  std::vector<std::string> ids(n), kinds(n);
  for (std::size_t i = 0; i < n; ++i) {
    ids[i] = rows[i].id;
    kinds[i] = rows[i].kind;
  }
  out.add_column("point", ids);
  out.add_column("kind", kinds);
  const auto qn = joint_column_names();
  for (int k = 0; k < kJointCount; ++k) {
    std::vector<double> v(n);
    for (std::size_t i = 0; i < n; ++i) v[i] = rows[i].q[k];
    out.add_numeric_column(qn[static_cast<std::size_t>(k)], v);
  }
  auto add_xyz = [&](const std::vector<Eigen::Vector3d>& p, const char* x, const char* y, const char* z) {
    std::vector<double> vx(n), vy(n), vz(n);
    for (std::size_t i = 0; i < n; ++i) {
      vx[i] = p[i].x();
      vy[i] = p[i].y();
      vz[i] = p[i].z();
    }
    out.add_numeric_column(x, vx);
    out.add_numeric_column(y, vy);
    out.add_numeric_column(z, vz);
  };
  add_xyz(nominal, "x", "y", "z");
  if (want_positions) add_xyz(measured, "mx", "my", "mz");
  if (want_distances)
    for (std::size_t k = 0; k < base_nominal.size(); ++k) {
      std::vector<double> d(n);
      for (std::size_t i = 0; i < n; ++i) d[i] = (measured[i] - measured[k]).norm();
      out.add_numeric_column("dist_b" + std::to_string(k), d);
    }
  if (want_distances)
    for (std::size_t k = 0; k < fixed.size(); ++k) {
      std::vector<double> d(n);
      for (std::size_t i = 0; i < n; ++i) d[i] = (measured[i] - fixed_measured[k]).norm();
      out.add_numeric_column("dist_b" + std::to_string(k), d);
    }
  if (a.truth_columns) add_xyz(truth, "true_x", "true_y", "true_z");

  std::ostringstream text;
  text << "# SIMULATED data (errfield simulate; not a real robot): seed " << config.seed << ", robot '"
       << config.nominal.name() << "'" << (a.config.empty() ? ", default simulation" : ", config " + a.config) << "\n"
       << "# q1..q6 commanded joints (deg); x,y,z nominal tool position (robot base frame, mm)";
  if (want_positions) text << "; mx,my,mz measured position (tracker frame, mm)";
  if (want_distances) text << "; dist_bK measured distance to base point bK (mm)";
  for (std::size_t k = 0; k < fixed.size(); ++k)
    text << "; b" << k << " is a fixed point at " << format_number(fixed[k].x()) << "," << format_number(fixed[k].y())
         << "," << format_number(fixed[k].z()) << " (true, robot base frame, mm; no base row)";
  if (a.truth_columns) text << "; true_x.. true position (robot base frame, mm; simulation only)";
  text << "\n" << out.to_csv();
  // All outputs or none (a bad --config-out must not leave a new --out next to an old --truth-out).
  AtomicFileSet outputs;
  outputs.add(a.out, text.str());
  if (!a.truth_out.empty())
    outputs.add(a.truth_out, robot.true_geometry().with_name("SIMULATED true geometry").to_json().dump(2) + "\n");
  if (!a.config_out.empty()) outputs.add(a.config_out, config.to_json().dump(2) + "\n");
  // The nominal robot (with the tool that is measured) is what plan/fit/compensate take as --robot.
  if (!a.robot_out.empty()) outputs.add(a.robot_out, config.nominal.to_json().dump(2) + "\n");
  outputs.commit();
  std::cerr << "simulate: " << n << " SIMULATED measurements (" << base_nominal.size() + fixed.size() << " base point(s)) written to "
            << a.out << "\n";
}

void add_simulate_command(CLI::App& app) {
  auto args = std::make_shared<SimulateArgs>();
  auto* cmd = app.add_subcommand(
      "simulate",
      "Simulated robot + laser tracker measurements (SIMULATED data, labelled as such), in the columns\n"
      "'errfield calibrate' and 'errfield fit' read: point, kind (base|target), q1..q6 (deg), x,y,z\n"
      "(nominal, mm), mx,my,mz (tracker frame, mm), dist_b0.. (mm). Base points are robot positions\n"
      "visited first (--base), or fixed points in the cell (--fixed-base; no base rows). Default: the\n"
      "paper's set-up (ER20-C10 with the Table 7 ball, 500 mm cube at\n"
      "tool-down orientation, 125 mm grid, base point at the cube corner).\n"
      "Example: errfield simulate --sample grid --step 125 --out grid.csv --truth-out true_robot.json");
  cmd->add_option("--config", args->config, "simulation JSON (docs/robot.md); default: the paper's set-up");
  cmd->add_option("--robot", args->robot, "nominal robot JSON (overrides the config's robot)");
  cmd->add_option("--seed", args->seed, "random seed (overrides the config's)")->check(kUnsignedInteger);
  cmd->add_option("--joints", args->joints, "CSV with commanded joints q1..q6 (deg) instead of cube points");
  cmd->add_option("--cube", args->cube, "X0,Y0,Z0,SIZE: cube min corner and side (mm); default the paper cube");
  cmd->add_option("--orientation", args->orientation, "RX,RY,RZ tool orientation in the cube (deg; default 180,0,0)");
  cmd->add_option("--sample", args->sample, "grid (default), cells (one random point per cell) or random:N");
  cmd->add_option("--step", args->step, "grid step (mm, must divide the cube side; default 125)");
  cmd->add_option("--base", args->bases, "nominal base point X,Y,Z (mm), repeatable; default the cube's min corner");
  cmd->add_option("--fixed-base", args->fixed_bases,
                  "fixed base point X,Y,Z (mm, true position in the robot base frame), repeatable: a point in the cell "
                  "not carried by the robot (e.g. a tracker nest); dist_b0.. are distances to these, no base rows "
                  "(calibrate: --base-point); not with --base");
  cmd->add_option("--measure", args->measure, "positions, distances or both (default)");
  cmd->add_flag("--truth-columns", args->truth_columns, "add true_x,true_y,true_z (the simulator's truth)");
  cmd->add_option("--truth-out", args->truth_out, "write the simulated true geometry as a robot JSON");
  cmd->add_option("--config-out", args->config_out, "write the full simulation configuration used as JSON");
  cmd->add_option("--robot-out", args->robot_out,
                  "write the nominal robot (with its measured tool point) as a robot JSON, the --robot of "
                  "plan/fit/compensate");
  cmd->add_option("--out", args->out, "output CSV (written atomically)")->required();
  cmd->callback([args] { run_simulate(*args); });
}

Registration reg{"simulate", 62, &add_simulate_command};

}  // namespace
}  // namespace errfield::cli
