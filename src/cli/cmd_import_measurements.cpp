// `errfield import-measurements`: a foreign measurement export (separator, decimal comma, its own
// column names, radians, metres, Euler or quaternion orientations) rewritten as errfield's
// measurement CSV (readers/measurement_import.hpp).

#include <iostream>
#include <sstream>

#include "cli/cli_support.hpp"
#include "cli/command_registry.hpp"
#include "errfield/atomic_file.hpp"
#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"
#include "errfield/readers/measurement_import.hpp"

namespace errfield::cli {
namespace {

using readers::AngleUnit;
using readers::ImportOptions;
using readers::LengthUnit;
using readers::PositionFrom;

struct ImportMeasurementsArgs {
  std::string in, out, preset, sep, decimal, map, joint_units, length_units, flange_length_units, angle_units, euler,
      quaternion, position_from, series;
  bool no_unit_check = false;
};

char parse_separator(const std::string& s) {
  if (s == "tab" || s == "\\t" || s == "\t") return '\t';
  if (s.size() == 1 && s != "\"" && s != "\n" && s != "\r") return s[0];
  throw ArgumentError("--sep: '" + s + "'; expected one character (',', ';', '|') or tab");
}

AngleUnit parse_angle_unit(const std::string& s, const char* option) {
  if (s == "deg") return AngleUnit::degrees;
  if (s == "rad") return AngleUnit::radians;
  throw ArgumentError(std::string(option) + ": '" + s + "'; expected deg or rad");
}

LengthUnit parse_length_unit(const std::string& s, const char* option) {
  if (s == "mm") return LengthUnit::millimetres;
  if (s == "m") return LengthUnit::metres;
  throw ArgumentError(std::string(option) + ": '" + s + "'; expected mm or m");
}

PositionFrom parse_position_from(const std::string& s) {
  if (s == "measured") return PositionFrom::measured;
  if (s == "target+dif") return PositionFrom::target_plus_difference;
  if (s == "target-dif") return PositionFrom::target_minus_difference;
  throw ArgumentError("--position-from: '" + s + "'; expected measured, target+dif or target-dif");
}

// "q1=joint_1,mx=X [mm]" -> pairs; an entry replaces the preset's for the same name.
void apply_map(const std::string& text, ImportOptions& o) {
  for (const std::string& item : split_list(text, "--map")) {
    const std::size_t eq = item.find('=');
    if (eq == std::string::npos || eq == 0)
      throw ArgumentError("--map: '" + item + "'; expected NAME=COLUMN (e.g. q1=joint_1)");
    const std::string name = item.substr(0, eq), column = item.substr(eq + 1);
    std::erase_if(o.columns, [&](const auto& c) { return c.first == name; });
    o.columns.emplace_back(name, column);
  }
}

void run_import_measurements(const ImportMeasurementsArgs& a) {
  refuse_same_output({{"--in", &a.in}, {"--out", &a.out}});
  const char separator = !a.sep.empty()        ? parse_separator(a.sep)
                         : !a.preset.empty()   ? readers::preset_separator(a.preset)
                                               : char{0};
  const CsvTable table = readers::read_foreign_csv(a.in, separator);
  ImportOptions o = a.preset.empty() ? ImportOptions{} : readers::preset_options(a.preset, table);
  o.separator = separator;
  if (!a.decimal.empty()) {
    if (a.decimal != "." && a.decimal != ",") throw ArgumentError("--decimal: '" + a.decimal + "'; expected . or ,");
    o.decimal = a.decimal[0];
  }
  if (!a.map.empty()) apply_map(a.map, o);
  if (!a.joint_units.empty()) o.joint_unit = parse_angle_unit(a.joint_units, "--joint-units");
  if (!a.angle_units.empty()) o.angle_unit = parse_angle_unit(a.angle_units, "--angle-units");
  if (!a.length_units.empty()) o.length_unit = parse_length_unit(a.length_units, "--length-units");
  if (!a.flange_length_units.empty())
    o.flange_length_unit = parse_length_unit(a.flange_length_units, "--flange-length-units");
  if (!a.euler.empty()) o.euler = readers::EulerConvention::parse(a.euler);
  if (!a.quaternion.empty()) o.quaternion = readers::parse_quaternion_order(a.quaternion);
  if (!a.position_from.empty()) o.position_from = parse_position_from(a.position_from);
  if (!a.series.empty()) o.series = a.series;
  if (a.no_unit_check) o.check_units = false;

  const readers::ImportedMeasurements imported = readers::import_measurements(table, o);
  std::ostringstream report;
  report << "import-measurements: " << a.in << ": " << imported.rows.size() << " rows -> " << a.out << " (columns ";
  for (std::size_t c = 0; c < imported.header.size(); ++c) report << (c ? "," : "") << imported.header[c];
  report << ")\n";
  for (const std::string& note : imported.notes) report << "  " << note << "\n";
  AtomicFileSet outputs;
  outputs.add(a.out, imported.csv());
  commit_after_standard_output(outputs, report.str());
}

void add_import_measurements_command(CLI::App& app) {
  auto a = std::make_shared<ImportMeasurementsArgs>();
  auto* cmd = app.add_subcommand(
      "import-measurements",
      "A foreign measurement file (a tracker's or controller's CSV export, a published data set) rewritten as\n"
      "errfield's measurement CSV, the file `errfield fit` reads: point,q1..q6 (deg), mx,my,mz (mm, tracker\n"
      "frame), mrx,mry,mrz (deg, fixed-axis XYZ: R = Rz Ry Rx) and, when the file has them, temperature_c,\n"
      "time and series (fit ignores these). Rows with a flange pose instead of joints (a hand-eye registration\n"
      "set) keep it as flange_x..flange_z (mm) and flange_rx..flange_rz (deg). Say how the file differs with\n"
      "--sep, --decimal, --map (the file's column for each errfield name), units and conventions, or name a\n"
      "preset for the two real data sets of docs/realdata.md. A bad cell is refused naming file, line, column\n"
      "and value; joints that look like radians given as degrees (and metres given as mm) are refused.\n"
      "Example: errfield import-measurements --in export.csv --out m.csv --sep ';' --decimal , --joint-units rad\n"
      "  --map q1=A1,q2=A2,q3=A3,q4=A4,q5=A5,q6=A6,mx=X,my=Y,mz=Z");
  cmd->add_option("--in", a->in, "the foreign measurement file (CSV text)")->required();
  cmd->add_option("--out", a->out, "errfield measurement CSV to write (atomically)")->required();
  cmd->add_option("--preset", a->preset,
                  "ur5-jacobi: the UR5 files of serial_robots_datasets (x_t..z_t + x_dif..z_dif, joints deg; the "
                  "7-axis WAM files are refused); ur10-ipa: the UR10 series and calibration_handeye.csv files of "
                  "ipa-robot-accuracy (';', decimal commas, joints rad, T-Mac pose with Euler 'XYZ' intrinsic deg). "
                  "Other options override the preset's choices");
  cmd->add_option("--sep", a->sep, "cell separator: one character or 'tab' (default: ',' or ';' from the header)");
  cmd->add_option("--decimal", a->decimal, "decimal mark: . (default) or , (then the separator is not ',')");
  cmd->add_option("--map", a->map,
                  "NAME=COLUMN,... the file's column for each errfield name: q1..q6, mx,my,mz, tx,ty,tz + dx,dy,dz "
                  "(with --position-from target+dif|target-dif), mrx,mry,mrz (Euler angle about x, y, z) or "
                  "mr1,mr2,mr3 (in sequence order), mqw,mqx,mqy,mqz or mq=A+B+C+D (order: --quaternion), flange_x.."
                  "flange_z with flange_qw..flange_qz, flange_q=A+B+C+D or flange_rx..flange_rz, temperature_c, "
                  "time, point. Unmapped names are looked up under their own name");
  cmd->add_option("--joint-units", a->joint_units, "deg (default) or rad");
  cmd->add_option("--length-units", a->length_units, "mm (default) or m: measured, target and difference positions");
  cmd->add_option("--flange-length-units", a->flange_length_units, "mm (default) or m: the flange position");
  cmd->add_option("--angle-units", a->angle_units, "deg (default) or rad: Euler angles");
  cmd->add_option("--euler", a->euler,
                  "the Euler angles' convention: three axes and the kind, e.g. xyz-extrinsic (default, errfield's "
                  "own: R = Rz Ry Rx), XYZ-intrinsic (R = Rx Ry Rz), zyx-extrinsic; scipy's short form (xyz "
                  "extrinsic, XYZ intrinsic) too");
  cmd->add_option("--quaternion", a->quaternion, "wxyz (default) or xyzw: the order of an mq=A+B+C+D map entry");
  cmd->add_option("--position-from", a->position_from,
                  "measured (default: mx,my,mz), target+dif or target-dif: a commanded position tx,ty,tz and a "
                  "measured difference dx,dy,dz, measured = target + dif or target - dif");
  cmd->add_option("--series", a->series, "a label written in a 'series' column on every row (a day, a set-up)");
  cmd->add_flag("--no-unit-check", a->no_unit_check,
                "take the units as given even when every joint lies within +-2 pi (degrees?) or every position "
                "within 10 of the origin (mm?)");
  cmd->callback([a] { run_import_measurements(*a); });
}

Registration register_import_measurements{"import-measurements", 56, &add_import_measurements_command};

}  // namespace
}  // namespace errfield::cli
