// errfield.calibrate_positions: kinematic calibration from tracker positions, the path of
// `errfield calibrate --model position` (registration, then MD-H + base + tool). Kept thin: the
// compensation pipeline is being reorganised (errfield::compensation), bind more when it settles.

#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "errfield/error.hpp"
#include "errfield/csv_table.hpp"
#include "errfield/robot/calibration.hpp"
#include "errfield/robot/distance_table.hpp"
#include "errfield/robot/input_checks.hpp"
#include "python/arrays.hpp"
#include "python/bindings.hpp"

namespace errfield::python {

namespace {

using namespace errfield::robot;

/// ArgumentError naming name[i, j] for a joint outside the robot's limits (deg).
void check_joint_limits(const Eigen::MatrixXd& q, const MdhModel& nominal, const std::string& name) {
  for (Eigen::Index i = 0; i < q.rows(); ++i)
    for (int j = 0; j < kJointCount; ++j) {
      const MdhLink& l = nominal.link(j);
      const double v = q(i, j);
      if (v >= l.q_min_deg - 1e-6 && v <= l.q_max_deg + 1e-6) continue;
      throw ArgumentError(name + "[" + std::to_string(i) + ", " + std::to_string(j) + "]: " + std::to_string(v) +
                          " deg is outside the joint limits [" + std::to_string(l.q_min_deg) + ", " +
                          std::to_string(l.q_max_deg) + "] of robot '" + nominal.name() +
                          "'; check units (degrees) and joint order");
    }
}

py::dict result_dict(const CalibrationResult& result, const MdhModel& identified) {
  py::list parameters, removed;
  for (const auto& p : result.parameters) {
    py::dict d;
    d["name"] = p.name;
    d["unit"] = p.unit;
    d["nominal"] = p.nominal;
    d["increment"] = p.increment;
    d["standard_error"] = p.standard_error;
    parameters.append(d);
  }
  for (const auto& r : result.removed) {
    py::dict d;
    d["name"] = r.name;
    d["reason"] = r.reason;
    removed.append(d);
  }
  py::dict out;
  out["robot"] = identified;
  out["parameters"] = parameters;
  out["removed"] = removed;
  out["condition_number"] = result.condition_number;
  out["regularization"] = result.regularization;  // distances: the weight of the penalty toward nominal
  out["rms_before_mm"] = result.before.rms_mm;
  out["rms_after_mm"] = result.after.rms_mm;
  out["max_after_mm"] = result.after.max_abs_mm;
  out["weights"] = to_numpy(result.weights);
  out["rejected"] = result.rejected;
  out["converged"] = result.converged;
  out["message"] = result.message;
  return out;
}

CalibrationOptions calibration_options(bool robust, double k0, double k1, double max_condition) {
  CalibrationOptions options;
  options.robust.enabled = robust;
  options.robust.k0 = k0;
  options.robust.k1 = k1;
  options.max_condition_number = max_condition;
  options.validate();
  return options;
}

py::dict calibrate_positions_py(const MdhModel& nominal, const py::object& q, const py::object& measured, bool robust,
                                double k0, double k1, double max_condition) {
  const MatrixArg joints = matrix_arg(q, "q", ArraySpec{2, 2, kJointCount, 1});
  const MatrixArg m = matrix_arg(measured, "measured", ArraySpec{2, 2, 3, 1});
  if (m.data.rows() != joints.data.rows())
    throw ArgumentError("measured: " + std::to_string(m.data.rows()) + " positions for " +
                        std::to_string(joints.data.rows()) + " joint vectors; expected one per row of q");
  check_joint_limits(joints.data, nominal, "q");
  const CalibrationOptions options = calibration_options(robust, k0, k1, max_condition);
  std::vector<PositionMeasurement> data;
  for (Eigen::Index i = 0; i < joints.data.rows(); ++i)
    data.push_back({joints.data.row(i).transpose(), m.data.row(i).transpose()});
  CalibrationResult reg, result;
  MdhModel identified = nominal;
  {
    py::gil_scoped_release release;
    reg = register_tracker(nominal, data, options);
    result = calibrate_positions(reg.model, data, options);
    // As the CLI: the identified model expressed in the nominal robot's base frame.
    identified = result.model.with_base(nominal.base() * reg.model.base().inverse() * result.model.base())
                     .with_name(nominal.name() + " (calibrated, position model)");
  }
  py::dict out = result_dict(result, identified);
  out["tracker_from_base"] = to_numpy(Eigen::MatrixXd(reg.model.base().matrix()));
  out["report"] = "== registration (tracker <- robot base, reflector offset) ==\n" + reg.report() +
                  "\n== kinematic calibration (position model) ==\n" + result.report();
  return out;
}

py::dict calibrate_distances_py(const py::object& robot, const py::object& data, const py::object& base_points,
                                bool robust, double k0, double k1, double max_condition) {
  const MdhModel nominal = robot_arg(robot);
  const CsvTable table = table_arg(data, "data");
  const CalibrationOptions options = calibration_options(robust, k0, k1, max_condition);
  std::vector<Eigen::Vector3d> fixed;
  if (!base_points.is_none()) {
    const Eigen::MatrixXd b = matrix_arg(base_points, "base_points", ArraySpec{1, 2, 3, 1, true, true}).data;
    for (Eigen::Index i = 0; i < b.rows(); ++i) fixed.emplace_back(b.row(i).transpose());
  }
  const std::vector<std::string> qcols{"q1", "q2", "q3", "q4", "q5", "q6"};
  for (const auto& c : qcols)
    if (!table.has_column(c)) throw InputError("data: needs columns q1..q6 (deg)", "data", 0, c);
  const Eigen::MatrixXd qm = table.numeric_columns(qcols);
  std::vector<JointVector> q(static_cast<std::size_t>(qm.rows()));
  for (Eigen::Index i = 0; i < qm.rows(); ++i) q[static_cast<std::size_t>(i)] = qm.row(i).transpose();
  // The checks of `errfield calibrate --model distance`, in its order.
  check_nominal_positions(table, nominal, !robot.is_none());
  check_joint_limits(qm, nominal, "data[q1..q6]");
  check_distance_columns(table);
  const DistanceTable pairs = distance_measurements_from_table(table, q, nominal, fixed);
  CalibrationResult result;
  {
    py::gil_scoped_release release;
    result = fixed.empty() ? calibrate_distances(nominal, pairs.data, options)
                           : calibrate_distances(nominal, pairs.data, fixed, options);
  }
  py::dict out = result_dict(result, result.model.with_name(nominal.name() + " (calibrated, distance model)"));
  out["fixed_bases"] = to_numpy([&] {
    Eigen::MatrixXd b(static_cast<Eigen::Index>(result.base_points.size()), 3);
    for (std::size_t k = 0; k < result.base_points.size(); ++k)
      b.row(static_cast<Eigen::Index>(k)) = result.base_points[k].position_mm.transpose();
    return b;
  }());
  out["skipped"] = pairs.skipped;
  out["report"] = pairs.note + "== kinematic calibration (distance model, " + std::to_string(result.before.count) +
                  " measurements) ==\n" + result.report();
  return out;
}

}  // namespace

void bind_calibration(py::module_& m) {
  m.def("calibrate_positions", &calibrate_positions_py, py::arg("robot"), py::arg("q"), py::arg("measured"),
        py::kw_only(), py::arg("robust") = false, py::arg("k0") = 1.5, py::arg("k1") = 3.0,
        py::arg("max_condition") = 1e3,
        "Kinematic calibration from tracker positions, as `errfield calibrate --model position`: registration\n"
        "(tracker <- robot base, reflector offset), then MD-H + base + tool by Levenberg-Marquardt with IGG3\n"
        "robust weights and automatic removal of unidentifiable parameters.\n\n"
        "robot: the nominal Robot. q: (N, 6) commanded joints, deg, within the limits. measured: (N, 3)\n"
        "tracker positions of the tool point, mm. Returns a dict: robot (identified, in the registered robot\n"
        "frame, as the CLI writes it), tracker_from_base (4, 4), parameters, removed, condition_number,\n"
        "regularization (distances: the Tikhonov weight toward nominal, 0 for positions),\n"
        "rms_before_mm, rms_after_mm, max_after_mm, weights, rejected, converged, message, report (text).\n"
        "Check converged before using the robot.");
  m.def("calibrate_distances", &calibrate_distances_py, py::arg("robot"), py::arg("data"), py::kw_only(),
        py::arg("base_points") = py::none(), py::arg("robust") = false, py::arg("k0") = 1.5, py::arg("k1") = 3.0,
        py::arg("max_condition") = 1e3,
        "Kinematic calibration from distances, as `errfield calibrate --model distance`: frame-free, from the\n"
        "distances dist_bK (mm) of each target to base point K. data: a dict of columns as `errfield simulate`\n"
        "writes them (kind base|target, q1..q6 deg, dist_b0..). Base points are the base rows (robot positions),\n"
        "or base_points (K, 3) mm: fixed points (one per dist_bK column; no base rows), identified with the\n"
        "robot. robot: None (built-in ER20-C10), a Robot, a built-in name or a robot JSON path. Returns the dict\n"
        "of calibrate_positions (robot, parameters, ..., report) with fixed_bases (K, 3) mm (identified) and skipped (pairs\n"
        "under 1 mm apart). robot.to_json() + '\\n' is the file `errfield calibrate --out` writes.");
}

}  // namespace errfield::python
