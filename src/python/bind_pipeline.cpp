// errfield.fit / predict / compensate / validate and CompensationModel: the robot pipeline of the
// CLI commands of the same names, on dicts of columns (the CLI's CSV column names; a pandas
// DataFrame works too) or arrays. The steps themselves are errfield/compensation/pipeline.hpp, which
// the CLI calls as well; this file only converts arguments and results.

#include <cmath>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "compensation/fitting/fit_checks.hpp"
#include "errfield/atomic_file.hpp"
#include "errfield/compensation/pipeline.hpp"
#include "errfield/compensation/planning/pose_selection.hpp"
#include "errfield/compensation/model/prediction.hpp"
#include "errfield/compensation/tools/probe_readings.hpp"
#include "errfield/compensation/validation/rotation_validation.hpp"
#include "errfield/compensation/tools/tool_location.hpp"
#include "errfield/robot/pose.hpp"
#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"
#include "errfield/robot/builtin_robots.hpp"
#include "python/arrays.hpp"
#include "python/bindings.hpp"

namespace errfield::python {

namespace {

using namespace errfield::compensation;
using robot::JointVector;
using robot::MdhModel;
using namespace pybind11::literals;

std::vector<JointVector> joints_of(const Eigen::MatrixXd& m) {
  std::vector<JointVector> q(static_cast<std::size_t>(m.rows()));
  for (Eigen::Index i = 0; i < m.rows(); ++i) q[static_cast<std::size_t>(i)] = m.row(i).transpose();
  return q;
}

Eigen::MatrixXd columns_matrix(const CsvTable& t, const std::vector<std::string>& cols) { return t.numeric_columns(cols); }

const std::vector<std::string> kJointCols{"q1", "q2", "q3", "q4", "q5", "q6"};
const std::vector<std::string> kPoseCols{"x", "y", "z", "rx", "ry", "rz"};

bool has_all(const CsvTable& t, const std::vector<std::string>& cols) {
  for (const auto& c : cols)
    if (!t.has_column(c)) return false;
  return true;
}

/// (N, 6) joints (deg) or a dict with q1..q6.
std::vector<JointVector> joint_vectors_arg(const py::object& o, const std::string& name) {
  if (is_columns(o)) {
    const CsvTable t = table_arg(o, name);
    if (!has_all(t, kJointCols)) throw InputError(name + ": needs columns q1..q6 (deg)", name);
    return joints_of(columns_matrix(t, kJointCols));
  }
  return joints_of(matrix_arg(o, name, ArraySpec{1, 2, robot::kJointCount, 0, true, true}).data);
}

py::dict columns_dict(const StepColumns& step) {
  py::dict d;
  const py::object array = py::module_::import("numpy").attr("array");
  for (const auto& c : step.columns) {
    if (c.is_words()) d[py::str(c.name)] = array(py::cast(c.words), "dtype"_a = "str");
    else d[py::str(c.name)] = to_numpy(c.numbers);
  }
  return d;
}

/// A compensation model (errfield fit) or a robot JSON read as one (errfield calibrate), with the
/// report of the fit that made it, if any.
struct PyModel {
  LoadedModel loaded;
  py::object fit_report = py::none();
};

std::string model_json(const PyModel& m) { return m.loaded.model.to_json().dump(1) + "\n"; }

py::dict fit_report_dict(const TableFit& f) {
  const FitResult& r = f.result;
  py::dict d;
  d["points"] = f.points;
  d["notes"] = r.notes;
  d["warnings"] = r.warnings;
  d["field"] = r.model.field() ? py::object(py::str(r.model.field()->describe())) : py::object(py::none());
  if (r.cross_validation) {
    const auto& cv = *r.cross_validation;
    py::dict c;
    c["method"] = cv.method;
    c["samples"] = cv.samples;
    c["mean_abs_mm"] = cv.mean_abs_mm;
    c["rms_mm"] = cv.rms_mm;
    c["max_abs_mm"] = cv.max_abs_mm;
    c["mean_squared_z"] = cv.mean_squared_z ? py::object(py::float_(*cv.mean_squared_z)) : py::object(py::none());
    d["cross_validation"] = c;
  } else {
    d["cross_validation"] = py::none();
  }
  d["registration_rms_mm"] =
      r.registration ? py::object(py::float_(r.registration->residual_rms_mm)) : py::object(py::none());
  return d;
}

std::vector<Eigen::Vector3d> base_points_arg(const py::object& o) {
  std::vector<Eigen::Vector3d> fixed;
  if (o.is_none()) return fixed;
  const Eigen::MatrixXd b = matrix_arg(o, "base_points", ArraySpec{1, 2, 3, 1, true, true}).data;
  for (Eigen::Index i = 0; i < b.rows(); ++i) fixed.emplace_back(b.row(i).transpose());
  return fixed;
}

/// tool=: None, or 3 (X,Y,Z; the tool's orientation kept) or 6 (X,Y,Z mm, RX,RY,RZ deg) numbers in the
/// flange frame, as the CLI's --tool.
CompensationModel with_tool_arg(const CompensationModel& model, const py::object& tool, const Eigen::Isometry3d& current) {
  if (tool.is_none()) return model;
  const Eigen::MatrixXd v = matrix_arg(tool, "tool", ArraySpec{1, 1, -1, 0, true, true}).data;
  if (v.size() != 3 && v.size() != 6)
    throw ArgumentError("tool: expected 3 numbers (X,Y,Z mm) or 6 (X,Y,Z mm, RX,RY,RZ deg), got " + std::to_string(v.size()));
  const double* x = v.data();  // one row or one column: the numbers in order
  Eigen::Isometry3d t = current;
  if (v.size() == 6) t = robot::to_isometry({x[0], x[1], x[2], x[3], x[4], x[5]});
  t.translation() = Eigen::Vector3d(x[0], x[1], x[2]);
  check_tool_point(t, "tool");
  return model.with_working_tool(model.tool_in_model_frame(t));
}

PyModel fit_py(const py::object& data, const py::object& robot, const std::string& method, const std::string& space,
               double power, const std::optional<std::string>& model, const std::string& kind, std::size_t base,
               const py::object& base_points, std::optional<double> region_margin,
               const std::optional<std::string>& calibration, const std::optional<std::string>& robust,
               double max_condition, double max_registration_rms, double outlier_limit, bool reflector_far_ok,
               const std::string& variance_calibration, int joint_functions, bool gravity_load) {
  const MdhModel nominal = robot_arg(robot);
  // A 6-DoF probe's rows become three points on the flange, as in the CLI.
  const CsvTable table = expand_probe_readings(table_arg(data, "data"));
  FitTableOptions fo;
  fo.fit = fit_options_from_text({method, space, power, model.value_or(""), kind, base, region_margin,
                                  calibration.value_or(""), robust.value_or(""), max_condition, outlier_limit, variance_calibration});
  fo.fit.reflector_far_ok = reflector_far_ok;
  fo.fit.joint_function_degree = joint_functions;
  fo.fit.gravity_load = gravity_load;
  fo.fit.validate();
  fo.fixed_bases = base_points_arg(base_points);
  fo.robot_given = !robot.is_none();
  fo.max_registration_rms_mm = max_registration_rms;
  std::optional<TableFit> fit;
  {
    py::gil_scoped_release release;
    fit = fit_table(nominal, table, fo);
  }
  for (const auto& w : fit->result.warnings)
    if (PyErr_WarnEx(PyExc_RuntimeWarning, w.c_str(), 1) != 0) throw py::error_already_set();
  PyModel m{LoadedModel{fit->result.model, false, std::string(method_name(fit->result.model.method())) + " model"},
            fit_report_dict(*fit)};
  return m;
}

py::dict predict_py(const PyModel& m, const py::object& joints, const py::object& tool, bool joints_are_degrees) {
  const std::vector<JointVector> q = joint_vectors_arg(joints, "joints");
  const CompensationModel model = with_tool_arg(m.loaded.model, tool, m.loaded.model.command_model().tool());
  // As the CLI: joints that look like radians against the model's training joints are refused.
  if (!joints_are_degrees) check_joints_not_radians(q, model, "joints", "joints_are_degrees=True");
  std::optional<StepColumns> step;
  {
    py::gil_scoped_release release;
    step = predict_columns(model, q);
  }
  return columns_dict(*step);
}

py::dict compensate_py(const PyModel& m, const py::object& targets, const py::object& robot, double tolerance,
                       const py::object& seed, double max_correction, const py::object& tool, const std::string& frame,
                       bool joints_are_degrees) {
  const TargetFrame target_frame = parse_target_frame(frame, "frame");
  const CompensationModel model = with_tool_arg(m.loaded.model, tool, m.loaded.model.aimed_model().tool());
  const bool kinematic =
      model.method() == CompensationMethod::kinematic || model.method() == CompensationMethod::kinematic_kriging;
  if (kinematic && robot.is_none() && !model.has_nominal_model())
    throw ArgumentError("robot: a kinematic model's command model is the calibrated robot; give the nominal robot");
  const MdhModel nominal_robot = robot.is_none() ? model.nominal_model() : robot_arg(robot);
  const MdhModel nominal = nominal_at_working_tool(model, nominal_robot);
  CompensationTargets t;
  if (!seed.is_none()) t.seed_deg = matrix_arg(seed, "seed", ArraySpec{1, 1, -1, robot::kJointCount}).data.col(0);
  if (is_columns(targets)) {
    const CsvTable table = table_arg(targets, "targets");
    if (has_all(table, kJointCols)) t.joints_deg = joints_of(columns_matrix(table, kJointCols));
    else if (has_all(table, kPoseCols)) {
      t.poses = columns_matrix(table, kPoseCols);
      // Per-row seeds (the CLI's sq1..sq6): each row solved from, and kept on, its seed's configuration.
      t.seed_rows_deg = seed_rows_of(table);
      check_seed_joints(t, nominal, &table);
    } else throw InputError("targets: need columns q1..q6 (nominal joints, deg) or x,y,z,rx,ry,rz (mm, deg)", "targets");
  } else {
    t.joints_deg = joint_vectors_arg(targets, "targets");
  }
  bring_targets_to_robot_frame(t, model, target_frame, "frame", "targets", "the model");
  check_seed_joints(t, nominal);  // --seed: within the joint limits
  if (!(std::isfinite(max_correction) && max_correction >= 0.0))
    throw ArgumentError("max_correction: " + format_number(max_correction) +
                        "; expected a ceiling > 0 (mm), or 0 for the default");
  if (!(std::isfinite(tolerance) && tolerance > 0.0))
    throw ArgumentError("tolerance: " + format_number(tolerance) + "; expected a finite tolerance > 0 (mm)");
  // As the CLI: joint targets that look like radians against the model's training joints are refused.
  if (!joints_are_degrees) check_joints_not_radians(t.joints_deg, model, "targets", "joints_are_degrees=True");
  std::optional<StepColumns> step;
  {
    py::gil_scoped_release release;
    step = compensate_columns(model, nominal, t, tolerance, max_correction);
  }
  return columns_dict(*step);
}

py::dict validate_py(const PyModel& m, const py::object& data, const py::object& robot, const py::object& base_points,
                     bool targets, const py::object& tool, const std::string& reflector) {
  CompensationModel model = with_tool_arg(m.loaded.model, tool, m.loaded.model.command_model().tool());
  // As the CLI: a probe's rows are three points, and a file of several points is scored at one label
  // (the model's own by default) with the flange's orientation from all of them.
  const CsvTable file = expand_probe_readings(table_arg(data, "data"));
  const CsvTable table = targets ? file : rows_of_one_reflector(file, reflector, !tool.is_none(), model, "");
  const auto fixed = base_points_arg(base_points);
  const MdhModel nominal_robot = robot.is_none() ? model.nominal_model() : robot_arg(robot);
  ValidationReport r;
  std::optional<RotationCheck> rotations;
  {
    py::gil_scoped_release release;
    if (targets) {
      r = validate_targets(table, model.registration(), fixed);
    } else {
      // As the CLI: the nominal robot at the point the readings are of ('before').
      r = validate_predictions(model, readings_at_measured_point(table, model, nominal_robot, fixed));
      if (file.has_column("reflector") && model.fielded_points().size() >= 3)
        rotations = validate_rotations(model, MeasurementSet::from_table(file, nominal_robot, fixed, true), nominal_robot);
    }
  }
  if (!targets && m.loaded.is_robot_json && robot.is_none() && !table.has_column("x"))
    r.notes.push_back("no robot and no x,y,z columns: 'before' is this robot's own FK; give the nominal robot "
                      "for an uncompensated baseline");
  py::dict d;
  d["points"] = columns_dict(validation_point_columns(r));
  nlohmann::json summary_object = r.summary_json();
  if (rotations) summary_object["orientation"] = rotations->summary_json();
  const std::string summary = summary_object.dump(2) + "\n";
  d["summary_json"] = summary;
  d["summary"] = py::module_::import("json").attr("loads")(summary);
  d["text"] = r.summary_text() + (rotations ? rotations->summary_text() : std::string());
  return d;
}

py::tuple locate_tool_py(const PyModel& m, const py::object& data, std::size_t min_orientations,
                         double distinct_orientation, double not_rigid_factor) {
  const CompensationModel& model = m.loaded.model;
  if (m.loaded.is_robot_json)
    throw ArgumentError("model: a robot JSON has no registration to put readings in the robot frame; give a model from fit()");
  const CsvTable table = table_arg(data, "data");
  ToolLocationOptions o;
  o.min_orientations = min_orientations;
  o.distinct_orientation_deg = distinct_orientation;
  o.not_rigid_factor = not_rigid_factor;
  std::optional<ToolLocation> t;
  {
    py::gil_scoped_release release;
    t = locate_tool(model, MeasurementSet::from_table(table, model.nominal_model()), o);
  }
  CompensationModel located = with_located_tool(model, *t);
  py::dict r;
  r["tool_mm"] = to_numpy(std::vector<double>{t->tool_mm.x(), t->tool_mm.y(), t->tool_mm.z()});
  r["sd_mm"] = to_numpy(std::vector<double>{t->sd_mm.x(), t->sd_mm.y(), t->sd_mm.z()});
  r["residual_rms_mm"] = t->residual_rms_mm;
  r["expected_rms_mm"] = t->expected_rms_mm;
  r["readings"] = t->readings;
  r["left_out"] = t->left_out;
  r["orientations"] = t->orientations;
  r["lever_mm"] = t->lever_mm;
  const OrientationPrior& prior = located.orientation_prior();
  r["orientation_sigma_mrad"] = prior.known() ? py::object(py::float_(prior.sigma_rad * 1e3)) : py::object(py::none());
  r["max_lever_mm"] = prior.known() ? py::object(py::float_(prior.max_lever_mm)) : py::object(py::none());
  // The readings' kriged residual at the point (tool_point_correction), as locate-tool prints it.
  if (const auto& c = t->correction) {
    py::dict d;
    d["readings"] = c->readings();
    d["excluded_readings"] = c->excluded_readings();
    d["sd_mm"] = to_numpy(std::vector<double>{std::sqrt(c->sill_mm2().x()), std::sqrt(c->sill_mm2().y()),
                                              std::sqrt(c->sill_mm2().z())});
    d["noise_mm"] = std::sqrt(c->noise_mm2());
    d["correlation"] = c->correlation().to_string();
    d["variance_factor"] = c->variance_factor();
    d["uncorrected_rms_mm"] = t->uncorrected_rms_mm;
    d["leave_one_out_rms_mm"] = t->correction_leave_one_out_rms_mm;
    r["correction"] = d;
  } else {
    r["correction"] = py::none();
  }
  const std::string what = std::string(method_name(located.method())) + " model";
  return py::make_tuple(PyModel{LoadedModel{std::move(located), false, what}, py::none()}, r);
}

py::dict plan_py(const py::object& candidates, std::size_t count, const py::object& model, const py::object& measured,
                 std::optional<double> target_rms, bool local_scale, double spacing_floor) {
  const std::vector<JointVector> pool = joint_vectors_arg(candidates, "candidates");
  const std::vector<JointVector> done =
      measured.is_none() ? std::vector<JointVector>{} : joint_vectors_arg(measured, "measured");
  const CompensationModel* cm = nullptr;
  if (!model.is_none()) cm = &model.cast<const PyModel&>().loaded.model;
  PoseSelectionOptions o;
  o.count = count;
  o.target_rms_mm = target_rms;
  o.local_scale = local_scale;
  o.spacing_floor = spacing_floor;
  PoseSelection sel;
  {
    py::gil_scoped_release release;
    sel = select_poses(pool, done, cm, o);
  }
  py::dict d;
  d["chosen"] = py::module_::import("numpy").attr("array")(py::cast(sel.chosen), "dtype"_a = "int64");
  d["design"] = sel.design;
  d["predicted_rms_mm"] = to_numpy(sel.predicted_rms_mm);
  auto count_or_none = [](const std::optional<std::size_t>& n) { return n ? py::object(py::int_(*n)) : py::object(py::none()); };
  d["poses_for_target"] = count_or_none(sel.poses_for_target);
  d["predicted_rms_low_mm"] = to_numpy(sel.predicted_rms_low_mm);
  d["predicted_rms_high_mm"] = to_numpy(sel.predicted_rms_high_mm);
  d["predicted_mse_relative_se"] = sel.predicted_mse_relative_se;
  d["poses_for_target_range"] = py::make_tuple(count_or_none(sel.poses_for_target_low), count_or_none(sel.poses_for_target_high));
  d["conditioned_on"] = sel.conditioned_on;
  return d;
}

}  // namespace

void bind_pipeline(py::module_& m) {
  py::class_<PyModel>(m, "CompensationModel",
                      "A compensation model as `errfield fit` writes it (or a robot JSON from `errfield calibrate`, "
                      "read as a model whose prediction is its FK). save() writes the CLI's model file byte for byte.")
      .def_static(
          "load", [](const std::filesystem::path& path) { return PyModel{load_model(path.string()), py::none()}; },
          py::arg("path"), "Reads a model JSON (errfield fit --out) or a robot JSON; InputError names file and member.")
      .def(
          "save", [](const PyModel& self, const std::filesystem::path& path) { write_file_atomically(path, model_json(self)); },
          py::arg("path"), "Writes the model JSON atomically, identical to `errfield fit --out`.")
      .def("to_json", &model_json, "The model file's text (JSON, as save() writes it).")
      .def_property_readonly("method", [](const PyModel& self) { return std::string(method_name(self.loaded.model.method())); },
                             "distance-idw | position-idw | distance-kriging | vector-kriging | kinematic | kinematic+kriging")
      .def_property_readonly("description", [](const PyModel& self) { return self.loaded.description; })
      .def_property_readonly("is_robot_json", [](const PyModel& self) { return self.loaded.is_robot_json; })
      .def_readonly("fit_report", &PyModel::fit_report,
                    "dict from fit(): points, notes, warnings, field, cross_validation (mm), registration_rms_mm; "
                    "None for a loaded model")
      .def("__repr__", [](const PyModel& self) { return "CompensationModel('" + self.loaded.description + "')"; });

  m.def("fit", &fit_py, py::arg("data"), py::kw_only(), py::arg("robot") = py::none(),
        py::arg("method") = "auto", py::arg("space") = "auto", py::arg("power") = 1.0,
        py::arg("model") = py::none(), py::arg("kind") = "ordinary", py::arg("base") = 0,
        py::arg("base_points") = py::none(), py::arg("region_margin") = py::none(), py::arg("calibration") = py::none(),
        py::arg("robust") = py::none(), py::arg("max_condition") = 1e3,
        py::arg("max_registration_rms") = robot::kRegistrationRmsLimitMm, py::arg("outlier_limit") = 5.0,
        py::arg("reflector_far_ok") = false, py::arg("variance_calibration") = "auto",
        py::arg("joint_functions") = FitOptions{}.joint_function_degree,
        py::arg("gravity_load") = FitOptions{}.gravity_load,
        "`errfield fit`: a CompensationModel from measurements, a dict of columns named as the CLI's CSV\n"
        "(point, kind, q1..q6 deg, x,y,z mm, mx,my,mz mm, dist_b0.. mm). robot: None (built-in ER20-C10), a Robot,\n"
        "a built-in name or a robot JSON path. The options are the CLI's (--method, --space, --power, --model,\n"
        "--kind, --base, --base-point as base_points (K, 3) mm, --region-margin, --calibration, --robust,\n"
        "--max-condition, --max-registration-rms mm, --outlier-limit, --reflector-far-ok, --variance-calibration,\n"
        "--joint-functions, --gravity-load as a bool); method='auto' chooses from the data as the\n"
        "CLI does (kinematic+kriging in joint space with tracker positions, kinematic from distances). The fit's warnings are RuntimeWarnings. Releases the GIL.");
  m.def("locate_tool", &locate_tool_py, py::arg("model"), py::arg("data"), py::kw_only(),
        py::arg("min_orientations") = ToolLocationOptions{}.min_orientations,
        py::arg("distinct_orientation") = ToolLocationOptions{}.distinct_orientation_deg,
        py::arg("not_rigid_factor") = ToolLocationOptions{}.not_rigid_factor,
        "`errfield locate-tool`: locates a point rigidly attached to the flange from readings of it (dict of\n"
        "columns point, q1..q6 deg, mx,my,mz tracker mm) through the model. Returns (model, report): the model with\n"
        "that working tool (everything else kept) and a dict tool_mm (flange frame), sd_mm (per axis), residual_rms_mm,\n"
        "expected_rms_mm, readings, left_out, orientations, lever_mm, orientation_sigma_mrad, max_lever_mm.\n"
        "InputError for fewer than min_orientations distinct orientations or readings that are not one rigid point.");
  m.def("predict", &predict_py, py::arg("model"), py::arg("joints"), py::kw_only(), py::arg("tool") = py::none(),
        py::arg("joints_are_degrees") = false,
        "`errfield predict`: where the tool goes at joints ((N, 6) deg or a dict with q1..q6). Returns a dict:\n"
        "px,py,pz (robot frame, mm), tx,ty,tz (tracker frame; models with a registration), where the model has a\n"
        "variance var_mm2 (a new reading: field + nugget, mm²), var_field_mm2 (field only) and r95_mm (95 % radius\n"
        "of a new reading, vector fields), status (ok | outside-region | not-credible | orientation-unknown; refused\n"
        "rows are NaN). tool: the CLI's --tool, 3 or 6 numbers (flange frame, mm, deg). Joints that look like\n"
        "radians (all within +-2 pi, spread far less than the model's training joints) are an InputError;\n"
        "joints_are_degrees=True skips that check (the CLI's --joints-are-degrees).");
  m.def("compensate", &compensate_py, py::arg("model"), py::arg("targets"), py::kw_only(),
        py::arg("robot") = py::none(), py::arg("tolerance") = 0.25, py::arg("seed") = py::none(),
        py::arg("max_correction") = 0.0, py::arg("tool") = py::none(), py::arg("frame") = "robot",
        py::arg("joints_are_degrees") = false,
        "`errfield compensate` (tool: the CLI's --tool; frame: its --frame, robot or tracker, the frame of pose\n"
        "targets; tracker ones are mapped with the model's registration; joints_are_degrees: the CLI's\n"
        "--joints-are-degrees, joint targets that look like radians are refused without it): joints to send. targets: (N, 6) nominal joints (deg) or a dict with q1..q6 or\n"
        "x,y,z,rx,ry,rz (mm, deg), optionally with per-row seed joints sq1..sq6 (deg; a row of NaN = none) whose arm\n"
        "configuration the solution keeps. max_correction: ceiling (mm) on move_mm, 0 = the CLI's default. Returns a dict: nq1..nq6, nx,ny,nz, pred_dx..dz, pred_dl, var_mm2 (new reading:\n"
        "field + nugget), p_inside (P(|3-D error| <= tolerance mm) of a new reading; distance models: the distance\n"
        "error), cmd_x..z, cq1..cq6 (NaN for refused targets: nothing to send), var_field_mm2, r95_mm and status.");
  m.def("plan", &plan_py, py::arg("candidates"), py::kw_only(), py::arg("count"), py::arg("model") = py::none(),
        py::arg("measured") = py::none(), py::arg("target_rms") = py::none(), py::arg("local_scale") = true,
        py::arg("spacing_floor") = 0.7,
        "`errfield plan --candidates`: which poses to measure next. candidates: (N, 6) joints (deg) or a dict with\n"
        "q1..q6 (drop the rows already measured first); measured: the poses measured so far (conditioned on, kept\n"
        "away from). Without a model, maximin in joint space; with a CompensationModel (vector-kriging field), greedy\n"
        "integrated variance reduction among the candidates at least spacing_floor (0..1) of the farthest one's distance\n"
        "from everything measured or chosen (plan --spacing-floor). Returns a dict: chosen (candidate rows, in measuring order), design,\n"
        "predicted_rms_mm ([0] now, [k] after k more poses; model only), poses_for_target (target_rms given: poses\n"
        "from now the prediction needs, None if not reached), predicted_rms_low_mm / predicted_rms_high_mm (its 90 % range\n"
        "from the spread of the model's leave-one-out scores), predicted_mse_relative_se, poses_for_target_range (low, high;\n"
        "None: not reached), conditioned_on. Releases the GIL.");
  m.def("validate", &validate_py, py::arg("model"), py::arg("data"), py::kw_only(), py::arg("robot") = py::none(),
        py::arg("base_points") = py::none(), py::arg("targets") = false, py::arg("tool") = py::none(),
        py::arg("reflector") = "",
        "`errfield validate` (tool: the CLI's --tool, reflector: its --reflector) on held-out measurements (dict of columns;\n"
        "a probe's mrx,mry,mrz or mqw..mqz rows are read as three points on the flange). Returns a dict: points (the columns of\n"
        "--out: point, status, before_mm, after_mm, before_dx.., after_dx.., before_dl_bK, after_dl_bK; mm; kriging\n"
        "models: var_mm2, var_field_mm2, r95_mm, nees),\n"
        "summary (dict; with three or more points per pose and a model fitted on them, summary['orientation']: the flange's\n"
        "orientation error before/after in mdeg, coverage95, mean_nees) and summary_json (the text of --summary-out), text\n"
        "(the printed summary).");
}

}  // namespace errfield::python
