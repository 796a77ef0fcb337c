// Robot adapter throughput (docs/benchmarks.md, section "Robot").
//
// BM_ForwardKinematics        : tool pose of the ER20-C10 (+ Table 7 ball), 1024 random joint vectors cycled.
// BM_ForwardPosition          : tool position only.
// BM_GeometricJacobian        : 6 x 6 Jacobian (includes the FK of every frame).
// BM_IdentificationJacobian   : 3 x 39 identification Jacobian (includes FK).
// BM_InverseKinematicsNearby  : full-pose IK from a seed 2 deg (per joint, random sign) away, as in
//                               compensation; the counter `iterations` is the mean LM iterations.
// BM_CalibrateDistances/125   : distance-model calibration (IGG3) on 125 simulated cube grid points.
// BM_CalibratePositions/125   : registration + position-model calibration on the same points.
// BM_ReproduceOneRun          : reproduce_paper with runs = 1 (what `errfield reproduce --runs 1`
//                               computes, without writing files); target < 10 s, on 2 threads.
// BM_PredictErrorKinematicKriging/{poses}/{degree}: CompensationModel::predict_error of a
//                               kinematic+kriging model fitted on {poses} SIMULATED KR 16 poses (joint-
//                               space field; degree 8: the default joint error functions with gravity-
//                               load terms, their variance less what the field's weights take back;
//                               0: the field alone): what validate and compensate pay per target.
// BM_FitKinematicKrigingDefault/{poses}: the default robot fit (kinematic calibration, then the
//                               joint-space kriging field whose model --model auto chooses among 10
//                               REML fits: ranked on 300 poses, the best two confirmed on all) on
//                               {poses} SIMULATED KR 16 poses; targets (issue 36, idle 2 cores):
//                               687 poses <= 3 s, 5,000 <= 10 s.
// Run: build/benchmarks/bm_robot
#include <vector>

#include <benchmark/benchmark.h>

#include "errfield/compensation/fitting/model_fitting.hpp"
#include "errfield/robot/builtin_robots.hpp"
#include "errfield/robot/calibration.hpp"
#include "errfield/reproduction/paper_reproduction.hpp"
#include "errfield/robot/simulator.hpp"

namespace {

using namespace errfield::robot;
using namespace errfield::reproduction;

MdhModel bench_model() { return MdhModel::er20_c10().with_tool(paper_ball()); }

std::vector<JointVector> joints(std::size_t n) {
  SimulationRng rng(1);
  std::vector<JointVector> q(n);
  for (auto& v : q)
    v << rng.uniform(-60, 60), rng.uniform(-140, -60), rng.uniform(-60, 30), rng.uniform(-90, 90),
        rng.uniform(-100, -20), rng.uniform(-90, 90);
  return q;
}

void BM_ForwardKinematics(benchmark::State& state) {
  const MdhModel m = bench_model();
  const auto q = joints(1024);
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(forward_kinematics(m, q[i++ & 1023]));
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_ForwardKinematics);

void BM_ForwardPosition(benchmark::State& state) {
  const MdhModel m = bench_model();
  const auto q = joints(1024);
  std::size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(forward_position(m, q[i++ & 1023]));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_ForwardPosition);

void BM_GeometricJacobian(benchmark::State& state) {
  const MdhModel m = bench_model();
  const auto q = joints(1024);
  std::size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(geometric_jacobian(m, q[i++ & 1023]));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_GeometricJacobian);

void BM_IdentificationJacobian(benchmark::State& state) {
  const MdhModel m = bench_model();
  const auto q = joints(1024);
  std::size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(identification_jacobian(m, q[i++ & 1023]));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_IdentificationJacobian);

void BM_InverseKinematicsNearby(benchmark::State& state) {
  const MdhModel m = bench_model();
  const auto q = joints(256);
  std::vector<Eigen::Isometry3d> targets;
  std::vector<JointVector> seeds;
  SimulationRng rng(2);
  for (const auto& v : q) {
    targets.push_back(forward_kinematics(m, v));
    JointVector s = v;
    for (int k = 0; k < kJointCount; ++k) s[k] += rng.uniform01() < 0.5 ? -2.0 : 2.0;
    seeds.push_back(s);
  }
  std::size_t i = 0;
  double iterations = 0, failures = 0;
  for (auto _ : state) {
    const std::size_t k = i++ & 255;
    const IkResult r = inverse_kinematics(m, targets[k], seeds[k]);
    iterations += r.iterations;
    failures += r.ok() ? 0 : 1;
    benchmark::DoNotOptimize(r);
  }
  state.counters["iterations"] = iterations / static_cast<double>(state.iterations());
  state.counters["failures"] = failures;
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_InverseKinematicsNearby)->Unit(benchmark::kMicrosecond);

struct CubeData {
  std::vector<DistanceMeasurement> distances;
  std::vector<PositionMeasurement> positions;
  MdhModel nominal = bench_model();
};

CubeData cube_data() {
  CubeData d;
  const SimulatedRobot robot(SimulatorConfig::paper_default());
  d.nominal = robot.nominal();
  const MeasurementCube cube = paper_cube();
  const IkResult seed = cube_seed(robot.nominal(), cube);
  SimulationRng rng(3);
  const Eigen::Vector3d b = paper_base_point_nominal();
  const JointVector qb = solve_cube_pose(robot.nominal(), cube, b, seed.q_deg).q_deg;
  const Eigen::Vector3d mb = robot.measure(robot.move(qb, rng), rng);
  for (const auto& p : cube.grid(125)) {
    const JointVector q = solve_cube_pose(robot.nominal(), cube, p, seed.q_deg).q_deg;
    const Eigen::Vector3d m = robot.measure(robot.move(q, rng), rng);
    d.positions.push_back({q, m});
    if ((p - b).norm() > 1) d.distances.push_back({q, qb, (m - mb).norm()});
  }
  return d;
}

void BM_CalibrateDistances(benchmark::State& state) {
  const CubeData d = cube_data();
  for (auto _ : state) benchmark::DoNotOptimize(calibrate_distances(d.nominal, d.distances));
  state.counters["points"] = static_cast<double>(d.positions.size());
}
BENCHMARK(BM_CalibrateDistances)->Arg(125)->Unit(benchmark::kMillisecond);

void BM_CalibratePositions(benchmark::State& state) {
  const CubeData d = cube_data();
  for (auto _ : state) {
    const CalibrationResult reg = register_tracker(d.nominal, d.positions);
    benchmark::DoNotOptimize(calibrate_positions(reg.model, d.positions));
  }
  state.counters["points"] = static_cast<double>(d.positions.size());
}
BENCHMARK(BM_CalibratePositions)->Arg(125)->Unit(benchmark::kMillisecond);

void BM_ReproduceOneRun(benchmark::State& state) {
  ReproductionOptions options;
  options.seed = 3;
  options.runs = 1;
  for (auto _ : state) {
    const ReproductionResult r = reproduce_paper(options);
    benchmark::DoNotOptimize(&r);
  }
}
BENCHMARK(BM_ReproduceOneRun)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

void BM_PredictErrorKinematicKriging(benchmark::State& state) {
  SimulatorConfig c = SimulatorConfig::paper_default();
  c.nominal = find_builtin_robot("kr16")->model;
  const SimulatedRobot robot(c);
  SimulationRng rng(5);
  const double lo[6] = {-150, -130, 70, -90, -110, -180}, hi[6] = {150, -30, 150, 90, 110, 180};
  auto draw = [&](std::size_t n) {
    std::vector<JointVector> q(n);
    for (auto& v : q)
      for (int j = 0; j < 6; ++j) v[j] = rng.uniform(lo[j], hi[j]);
    return q;
  };
  errfield::compensation::MeasurementSet d;
  d.source = "SIMULATED";
  d.q_deg = draw(static_cast<std::size_t>(state.range(0)));
  for (std::size_t i = 0; i < d.q_deg.size(); ++i) {
    d.id.push_back("p" + std::to_string(i));
    d.nominal_mm.push_back(forward_position(robot.nominal(), d.q_deg[i]));
    d.measured_mm.push_back(robot.measure(robot.move(d.q_deg[i], rng), rng));
  }
  errfield::compensation::FitOptions o;
  o.method = errfield::compensation::CompensationMethod::kinematic_kriging;
  o.space = errfield::compensation::FieldSpace::joint;
  o.joint_function_degree = static_cast<int>(state.range(1));
  const errfield::compensation::FitResult fit = errfield::compensation::fit_compensation_model(robot.nominal(), d, o);
  const std::vector<JointVector> targets = draw(256);
  std::size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(fit.model.predict_error(targets[i++ & 255]));
  state.SetItemsProcessed(state.iterations());
}
void BM_FitKinematicKrigingDefault(benchmark::State& state) {
  SimulatorConfig c = SimulatorConfig::paper_default();
  c.nominal = find_builtin_robot("kr16")->model;
  const SimulatedRobot robot(c);
  SimulationRng rng(7);
  const double lo[6] = {-150, -130, 70, -90, -110, -180}, hi[6] = {150, -30, 150, 90, 110, 180};
  errfield::compensation::MeasurementSet d;
  d.source = "SIMULATED";
  for (long i = 0; i < state.range(0); ++i) {
    JointVector q;
    for (int j = 0; j < 6; ++j) q[j] = rng.uniform(lo[j], hi[j]);
    d.q_deg.push_back(q);
    d.id.push_back("p" + std::to_string(i));
    d.nominal_mm.push_back(forward_position(robot.nominal(), q));
    d.measured_mm.push_back(robot.measure(robot.move(q, rng), rng));
  }
  errfield::compensation::FitOptions o;
  o.method = errfield::compensation::CompensationMethod::kinematic_kriging;
  o.space = errfield::compensation::FieldSpace::joint;
  for (auto _ : state) {
    const errfield::compensation::FitResult fit = errfield::compensation::fit_compensation_model(robot.nominal(), d, o);
    benchmark::DoNotOptimize(&fit);
  }
}
BENCHMARK(BM_FitKinematicKrigingDefault)->ArgName("poses")->Arg(687)->Arg(5000)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

BENCHMARK(BM_PredictErrorKinematicKriging)
    ->ArgNames({"poses", "degree"})
    ->ArgsProduct({{300, 700}, {0, 8}})
    ->Unit(benchmark::kMicrosecond);

}  // namespace
