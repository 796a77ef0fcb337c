// The varying-orientation experiment (beyond the paper): task- vs joint-space vector kriging.
// Protocol in the header; every random stream is separate, so the two orientation cases share
// their target positions and nothing depends on which method runs first.
#include "errfield/reproduction/orientation_experiment.hpp"

#include <cmath>

#include "errfield/error.hpp"
#include "errfield/compensation/model/compensation.hpp"
#include "errfield/robot/kinematics.hpp"
#include "errfield/compensation/model/kriging_fields.hpp"
#include "errfield/compensation/fitting/model_fitting.hpp"
#include "errfield/reproduction/paper_reproduction.hpp"
#include "errfield/robot/pose.hpp"
#include "reproduction/seed_streams.hpp"

namespace errfield::reproduction {

using namespace errfield::robot;
using namespace errfield::compensation;

void OrientationExperimentOptions::validate() const {
  const std::string where = "orientation experiment: ";
  if (training_poses < 8)
    throw ArgumentError(where + "training_poses = " + std::to_string(training_poses) + "; expected >= 8");
  if (validation_poses < 1)
    throw ArgumentError(where + "validation_poses = " + std::to_string(validation_poses) + "; expected >= 1");
  if (!(orientation_spread_deg > 0.0 && orientation_spread_deg <= 90.0))
    throw ArgumentError(where + "orientation_spread_deg = " + std::to_string(orientation_spread_deg) +
                        "; expected a value in (0, 90]");
  if (!(region_margin_deg >= 0.0) || !std::isfinite(region_margin_deg))
    throw ArgumentError(where + "region_margin_deg = " + std::to_string(region_margin_deg) + "; expected >= 0");
  if (!(region_margin_mm >= 0.0) || !std::isfinite(region_margin_mm))
    throw ArgumentError(where + "region_margin_mm = " + std::to_string(region_margin_mm) +
                        "; expected a finite value >= 0");
  if (max_orientation_draws < 1)
    throw ArgumentError(where + "max_orientation_draws = " + std::to_string(max_orientation_draws) +
                        "; expected >= 1");
}

namespace {

enum OrientationStream : std::uint64_t {
  kTrainingPositions = 1,
  kValidationPositions = 2,
  kTrainingOrientations = 3,
  kValidationOrientations = 4,
  kMeasure = 10,     // + case
  kEvaluate = 20,    // + 4 * case + method
};

struct Poses {
  std::vector<Eigen::Vector3d> position_mm;
  std::vector<JointVector> joints_deg;
};

std::vector<Eigen::Vector3d> cube_positions(const MeasurementCube& cube, int n, SimulationRng& rng) {
  std::vector<Eigen::Vector3d> out(static_cast<std::size_t>(n));
  for (auto& p : out)
    for (int k = 0; k < 3; ++k) p[k] = cube.min_corner_mm[k] + rng.uniform(0.0, cube.size_mm);
  return out;
}

/// Nominal joints for each position, at tool-down (spread 0) or at an orientation drawn within
/// ±spread of it; a draw whose IK fails (joint limits, unreachable) is drawn again.
Poses reach(const MdhModel& nominal, const MeasurementCube& cube, const JointVector& seed_q,
            const std::vector<Eigen::Vector3d>& positions, double spread_deg, SimulationRng& rng,
            int max_draws, std::size_t& rejected, const char* what) {
  Poses out;
  out.position_mm = positions;
  for (std::size_t i = 0; i < positions.size(); ++i) {
    bool found = false;
    for (int d = 0; d < max_draws && !found; ++d) {
      Eigen::Isometry3d target = cube.pose(positions[i]);
      if (spread_deg > 0.0)
        target.linear() = rotation_from_rpy_deg(180.0 + rng.uniform(-spread_deg, spread_deg),
                                                rng.uniform(-spread_deg, spread_deg),
                                                rng.uniform(-spread_deg, spread_deg));
      const IkResult r = inverse_kinematics(nominal, target, seed_q);
      if (r.ok()) {
        out.joints_deg.push_back(r.q_deg);
        found = true;
      } else {
        ++rejected;
      }
    }
    if (!found)
      throw Error(std::string("orientation experiment: no reachable orientation for ") + what + " " +
                  std::to_string(i) + " at (" + std::to_string(positions[i].x()) + ", " +
                  std::to_string(positions[i].y()) + ", " + std::to_string(positions[i].z()) + ") mm after " +
                  std::to_string(max_draws) + " draws");
  }
  return out;
}

struct CaseResult {
  std::vector<OrientationExperimentRow> rows;
  Poses training, validation;
};

CaseResult run_case(const SimulatedRobot& sim, const MeasurementCube& cube, const JointVector& seed_q,
                    const std::vector<Eigen::Vector3d>& training_positions,
                    const std::vector<Eigen::Vector3d>& validation_positions, const OrientationExperimentOptions& o,
                    std::uint64_t case_index, std::size_t& rejected) {
  const bool varying = case_index == 0;
  const double spread = varying ? o.orientation_spread_deg : 0.0;
  const std::string name = varying ? "varying" : "constant";
  const MdhModel& nominal = sim.nominal();
  // The same orientation streams in both cases; the constant case draws nothing from them.
  SimulationRng train_rng(detail::stream_seed(o.seed, kTrainingOrientations));
  SimulationRng val_rng(detail::stream_seed(o.seed, kValidationOrientations));
  CaseResult out;
  out.training = reach(nominal, cube, seed_q, training_positions, spread, train_rng, o.max_orientation_draws, rejected,
                       "training pose");
  out.validation = reach(nominal, cube, seed_q, validation_positions, spread, val_rng, o.max_orientation_draws,
                         rejected, "validation pose");

  // Measurement: one move and one tracker reading per training pose; registration on them.
  SimulationRng mrng(detail::stream_seed(o.seed, kMeasure + case_index));
  const std::size_t n = out.training.position_mm.size();
  std::vector<Eigen::Vector3d> measured(n);
  for (std::size_t i = 0; i < n; ++i) measured[i] = sim.measure(sim.move(out.training.joints_deg[i], mrng), mrng);
  const Registration reg = fit_registration(measured, out.training.position_mm);
  std::vector<Eigen::Vector3d> error(n);
  Eigen::MatrixXd flat(static_cast<Eigen::Index>(n), 3);
  for (std::size_t i = 0; i < n; ++i) {
    error[i] = reg.robot_from_tracker * measured[i] - out.training.position_mm[i];
    flat.row(static_cast<Eigen::Index>(i)) = error[i].transpose();
  }
  const FieldSamples samples{out.training.position_mm, out.training.joints_deg};

  struct Method {
    std::string space;
    VariogramModel model;
    CompensationModel compensation;
  };
  std::vector<Method> methods;
  methods.push_back({"-", VariogramModel(), CompensationModel(CompensationMethod::none, nominal, nullptr)});
  for (FieldSpace space : {FieldSpace::task, FieldSpace::joint}) {
    KrigingFieldOptions ko;
    ko.space = space;
    ko.region_margin_mm = o.region_margin_mm;
    ko.region_margin_deg = o.region_margin_deg;
    try {
      ko.model = estimate_field_variogram(samples, flat, space);
      methods.push_back({std::string(field_space_name(space)), *ko.model,
                         CompensationModel(CompensationMethod::vector_kriging, nominal,
                                           make_vector_kriging_field(samples, error, ko))});
    } catch (const InputError& e) {
      throw Error("orientation experiment (" + name + " orientation, " + std::string(field_space_name(space)) +
                  " space): " + e.what());
    }
  }

  // Evaluation: the true robot with fresh repeatability noise, in the registered frame.
  const Eigen::Isometry3d registered_from_world = reg.robot_from_tracker * sim.config().tracker.tracker_from_world;
  for (std::size_t m = 0; m < methods.size(); ++m) {
    SimulationRng erng(detail::stream_seed(o.seed, kEvaluate + 4 * case_index + m));
    OrientationExperimentRow row;
    row.orientation = name;
    row.method = m == 0 ? "none" : "vector-kriging";
    row.space = methods[m].space;
    row.model = methods[m].model;
    std::vector<double> residual;
    for (std::size_t i = 0; i < out.validation.position_mm.size(); ++i) {
      const CompensatedTarget c = methods[m].compensation.compensate_joints(nominal, out.validation.joints_deg[i]);
      if (!c.ok()) ++row.refused;
      const Eigen::Vector3d actual = sim.move(c.ok() ? c.q_command_deg : out.validation.joints_deg[i], erng);
      residual.push_back((registered_from_world * actual - out.validation.position_mm[i]).norm());
    }
    const ErrorStats st = error_stats(residual);
    row.max_mm = st.max_mm;
    row.mean_mm = st.mean_mm;
    row.std_mm = st.std_mm;
    out.rows.push_back(std::move(row));
  }
  return out;
}

}  // namespace

OrientationExperiment run_orientation_experiment(const SimulatorConfig& config,
                                                 const OrientationExperimentOptions& options) {
  options.validate();
  config.validate();
  const SimulatedRobot sim(config);
  const MeasurementCube cube = paper_cube();
  const IkResult seed = cube_seed(sim.nominal(), cube);
  if (!seed.ok()) throw Error("orientation experiment: no IK solution at the cube centre for the nominal robot");

  SimulationRng train_pos(detail::stream_seed(options.seed, kTrainingPositions));
  SimulationRng val_pos(detail::stream_seed(options.seed, kValidationPositions));
  const auto training_positions = cube_positions(cube, options.training_poses, train_pos);
  const auto validation_positions = cube_positions(cube, options.validation_poses, val_pos);

  OrientationExperiment out;
  out.options = options;
  std::size_t constant_rejected = 0;
  const CaseResult varying = run_case(sim, cube, seed.q_deg, training_positions, validation_positions, options, 0,
                                      out.rejected_orientation_draws);
  const CaseResult constant = run_case(sim, cube, seed.q_deg, training_positions, validation_positions, options, 1,
                                       constant_rejected);
  if (constant_rejected > 0)
    throw Error("orientation experiment: " + std::to_string(constant_rejected) +
                " positions of the cube are not reachable at tool-down orientation");
  out.rows = varying.rows;
  out.rows.insert(out.rows.end(), constant.rows.begin(), constant.rows.end());

  // What orientation alone does to the true error at a fixed position (noise-free).
  std::vector<double> effect;
  for (std::size_t i = 0; i < varying.validation.position_mm.size(); ++i) {
    const Eigen::Vector3d& p = varying.validation.position_mm[i];
    const Eigen::Vector3d d_var = sim.true_position(varying.validation.joints_deg[i]) - p;
    const Eigen::Vector3d d_down = sim.true_position(constant.validation.joints_deg[i]) - p;
    effect.push_back((d_var - d_down).norm());
  }
  const ErrorStats e = error_stats(effect);
  out.orientation_effect_max_mm = e.max_mm;
  out.orientation_effect_mean_mm = e.mean_mm;
  out.orientation_effect_std_mm = e.std_mm;
  for (int k = 0; k < kJointCount; ++k) {
    double lo = INFINITY, hi = -INFINITY;
    for (const auto& q : varying.training.joints_deg) {
      lo = std::min(lo, q[k]);
      hi = std::max(hi, q[k]);
    }
    out.joint_span_deg[k] = hi - lo;
  }
  return out;
}

}  // namespace errfield::reproduction
