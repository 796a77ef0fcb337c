// fit_compensation_model's cross-validation summary for the kriging methods comes from the closed
// form leave-one-out of one factorization; here it is checked against the definition: refit
// ordinary kriging without sample i, predict sample i, for every i (SIMULATED measurements).

#include "errfield/robot/model_fitting.hpp"

#include <algorithm>
#include <cmath>
#include <span>

#include <gtest/gtest.h>

#include "errfield/kriging.hpp"
#include "errfield/robot/measurement_plan.hpp"
#include "errfield/robot/simulator.hpp"

namespace errfield::robot {
namespace {

// The paper's cube on a 250 mm grid (27 points), measured by the simulated tracker from a base
// point at the cube's corner.
MeasurementSet simulated_grid(const SimulatedRobot& sim) {
  const MdhModel& robot = sim.nominal();
  const MeasurementCube cube = paper_cube();
  const JointVector seed = cube_seed(robot, cube).q_deg;
  SimulationRng rng(5);
  MeasurementSet data;
  data.source = "simulated grid";
  const JointVector q_base = solve_cube_pose(robot, cube, cube.min_corner_mm, seed).q_deg;
  const Eigen::Vector3d base_reading = sim.measure(sim.move(q_base, rng), rng);
  data.base_nominal_mm = {cube.min_corner_mm};
  data.base_q_deg = {q_base};
  data.distance_mm.resize(1);
  for (const Eigen::Vector3d& p : cube.grid(250.0)) {
    const JointVector q = solve_cube_pose(robot, cube, p, seed).q_deg;
    const Eigen::Vector3d reading = sim.measure(sim.move(q, rng), rng);
    std::string id = "g";
    id += std::to_string(data.id.size());
    data.id.push_back(id);
    data.q_deg.push_back(q);
    data.nominal_mm.push_back(p);
    data.measured_mm.push_back(reading);
    data.distance_mm[0].push_back((reading - base_reading).norm());
  }
  return data;
}

struct Summary {
  double mean_abs = 0, rms = 0, max_abs = 0, mean_z2 = 0;
};

// Leave-one-out by refitting, scalar values, as CrossValidationReport defines its fields.
template <class L, class M>
Summary brute_force_loo(const std::vector<L>& locations, const std::vector<double>& values,
                        const VariogramModel& model) {
  KrigingOptions options;
  options.nugget = NuggetTreatment::MeasurementError;
  Summary s;
  const auto n = locations.size();
  for (std::size_t i = 0; i < n; ++i) {
    std::vector<L> rest_l;
    std::vector<double> rest_v;
    for (std::size_t j = 0; j < n; ++j)
      if (j != i) rest_l.push_back(locations[j]), rest_v.push_back(values[j]);
    const Kriging<L, double, M> k(std::span<const L>(rest_l), std::span<const double>(rest_v), model, options);
    const auto p = k.predict(std::span<const L>(&locations[i], 1));
    const double e = values[i] - p.mean[0];
    const double var = p.variance[0] + model.nugget();  // a new observation carries the nugget
    s.mean_abs += std::abs(e) / static_cast<double>(n);
    s.rms += e * e / static_cast<double>(n);
    s.max_abs = std::max(s.max_abs, std::abs(e));
    s.mean_z2 += e * e / var / static_cast<double>(n);
  }
  s.rms = std::sqrt(s.rms);
  return s;
}

TEST(FitCompensationModel, KrigingLeaveOneOutEqualsRefittingWithoutEachSample) {
  const SimulatedRobot sim(SimulatorConfig::paper_default());
  const MeasurementSet data = simulated_grid(sim);
  const std::vector<double> dl = data.distance_errors(0);
  const VariogramModel model = VariogramModel::parse("sph(sill=0.02,range=700)+nug(0.001)");
  for (FieldSpace space : {FieldSpace::task, FieldSpace::joint}) {
    FitOptions o;
    o.method = CompensationMethod::distance_kriging;
    o.space = space;
    o.model = model;
    const FitResult fit = fit_compensation_model(sim.nominal(), data, o);
    ASSERT_TRUE(fit.cross_validation.has_value());
    const CrossValidationReport& cv = *fit.cross_validation;
    const Summary want = space == FieldSpace::task
                             ? brute_force_loo<Eigen::Vector3d, EuclideanMetric>(data.nominal_mm, dl, model)
                             : brute_force_loo<JointVector, JointSpaceMetric>(data.q_deg, dl, model);
    const char* name = space == FieldSpace::task ? "task" : "joint";
    EXPECT_EQ(cv.samples, dl.size()) << name;
    EXPECT_NEAR(cv.mean_abs_mm, want.mean_abs, 1e-9) << name;
    EXPECT_NEAR(cv.rms_mm, want.rms, 1e-9) << name;
    EXPECT_NEAR(cv.max_abs_mm, want.max_abs, 1e-9) << name;
    ASSERT_TRUE(cv.mean_squared_z.has_value()) << name;
    EXPECT_NEAR(*cv.mean_squared_z, want.mean_z2, 1e-7 * want.mean_z2) << name;
    EXPECT_GT(want.rms, 0.0);
  }
}

}  // namespace
}  // namespace errfield::robot
