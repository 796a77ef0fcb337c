#include "errfield/readers/measurement_import.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <set>
#include <sstream>

#include <Eigen/Geometry>

#include "errfield/csv_writing.hpp"
#include "errfield/error.hpp"
#include "errfield/number_format.hpp"
#include "errfield/robot/pose.hpp"

namespace errfield::readers {

namespace {

constexpr double kDegPerRad = 180.0 / std::numbers::pi;

const std::vector<std::string> kJoints = {"q1", "q2", "q3", "q4", "q5", "q6"};
const std::vector<std::string> kMeasured = {"mx", "my", "mz"};
const std::vector<std::string> kTarget = {"tx", "ty", "tz"};
const std::vector<std::string> kDifference = {"dx", "dy", "dz"};
const std::vector<std::string> kEulerByAxis = {"mrx", "mry", "mrz"};
const std::vector<std::string> kEulerBySequence = {"mr1", "mr2", "mr3"};
const std::vector<std::string> kQuaternion = {"mqw", "mqx", "mqy", "mqz"};
const std::vector<std::string> kFlangePosition = {"flange_x", "flange_y", "flange_z"};
const std::vector<std::string> kFlangeQuaternion = {"flange_qw", "flange_qx", "flange_qy", "flange_qz"};
const std::vector<std::string> kFlangeEuler = {"flange_rx", "flange_ry", "flange_rz"};

// Positions nearer than this to the origin on every row, given in mm, are metres; farther than
// kMostMetres given in metres are mm. A robot's reach and a tracker's range sit between the two.
constexpr double kFewestMillimetres = 10.0;
constexpr double kMostMetres = 200.0;
// Joints in degrees within +-2 pi on every row of a file this long are radians; joints in radians
// beyond +-4 pi (two turns, more than any arm's range) are degrees.
constexpr std::size_t kRowsForUnitCheck = 5;

std::string line_of(const CsvTable& t, std::size_t row) {
  return t.source() + ":" + std::to_string(t.line_of_row(row));
}

std::string join(const std::vector<std::string>& names) {
  std::string s;
  for (const std::string& n : names) s += (s.empty() ? "" : ",") + n;
  return s;
}

std::vector<std::string> split_plus(const std::string& text) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  while (true) {
    const std::size_t p = text.find('+', start);
    parts.push_back(text.substr(start, p == std::string::npos ? std::string::npos : p - start));
    if (p == std::string::npos) return parts;
    start = p + 1;
  }
}

// The columns of one group of errfield names, all or none present; `what` names the group.
struct Group {
  std::vector<std::size_t> columns;
  std::vector<std::string> file_names;
  bool present() const { return !columns.empty(); }
};

Group find_group(const CsvTable& t, const ImportOptions& o, const std::vector<std::string>& names,
                 const std::string& what) {
  Group g;
  std::vector<std::string> missing;
  bool any_mapped = false;
  for (const std::string& n : names) {
    const std::string column = o.column_for(n);
    any_mapped = any_mapped || o.mapped(n);
    if (t.has_column(column)) {
      g.columns.push_back(t.column_index(column));
      g.file_names.push_back(column);
    } else {
      missing.push_back(o.mapped(n) ? n + "=" + column : n);
    }
  }
  if (missing.empty()) return g;
  if (g.columns.empty() && !any_mapped) return {};
  // Some of the group found, or a mapped column absent: the file does not have what was said.
  std::string available;
  for (const std::string& h : t.header()) available += (available.empty() ? "" : ", ") + h;
  throw InputError(t.source() + ": " + what + ": column" + (missing.size() > 1 ? "s " : " ") + join(missing) +
                       " not found (give it with --map NAME=COLUMN); the file's columns are: " + available,
                   t.source(), 1, missing.front());
}

// A group given as one map entry "NAME=A+B+C+D": the columns in the order `order` names them.
Group find_joined_group(const CsvTable& t, const ImportOptions& o, const std::string& key, std::size_t count,
                        const std::string& what) {
  if (!o.mapped(key)) return {};
  const std::vector<std::string> parts = split_plus(o.column_for(key));
  if (parts.size() != count)
    throw ArgumentError("--map " + key + "=" + o.column_for(key) + ": expected " + std::to_string(count) +
                        " columns joined by '+' (" + what + ")");
  Group g;
  for (const std::string& p : parts) {
    g.columns.push_back(t.column_index(p));
    g.file_names.push_back(p);
  }
  return g;
}

// Reorders a joined quaternion group to w, x, y, z.
Group quaternion_wxyz(Group g, QuaternionOrder order) {
  if (g.present() && order == QuaternionOrder::xyzw) {
    std::rotate(g.columns.begin(), g.columns.begin() + 3, g.columns.end());
    std::rotate(g.file_names.begin(), g.file_names.begin() + 3, g.file_names.end());
  }
  return g;
}

double length_scale(LengthUnit u) {
  return u == LengthUnit::metres ? 1000.0 : 1.0;
}
double angle_scale_deg(AngleUnit u) {
  return u == AngleUnit::radians ? kDegPerRad : 1.0;
}

// A spreadsheet's rounding of a long integer such as a timestamp: "2,02011E+13" (six significant
// digits of a 14-digit number). Such a cell no longer tells the time.
bool spreadsheet_rounded(std::string_view cell) {
  const std::size_t e = cell.find_first_of("eE");
  if (e == std::string_view::npos || e == 0) return false;
  int exponent = 0;
  std::string_view exp_text = cell.substr(e + 1);
  if (!exp_text.empty() && exp_text.front() == '+') exp_text.remove_prefix(1);
  const auto r = std::from_chars(exp_text.data(), exp_text.data() + exp_text.size(), exponent);
  if (r.ec != std::errc() || r.ptr != exp_text.data() + exp_text.size()) return false;
  std::size_t digits = 0;
  for (char c : cell.substr(0, e)) digits += c >= '0' && c <= '9';
  return exponent >= 9 && digits <= 15 && static_cast<int>(digits) <= exponent;
}

struct Orientation {
  enum class Kind { none, euler_by_axis, euler_by_sequence, quaternion } kind = Kind::none;
  Group group;
};

Orientation find_orientation(const CsvTable& t, const ImportOptions& o, const std::vector<std::string>& by_axis,
                             const std::vector<std::string>* by_sequence, const std::vector<std::string>& quaternion,
                             const std::string& joined_quaternion, const std::string& what) {
  std::vector<Orientation> found;
  if (Group g = find_group(t, o, by_axis, what + " (Euler angles by axis)"); g.present())
    found.push_back({Orientation::Kind::euler_by_axis, g});
  if (by_sequence)
    if (Group g = find_group(t, o, *by_sequence, what + " (Euler angles in sequence order)"); g.present())
      found.push_back({Orientation::Kind::euler_by_sequence, g});
  if (Group g = find_group(t, o, quaternion, what + " (quaternion)"); g.present())
    found.push_back({Orientation::Kind::quaternion, g});
  if (Group g = quaternion_wxyz(find_joined_group(t, o, joined_quaternion, 4, "a quaternion"), o.quaternion);
      g.present())
    found.push_back({Orientation::Kind::quaternion, g});
  if (found.size() > 1)
    throw InputError(t.source() + ": " + what + " is given " + std::to_string(found.size()) +
                         " ways (Euler angles and a quaternion?); map one",
                     t.source(), 1, found[1].group.file_names.front());
  if (found.empty()) return {};
  if (found.front().kind == Orientation::Kind::euler_by_axis && !o.euler.tait_bryan())
    throw ArgumentError("--euler " + o.euler.name() + " turns twice about one axis: name its angles mr1,mr2,mr3 " +
                        "(in the sequence's order), not " + join(by_axis));
  return found.front();
}

Eigen::Matrix3d read_rotation(const CsvTable& t, std::size_t r, const Orientation& orientation,
                              const ImportOptions& o) {
  const Group& g = orientation.group;
  if (orientation.kind == Orientation::Kind::quaternion) {
    double v[4];
    for (int k = 0; k < 4; ++k) v[k] = decimal_cell(t, r, g.columns[static_cast<std::size_t>(k)], o.decimal);
    const Eigen::Quaterniond q(v[0], v[1], v[2], v[3]);
    if (!(std::abs(q.norm() - 1.0) <= 1e-3))
      throw InputError(line_of(t, r) + ": the quaternion " + join(g.file_names) + " has norm " + format_number(q.norm()) +
                           ", not 1 (is the order right? w first or last: --quaternion)",
                       t.source(), t.line_of_row(r), g.file_names.front());
    return q.normalized().toRotationMatrix();
  }
  Eigen::Vector3d in_sequence;
  for (int k = 0; k < 3; ++k) {
    // By axis: the sequence's k-th angle is the one about its k-th axis.
    const std::size_t at = orientation.kind == Orientation::Kind::euler_by_axis
                               ? static_cast<std::size_t>(o.euler.axes[static_cast<std::size_t>(k)])
                               : static_cast<std::size_t>(k);
    in_sequence[k] = decimal_cell(t, r, g.columns[at], o.decimal) * angle_scale_deg(o.angle_unit) / kDegPerRad;
  }
  return o.euler.rotation(in_sequence);
}

void check_lengths(const CsvTable& t, const std::vector<Eigen::Vector3d>& points, LengthUnit unit,
                   const std::string& what, const std::string& option, const ImportOptions& o) {
  if (!o.check_units || points.size() < kRowsForUnitCheck) return;
  double largest = 0.0;
  for (const Eigen::Vector3d& p : points) largest = std::max(largest, p.norm());
  const double in_file = largest / length_scale(unit);
  if (unit == LengthUnit::millimetres && in_file < kFewestMillimetres)
    throw InputError(t.source() + ": " + what + ": every one of " + std::to_string(points.size()) +
                         " positions lies within " + format_number(kFewestMillimetres) +
                         " of the origin (farthest " + format_number(in_file) +
                         "), read as mm: metres? Give " + option + " m (or --no-unit-check if they are mm)",
                     t.source());
  if (unit == LengthUnit::metres && in_file > kMostMetres)
    throw InputError(t.source() + ": " + what + ": a position " + format_number(in_file) +
                         " from the origin, read as metres: millimetres? Give " + option +
                         " mm (or --no-unit-check if they are metres)",
                     t.source());
}

void check_joints(const CsvTable& t, const std::vector<std::array<double, 6>>& joints, const ImportOptions& o) {
  if (!o.check_units || joints.empty()) return;
  double largest = 0.0;
  for (const auto& q : joints)
    for (double v : q) largest = std::max(largest, std::abs(v));
  const double in_file = largest / angle_scale_deg(o.joint_unit);
  if (o.joint_unit == AngleUnit::degrees && joints.size() >= kRowsForUnitCheck && in_file < 2 * std::numbers::pi)
    throw InputError(t.source() + ": every joint value of " + std::to_string(joints.size()) +
                         " rows lies within +-2 pi (largest |q| " + format_number(in_file) +
                         "), read as degrees: radians? Give --joint-units rad (or --no-unit-check if they are degrees)",
                     t.source());
  if (o.joint_unit == AngleUnit::radians && in_file > 4 * std::numbers::pi)
    throw InputError(t.source() + ": a joint value of " + format_number(in_file) +
                         " read as radians is more than two turns: degrees? Give --joint-units deg (or --no-unit-check)",
                     t.source());
}

}  // namespace

const std::vector<std::string>& mappable_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    for (const auto* group : {&kJoints, &kMeasured, &kTarget, &kDifference, &kEulerByAxis, &kEulerBySequence,
                              &kQuaternion, &kFlangePosition, &kFlangeQuaternion, &kFlangeEuler})
      n.insert(n.end(), group->begin(), group->end());
    for (const char* s : {"mq", "flange_q", "temperature_c", "time", "point"}) n.emplace_back(s);
    return n;
  }();
  return names;
}

void ImportOptions::validate() const {
  std::set<std::string> seen;
  for (const auto& [name, column] : columns) {
    const auto& names = mappable_names();
    if (std::find(names.begin(), names.end(), name) == names.end()) {
      std::string hint;
      if (name.size() == 2 && name[0] == 'q' && name[1] >= '7' && name[1] <= '9')
        hint = " (errfield's robots have 6 axes: a 7-axis arm cannot be read)";
      throw ArgumentError("--map: '" + name + "' is not one of errfield's names" + hint + "; expected " +
                          join(names));
    }
    if (!seen.insert(name).second) throw ArgumentError("--map: '" + name + "' is mapped twice");
    if (column.empty()) throw ArgumentError("--map: '" + name + "=' names no column");
  }
  if (decimal != '.' && decimal != ',')
    throw ArgumentError(std::string("--decimal: '") + decimal + "'; expected '.' or ','");
  if (separator != 0 && separator == decimal)
    throw ArgumentError(std::string("--sep and --decimal are both '") + decimal +
                        "': a file with decimal commas separates its cells with ';' (--sep ';')");
}

std::string ImportOptions::column_for(std::string_view name) const {
  for (const auto& [n, column] : columns)
    if (n == name) return column;
  return std::string(name);
}

bool ImportOptions::mapped(std::string_view name) const {
  return std::any_of(columns.begin(), columns.end(), [&](const auto& c) { return c.first == name; });
}

double decimal_cell(const CsvTable& t, std::size_t row, std::size_t column, char decimal) {
  const std::string_view text = t.cell(row, column);
  const std::string& name = t.header()[column];
  const auto fail = [&](const std::string& what) {
    throw InputError(line_of(t, row) + ": column '" + name + "'" + what, t.source(), t.line_of_row(row), name);
  };
  if (text.empty()) fail(" is empty; expected a number");
  const char other = decimal == ',' ? '.' : ',';
  if (text.find(other) != std::string_view::npos)
    fail(": '" + std::string(text) + "' has a decimal " + (other == ',' ? "comma" : "point") + " in a file read with " +
         (decimal == ',' ? "decimal commas (--decimal ,)" : "decimal points (--decimal .)") + "; give --decimal " +
         other + (other == ',' ? " (and --sep ';')" : ""));
  std::string s(text);
  if (decimal == ',') std::replace(s.begin(), s.end(), ',', '.');
  const char* first = s.data();
  const char* last = s.data() + s.size();
  if (*first == '+') ++first;
  double v = 0.0;
  const auto res = std::from_chars(first, last, v);
  if (res.ec != std::errc() || res.ptr != last) fail(": '" + std::string(text) + "' is not a number");
  if (!std::isfinite(v)) fail(": '" + std::string(text) + "' is not a finite number");
  return v;
}

CsvTable read_foreign_csv(const std::string& path, char separator) {
  if (separator == 0) return CsvTable::read(path);
  if (separator == '"' || separator == '\n' || separator == '\r')
    throw ArgumentError("--sep: a quote or a line break cannot separate cells");
  // CsvTable splits at ',' or ';' as its header line says; another separator (or ';' in a header
  // that also holds commas) is re-written line for line as ',' CSV first, so that its reader's
  // quoting, limits and line numbers hold unchanged.
  std::string text;
  {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path + ": cannot open for reading", path);
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) throw InputError(path + ": is a directory, not a CSV file", path);
    std::ostringstream buffer;
    buffer << in.rdbuf();
    text = buffer.str();
    if (text.size() > CsvTable::kMaxInputBytes)
      throw ResourceError(path + ": the file holds more than " + std::to_string(CsvTable::kMaxInputBytes) +
                          " bytes, the most a CSV input may have; split it or thin it out");
  }
  std::string rewritten;
  rewritten.reserve(text.size() + text.size() / 8);
  std::vector<std::string> cells;
  std::string cell;
  bool quoted = false, cell_was_quoted = false, line_start = true;
  const auto end_cell = [&] {
    if (!cell_was_quoted) {
      const std::size_t a = cell.find_first_not_of(" \t"), b = cell.find_last_not_of(" \t");
      cell = a == std::string::npos ? std::string() : cell.substr(a, b - a + 1);
    }
    cells.push_back(std::move(cell));
    cell.clear();
    cell_was_quoted = false;
  };
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (line_start) {
      // Blank and comment lines are copied as they are (CsvTable skips them; the lines still count).
      const std::size_t eol = std::min(text.find('\n', i), text.size());
      const std::string_view line(text.data() + i, eol - i);
      const std::size_t first = line.find_first_not_of(" \t\r");
      if (first == std::string_view::npos || line[first] == '#') {
        rewritten.append(line);
        rewritten.push_back('\n');
        i = eol;
        continue;
      }
      line_start = false;
    }
    if (quoted) {
      if (c == '"' && i + 1 < text.size() && text[i + 1] == '"') {
        cell.push_back('"');
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        cell.push_back(c);
      }
    } else if (c == '"') {
      quoted = cell_was_quoted = true;
    } else if (c == separator) {
      end_cell();
    } else if (c == '\n') {
      if (!cell.empty() && cell.back() == '\r') cell.pop_back();
      end_cell();
      append_csv_line(rewritten, cells);
      cells.clear();
      line_start = true;
    } else {
      cell.push_back(c);
    }
  }
  if (!line_start) {
    if (!cell.empty() && cell.back() == '\r') cell.pop_back();
    end_cell();
    append_csv_line(rewritten, cells);
  }
  return CsvTable::parse(rewritten, path);
}

std::string ImportedMeasurements::csv() const {
  std::string out;
  append_csv_line(out, header);
  for (const auto& row : rows) append_csv_line(out, row);
  return out;
}

namespace {

constexpr std::size_t kAbsent = static_cast<std::size_t>(-1);

// Where each quantity is in the file: groups of columns, orientations, and the optional single
// columns (their index, or kAbsent).
struct SourceColumns {
  Group joints, measured, target, difference, flange;
  Orientation orientation, flange_orientation;
  bool from_target = false;
  std::size_t temperature = kAbsent, time = kAbsent, point = kAbsent;
};

// Every column the options name or imply, refusing a file that lacks what an import needs.
SourceColumns find_columns(const CsvTable& t, const ImportOptions& o) {
  const std::string& src = t.source();
  SourceColumns c;
  c.joints = find_group(t, o, kJoints, "joints q1..q6");
  c.from_target = o.position_from != PositionFrom::measured;
  const bool from_target = c.from_target;
  c.measured = from_target ? Group{} : find_group(t, o, kMeasured, "measured position mx,my,mz");
  c.target = from_target ? find_group(t, o, kTarget, "target position tx,ty,tz") : Group{};
  c.difference = from_target ? find_group(t, o, kDifference, "difference dx,dy,dz") : Group{};
  if (from_target && (!c.target.present() || !c.difference.present()))
    throw InputError(src + ": --position-from " +
                         (o.position_from == PositionFrom::target_plus_difference ? "target+dif" : "target-dif") +
                         " needs the target tx,ty,tz and the difference dx,dy,dz (map them with --map tx=COLUMN,...)",
                     src, 1, c.target.present() ? "dx" : "tx");
  if (!from_target && !c.measured.present())
    throw InputError(src + ": no measured position: map mx,my,mz (--map mx=COLUMN,...), or a target and a difference "
                         "(tx..tz, dx..dz with --position-from target+dif or target-dif)",
                     src, 1, "mx");
  c.orientation = find_orientation(t, o, kEulerByAxis, &kEulerBySequence, kQuaternion, "mq", "measured orientation");
  c.flange = find_group(t, o, kFlangePosition, "flange position flange_x..flange_z");
  c.flange_orientation =
      find_orientation(t, o, kFlangeEuler, nullptr, kFlangeQuaternion, "flange_q", "flange orientation");
  if (c.flange.present() != (c.flange_orientation.kind != Orientation::Kind::none))
    throw InputError(src + ": a flange pose needs its position and its orientation (flange_x..flange_z and "
                         "flange_qw..flange_qz or flange_rx..flange_rz)",
                     src, 1, c.flange.present() ? "flange_qw" : "flange_x");
  if (!c.joints.present() && !c.flange.present()) {
    std::string available;
    for (const std::string& h : t.header()) available += (available.empty() ? "" : ", ") + h;
    throw InputError(src + ": no joints q1..q6 (map them: --map q1=COLUMN,...,q6=COLUMN) and no flange pose; the "
                         "file's columns are: " + available,
                     src, 1, "q1");
  }
  const auto optional_column = [&](const char* name) {
    return t.has_column(o.column_for(name)) ? t.column_index(o.column_for(name)) : kAbsent;
  };
  c.temperature = optional_column("temperature_c");
  c.time = optional_column("time");
  c.point = optional_column("point");
  for (const char* name : {"temperature_c", "time", "point"})
    if (o.mapped(name)) (void)t.column_index(o.column_for(name));  // a mapped column must exist: say which
  return c;
}

// Timestamps a spreadsheet rounded are dropped whole: some rows' times and not others' would be
// worse than none. Returns the time column to keep (kAbsent when dropped), noting why in `notes`.
std::size_t time_column_kept(const CsvTable& t, std::size_t time, std::vector<std::string>& notes) {
  if (time == kAbsent) return time;
  std::size_t rounded = 0;
  std::string example;
  for (std::size_t r = 0; r < t.row_count(); ++r)
    if (spreadsheet_rounded(t.cell(r, time))) {
      if (rounded++ == 0) example = std::string(t.cell(r, time));
    }
  if (rounded == 0) return time;
  notes.push_back("column '" + t.header()[time] + "' dropped: " + std::to_string(rounded) + " of " +
                  std::to_string(t.row_count()) + " cells are a spreadsheet's rounding ('" + example +
                  "': a few significant digits of a long number), not a time");
  return kAbsent;
}

struct RowValues {
  std::array<double, 6> q{};
  Eigen::Vector3d position, flange_position;
  Eigen::Matrix3d rotation, flange_rotation;
};

// Every row's numbers in errfield's units (mm, degrees), checked as a whole for units that look
// wrong before anything is written.
std::vector<RowValues> read_values(const CsvTable& t, const ImportOptions& o, const SourceColumns& c) {
  std::vector<std::array<double, 6>> all_joints;
  std::vector<Eigen::Vector3d> positions, flange_positions;
  std::vector<RowValues> values(t.row_count());
  const double length = length_scale(o.length_unit);
  for (std::size_t r = 0; r < t.row_count(); ++r) {
    RowValues& v = values[r];
    if (c.joints.present()) {
      for (std::size_t j = 0; j < 6; ++j)
        v.q[j] = decimal_cell(t, r, c.joints.columns[j], o.decimal) * angle_scale_deg(o.joint_unit);
      all_joints.push_back(v.q);
    }
    for (int k = 0; k < 3; ++k) {
      const auto i = static_cast<std::size_t>(k);
      if (c.from_target) {
        const double sign = o.position_from == PositionFrom::target_plus_difference ? 1.0 : -1.0;
        v.position[k] = (decimal_cell(t, r, c.target.columns[i], o.decimal) +
                         sign * decimal_cell(t, r, c.difference.columns[i], o.decimal)) *
                        length;
      } else {
        v.position[k] = decimal_cell(t, r, c.measured.columns[i], o.decimal) * length;
      }
    }
    positions.push_back(v.position);
    if (c.orientation.kind != Orientation::Kind::none) v.rotation = read_rotation(t, r, c.orientation, o);
    if (c.flange.present()) {
      for (int k = 0; k < 3; ++k)
        v.flange_position[k] = decimal_cell(t, r, c.flange.columns[static_cast<std::size_t>(k)], o.decimal) *
                               length_scale(o.flange_length_unit);
      flange_positions.push_back(v.flange_position);
      v.flange_rotation = read_rotation(t, r, c.flange_orientation, o);
    }
  }
  check_joints(t, all_joints, o);
  check_lengths(t, positions, o.length_unit, "measured positions", "--length-units", o);
  if (c.flange.present()) check_lengths(t, flange_positions, o.flange_length_unit, "flange positions", "--flange-length-units", o);
  return values;
}

std::vector<std::string> output_header(const SourceColumns& c, const ImportOptions& o) {
  std::vector<std::string> header = {"point"};
  if (c.joints.present()) header.insert(header.end(), kJoints.begin(), kJoints.end());
  header.insert(header.end(), kMeasured.begin(), kMeasured.end());
  if (c.orientation.kind != Orientation::Kind::none) header.insert(header.end(), kEulerByAxis.begin(), kEulerByAxis.end());
  if (c.flange.present()) {
    header.insert(header.end(), kFlangePosition.begin(), kFlangePosition.end());
    header.insert(header.end(), kFlangeEuler.begin(), kFlangeEuler.end());
  }
  if (c.temperature != kAbsent) header.emplace_back("temperature_c");
  if (c.time != kAbsent) header.emplace_back("time");
  if (!o.series.empty()) header.emplace_back("series");
  return header;
}

// A time cell: a number (a timestamp such as 20200714163904, seconds) in errfield's decimal point;
// any other text (an ISO date) as given.
std::string time_text(std::string_view cell, char decimal) {
  std::string text(cell);
  if (decimal == ',') std::replace(text.begin(), text.end(), ',', '.');
  double seconds = 0.0;
  const auto res = std::from_chars(text.data(), text.data() + text.size(), seconds);
  return res.ec == std::errc() && res.ptr == text.data() + text.size() && std::isfinite(seconds) &&
                 cell.find_first_of("eE") == std::string_view::npos
             ? text
             : std::string(cell);
}

// The point's name: the file's, or the row's number; names must be present and unique.
std::string point_name(const CsvTable& t, std::size_t r, std::size_t point,
                       std::map<std::string, std::size_t>& line_of_point) {
  const std::string& src = t.source();
  std::string name = point != kAbsent ? std::string(t.cell(r, point)) : std::to_string(r + 1);
  if (name.empty())
    throw InputError(line_of(t, r) + ": column '" + t.header()[point] + "' is empty; expected the point's name", src,
                     t.line_of_row(r), t.header()[point]);
  if (const auto [it, fresh] = line_of_point.emplace(name, t.line_of_row(r)); !fresh)
    throw InputError(line_of(t, r) + ": point '" + name + "' again (first on line " + std::to_string(it->second) +
                         "); every row needs its own point name",
                     src, t.line_of_row(r), point != kAbsent ? t.header()[point] : "point");
  return name;
}

std::vector<std::string> output_row(const CsvTable& t, std::size_t r, const RowValues& v, const SourceColumns& c,
                                    const ImportOptions& o, std::string name, std::size_t width) {
  std::vector<std::string> row;
  row.reserve(width);
  row.push_back(std::move(name));
  if (c.joints.present())
    for (double q : v.q) row.push_back(format_number(q));
  for (int k = 0; k < 3; ++k) row.push_back(format_number(v.position[k]));
  if (c.orientation.kind != Orientation::Kind::none) {
    const Eigen::Vector3d rpy = robot::rpy_deg_from_rotation(v.rotation);
    for (int k = 0; k < 3; ++k) row.push_back(format_number(rpy[k]));
  }
  if (c.flange.present()) {
    for (int k = 0; k < 3; ++k) row.push_back(format_number(v.flange_position[k]));
    const Eigen::Vector3d rpy = robot::rpy_deg_from_rotation(v.flange_rotation);
    for (int k = 0; k < 3; ++k) row.push_back(format_number(rpy[k]));
  }
  if (c.temperature != kAbsent) row.push_back(format_number(decimal_cell(t, r, c.temperature, o.decimal)));
  if (c.time != kAbsent) row.push_back(time_text(t.cell(r, c.time), o.decimal));
  if (!o.series.empty()) row.push_back(o.series);
  return row;
}

}  // namespace

ImportedMeasurements import_measurements(const CsvTable& t, const ImportOptions& o) {
  o.validate();
  const std::string& src = t.source();
  if (t.row_count() == 0) throw InputError(src + ": no data rows below the header", src);
  SourceColumns columns = find_columns(t, o);
  ImportedMeasurements out;
  out.notes = o.notes;
  columns.time = time_column_kept(t, columns.time, out.notes);
  const std::vector<RowValues> values = read_values(t, o, columns);
  out.header = output_header(columns, o);
  std::map<std::string, std::size_t> line_of_point;
  out.rows.reserve(t.row_count());
  for (std::size_t r = 0; r < t.row_count(); ++r) {
    std::string name = point_name(t, r, columns.point, line_of_point);
    out.rows.push_back(output_row(t, r, values[r], columns, o, std::move(name), out.header.size()));
  }
  return out;
}

}  // namespace errfield::readers
