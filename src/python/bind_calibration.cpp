// errfield.calibrate_positions: kinematic calibration from tracker positions, the path of
// `errfield calibrate --model position` (registration, then MD-H + base + tool). Kept thin: the
// compensation pipeline is being reorganised (errfield::compensation), bind more when it settles.

#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "errfield/error.hpp"
#include "errfield/robot/calibration.hpp"
#include "python/arrays.hpp"
#include "python/bindings.hpp"

namespace errfield::python {

namespace {

using namespace errfield::robot;

py::dict calibrate_positions_py(const MdhModel& nominal, const py::object& q, const py::object& measured, bool robust,
                                double k0, double k1, double max_condition) {
  const MatrixArg joints = matrix_arg(q, "q", ArraySpec{2, 2, kJointCount, 1});
  const MatrixArg m = matrix_arg(measured, "measured", ArraySpec{2, 2, 3, 1});
  if (m.data.rows() != joints.data.rows())
    throw ArgumentError("measured: " + std::to_string(m.data.rows()) + " positions for " +
                        std::to_string(joints.data.rows()) + " joint vectors; expected one per row of q");
  for (Eigen::Index i = 0; i < joints.data.rows(); ++i)
    for (int j = 0; j < kJointCount; ++j) {
      const MdhLink& l = nominal.link(j);
      const double v = joints.data(i, j);
      if (v >= l.q_min_deg - 1e-6 && v <= l.q_max_deg + 1e-6) continue;
      throw ArgumentError("q[" + std::to_string(i) + ", " + std::to_string(j) + "]: " + std::to_string(v) +
                          " deg is outside the joint limits [" + std::to_string(l.q_min_deg) + ", " +
                          std::to_string(l.q_max_deg) + "] of robot '" + nominal.name() +
                          "'; check units (degrees) and joint order");
    }
  CalibrationOptions options;
  options.robust.enabled = robust;
  options.robust.k0 = k0;
  options.robust.k1 = k1;
  options.max_condition_number = max_condition;
  options.validate();
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
  out["tracker_from_base"] = [&] {
    Eigen::MatrixXd t = reg.model.base().matrix();
    return to_numpy(t);
  }();
  out["parameters"] = parameters;
  out["removed"] = removed;
  out["condition_number"] = result.condition_number;
  out["rms_before_mm"] = result.before.rms_mm;
  out["rms_after_mm"] = result.after.rms_mm;
  out["max_after_mm"] = result.after.max_abs_mm;
  out["weights"] = to_numpy(result.weights);
  out["rejected"] = result.rejected;
  out["converged"] = result.converged;
  out["message"] = result.message;
  out["report"] = "== registration (tracker <- robot base, reflector offset) ==\n" + reg.report() +
                  "\n== kinematic calibration (position model) ==\n" + result.report();
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
        "rms_before_mm, rms_after_mm, max_after_mm, weights, rejected, converged, message, report (text).\n"
        "Check converged before using the robot.");
}

}  // namespace errfield::python
