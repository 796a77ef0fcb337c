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
#include "errfield/programs/krl_program.hpp"
#include "errfield/programs/rapid_module.hpp"
#include "errfield/programs/urscript_program.hpp"
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

// NAME=X,Y,Z[,R1,R2,R3]: the name and its 3 or 6 numbers, read as the program's format writes a
// tool or frame (frame_of).
std::pair<std::string, std::vector<double>> named_numbers(const std::string& text, const std::string& option) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0)
    throw ArgumentError(option + " '" + text + "': expected NAME=X,Y,Z[,R1,R2,R3], e.g. " + option +
                        " tGripper=0,0,211,0,90,0 (see --help for each format's units)");
  const std::string name = text.substr(0, eq), values = text.substr(eq + 1);
  const std::size_t count = split_list(values, option).size();
  if (count != 3 && count != 6) throw ArgumentError(option + " '" + text + "': expected 3 or 6 numbers after " + name + "=");
  std::vector<double> v = parse_numbers(values, count, option);
  v.resize(6, 0.0);
  return {name, v};
}

// The numbers of --tool/--wobj as each format writes a frame: RAPID mm and errfield's fixed-axis
// XYZ angles (deg, robot/pose.hpp); KRL mm and KUKA's A,B,C (deg, as TOOL_DATA in $config.dat);
// URScript set_tcp's p[...] (m, a rotation vector in rad).
Eigen::Isometry3d frame_of(const std::vector<double>& v, const std::string& format) {
  if (format == "krl") {
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.translation() << v[0], v[1], v[2];
    t.linear() = programs::kuka_abc_rotation(v[3], v[4], v[5]);
    return t;
  }
  if (format == "urscript") return programs::urscript_pose({v[0], v[1], v[2], v[3], v[4], v[5]});
  return robot::to_isometry(robot::PoseXyzRpy{v[0], v[1], v[2], v[3], v[4], v[5]});
}

// The .dat beside a .src (same stem, .dat or .DAT); empty when there is none.
std::string dat_beside(const std::string& src) {
  for (const char* ext : {".dat", ".DAT", ".Dat"}) {
    const std::filesystem::path p = std::filesystem::path(src).replace_extension(ext);
    if (std::filesystem::exists(p)) return p.string();
  }
  return {};
}

std::string fixed(double v, int decimals) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(decimals);
  s << v;
  return s.str();
}

// --tool NAME=... and --wobj NAME=...: frames the program names but does not declare.
struct NamedFrames {
  std::map<std::string, Eigen::Isometry3d> tools, wobjs;
};

NamedFrames named_frames(const CompensateProgramArgs& a, const std::string& format) {
  NamedFrames f;
  for (const std::string& t : a.tools) {
    auto [name, numbers] = named_numbers(t, "--tool");
    const Eigen::Isometry3d tool = frame_of(numbers, format);
    compensation::check_tool_point(tool, "--tool " + name);
    f.tools[name] = tool;
  }
  for (const std::string& w : a.wobjs) {
    auto [name, numbers] = named_numbers(w, "--wobj");
    f.wobjs[name] = frame_of(numbers, format);
  }
  return f;
}

// The files a reader may rewrite (the program, and for KRL the .dat beside the .src), where each
// is written, and the targets read from them.
struct ReadProgram {
  std::vector<programs::ProgramFile> written;
  std::vector<std::string> written_to;
  std::vector<programs::ProgramTarget> targets;
};

ReadProgram read_program(const CompensateProgramArgs& a, const std::string& format, const NamedFrames& frames,
                         const robot::MdhModel& nominal_robot) {
  using namespace programs;
  ReadProgram p{{{a.program, read_program_bytes(a.program, "--program")}}, {a.out}, {}};
  std::vector<ProgramFile> includes;
  for (const std::string& path : a.includes) includes.push_back({path, read_program_bytes(path, "--include")});
  if (format == "rapid") {
    RapidReadOptions options;
    options.tools = frames.tools;
    options.wobjs = frames.wobjs;
    p.targets = read_rapid_targets(p.written.front(), includes, nominal_robot, options);
  } else if (format == "krl") {
    KrlReadOptions options;
    options.tools = frames.tools;
    options.bases = frames.wobjs;
    ProgramFile dat;
    if (const std::string path = dat_beside(a.program); !path.empty()) {
      dat = {path, read_program_bytes(path, "the .dat beside --program")};
      p.written.push_back(dat);
      p.written_to.push_back(std::filesystem::path(a.out).replace_extension(std::filesystem::path(path).extension()).string());
      refuse_same_output(
          {{"--out's .dat", &p.written_to.back()}, {"--out", &a.out}, {"--program's .dat", &path}, {"--report", &a.report}});
    }
    p.targets = read_krl_targets(p.written.front(), dat, includes, nominal_robot, options);
  } else {
    if (!frames.wobjs.empty()) throw ArgumentError("--wobj: URScript poses are in the robot base frame; there is no work object to give");
    for (const auto& [name, tool] : frames.tools)
      if (name != "tcp") throw ArgumentError("--tool " + name + "=...: a URScript program's tool is named tcp (--tool tcp=X,Y,Z,RX,RY,RZ)");
    if (!includes.empty()) throw ArgumentError("--include: a URScript program is read as one file");
    UrscriptReadOptions options;
    options.tools = frames.tools;
    p.targets = read_urscript_targets(p.written.front(), options);
  }
  if (p.targets.empty())
    throw InputError(a.program + ": no motion with a target found (" +
                         std::string(format == "rapid" ? "MoveL, MoveJ, MoveC, MoveAbsJ" : format == "krl" ? "PTP, LIN, CIRC, SPTP, SLIN, SPL" : "movel, movej, movep, movec") +
                         ", ...); " + a.out + " not written",
                     a.program);
  return p;
}

// Counts per status and each problem once (the reason's first clause, with how many rows and the first line).
struct StatusTally {
  std::map<std::string, std::size_t> count;
  std::vector<std::pair<std::string, std::pair<std::size_t, std::string>>> problems;
  std::string problem_lines;
};

StatusTally tally_statuses(const programs::ProgramCompensation& result) {
  StatusTally t;
  for (const programs::ProgramReportRow& r : result.rows) {
    ++t.count[r.status];
    if (r.status != programs::kStatusRefused) continue;
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
    auto it = std::find_if(t.problems.begin(), t.problems.end(), [&](const auto& p) { return p.first == problem; });
    if (it == t.problems.end()) t.problems.push_back({problem, {1, r.file + ":" + std::to_string(r.line)}});
    else ++it->second.first;
  }
  for (const auto& [p, where] : t.problems)
    t.problem_lines += "  problem: " + p + " (" + std::to_string(where.first) + " target(s), first at " + where.second + ")\n";
  return t;
}

// What a controller of this kind already corrects, so that the model does not correct it twice.
const char* controller_note(const std::string& format) {
  if (format == "rapid")
    return "  note: if this controller runs ABB Absolute Accuracy it already corrects pose targets: a model fitted on the "
           "nominal kinematics would correct twice; fit the model on data taken with Absolute Accuracy active, or "
           "turn it off\n";
  if (format == "krl")
    return "  note: if this robot is a KUKA positionally accurate robot (absolutely accurate model active) the "
           "controller already corrects pose targets: a model fitted on the nominal kinematics would correct twice; "
           "fit the model on data taken with it active, or turn it off\n";
  return "  warning: a Universal Robots controller applies its factory kinematic calibration to every pose target: "
         "a model fitted on the nominal D-H would correct twice; fit the model on poses commanded through that "
         "controller (measured targets against the poses the program sent), so it learns only the error left "
         "after the factory calibration\n";
}

std::string program_summary(const CompensateProgramArgs& a, const std::string& format, const ReadProgram& p,
                            const programs::ProgramCompensation& result, StatusTally& t) {
  using namespace programs;
  std::ostringstream summary;
  summary << "  largest correction " << fixed(result.largest_correction_mm, 3) << " mm (ceiling "
          << fixed(result.max_correction_mm, 3) << " mm)\n"
          << t.problem_lines;
  if (t.count[kStatusComputed])
    summary << "  " << t.count[kStatusComputed]
            << " target(s) are computed by the controller (relative moves, frame products, function calls, run-time "
               "assignments): they are not rewritten; a computed target moves with the literal it is computed from only "
               "where that literal was rewritten\n";
  summary << controller_note(format);
  summary << "  program written to " << a.out;
  for (std::size_t f = 1; f < p.written_to.size(); ++f) summary << " and " << p.written_to[f];
  summary << (a.report.empty() ? "" : "; report to " + a.report) << "\n";
  return summary.str();
}

// --report: one row per target occurrence, in the order of the program.
std::string program_report_csv(const programs::ProgramCompensation& result) {
  OutputTable t;
  const std::size_t n = result.rows.size();
  std::vector<std::string> file(n), line(n), target(n), status(n), reason(n);
  std::vector<std::vector<double>> num(12, std::vector<double>(n));
  for (std::size_t i = 0; i < n; ++i) {
    const programs::ProgramReportRow& r = result.rows[i];
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
  return t.to_csv();
}

void run_compensate_program(const CompensateProgramArgs& a) {
  using namespace programs;
  refuse_same_output({{"--out", &a.out}, {"--report", &a.report}, {"--program", &a.program}});
  if (!(std::isfinite(a.max_correction) && a.max_correction >= 0.0))
    throw ArgumentError("--max-correction: " + format_number(a.max_correction) + "; expected a ceiling > 0 (mm), or 0 for the default");
  const std::string format = program_format(a);
  const std::string extension = lower_text(std::filesystem::path(a.program).extension().string());
  if (format == "krl" && extension == ".dat")
    throw ArgumentError("--program " + a.program + ": give the .src (the motions are there; the .dat beside it is read and "
                        "written with it)");
  const nlohmann::json j = read_json_file(a.model, "model file");
  const compensation::CompensationModel model =
      with_json_source(a.model, [&] { return compensation::CompensationModel::from_json(j, a.model); });
  const bool kinematic = model.method() == compensation::CompensationMethod::kinematic ||
                         model.method() == compensation::CompensationMethod::kinematic_kriging;
  if (kinematic && a.robot.empty() && !model.has_nominal_model())
    throw ArgumentError("--robot: a kinematic model's command model is the calibrated robot; give the nominal robot JSON");
  const robot::MdhModel nominal_robot = a.robot.empty() ? model.nominal_model() : load_robot_or_default(a.robot);
  const NamedFrames frames = named_frames(a, format);
  const ReadProgram p = read_program(a, format, frames, nominal_robot);
  ProgramCompensationOptions copt;
  copt.tolerance_mm = a.tolerance;
  copt.max_correction_mm = a.max_correction;
  const ProgramCompensation result = compensate_program_targets(model, nominal_robot, p.targets, copt);

  StatusTally tally = tally_statuses(result);
  std::ostringstream summary;
  summary << "compensate-program: " << p.targets.size() << " target occurrence(s) in " << a.program << ": ";
  bool first = true;
  for (const char* s : {kStatusOk, kStatusComputed, kStatusUnchanged, kStatusRefused}) {
    summary << (first ? "" : ", ") << tally.count[s] << " " << s;
    first = false;
  }
  summary << "\n";
  if (tally.count[kStatusOk] == 0 && tally.count[kStatusRefused] > 0)
    throw Error("compensate-program: no target of " + a.program + " could be compensated with " +
                std::string(compensation::method_name(model.method())) + " from " + a.model + ":\n" + tally.problem_lines +
                a.out + " not written");
  summary << program_summary(a, format, p, result, tally);

  AtomicFileSet outputs;
  for (std::size_t f = 0; f < p.written.size(); ++f) {
    std::vector<Replacement> edits;
    for (const Replacement& r : result.replacements)
      if (r.file == f) edits.push_back(r);
    outputs.add(p.written_to[f], apply_replacements(p.written[f].bytes, std::move(edits)));
  }
  if (!a.report.empty()) outputs.add(a.report, program_report_csv(result));
  commit_after_standard_output(outputs, summary.str());
}

void add_compensate_program_command(CLI::App& app) {
  auto a = std::make_shared<CompensateProgramArgs>();
  auto* cmd = app.add_subcommand(
      "compensate-program",
      "Compensate a robot program's targets with a fitted model and write the program back: only the numbers of\n"
      "rewritten targets change, every other byte stays (encoding, line ends, comments, spacing). Formats (from the\n"
      "extension, or --format):\n"
      "  rapid (.mod/.prg/.sys): robtargets inline in MoveL/MoveJ/MoveC and declared CONST/PERS/VAR, with the\n"
      "    tooldata and wobjdata (uframe o oframe) in force, confdata picking the joint solution (ConfL\\Off/ConfJ\\Off:\n"
      "    the solution nearest the previous target's);\n"
      "  krl (.src, with the .dat beside it, read and written as OUT's stem + .dat): E6POS/POS/FRAME points and\n"
      "    inline {X,Y,Z,A,B,C} aggregates of PTP/LIN/CIRC/SPTP/SLIN/SCIRC/SPL, the tool and base from $TOOL/$BASE,\n"
      "    BAS, FDAT_ACT and the fold line's Tool[n] Base[n], TOOL_DATA[n]/BASE_DATA[n] from an --include such as\n"
      "    $config.dat; Status/Turn pick the solution of PTP motions (Turn and Status bit 0 checked);\n"
      "  urscript (.script/.urscript): p[x,y,z,rx,ry,rz] poses (m, rotation vector in rad) of movel/movej/movep/movec,\n"
      "    inline or in a variable, the TCP of the last set_tcp (before any: refused unless --tool tcp=...); no\n"
      "    configuration: the solution nearest the previous target's (or the Name_q joints stored beside Name_p).\n"
      "Each target goes through the same computation as 'errfield compensate' (the tool point, orientation where the\n"
      "model predicts it, the credible region, the ceiling); the rewritten pose is the nominal FK of the compensated\n"
      "joints. Report (--report CSV): one row per target occurrence,\n"
      "file,line,target,status,reason,dx_mm,dy_mm,dz_mm,q1..q6 (deg, compensated joints),dwx_mdeg..dwz_mdeg\n"
      "(rotation change); status ok (rewritten), computed (Offs, RelTool, frame products, pose_trans, run-time\n"
      "assignments: reported with what they depend on, not rewritten), unchanged (joint targets), refused (with the\n"
      "reason: tool or work object/base unknown, configuration matching no solution, outside-region, ...). The input\n"
      "is never modified; if no target can be compensated nothing is written (exit 1).\n"
      "Example: errfield compensate-program --model model.json --program cell.mod --out cell_comp.mod --report r.csv"
      "  # not-run: needs a robot program; docs/robot.md, \"Compensating a robot program\", runs one per format");
  cmd->add_option("--model", a->model, "model JSON from 'errfield fit'")->required();
  cmd->add_option("--program", a->program, "robot program to read (never modified)")->required();
  cmd->add_option("--out", a->out,
                  "the compensated program (written atomically; krl: and OUT's stem + .dat, the compensated .dat)")
      ->required();
  cmd->add_option("--report", a->report, "report CSV, one row per target occurrence (written atomically)");
  cmd->add_option("--format", a->format,
                  "rapid, krl or urscript (default from the extension: .mod/.prg/.sys, .src, .script/.urscript)");
  cmd->add_option("--tool", a->tools,
                  "NAME=X,Y,Z[,R1,R2,R3]: tool NAME's TCP in the flange frame, used instead of (or where there is no) "
                  "declaration; repeatable. Numbers as the format writes a tool: rapid mm and errfield's fixed-axis XYZ "
                  "angles (deg); krl NAME like TOOL_DATA[1], mm and KUKA's A,B,C (deg); urscript NAME tcp (the TCP "
                  "before any set_tcp), set_tcp's m and rotation vector (rad)");
  cmd->add_option("--wobj", a->wobjs,
                  "NAME=X,Y,Z[,R1,R2,R3]: work object NAME's frame (rapid: user frame o object frame; krl: NAME like "
                  "BASE_DATA[2]) in the robot base frame, numbers as for --tool; repeatable");
  cmd->add_option("--include", a->includes,
                  "another file to read declarations from (rapid: tooldata, wobjdata, robtargets; krl: $config.dat's "
                  "TOOL_DATA/BASE_DATA, points; never rewritten); repeatable");
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
