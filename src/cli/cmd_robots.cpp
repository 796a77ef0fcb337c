// `errfield robots`: the built-in nominal robots (robot/builtin_robots.hpp), and one of them as a
// robot JSON to start a user's own description from.

#include <iostream>

#include <nlohmann/json.hpp>

#include "cli/cli_support.hpp"
#include "cli/command_registry.hpp"
#include "errfield/atomic_file.hpp"
#include "errfield/error.hpp"
#include "errfield/robot/builtin_robots.hpp"
#include "errfield/robot/input_checks.hpp"

namespace errfield::cli {
namespace {

struct RobotsArgs {
  std::string show, out;
};

void run_robots(const RobotsArgs& a) {
  if (a.show.empty()) {
    if (!a.out.empty()) throw ArgumentError("--out: give the robot to write with --show NAME");
    for (const robot::BuiltinRobot& r : robot::builtin_robots()) {
      std::cout << r.name << "\n  " << r.description << "\n  source: " << r.source
                << "\n  reach scale (sum of |a|+|d|): " << format_number(robot::reach_scale_mm(r.model))
                << " mm; joint limits (deg):";
      for (int j = 0; j < robot::kJointCount; ++j)
        std::cout << " q" << j + 1 << " [" << format_number(r.model.link(j).q_min_deg) << ", "
                  << format_number(r.model.link(j).q_max_deg) << "]";
      std::cout << "\n  default simulate cube: min corner " << format_number(r.cube_min_mm.x()) << ","
                << format_number(r.cube_min_mm.y()) << "," << format_number(r.cube_min_mm.z()) << ", side "
                << format_number(r.cube_size_mm) << " mm\n";
    }
    std::cout << "Use a name wherever --robot is accepted (e.g. --robot kr16); errfield robots --show NAME "
                 "prints its robot JSON.\n";
    return;
  }
  const robot::BuiltinRobot* r = robot::find_builtin_robot(a.show);
  if (!r) throw ArgumentError("--show: '" + a.show + "' is not a built-in robot; expected one of " + robot::builtin_robot_names());
  nlohmann::json j = r->model.to_json();
  j["comment"] = "errfield built-in robot '" + r->name + "': " + r->source + "; no tool (add yours as \"tool\")";
  const std::string text = j.dump(2) + "\n";
  if (a.out.empty()) {
    std::cout << text;
  } else {
    write_file_atomically(a.out, text);
    std::cerr << "robots: " << r->name << " written to " << a.out << "\n";
  }
}

void add_robots_command(CLI::App& app) {
  auto args = std::make_shared<RobotsArgs>();
  auto* cmd = app.add_subcommand(
      "robots",
      "The built-in nominal robots (er20-c10, kr16, ur5e, ur5, ur10; from published datasheets,\n"
      "docs/robot.md), usable by name wherever --robot is accepted. Without options: lists them with their\n"
      "sources and joint limits. --show NAME prints (or --out writes) one as a robot JSON.\n"
      "Example: errfield robots --show ur5e --out ur5e.json");
  cmd->add_option("--show", args->show, "a built-in robot's name: print its robot JSON");
  cmd->add_option("--out", args->out, "with --show: write the robot JSON to this file (atomically)");
  cmd->callback([args] { run_robots(*args); });
}

Registration register_robots{"robots", 59, &add_robots_command};

}  // namespace
}  // namespace errfield::cli
