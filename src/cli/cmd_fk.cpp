// `errfield fk`: forward kinematics of a list of joint vectors.

#include <iostream>

#include "cli/cli_support.hpp"
#include "cli/command_registry.hpp"
#include "cli/interpolation_methods.hpp"
#include "cli/robot_cli.hpp"
#include "errfield/compensation/model/prediction.hpp"
#include "errfield/robot/input_checks.hpp"
#include "errfield/robot/kinematics.hpp"
#include "errfield/robot/pose.hpp"

namespace errfield::cli {
namespace {

struct FkArgs {
  std::string input, robot, frame = "tool", out;
};

void run_fk(const FkArgs& a) {
  // --robot: a robot JSON or a compensation model (its command model); either may hold the tracker
  // registration, and then the tracker-frame position is written too.
  robot::MdhModel model = load_robot_or_default("");
  std::optional<compensation::Registration> registration;
  if (!a.robot.empty()) {
    if (a.robot == "list") (void)load_robot_or_default(a.robot);  // lists the built-in robots (exit 2)
    const compensation::LoadedModel loaded = compensation::load_model(a.robot);
    model = loaded.is_robot_json ? load_robot_or_default(a.robot) : loaded.model.command_model();
    registration = loaded.model.registration();
  }
  const robot::EndFrame frame = robot::parse_end_frame(a.frame);
  const CsvTable table = CsvTable::read(a.input);
  const auto joints = read_joint_columns(table);
  const std::size_t n = joints.size();
  if (const auto warning = robot::joints_outside_limits(joints, model, row_labels_of(table, "row")))
    std::cerr << "errfield fk: warning: " << *warning << "\n";
  std::vector<double> x(n), y(n), z(n), tx(n), ty(n), tz(n);
  std::vector<std::vector<double>> r(9, std::vector<double>(n));
  std::vector<double> rx(n), ry(n), rz(n);  // the same orientation as every pose input takes it
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Isometry3d t = robot::forward_kinematics(model, joints[i], frame);
    x[i] = t.translation().x();
    y[i] = t.translation().y();
    z[i] = t.translation().z();
    if (registration) {
      const Eigen::Vector3d p = registration->robot_from_tracker.inverse() * t.translation();
      tx[i] = p.x();
      ty[i] = p.y();
      tz[i] = p.z();
    }
    for (int k = 0; k < 9; ++k) r[static_cast<std::size_t>(k)][i] = t.linear()(k / 3, k % 3);
    const Eigen::Vector3d rpy = robot::rpy_deg_from_rotation(t.linear());
    rx[i] = rpy.x();
    ry[i] = rpy.y();
    rz[i] = rpy.z();
  }
  OutputTable out;
  out.add_all_columns(table);
  out.add_numeric_column("x", x);
  out.add_numeric_column("y", y);
  out.add_numeric_column("z", z);
  for (int k = 0; k < 9; ++k) out.add_numeric_column(rotation_column_names()[static_cast<std::size_t>(k)], r[static_cast<std::size_t>(k)]);
  out.add_numeric_column("rx", rx);
  out.add_numeric_column("ry", ry);
  out.add_numeric_column("rz", rz);
  if (registration) {
    out.add_numeric_column("tx", tx);
    out.add_numeric_column("ty", ty);
    out.add_numeric_column("tz", tz);
  }
  out.write(a.out);
  std::cerr << "fk: " << n << " poses of " << model.name() << " (" << a.frame << " frame) written to " << a.out << "\n";
}

void add_fk_command(CLI::App& app) {
  auto args = std::make_shared<FkArgs>();
  auto* cmd = app.add_subcommand(
      "fk",
      "Forward kinematics: joint angles -> tool or flange poses.\n"
      "Input columns q1..q6 (degrees); output keeps the input columns and adds x,y,z (mm, world frame)\n"
      "and the rotation matrix r11,r12,r13,r21,r22,r23,r31,r32,r33, also as rx,ry,rz (deg, R = Rz(rz) Ry(ry) Rx(rx),\n"
      "ry in [-90, 90]: the form ik and compensate take pose targets in); with a stored tracker registration (robot\n"
      "JSON from 'calibrate --model position', or a model from 'fit') also tx,ty,tz (tracker frame, mm).\n"
      "Example: errfield fk --input joints.csv --robot robot.json --frame tool --out poses.csv");
  cmd->add_option("--input", args->input, "CSV with columns q1..q6 (deg)")->required();
  cmd->add_option("--robot", args->robot,
                  "robot description JSON (docs/robot.md), built-in name (er20-c10, kr16, ur5e, ur5, ur10; errfield robots) or "
                  "compensation model JSON (its command model); default: built-in nominal ER20-C10, no tool");
  cmd->add_option("--frame", args->frame, "flange or tool (default tool)");
  cmd->add_option("--out", args->out, "output CSV (written atomically)")->required();
  cmd->callback([args] { run_fk(*args); });
}

Registration register_fk{"fk", 60, &add_fk_command};

}  // namespace
}  // namespace errfield::cli
