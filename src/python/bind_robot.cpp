// errfield.Robot: a 6R arm in modified DH (errfield::robot::MdhModel) with FK, IK and Jacobians
// vectorized over arrays of joint vectors (deg) and poses (mm), as `errfield fk` / `errfield ik`.

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include <Eigen/SVD>
#include <nlohmann/json.hpp>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "errfield/error.hpp"
#include "errfield/robot/inverse_kinematics.hpp"
#include "errfield/robot/kinematics.hpp"
#include "errfield/robot/mdh_model.hpp"
#include "python/arrays.hpp"
#include "python/bindings.hpp"

namespace errfield::python {

namespace {

using robot::JointVector;
using robot::MdhModel;
constexpr int kJ = robot::kJointCount;

/// Joint vectors (N, 6) or one (6,) in degrees.
/// Read in place (no copy) when q is a C-contiguous float64 array.
RowsArg joints_arg(const py::object& q, const std::string& name = "q") {
  ArraySpec spec;
  spec.cols = kJ;
  spec.min_rows = 0;
  spec.one_d_is_row = true;
  return rows_arg(q, name, spec);
}

template <class M>
JointVector row_joints(const M& m, Eigen::Index r) { return m.row(r).transpose(); }

py::array_t<double> stack(std::size_t n, py::ssize_t rows, py::ssize_t cols, bool single) {
  if (single) return py::array_t<double>({rows, cols});
  return py::array_t<double>({static_cast<py::ssize_t>(n), rows, cols});
}

robot::EndFrame frame_arg(const std::string& frame) { return robot::parse_end_frame(frame, "frame"); }

py::array_t<double> isometry_to_numpy(const Eigen::Isometry3d& t) {
  py::array_t<double> out({4, 4});
  auto w = out.mutable_unchecked<2>();
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) w(r, c) = t.matrix()(r, c);
  return out;
}

/// A 4 x 4 rigid transform argument (mm); the rotation block is re-orthonormalized as `errfield ik` does.
Eigen::Isometry3d rigid_from(const double* p, const std::string& where) {
  Eigen::Matrix4d m;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) {
      m(r, c) = p[4 * r + c];
      if (!std::isfinite(m(r, c)))
        throw ArgumentError(where + "[" + std::to_string(r) + ", " + std::to_string(c) + "] is not finite");
    }
  const Eigen::Matrix3d rot = m.topLeftCorner<3, 3>();
  const double orth = (rot.transpose() * rot - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (orth > 1e-6 || rot.determinant() < 0)
    throw ArgumentError(where + ": the upper-left 3 x 3 block is not a rotation matrix (|R^T R - I| = " +
                        std::to_string(orth) + ")");
  if ((m.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-12)
    throw ArgumentError(where + ": the last row is not (0, 0, 0, 1)");
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(rot, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = svd.matrixU() * svd.matrixV().transpose();
  t.translation() = m.topRightCorner<3, 1>();
  return t;
}

Eigen::Isometry3d transform_arg(const py::object& object, const std::string& name) {
  const auto a = float_array(object, name);
  if (a.ndim() != 2 || a.shape(0) != 4 || a.shape(1) != 4)
    throw ArgumentError(name + ": expected a 4 x 4 homogeneous transform (mm)");
  return rigid_from(a.data(), name);
}

/// Result of Robot.ik, one entry per target; the columns of `errfield ik`.
struct PyIkSolution {
  py::object q, ok, residual_mm, residual_deg, iterations;
  std::vector<std::string> status;
};

PyIkSolution solve_ik(const MdhModel& model, const py::object& targets, const py::object& seed, const std::string& frame,
                      bool position_only, int max_iterations) {
  robot::IkOptions options;
  options.frame = frame_arg(frame);
  options.position_only = position_only;
  options.max_iterations = max_iterations;
  options.validate();
  const auto a = float_array(targets, "targets");
  std::vector<Eigen::Isometry3d> goal;
  bool single = false;
  if (position_only && (a.ndim() == 1 || a.ndim() == 2) && a.shape(a.ndim() - 1) == 3) {
    // positions (N, 3) or (3,)
    single = a.ndim() == 1;
    const py::ssize_t n = single ? 1 : a.shape(0);
    for (py::ssize_t i = 0; i < n; ++i) {
      Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
      for (int k = 0; k < 3; ++k) {
        const double v = a.data()[3 * i + k];
        if (!std::isfinite(v))
          throw ArgumentError("targets[" + std::to_string(i) + ", " + std::to_string(k) + "] is not finite");
        t.translation()[k] = v;
      }
      goal.push_back(t);
    }
  } else if ((a.ndim() == 2 || a.ndim() == 3) && a.shape(a.ndim() - 1) == 4 && a.shape(a.ndim() - 2) == 4) {
    single = a.ndim() == 2;
    const py::ssize_t n = single ? 1 : a.shape(0);
    for (py::ssize_t i = 0; i < n; ++i)
      goal.push_back(rigid_from(a.data() + 16 * i, single ? std::string("targets") : "targets[" + std::to_string(i) + "]"));
  } else {
    throw ArgumentError(std::string("targets: expected poses (N, 4, 4) or (4, 4) in mm") +
                        (position_only ? ", or positions (N, 3) or (3,)" : " (positions (N, 3) need position_only=True)"));
  }
  const std::size_t n = goal.size();
  RowMatrixXd seeds;
  if (!seed.is_none()) {
    seeds = joints_arg(seed, "seed").data;
    if (static_cast<std::size_t>(seeds.rows()) != n)
      throw ArgumentError("seed: " + std::to_string(seeds.rows()) + " joint vectors for " + std::to_string(n) +
                          " targets; expected one per target");
  }
  std::vector<robot::IkResult> results(n);
  {
    py::gil_scoped_release release;
    JointVector previous;
    bool have_previous = false;
    for (std::size_t i = 0; i < n; ++i) {
      robot::IkResult r;
      if (seeds.size()) {
        r = robot::inverse_kinematics(model, goal[i], row_joints(seeds, static_cast<Eigen::Index>(i)), options);
      } else {
        // As `errfield ik`: the previous row's solution keeps neighbouring targets on one branch.
        if (have_previous) r = robot::inverse_kinematics(model, goal[i], previous, options);
        if (!have_previous || !r.ok()) r = robot::inverse_kinematics_multistart(model, goal[i], options);
      }
      if (r.ok()) {
        previous = r.q_deg;
        have_previous = true;
      }
      results[i] = r;
    }
  }
  PyIkSolution s;
  Eigen::MatrixXd q(static_cast<Eigen::Index>(n), kJ);
  std::vector<double> res_mm(n), res_deg(n);
  py::array_t<bool> ok(static_cast<py::ssize_t>(n));
  py::array_t<std::int64_t> iterations(static_cast<py::ssize_t>(n));
  for (std::size_t i = 0; i < n; ++i) {
    q.row(static_cast<Eigen::Index>(i)) = results[i].q_deg.transpose();
    res_mm[i] = results[i].position_residual_mm;
    res_deg[i] = results[i].orientation_residual_rad * 180.0 / std::numbers::pi;
    ok.mutable_data()[i] = results[i].ok();
    iterations.mutable_data()[i] = results[i].iterations;
    s.status.emplace_back(robot::to_string(results[i].status));
  }
  py::object qa = to_numpy(q);
  s.q = single ? py::object(qa[py::int_(0)]) : qa;
  s.ok = ok;
  s.residual_mm = to_numpy(res_mm);
  s.residual_deg = to_numpy(res_deg);
  s.iterations = iterations;
  return s;
}

MdhModel from_json_text(const std::string& text, const std::string& source) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw InputError(source + ": not valid JSON: " + e.what(), source);
  }
  return MdhModel::from_json(j, source);
}

void bind_ik_solution(py::module_& m) {
  py::class_<PyIkSolution>(m, "IkSolution",
                           "Inverse kinematics per target, the columns of `errfield ik`. A target counts as solved "
                           "only where ok is True (status 'converged'); elsewhere q is the best joints found within "
                           "the limits and must not be sent to a robot.")
      .def_readonly("q", &PyIkSolution::q, "(N, 6) joints, deg ((6,) for one target)")
      .def_readonly("ok", &PyIkSolution::ok, "(N,) bool: converged within tolerance and joint limits")
      .def_readonly("status", &PyIkSolution::status, "per target: converged | joint_limits | unreachable | max_iterations")
      .def_readonly("residual_mm", &PyIkSolution::residual_mm, "(N,) position residual, mm")
      .def_readonly("residual_deg", &PyIkSolution::residual_deg, "(N,) orientation residual, deg")
      .def_readonly("iterations", &PyIkSolution::iterations);
}

// Construction, the MD-H table, limits, base and tool.
void bind_robot_description(py::class_<MdhModel>& robot_class) {
  robot_class
      .def_static(
          "builtin",
          [](const std::string& name) {
            if (name == "er20_c10" || name == "ER20-C10") return MdhModel::er20_c10();
            throw ArgumentError("name: '" + name + "'; the built-in robots are: er20_c10");
          },
          py::arg("name") = "er20_c10", "A built-in robot: 'er20_c10' (the paper's Efort ER20-C10, no tool).")
      .def_static(
          "load", [](const std::filesystem::path& path) { return MdhModel::load(path); }, py::arg("path"),
          "Reads a robot JSON file (docs/robot.md); errors name the file and field.")
      .def_static("from_json", &from_json_text, py::arg("text"), py::arg("source") = "robot JSON",
                  "Parses a robot JSON description given as a string.")
      .def(
          "to_json", [](const MdhModel& r) { return r.to_json().dump(2); },
          "The robot JSON description (shortest round-trip numbers).")
      .def(
          "save", [](const MdhModel& r, const std::filesystem::path& path) { r.save(path); }, py::arg("path"),
          "Writes the robot JSON atomically.")
      .def_property_readonly("name", &MdhModel::name)
      .def_property_readonly(
          "mdh",
          [](const MdhModel& r) {
            Eigen::MatrixXd t(kJ, 5);
            for (int i = 0; i < kJ; ++i) {
              const auto& l = r.link(i);
              t.row(i) << l.alpha_deg, l.a_mm, l.theta0_deg, l.d_mm, l.beta_deg;
            }
            return to_numpy(t);
          },
          "(6, 5) MD-H table: alpha_{i-1} (deg), a_{i-1} (mm), theta0_i (deg), d_i (mm), beta_i (deg)")
      .def_property_readonly(
          "q_min", [](const MdhModel& r) { return to_numpy(Eigen::MatrixXd(r.q_min_deg()), true); },
          "(6,) lower joint limits, deg")
      .def_property_readonly(
          "q_max", [](const MdhModel& r) { return to_numpy(Eigen::MatrixXd(r.q_max_deg()), true); },
          "(6,) upper joint limits, deg")
      .def_property_readonly(
          "base", [](const MdhModel& r) { return isometry_to_numpy(r.base()); }, "(4, 4) world <- base frame 0, mm")
      .def_property_readonly(
          "tool", [](const MdhModel& r) { return isometry_to_numpy(r.tool()); }, "(4, 4) flange <- tool frame, mm")
      .def(
          "with_tool", [](const MdhModel& r, const py::object& t) { return r.with_tool(transform_arg(t, "tool")); },
          py::arg("tool"), "A copy with the tool transform (4, 4), mm.")
      .def(
          "with_base", [](const MdhModel& r, const py::object& t) { return r.with_base(transform_arg(t, "base")); },
          py::arg("base"), "A copy with the base transform (4, 4), mm.");
}

void bind_robot_kinematics(py::class_<MdhModel>& robot_class) {
  robot_class
      .def(
          "within_limits",
          [](const MdhModel& r, const py::object& q, double slack_deg) {
            const RowsArg j = joints_arg(q);
            py::array_t<bool> out(static_cast<py::ssize_t>(j.data.rows()));
            for (Eigen::Index i = 0; i < j.data.rows(); ++i) out.mutable_data()[i] = r.within_limits(row_joints(j.data, i), slack_deg);
            return out;
          },
          py::arg("q"), py::arg("slack_deg") = 0.0, "(N,) bool: every joint within its limits (deg).")
      .def(
          "fk",
          [](const MdhModel& r, const py::object& q, const std::string& frame) {
            const RowsArg j = joints_arg(q);
            const auto f = frame_arg(frame);
            const auto n = static_cast<std::size_t>(j.data.rows());
            const bool single = j.one_d;
            auto out = stack(n, 4, 4, single);
            double* w = out.mutable_data();
            {
              py::gil_scoped_release release;
              for (std::size_t i = 0; i < n; ++i) {
                const Eigen::Matrix4d t = robot::forward_kinematics(r, row_joints(j.data, static_cast<Eigen::Index>(i)), f).matrix();
                for (int a = 0; a < 16; ++a) w[16 * i + a] = t(a / 4, a % 4);
              }
            }
            return out;
          },
          py::arg("q"), py::arg("frame") = "tool",
          "Forward kinematics: world poses (N, 4, 4) (or (4, 4) for q of shape (6,)) of the tool or flange for\n"
          "joints q (N, 6) in deg; translation in mm. As `errfield fk` (x, y, z = [:, :3, 3], r11..r33 = [:, :3, :3]).")
      .def(
          "position",
          [](const MdhModel& r, const py::object& q, const std::string& frame) {
            const RowsArg j = joints_arg(q);
            const auto f = frame_arg(frame);
            Eigen::MatrixXd p(j.data.rows(), 3);
            {
              py::gil_scoped_release release;
              for (Eigen::Index i = 0; i < j.data.rows(); ++i)
                p.row(i) = robot::forward_position(r, row_joints(j.data, i), f).transpose();
            }
            py::object out = to_numpy(p);
            return j.one_d ? py::object(out[py::int_(0)]) : out;
          },
          py::arg("q"), py::arg("frame") = "tool", "Tool (or flange) positions (N, 3) in mm for joints (N, 6) in deg.")
      .def(
          "jacobian",
          [](const MdhModel& r, const py::object& q, const std::string& frame) {
            const RowsArg j = joints_arg(q);
            const auto f = frame_arg(frame);
            const auto n = static_cast<std::size_t>(j.data.rows());
            auto out = stack(n, 6, kJ, j.one_d);
            double* w = out.mutable_data();
            {
              py::gil_scoped_release release;
              for (std::size_t i = 0; i < n; ++i) {
                const auto g = robot::geometric_jacobian(r, row_joints(j.data, static_cast<Eigen::Index>(i)), f);
                for (int a = 0; a < 6 * kJ; ++a) w[6 * kJ * i + a] = g(a / kJ, a % kJ);
              }
            }
            return out;
          },
          py::arg("q"), py::arg("frame") = "tool",
          "Geometric Jacobians (N, 6, 6) in the world frame at the frame's origin: rows 0-2 linear velocity\n"
          "(mm/rad), rows 3-5 angular velocity (rad/rad); column j is joint j+1. NOTE: per radian, while q is in deg.")
      .def(
          "identification_jacobian",
          [](const MdhModel& r, const py::object& q) {
            const RowsArg j = joints_arg(q);
            const auto n = static_cast<std::size_t>(j.data.rows());
            constexpr int P = robot::param::kCount;
            auto out = stack(n, 3, P, j.one_d);
            double* w = out.mutable_data();
            {
              py::gil_scoped_release release;
              for (std::size_t i = 0; i < n; ++i) {
                const auto g = robot::identification_jacobian(r, row_joints(j.data, static_cast<Eigen::Index>(i)));
                for (int a = 0; a < 3 * P; ++a) w[3 * P * i + a] = g(a / P, a % P);
              }
            }
            return out;
          },
          py::arg("q"),
          "Derivative (N, 3, 39) of the world tool position with respect to the identification parameters\n"
          "(names: Robot.parameter_names(); angles per rad, lengths per mm).");
}

void bind_robot_parameters(py::class_<MdhModel>& robot_class) {
  robot_class
      .def_static(
          "parameter_names",
          [] {
            std::vector<std::string> names;
            for (int i = 0; i < robot::param::kCount; ++i) names.push_back(robot::parameter_name(i));
            return names;
          },
          "Names of the 39 identification parameters ('link1.alpha', ..., 'base.x', ..., 'tool.z').")
      .def(
          "apply_parameter_increment",
          [](const MdhModel& r, const py::object& delta) {
            const auto d = vector_arg(delta, "delta", robot::param::kCount);
            if (d.size() != static_cast<std::size_t>(robot::param::kCount))
              throw ArgumentError("delta: " + std::to_string(d.size()) + " elements; expected " +
                                  std::to_string(robot::param::kCount) + " (Robot.parameter_names())");
            return robot::apply_parameter_increment(r, Eigen::Map<const robot::ParameterVector>(d.data()));
          },
          py::arg("delta"),
          "A copy with an identification-parameter increment (39,) applied (angles rad, lengths mm); FK of the\n"
          "result equals FK + identification_jacobian @ delta to first order.");
}

void bind_robot_ik(py::class_<MdhModel>& robot_class) {
  robot_class
      .def("ik", &solve_ik, py::arg("targets"), py::kw_only(), py::arg("seed") = py::none(), py::arg("frame") = "tool",
           py::arg("position_only") = false, py::arg("max_iterations") = 100,
           "Inverse kinematics as `errfield ik`: targets (N, 4, 4) poses in mm (or (N, 3) positions with\n"
           "position_only=True); seed (N, 6) deg, or None: each target then starts from the previous solution\n"
           "(the first from a few standard postures). Returns IkSolution; only rows with ok=True are solutions.")
      .def("__repr__", [](const MdhModel& r) { return "Robot('" + r.name() + "')"; });
}

}  // namespace

void bind_robot(py::module_& m) {
  bind_ik_solution(m);

  py::class_<MdhModel> robot_class(m, "Robot",
                                   "A 6-joint serial robot in modified (Craig) Denavit-Hartenberg form with joint "
                                   "limits, base and tool transforms. Joints in degrees, lengths in mm. docs/robot.md.");
  bind_robot_description(robot_class);
  bind_robot_kinematics(robot_class);
  bind_robot_parameters(robot_class);
  bind_robot_ik(robot_class);
}

}  // namespace errfield::python
