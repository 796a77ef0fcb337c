// `errfield import-urdf`: a URDF's base -> tip chain as an MD-H robot JSON, with an FK check.

#include <cmath>
#include <cstdio>
#include <iostream>

#include <nlohmann/json.hpp>

#include "cli/cli_support.hpp"
#include "cli/command_registry.hpp"
#include "errfield/atomic_file.hpp"
#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"
#include "errfield/robot/pose.hpp"
#include "errfield/robot/urdf_import.hpp"

namespace errfield::cli {
namespace {

struct ImportUrdfArgs {
  std::string urdf, base, tip, tool, out;
};

robot::PoseXyzRpy parse_tool(const std::string& text) {
  const auto items = split_list(text, "--tool");
  if (items.size() != 6) throw ArgumentError("--tool: expected X,Y,Z,RX,RY,RZ (mm, deg), got '" + text + "'");
  double v[6];
  for (std::size_t i = 0; i < 6; ++i) {
    try {
      std::size_t used = 0;
      v[i] = std::stod(items[i], &used);
      if (used != items[i].size() || !std::isfinite(v[i])) throw std::invalid_argument("not a number");
    } catch (const std::exception&) {
      throw ArgumentError("--tool: '" + items[i] + "' is not a finite number");
    }
  }
  return {v[0], v[1], v[2], v[3], v[4], v[5]};
}

std::string num(double v, const char* format = "%.10g") {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v + 0.0);  // + 0.0: no "-0"
  return buf;
}

void run_import_urdf(const ImportUrdfArgs& a) {
  if (!robot::urdf_support_available())
    throw Error("import-urdf: this errfield was built without URDF support (urdfdom, Debian liburdfdom-dev, was "
                "not found at configure time); install it (scripts/setup.sh) and rebuild");
  const Eigen::Isometry3d tool =
      a.tool.empty() ? Eigen::Isometry3d::Identity() : robot::to_isometry(parse_tool(a.tool));
  const robot::UrdfChain chain = robot::read_urdf_chain(a.urdf, a.base, a.tip);
  const robot::MdhModel converted = robot::mdh_from_urdf_chain(chain, tool);
  std::string joints;
  for (const auto* jt : chain.revolute()) joints += (joints.empty() ? "" : ", ") + jt->name;
  nlohmann::json j = converted.to_json();
  j["comment"] = "imported by errfield import-urdf from " + a.urdf + ", chain '" + a.base + "' -> '" + a.tip +
                 "'; q1..q6 are the URDF positions of joints " + joints + " in degrees";
  // Verify the model as it will be read back (base and tool pass through their rpy form).
  const robot::MdhModel model = robot::MdhModel::from_json(j, a.out);
  const robot::UrdfVerification v = robot::verify_urdf_import(model, chain, tool, 1000, 1);

  std::cout << "import-urdf: " << a.urdf << ": robot '" << model.name() << "', chain '" << a.base << "' -> '"
            << a.tip << "': revolute joints " << joints << "; fixed joints absorbed: "
            << chain.joints.size() - chain.revolute().size() << "\n";
  std::cout << "  i     alpha_deg          a_mm    theta0_deg          d_mm      beta_deg     q_min_deg     q_max_deg\n";
  for (int i = 0; i < robot::kJointCount; ++i) {
    const robot::MdhLink& l = model.link(i);
    std::cout << "  " << i + 1;
    for (double x : {l.alpha_deg, l.a_mm, l.theta0_deg, l.d_mm, l.beta_deg, l.q_min_deg, l.q_max_deg})
      std::cout << " " << num(x, "%13.10g");
    std::cout << "\n";
  }
  const auto base = robot::to_xyz_rpy(model.base()), tl = robot::to_xyz_rpy(model.tool());
  std::cout << "  base (mm, deg): " << num(base.x_mm) << ", " << num(base.y_mm) << ", " << num(base.z_mm) << ", "
            << num(base.rx_deg) << ", " << num(base.ry_deg) << ", " << num(base.rz_deg) << "\n";
  std::cout << "  tool (mm, deg): " << num(tl.x_mm) << ", " << num(tl.y_mm) << ", " << num(tl.z_mm) << ", "
            << num(tl.rx_deg) << ", " << num(tl.ry_deg) << ", " << num(tl.rz_deg) << "\n";
  const std::string check = "FK of the robot JSON vs the URDF chain at " + std::to_string(v.samples) +
                            " joint vectors (zero and random within the limits): largest difference " +
                            num(v.max_position_mm, "%.3g") + " mm in position, " + num(v.max_rotation_rad, "%.3g") +
                            " rad in orientation (tolerance " + num(robot::kUrdfPositionTolerance_mm, "%g") + " mm, " +
                            num(robot::kUrdfRotationTolerance_rad, "%g") + " rad)";
  if (!v.passed)
    throw Error("import-urdf: verification failed: " + check + "; " + a.out +
                " not written (consecutive joint axes that are almost but not quite parallel or intersecting can "
                "cause this; please report the URDF)");
  std::cout << "verification: " << check << ": ok\n";
  require_standard_output();  // the table went to standard output: all or nothing
  write_file_atomically(a.out, j.dump(2) + "\n");
  std::cerr << "import-urdf: robot JSON written to " << a.out << "\n";
}

void add_import_urdf_command(CLI::App& app) {
  auto args = std::make_shared<ImportUrdfArgs>();
  auto* cmd = app.add_subcommand(
      "import-urdf",
      "Robot JSON (modified D-H table, limits, base, tool) from the chain BASE_LINK -> TIP_LINK of a URDF.\n"
      "The chain must have exactly six revolute joints (fixed joints are absorbed). The result is checked:\n"
      "its FK must equal the URDF chain's to 1e-9 mm at 1000 joint vectors, else nothing is written (exit 1).\n"
      "Example: errfield import-urdf --urdf arm.urdf --base base_link --tip tool0 --out arm.json");
  cmd->add_option("--urdf", args->urdf, "URDF file (metres, radians)")->required();
  cmd->add_option("--base", args->base, "base link of the chain (the robot JSON's world frame)")->required();
  cmd->add_option("--tip", args->tip, "tip link of the chain (the flange; the tool is relative to it)")->required();
  cmd->add_option("--tool", args->tool, "X,Y,Z,RX,RY,RZ tool frame in the tip link frame (mm, deg; default identity)");
  cmd->add_option("--out", args->out, "output robot JSON (written atomically)")->required();
  cmd->callback([args] { run_import_urdf(*args); });
}

Registration register_import_urdf{"import-urdf", 55, &add_import_urdf_command};

}  // namespace
}  // namespace errfield::cli
