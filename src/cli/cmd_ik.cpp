// `errfield ik`: inverse kinematics of a list of target poses.

#include <algorithm>
#include <iostream>
#include <numbers>

#include "cli/cli_support.hpp"
#include "cli/command_registry.hpp"
#include "cli/robot_cli.hpp"
#include "errfield/error.hpp"
#include "errfield/robot/arm_configuration.hpp"
#include "errfield/robot/inverse_kinematics.hpp"

namespace errfield::cli {
namespace {

struct IkArgs {
  std::string input, robot, frame = "tool", out;
  bool position_only = false;
  int max_iterations = 100;
};

// Each target's orientation: r11..r33 (re-orthonormalized) or rx,ry,rz; identity with --position-only.
std::vector<Eigen::Matrix3d> target_rotations(const IkArgs& a, const CsvTable& table, std::size_t n) {
  std::vector<Eigen::Matrix3d> rotations(n, Eigen::Matrix3d::Identity());
  if (a.position_only) return rotations;
  if (table.has_column("r11")) {
    const Eigen::MatrixXd r = table.numeric_columns(rotation_column_names());
    for (std::size_t i = 0; i < n; ++i) {
      Eigen::Matrix3d m;
      for (int k = 0; k < 9; ++k) m(k / 3, k % 3) = r(static_cast<Eigen::Index>(i), k);
      const double orth = (m.transpose() * m - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
      if (orth > 1e-6 || m.determinant() < 0)
        throw InputError(table.source() + ":" + std::to_string(table.line_of_row(i)) +
                             ": r11..r33 is not a rotation matrix (|R^T R - I| = " + std::to_string(orth) + ")",
                         table.source(), table.line_of_row(i), "r11");
      // Re-orthonormalize so a matrix printed with 6 digits is still an exact rotation.
      Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
      rotations[i] = svd.matrixU() * svd.matrixV().transpose();
    }
  } else if (table.has_column("rx")) {
    const Eigen::MatrixXd e = table.numeric_columns({"rx", "ry", "rz"});
    for (std::size_t i = 0; i < n; ++i) {
      const auto r = static_cast<Eigen::Index>(i);
      rotations[i] = robot::rotation_from_rpy_deg(e(r, 0), e(r, 1), e(r, 2));
    }
  } else {
    throw InputError(table.source() +
                         ": no orientation columns: expected r11..r33 (rotation matrix) or rx,ry,rz (deg, "
                         "R = Rz(rz) Ry(ry) Rx(rx)); use --position-only for 3-D targets",
                     table.source(), 1, "r11");
  }
  return rotations;
}

// The solutions' columns, one cell per target.
struct IkColumns {
  std::vector<std::vector<double>> q;
  std::vector<std::string> status, config, config_source;
  std::vector<double> res_mm, res_deg;
  std::size_t failures = 0;
};

IkColumns solve_targets(const robot::MdhModel& model, const robot::IkOptions& options, const Eigen::MatrixXd& xyz,
                        const std::vector<Eigen::Matrix3d>& rotations, const std::vector<robot::JointVector>& seeds) {
  const std::size_t n = rotations.size();
  const bool has_seed = !seeds.empty();
  IkColumns c{std::vector<std::vector<double>>(robot::kJointCount, std::vector<double>(n)),
              std::vector<std::string>(n), std::vector<std::string>(n), std::vector<std::string>(n),
              std::vector<double>(n), std::vector<double>(n), 0};
  robot::JointVector previous;
  bool have_previous = false;
  Progress progress("ik", n);
  for (std::size_t i = 0; i < n; ++i) {
    Eigen::Isometry3d target = Eigen::Isometry3d::Identity();
    target.linear() = rotations[i];
    target.translation() = xyz.row(static_cast<Eigen::Index>(i)).transpose();
    robot::IkResult r;
    // Where the solution's arm configuration came from (column config_source): the row's seed,
    // the previous row's solution, or the multistart's first converged posture, which need not be
    // the configuration the pose was taught on (issue 35: never silent).
    if (has_seed) {
      r = robot::inverse_kinematics(model, target, seeds[i], options);
      c.config_source[i] = "seed";
    } else {
      // Without seeds, the previous row's solution keeps neighbouring targets on one branch.
      if (have_previous) {
        r = robot::inverse_kinematics(model, target, previous, options);
        c.config_source[i] = "previous-row";
      }
      if (!have_previous || !r.ok()) {
        r = robot::inverse_kinematics_multistart(model, target, options);
        c.config_source[i] = "multistart";
      }
    }
    if (r.ok()) c.config[i] = robot::arm_configuration(model, r.q_deg).to_string();
    if (r.ok()) {
      previous = r.q_deg;
      have_previous = true;
    } else {
      ++c.failures;
    }
    for (int k = 0; k < robot::kJointCount; ++k) c.q[static_cast<std::size_t>(k)][i] = r.q_deg[k];
    c.status[i] = robot::to_string(r.status);
    c.res_mm[i] = r.position_residual_mm;
    c.res_deg[i] = r.orientation_residual_rad * 180.0 / std::numbers::pi;
    progress.update(i + 1);
  }
  progress.finish();
  return c;
}

OutputTable ik_table(const CsvTable& table, bool has_seed, const IkColumns& c) {
  const std::size_t n = table.row_count();
  OutputTable out;
  // Input columns are kept, except seed columns q1..q6, which the solution replaces.
  const auto qnames = joint_column_names();
  // So are the columns ik computes (ik run on its own output): dropped here and written anew, in
  // the same order as the first time.
  const std::vector<std::string> computed{"status", "residual_mm", "residual_deg", "config", "config_source"};
  for (std::size_t col = 0; col < table.header().size(); ++col) {
    bool is_seed = false;
    for (const auto& qn : qnames) is_seed = is_seed || (has_seed && table.column_index(qn) == col);
    if (is_seed || std::find(computed.begin(), computed.end(), column_key(table.header()[col])) != computed.end()) continue;
    std::vector<std::string> cells(n);
    for (std::size_t r = 0; r < n; ++r) cells[r] = table.cell(r, col);
    out.put_column(table.header()[col], std::move(cells));  // the input's own text
  }
  for (int k = 0; k < robot::kJointCount; ++k) out.add_numeric_column(qnames[static_cast<std::size_t>(k)], c.q[static_cast<std::size_t>(k)]);
  out.add_column("status", c.status);
  out.add_numeric_column("residual_mm", c.res_mm);
  out.add_numeric_column("residual_deg", c.res_deg);
  out.add_column("config", c.config);
  out.add_column("config_source", c.config_source);
  return out;
}

void run_ik(const IkArgs& a) {
  const robot::MdhModel model = load_robot_or_default(a.robot);
  robot::IkOptions options;
  options.frame = robot::parse_end_frame(a.frame);
  options.position_only = a.position_only;
  options.max_iterations = a.max_iterations;
  naming_options([&] { options.validate(); }, {{"IkOptions::max_iterations", "--max-iterations"}});
  const CsvTable table = CsvTable::read(a.input);
  const Eigen::MatrixXd xyz = table.numeric_columns({"x", "y", "z"});
  const std::size_t n = static_cast<std::size_t>(xyz.rows());
  warn_if_metres(table, model, "ik", kNominalXyz);
  const std::vector<Eigen::Matrix3d> rotations = target_rotations(a, table, n);
  const bool has_seed = has_joint_columns(table);
  std::vector<robot::JointVector> seeds;
  if (has_seed) seeds = read_joint_columns(table);
  const IkColumns c = solve_targets(model, options, xyz, rotations, seeds);
  ik_table(table, has_seed, c).write(a.out);
  std::cerr << "ik: " << n - c.failures << " of " << n << " targets solved";
  if (c.failures) std::cerr << "; " << c.failures << " not (see the status and residual columns)";
  std::cerr << "; arm configuration from (column config_source):";
  bool first = true;
  for (const char* source : {"seed", "previous-row", "multistart"}) {
    const auto count = std::count(c.config_source.begin(), c.config_source.end(), source);
    if (count == 0) continue;
    std::cerr << (first ? " " : ", ") << source << " " << count;
    first = false;
  }
  std::cerr << "; written to " << a.out << "\n";
}

void add_ik_command(CLI::App& app) {
  auto args = std::make_shared<IkArgs>();
  auto* cmd = app.add_subcommand(
      "ik",
      "Inverse kinematics: target poses -> joint angles (damped least squares within the joint limits).\n"
      "Input columns x,y,z (mm) and either r11..r33 (rotation matrix, row-major) or rx,ry,rz (deg,\n"
      "fixed-axis XYZ: R = Rz(rz) Ry(ry) Rx(rx)); optional seed columns q1..q6 (deg). Without seeds\n"
      "each row starts from the previous row's solution (first row: a few standard postures).\n"
      "Output: the input columns (seeds replaced) plus q1..q6 (deg), status (converged, joint_limits,\n"
      "unreachable, max_iterations), residual_mm, residual_deg, config (the solution's arm configuration,\n"
      "s+e+w- style) and config_source (seed, previous-row or multistart: where that configuration came\n"
      "from; give seeds q1..q6 of the taught joints to hold a taught configuration).\n"
      "Example: errfield fk --input targets.csv --robot robot.json --out poses.csv   # poses: x,y,z,rx,ry,rz\n"
      "         errfield ik --input poses.csv --robot robot.json --out joints.csv\n"
      "Example: errfield ik --input targets.csv --robot robot.json --position-only --out joints.csv   # x,y,z only");
  cmd->add_option("--input", args->input, "CSV with x,y,z and r11..r33 or rx,ry,rz")->required();
  cmd->add_option("--robot", args->robot,
                  "robot description JSON (docs/robot.md) or built-in name (er20-c10, kr16, ur5e, ur5, ur10; errfield robots); "
                  "default: built-in nominal ER20-C10, no tool");
  cmd->add_option("--frame", args->frame, "flange or tool (default tool)");
  cmd->add_flag("--position-only", args->position_only, "match the position only (orientation free)");
  cmd->add_option("--max-iterations", args->max_iterations, "iteration budget per target (default 100)");
  cmd->add_option("--out", args->out, "output CSV (written atomically)")->required();
  cmd->callback([args] { run_ik(*args); });
}

Registration register_ik{"ik", 61, &add_ik_command};

}  // namespace
}  // namespace errfield::cli
