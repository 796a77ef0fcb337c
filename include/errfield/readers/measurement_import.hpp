#pragma once
/// Foreign measurement files (a tracker's or a controller's CSV export, a published data set) read
/// as they come and rewritten as errfield's measurement CSV, the file `errfield fit` reads
/// (docs/data-formats.md, "Measurements"): `point,q1..q6` (deg), `mx,my,mz` (mm, tracker frame),
/// `mrx,mry,mrz` (deg, fixed-axis XYZ: R = Rz·Ry·Rx) and the extra columns `temperature_c`, `time`,
/// `series`. Use it at the edge: `errfield import-measurements` is this adapter's command, and
/// docs/realdata.md shows it on the two real data sets errfield is developed with.
///
/// What a foreign file may differ in, each an ImportOptions member: the separator and the decimal
/// mark (`;` and `0,5`), the column names (a map from errfield's names to the file's), joint units
/// (deg, rad), lengths (mm, m), the orientation's convention (Euler sequence, intrinsic or
/// extrinsic, degrees or radians; quaternion w first or last), and a position given as a commanded
/// position plus or minus a measured difference. Rows with a flange pose instead of joints (a
/// hand-eye registration set) become registration readings: the measurement columns plus
/// `flange_x,flange_y,flange_z` (mm, robot base frame) and `flange_rx,flange_ry,flange_rz` (deg,
/// fixed-axis XYZ).
///
/// Every bad cell is refused with file, line, column and value (a decimal comma in a '.' file, a
/// missing column, a non-finite number); so are units that do not fit the numbers (joints all
/// within ±2π given as degrees: radians?; positions all within 10 of the origin given as mm:
/// metres?), unless the check is switched off.

#include <cstddef>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "errfield/csv_table.hpp"
#include "errfield/readers/orientation_conventions.hpp"

namespace errfield::readers {

enum class AngleUnit { degrees, radians };
enum class LengthUnit { millimetres, metres };
/// Where the measured position comes from: its own columns, or a commanded (target) position and
/// a difference, measured = target + difference or target − difference.
enum class PositionFrom { measured, target_plus_difference, target_minus_difference };

/// errfield's names a column map may assign (`q1=joint_1`): joints q1..q6; measured position
/// mx,my,mz; or target tx,ty,tz and difference dx,dy,dz (with PositionFrom::target_*); the
/// orientation as Euler angles by axis (mrx,mry,mrz: the angle about x, y, z; Tait–Bryan
/// sequences) or by place in the sequence (mr1,mr2,mr3), or a quaternion (mqw,mqx,mqy,mqz, or
/// mq=A+B+C+D in the order of ImportOptions::quaternion); the flange pose of a registration row
/// (flange_x,flange_y,flange_z and flange_qw..flange_qz, flange_q=A+B+C+D or flange_rx..flange_rz);
/// temperature_c, time, point.
const std::vector<std::string>& mappable_names();

struct ImportOptions {
  char separator = 0;  ///< 0: ',' or ';' detected from the header line.
  char decimal = '.';  ///< '.' or ','.
  /// errfield name -> the file's column (mappable_names()). A name not mapped is looked up under
  /// its own name in the file (a file already in errfield's names needs no map).
  std::vector<std::pair<std::string, std::string>> columns;
  AngleUnit joint_unit = AngleUnit::degrees;
  AngleUnit angle_unit = AngleUnit::degrees;  ///< of Euler angles (measured and flange)
  LengthUnit length_unit = LengthUnit::millimetres;         ///< measured, target, difference
  LengthUnit flange_length_unit = LengthUnit::millimetres;  ///< flange position
  EulerConvention euler;                                    ///< default xyz-extrinsic: errfield's
  QuaternionOrder quaternion = QuaternionOrder::wxyz;       ///< order of an `mq=A+B+C+D` map entry
  PositionFrom position_from = PositionFrom::measured;
  std::string series;  ///< written in a `series` column on every row when not empty
  bool check_units = true;
  /// Lines said once in the output's notes (what a preset chose and why).
  std::vector<std::string> notes;

  /// Throws ArgumentError for an unknown name or a name mapped twice, a decimal mark other than
  /// '.' or ',', a decimal mark equal to the separator.
  void validate() const;
  /// The column the file holds errfield's `name` under: the map's, else `name` itself.
  std::string column_for(std::string_view name) const;
  bool mapped(std::string_view name) const;
};

/// The options a named preset stands for, for a file with this header: "ur5-jacobi" (the UR5
/// files of github.com/pauljac7700/serial_robots_datasets; a 7-joint file, the WAM, is refused
/// naming its joint columns, since errfield's robots have 6 axes) or "ur10-ipa" (the UR10 series
/// of github.com/christianlandgraf/ipa-robot-accuracy and their calibration_handeye.csv files).
/// docs/realdata.md says what each chooses and how it was checked. Throws ArgumentError for an
/// unknown name, InputError (naming the file) for a file the preset does not describe.
ImportOptions preset_options(std::string_view preset, const CsvTable& table);
/// The separator a preset's files use (0: detect).
char preset_separator(std::string_view preset);
/// "ur10-ipa, ur5-jacobi" for messages.
std::string preset_names();

/// Reads a foreign CSV file split at `separator` (any character but a quote or a line break; 0:
/// ',' or ';' detected from the header line, as CsvTable::read does). Quoting, comments, limits
/// and the messages' line numbers are CsvTable's.
CsvTable read_foreign_csv(const std::string& path, char separator);

/// A file rewritten in errfield's columns.
struct ImportedMeasurements {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  /// What the reading decided (dropped columns, conventions applied), one sentence each.
  std::vector<std::string> notes;
  /// The CSV text (header, rows), cells written so that CsvTable reads them back exactly.
  std::string csv() const;
};

/// Reads `table` (already split by the options' separator) as `options` say. Throws InputError
/// naming file, line, column and value for a bad cell, a missing column or units that do not fit.
ImportedMeasurements import_measurements(const CsvTable& table, const ImportOptions& options);

/// A cell as a number with decimal mark `decimal`: "0,5" with ',' and "0.5" with '.' are 0.5.
/// Throws InputError naming the table's file, line, column and the cell (a comma in a '.' file
/// says so), for an empty, non-numeric or non-finite cell.
double decimal_cell(const CsvTable& table, std::size_t row, std::size_t column, char decimal);

}  // namespace errfield::readers
