#include "errfield/compensation/tools/probe_readings.hpp"

#include <cmath>
#include <vector>

#include <Eigen/Geometry>

#include "errfield/error.hpp"
#include "errfield/robot/pose.hpp"

namespace errfield::compensation {

namespace {

const std::vector<std::string> kAngleColumns = {"mrx", "mry", "mrz"};
constexpr double kMaxProbeAngleDeg = 720.0;  // two turns: any unwrapped angle a tracker writes
const std::vector<std::string> kQuaternionColumns = {"mqw", "mqx", "mqy", "mqz"};

bool has_all(const CsvTable& t, const std::vector<std::string>& names) {
  for (const std::string& n : names)
    if (!t.has_column(n)) return false;
  return true;
}

bool has_any(const CsvTable& t, const std::vector<std::string>& names) {
  for (const std::string& n : names)
    if (t.has_column(n)) return true;
  return false;
}

/// Every orientation column of the chosen spelling (`names`), and the position beside them.
void require_probe_columns(const CsvTable& table, const std::vector<std::string>& names, bool angles) {
  const std::string& source = table.source();
  if (!has_all(table, names)) {
    std::string missing;
    for (const std::string& n : names)
      if (!table.has_column(n)) missing += (missing.empty() ? "" : ",") + n;
    throw InputError(source + ": the probe's orientation needs columns " + (angles ? "mrx,mry,mrz" : "mqw,mqx,mqy,mqz") +
                         "; missing " + missing,
                     source, 0, missing);
  }
  for (const char* n : {"mx", "my", "mz"})
    if (!table.has_column(n))
      throw InputError(source + ": probe orientation without its position: column '" + std::string(n) + "' missing",
                       source, 0, n);
}

/// The probe's rotation in row r, from its angles (deg) or its unit quaternion (w first).
Eigen::Matrix3d probe_rotation(const CsvTable& table, std::size_t r, const std::vector<std::string>& names,
                               const std::vector<std::size_t>& orientation_col, bool angles) {
  const std::string& source = table.source();
  const std::string line = source + ":" + std::to_string(table.line_of_row(r));
  if (angles) {
    double a[3];
    for (int k = 0; k < 3; ++k) {
      a[k] = table.numeric_cell(r, orientation_col[static_cast<std::size_t>(k)]);
      // An angle far beyond a turn (1e300) is no tracker's output: its sine is rounding noise, a
      // rotation that was accepted and then failed later without a line.
      if (!(std::abs(a[k]) <= kMaxProbeAngleDeg))
        throw InputError(line + ": column " + names[static_cast<std::size_t>(k)] + " = " + format_number(a[k]) +
                             " deg; expected a probe angle in degrees within +-" + format_number(kMaxProbeAngleDeg),
                         source, table.line_of_row(r), names[static_cast<std::size_t>(k)]);
    }
    return robot::rotation_from_rpy_deg(a[0], a[1], a[2]);
  }
  double v[4];
  for (int k = 0; k < 4; ++k) v[k] = table.numeric_cell(r, orientation_col[static_cast<std::size_t>(k)]);
  const Eigen::Quaterniond q(v[0], v[1], v[2], v[3]);
  if (!(std::abs(q.norm() - 1.0) <= 1e-3))
    throw InputError(line + ": the quaternion mqw,mqx,mqy,mqz has norm " + format_number(q.norm()) +
                         ", not 1 (a probe's orientation is a unit quaternion, w first)",
                     source, table.line_of_row(r), "mqw");
  return q.normalized().toRotationMatrix();
}

}  // namespace

bool has_probe_orientation(const CsvTable& table) {
  return has_any(table, kAngleColumns) || has_any(table, kQuaternionColumns);
}

CsvTable expand_probe_readings(const CsvTable& table) {
  if (!has_probe_orientation(table)) return table;
  const std::string& source = table.source();
  const bool angles = has_any(table, kAngleColumns), quaternion = has_any(table, kQuaternionColumns);
  if (angles && quaternion)
    throw InputError(source + ": both mrx,mry,mrz and mqw,mqx,mqy,mqz: give the probe's orientation one way", source, 0,
                     "mrx");
  const std::vector<std::string>& names = angles ? kAngleColumns : kQuaternionColumns;
  require_probe_columns(table, names, angles);
  std::vector<std::size_t> orientation_col, position_col;
  for (const std::string& n : names) orientation_col.push_back(table.column_index(n));
  for (const char* n : {"mx", "my", "mz"}) position_col.push_back(table.column_index(n));
  const bool labelled = table.has_column("reflector");
  // The new header: every column but the orientation's, and `reflector` (added last if absent).
  std::vector<std::string> header;
  std::vector<std::size_t> kept;
  for (std::size_t c = 0; c < table.header().size(); ++c) {
    bool orientation = false;
    for (std::size_t o : orientation_col) orientation = orientation || o == c;
    if (orientation) continue;
    header.push_back(table.header()[c]);
    kept.push_back(c);
  }
  if (!labelled) header.push_back("reflector");
  const std::size_t label_at = labelled ? [&] {
    for (std::size_t k = 0; k < kept.size(); ++k)
      if (kept[k] == table.column_index("reflector")) return k;
    return kept.size();
  }()
                                        : header.size() - 1;
  std::vector<std::size_t> from;
  std::vector<std::vector<std::string>> cells;
  for (std::size_t r = 0; r < table.row_count(); ++r) {
    const std::string line = source + ":" + std::to_string(table.line_of_row(r));
    std::vector<std::string> row;
    for (std::size_t c : kept) row.emplace_back(table.cell(r, c));
    if (!labelled) row.emplace_back("probe");
    const std::string label = row[label_at].empty() ? std::string("probe") : row[label_at];
    std::size_t given = 0;
    for (std::size_t o : orientation_col) given += !table.cell(r, o).empty();
    bool position_given = true;
    for (std::size_t p : position_col) position_given = position_given && !table.cell(r, p).empty();
    if (given == 0 || !position_given) {
      // A row without a probe reading (a base row, a pose not measured): as it is.
      if (given != 0)
        throw InputError(line + ": an orientation without a position (mx,my,mz empty)", source, table.line_of_row(r), "mx");
      row[label_at] = label;
      from.push_back(r);
      cells.push_back(std::move(row));
      continue;
    }
    if (given != orientation_col.size())
      throw InputError(line + ": the probe's orientation is given in part: fill " +
                           (angles ? std::string("mrx,mry,mrz") : std::string("mqw,mqx,mqy,mqz")) + " or none",
                       source, table.line_of_row(r), names.front());
    const Eigen::Matrix3d rotation = probe_rotation(table, r, names, orientation_col, angles);
    Eigen::Vector3d probe;
    for (int k = 0; k < 3; ++k) probe[k] = table.numeric_cell(r, position_col[static_cast<std::size_t>(k)]);
    const Eigen::Vector3d along[2] = {rotation.col(0) * kProbeLeverMm, rotation.col(1) * kProbeLeverMm};
    row[label_at] = label;
    from.push_back(r);
    cells.push_back(row);
    const char* suffix[2] = {"+x", "+y"};
    for (int k = 0; k < 2; ++k) {
      std::vector<std::string> lever = row;
      const Eigen::Vector3d at = probe + along[k];
      for (std::size_t p = 0; p < 3; ++p) {
        std::size_t index = 0;
        for (std::size_t c = 0; c < kept.size(); ++c)
          if (kept[c] == position_col[p]) index = c;
        lever[index] = format_number(at[static_cast<Eigen::Index>(p)]);
      }
      lever[label_at] = label + suffix[k];
      from.push_back(r);
      cells.push_back(std::move(lever));
    }
  }
  return table.derived(std::move(header), from, cells);
}

}  // namespace errfield::compensation
