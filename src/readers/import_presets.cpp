// The named presets of import-measurements: the two public laser-tracker data sets errfield is
// developed with (docs/realdata.md says what each is and how the choices below were checked).

#include <string>

#include "errfield/error.hpp"
#include "errfield/readers/measurement_import.hpp"

namespace errfield::readers {

namespace {

ImportOptions ur5_jacobi(const CsvTable& t) {
  // The Barrett WAM files of the same data set have joint_7: refuse by name rather than read six
  // of its seven joints.
  std::string extra;
  for (int j = 7; j <= 9; ++j)
    if (t.has_column("joint_" + std::to_string(j))) extra += (extra.empty() ? "" : ", ") + ("joint_" + std::to_string(j));
  if (!extra.empty())
    throw InputError(t.source() + ": joint columns joint_1 .. " + extra.substr(extra.rfind(' ') + 1) +
                         ": a 7-axis arm (the Barrett WAM of this data set); errfield's robots have 6 axes (q1..q6), "
                         "so these rows cannot be read as one of its robots' joints",
                     t.source(), 1, "joint_7");
  ImportOptions o;
  o.separator = ',';
  o.decimal = '.';
  o.columns = {{"point", "step_order"}, {"tx", "x_t"}, {"ty", "y_t"}, {"tz", "z_t"},
               {"dx", "x_dif"},         {"dy", "y_dif"}, {"dz", "z_dif"}};
  for (int j = 1; j <= 6; ++j) o.columns.emplace_back("q" + std::to_string(j), "joint_" + std::to_string(j));
  o.joint_unit = AngleUnit::degrees;
  o.length_unit = LengthUnit::millimetres;
  // The data set's README calls *_dif "the difference between target and achieved position";
  // its sign was decided from the data: measured = target + dif leaves the smaller residual to a
  // kinematic fit on both robots' grids and makes the gravity sag point down (docs/realdata.md).
  o.position_from = PositionFrom::target_plus_difference;
  o.notes.push_back("preset ur5-jacobi: measured position = x_t,y_t,z_t + x_dif,y_dif,z_dif (mm, the robot base frame "
                    "the data set registered its tracker to; sign checked on the data, docs/realdata.md); joints "
                    "joint_1..joint_6 in degrees; point = step_order");
  return o;
}

ImportOptions ur10_ipa(const CsvTable& t) {
  ImportOptions o;
  o.separator = ';';
  o.decimal = ',';
  // The T-Mac's orientation: dataset.py builds it with scipy's Rotation.from_euler('XYZ', ...,
  // degrees=True), upper case = intrinsic: R = Rx(rx)·Ry(ry)·Rz(rz).
  o.euler = EulerConvention::parse("XYZ-intrinsic");
  o.angle_unit = AngleUnit::degrees;
  o.length_unit = LengthUnit::millimetres;
  o.columns = {{"mx", "measurement_x"},   {"my", "measurement_y"},   {"mz", "measurement_z"},
               {"mrx", "measurement_rx"}, {"mry", "measurement_ry"}, {"mrz", "measurement_rz"}};
  if (t.has_column("flange_x")) {
    // calibration_handeye.csv: the flange pose in the robot base frame (m, quaternion x,y,z,w as
    // scipy's from_quat in dataset.py) beside the T-Mac's measured pose.
    o.flange_length_unit = LengthUnit::metres;
    for (const char* axis : {"x", "y", "z"}) o.columns.emplace_back(std::string("flange_") + axis, std::string("flange_") + axis);
    for (const char* part : {"qw", "qx", "qy", "qz"}) o.columns.emplace_back(std::string("flange_") + part, std::string("flange_") + part);
    o.notes.push_back("preset ur10-ipa (hand-eye registration set): flange_x..flange_z (m) and flange_qx..flange_qw "
                      "(robot base frame) written as flange_x..flange_z mm and flange_rx..flange_rz deg (fixed-axis "
                      "XYZ); measurement_rx..rz read as Euler 'XYZ' intrinsic degrees (dataset.py) and written as "
                      "errfield's fixed-axis mrx,mry,mrz");
    return o;
  }
  const char* joints[6] = {"shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
                           "wrist_1_joint",      "wrist_2_joint",       "wrist_3_joint"};
  for (int j = 0; j < 6; ++j) o.columns.emplace_back("q" + std::to_string(j + 1), joints[j]);
  o.joint_unit = AngleUnit::radians;
  o.columns.emplace_back("temperature_c", "measurement_temperature");
  o.columns.emplace_back("time", "Timestamp");
  o.notes.push_back("preset ur10-ipa: ';' separated, decimal commas; joints shoulder_pan_joint..wrist_3_joint in "
                    "radians; measurement_x..z mm (tracker frame); measurement_rx..rz read as Euler 'XYZ' intrinsic "
                    "degrees (dataset.py) and written as errfield's fixed-axis mrx,mry,mrz; temperature_c = "
                    "measurement_temperature; time = Timestamp");
  return o;
}

}  // namespace

std::string preset_names() {
  return "ur5-jacobi, ur10-ipa";
}

char preset_separator(std::string_view preset) {
  if (preset == "ur5-jacobi") return ',';
  if (preset == "ur10-ipa") return ';';
  throw ArgumentError("--preset: '" + std::string(preset) + "'; expected one of " + preset_names());
}

ImportOptions preset_options(std::string_view preset, const CsvTable& table) {
  if (preset == "ur5-jacobi") return ur5_jacobi(table);
  if (preset == "ur10-ipa") return ur10_ipa(table);
  throw ArgumentError("--preset: '" + std::string(preset) + "'; expected one of " + preset_names());
}

}  // namespace errfield::readers
