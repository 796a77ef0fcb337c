// `errfield compensate-program`: a robot program in, the same program out with its literal targets
// compensated (every other byte kept), and a report of every target occurrence.
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <sstream>

#include <nlohmann/json.hpp>

#include "cli/cli_support.hpp"
#include "cli/command_registry.hpp"
#include "cli/pipeline_cli.hpp"
#include "cli/robot_cli.hpp"
#include "errfield/atomic_file.hpp"
#include "errfield/compensation/model/compensation.hpp"
#include "errfield/compensation/pipeline.hpp"
#include "errfield/error.hpp"
#include "errfield/json_file.hpp"
#include "errfield/programs/program_compensation.hpp"
#include "errfield/programs/rapid_module.hpp"
#include "errfield/robot/pose.hpp"

namespace errfield::cli {
namespace {

struct CompensateProgramArgs {
  std::string model, program, out, report, format, robot;
  std::vector<std::string> tools, wobjs, includes;
  double tolerance = 0.25, max_correction = 0.0;
};

std::string lower_text(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// The program's format from --format or the file's extension.
std::string program_format(const CompensateProgramArgs& a) {
  if (!a.format.empty()) {
    const std::string f = lower_text(a.format);
    if (f != "rapid" && f != "krl" && f != "urscript")
      throw ArgumentError("--format: '" + a.format + "'; expected rapid, krl or urscript");
    return f;
  }
  const std::string ext = lower_text(std::filesystem::path(a.program).extension().string());
  if (ext == ".mod" || ext == ".prg" || ext == ".sys" || ext == ".modx" || ext == ".sysx") return "rapid";
  if (ext == ".src" || ext == ".dat") return "krl";
  if (ext == ".script" || ext == ".urscript") return "urscript";
  throw ArgumentError("--program " + a.program + ": the extension '" + ext +
                      "' names no known format (.mod/.prg/.sys: rapid, .src/.dat: krl, .script: urscript); give --format");
}

// NAME=X,Y,Z[,RX,RY,RZ] (mm, deg; errfield's fixed-axis XYZ angles, robot/pose.hpp).
std::pair<std::string, Eigen::Isometry3d> named_frame(const std::string& text, const std::string& option) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0)
    throw ArgumentError(option + " '" + text + "': expected NAME=X,Y,Z[,RX,RY,RZ] (mm, deg), e.g. " + option +
                        " tGripper=0,0,211,0,90,0");
  const std::string name = text.substr(0, eq), values = text.substr(eq + 1);
  const std::size_t count = split_list(values, option).size();
  if (count != 3 && count != 6) throw ArgumentError(option + " '" + text + "': expected 3 or 6 numbers after " + name + "=");
  const std::vector<double> v = parse_numbers(values, count, option);
  robot::PoseXyzRpy p{v[0], v[1], v[2]};
  if (count == 6) {
    p.rx_deg = v[3];
    p.ry_deg = v[4];
    p.rz_deg = v[5];
  }
  return {name, robot::to_isometry(p)};
}

std::string fixed(double v, int decimals) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(decimals);
  s << v;
  return s.str();
}

void run_compensate_program(const CompensateProgramArgs& a) {
  using namespace programs;
  refuse_same_output({{"--out", &a.out}, {"--report", &a.report}, {"--program", &a.program}});
  if (!(std::isfinite(a.max_correction) && a.max_correction >= 0.0))
    throw ArgumentError("--max-correction: " + format_number(a.max_correction) + "; expected a ceiling > 0 (mm), or 0 for the default");
  const std::string format = program_format(a);
  if (format != "rapid")
    throw ArgumentError("--program " + a.program + ": " + format +
                        " programs are not read yet (this version reads ABB RAPID .mod/.prg/.sys); see docs/robot.md");
  const nlohmann::json j = read_json_file(a.model, "model file");
  const compensation::CompensationModel model =
      with_json_source(a.model, [&] { return compensation::CompensationModel::from_json(j, a.model); });
  const bool kinematic = model.method() == compensation::CompensationMethod::kinematic ||
                         model.method() == compensation::CompensationMethod::kinematic_kriging;
  if (kinematic && a.robot.empty() && !model.has_nominal_model())
    throw ArgumentError("--robot: a kinematic model's command model is the calibrated robot; give the nominal robot JSON");
  const robot::MdhModel nominal_robot = a.robot.empty() ? model.nominal_model() : load_robot_or_default(a.robot);

  RapidReadOptions options;
  for (const std::string& t : a.tools) {
    auto [name, tool] = named_frame(t, "--tool");
    compensation::check_tool_point(tool, "--tool " + name);
    options.tools[name] = tool;
  }
  for (const std::string& w : a.wobjs) {
    auto [name, frame] = named_frame(w, "--wobj");
    options.wobjs[name] = frame;
  }
  const ProgramFile program{a.program, read_program_bytes(a.program, "--program")};
  std::vector<ProgramFile> includes;
  for (const std::string& path : a.includes) includes.push_back({path, read_program_bytes(path, "--include")});
  const std::vector<ProgramTarget> targets = read_rapid_targets(program, includes, nominal_robot, options);
  if (targets.empty())
    throw InputError(a.program + ": no move instruction with a target found (MoveL, MoveJ, MoveC, MoveAbsJ, ...); " + a.out +
                         " not written",
                     a.program);
  ProgramCompensationOptions copt;
  copt.tolerance_mm = a.tolerance;
  copt.max_correction_mm = a.max_correction;
  const ProgramCompensation result = compensate_program_targets(model, nominal_robot, targets, copt);

  // Counts per status and each problem once (the reason's first clause, with how many rows and the first line).
  std::map<std::string, std::size_t> count;
  std::vector<std::pair<std::string, std::pair<std::size_t, std::string>>> problems;
  for (const ProgramReportRow& r : result.rows) {
    ++count[r.status];
    if (r.status != kStatusRefused) continue;
    // The reason's first clause: up to the first "; " outside parentheses.
    std::size_t cut = r.reason.size();
    int depth = 0;
    for (std::size_t c = 0; c + 1 < r.reason.size(); ++c) {
      depth += r.reason[c] == '(' ? 1 : r.reason[c] == ')' ? -1 : 0;
      if (depth == 0 && r.reason[c] == ';' && r.reason[c + 1] == ' ') {
        cut = c;
        break;
      }
    }
    const std::string problem = r.reason.substr(0, cut);
    auto it = std::find_if(problems.begin(), problems.end(), [&](const auto& p) { return p.first == problem; });
    if (it == problems.end()) problems.push_back({problem, {1, r.file + ":" + std::to_string(r.line)}});
    else ++it->second.first;
  }
  std::ostringstream summary;
  summary << "compensate-program: " << targets.size() << " target occurrence(s) in " << a.program << ": ";
  bool first = true;
  for (const char* s : {kStatusOk, kStatusComputed, kStatusUnchanged, kStatusRefused}) {
    summary << (first ? "" : ", ") << count[s] << " " << s;
    first = false;
  }
  summary << "\n";
  std::string problem_lines;
  for (const auto& [p, where] : problems)
    problem_lines += "  problem: " + p + " (" + std::to_string(where.first) + " target(s), first at " + where.second + ")\n";
  if (count[kStatusOk] == 0 && count[kStatusRefused] > 0)
    throw Error("compensate-program: no target of " + a.program + " could be compensated with " +
                std::string(compensation::method_name(model.method())) + " from " + a.model + ":\n" + problem_lines + a.out +
                " not written");
  summary << "  largest correction " << fixed(result.largest_correction_mm, 3) << " mm (ceiling "
          << fixed(result.max_correction_mm, 3) << " mm)\n"
          << problem_lines;
  if (count[kStatusComputed])
    summary << "  " << count[kStatusComputed]
            << " target(s) are computed by the controller (Offs, RelTool, assignments): they are not rewritten; a computed "
               "target moves with the literal it is computed from only where that literal was rewritten\n";
  summary << "  note: if this controller runs ABB Absolute Accuracy it already corrects pose targets: a model fitted on the "
             "nominal kinematics would correct twice; fit the model on data taken with Absolute Accuracy active, or "
             "turn it off\n";
  summary << "  program written to " << a.out << (a.report.empty() ? "" : "; report to " + a.report) << "\n";

  AtomicFileSet outputs;
  outputs.add(a.out, apply_replacements(program.bytes, result.replacements));
  if (!a.report.empty()) {
    OutputTable t;
    const std::size_t n = result.rows.size();
    std::vector<std::string> file(n), line(n), target(n), status(n), reason(n);
    std::vector<std::vector<double>> num(12, std::vector<double>(n));
    for (std::size_t i = 0; i < n; ++i) {
      const ProgramReportRow& r = result.rows[i];
      file[i] = r.file;
      line[i] = std::to_string(r.line);
      target[i] = r.target;
      status[i] = r.status;
      reason[i] = r.reason;
      for (int k = 0; k < 3; ++k) num[static_cast<std::size_t>(k)][i] = r.d_mm[k];
      for (int k = 0; k < 6; ++k) num[static_cast<std::size_t>(3 + k)][i] = r.q_deg[k];
      for (int k = 0; k < 3; ++k) num[static_cast<std::size_t>(9 + k)][i] = r.rotation_mdeg[k];
    }
    t.add_column("file", file);
    t.add_column("line", line);
    t.add_column("target", target);
    t.add_column("status", status);
    t.add_column("reason", reason);
    const char* names[] = {"dx_mm", "dy_mm", "dz_mm", "q1", "q2", "q3", "q4", "q5", "q6", "dwx_mdeg", "dwy_mdeg", "dwz_mdeg"};
    for (std::size_t c = 0; c < 12; ++c) t.add_numbers(names[c], std::move(num[c]));
    outputs.add(a.report, t.to_csv());
  }
  commit_after_standard_output(outputs, summary.str());
}

void add_compensate_program_command(CLI::App& app) {
  auto a = std::make_shared<CompensateProgramArgs>();
  auto* cmd = app.add_subcommand(
      "compensate-program",
      "Compensate a robot program's targets with a fitted model and write the program back: only the numbers of\n"
      "rewritten targets change, every other byte stays (encoding, line ends, comments, spacing). Reads ABB RAPID\n"
      "(.mod/.prg/.sys): robtargets inline in MoveL/MoveJ/MoveC and declared CONST/PERS/VAR, with the tooldata\n"
      "and wobjdata (uframe o oframe) in force at each move (declared in the module, an --include, or given by\n"
      "--tool/--wobj NAME=...), the confdata picking the joint solution (ConfL\\Off/ConfJ\\Off: the solution nearest\n"
      "the previous target's). Each target goes through the same computation as 'errfield compensate' (the tool\n"
      "point, orientation where the model predicts it, the credible region, the ceiling); the rewritten pose is the\n"
      "nominal FK of the compensated joints. Report (--report CSV): one row per target occurrence,\n"
      "file,line,target,status,reason,dx_mm,dy_mm,dz_mm,q1..q6 (deg, compensated joints),dwx_mdeg..dwz_mdeg\n"
      "(rotation change); status ok (rewritten), computed (Offs, RelTool, run-time assignments: reported with\n"
      "what they depend on, not rewritten), unchanged (MoveAbsJ: joint targets), refused (with the reason: tool or\n"
      "work object unknown, configuration matching no solution, outside-region, not-credible, ...). The input is\n"
      "never modified; if no target can be compensated nothing is written (exit 1).\n"
      "Example: errfield compensate-program --model model.json --program cell.mod --out cell_comp.mod --report r.csv"
      "  # not-run: needs a RAPID module; docs/robot.md, \"Compensating a robot program\", runs one");
  cmd->add_option("--model", a->model, "model JSON from 'errfield fit'")->required();
  cmd->add_option("--program", a->program, "robot program to read (never modified)")->required();
  cmd->add_option("--out", a->out, "the compensated program (written atomically)")->required();
  cmd->add_option("--report", a->report, "report CSV, one row per target occurrence (written atomically)");
  cmd->add_option("--format", a->format, "rapid (default from the extension: .mod/.prg/.sys)");
  cmd->add_option("--tool", a->tools,
                  "NAME=X,Y,Z[,RX,RY,RZ]: tool NAME's TCP in the flange frame (mm; deg, errfield's fixed-axis XYZ "
                  "angles), used instead of (or where there is no) declaration; repeatable");
  cmd->add_option("--wobj", a->wobjs,
                  "NAME=X,Y,Z[,RX,RY,RZ]: work object NAME's frame (user frame o object frame) in the robot base frame "
                  "(mm, deg); repeatable");
  cmd->add_option("--include", a->includes,
                  "another module to read declarations from (tooldata, wobjdata, robtargets; never rewritten); repeatable");
  cmd->add_option("--robot", a->robot, "nominal robot JSON or built-in name (default: the model's nominal robot)");
  cmd->add_option("--tolerance", a->tolerance, "tolerance for compensate's p_inside (mm)")->capture_default_str();
  cmd->add_option("--max-correction", a->max_correction,
                  "MM: refuse targets whose correction is larger (as compensate; 0: the model's default ceiling)")
      ->capture_default_str();
  cmd->callback([a] { run_compensate_program(*a); });
}

Registration register_compensate_program{"compensate-program", 72, &add_compensate_program_command};

}  // namespace
}  // namespace errfield::cli
