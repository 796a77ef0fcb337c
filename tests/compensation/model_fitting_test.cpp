// fit_compensation_model's cross-validation summary for the kriging methods comes from the closed
// form leave-one-out of one factorization; here it is checked against the definition: refit
// ordinary kriging without sample i, predict sample i, for every i (SIMULATED measurements).

#include "errfield/compensation/fitting/model_fitting.hpp"

#include <algorithm>
#include <cmath>
#include <span>

#include <gtest/gtest.h>

#include "errfield/error.hpp"
#include "errfield/kriging.hpp"
#include "errfield/compensation/planning/measurement_plan.hpp"
#include "errfield/robot/simulator.hpp"

namespace errfield::compensation {
using namespace errfield::robot;
namespace model_fitting_test {

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

TEST(FitCompensationModel, RepeatedMeasurementsOfAPoseAreAveragedNotRejected) {
  // A pose measured twice used to make fit's leave-one-out refuse the data as duplicates (its own
  // kriging rejected them while the field averaged them). Now field and leave-one-out share one
  // factorization. Ground truth: an exact repeat averages to the same value, so without a nugget
  // the result must equal the fit without it (checked above against refitting), over the 27
  // distinct locations. (fit's nugget is measurement error: two measurements of a pose then carry
  // nugget/2, which legitimately changes the field; kriging_test checks that against kriging with
  // both repeats kept.)
  const SimulatedRobot sim(SimulatorConfig::paper_default());
  const MeasurementSet data = simulated_grid(sim);
  MeasurementSet repeated = data;
  for (std::size_t i : {std::size_t{3}, std::size_t{11}}) {
    repeated.id.push_back(data.id[i] + "-again");
    repeated.q_deg.push_back(data.q_deg[i]);
    repeated.nominal_mm.push_back(data.nominal_mm[i]);
    repeated.measured_mm.push_back(data.measured_mm[i]);
    repeated.distance_mm[0].push_back(data.distance_mm[0][i]);
  }
  FitOptions o;
  o.method = CompensationMethod::distance_kriging;
  o.model = VariogramModel::parse("sph(sill=0.02,range=700)");
  const FitResult once = fit_compensation_model(sim.nominal(), data, o);
  const FitResult twice = fit_compensation_model(sim.nominal(), repeated, o);
  ASSERT_TRUE(once.cross_validation && twice.cross_validation);
  const CrossValidationReport& a = *once.cross_validation;
  const CrossValidationReport& b = *twice.cross_validation;
  EXPECT_EQ(b.samples, data.id.size());
  EXPECT_NEAR(b.rms_mm, a.rms_mm, 1e-12);
  EXPECT_NEAR(b.max_abs_mm, a.max_abs_mm, 1e-12);
  EXPECT_NE(b.method.find("2 repeated measurements averaged"), std::string::npos) << b.method;
  EXPECT_EQ(a.method.find("repeated"), std::string::npos) << a.method;
}

TEST(FitCompensationModel, IllConditionedUserKrigingModelIsRefused) {
  // A smooth model without nugget and a range far beyond the 250 mm spacing: the system is nearly
  // singular. Such a model is never written as if fine (issue 10 item 5): a model the user gave is
  // refused (a failed job, not bad input), naming the problem and suggesting a nugget.
  const SimulatedRobot sim(SimulatorConfig::paper_default());
  const MeasurementSet data = simulated_grid(sim);
  FitOptions o;
  o.method = CompensationMethod::distance_kriging;
  o.model = VariogramModel::parse("gau(sill=0.5,range=5000)");
  try {
    (void)fit_compensation_model(sim.nominal(), data, o);
    ADD_FAILURE() << "an ill-conditioned model must not be returned";
  } catch (const InputError& e) {
    ADD_FAILURE() << "refusal is a failed job (exit 1), not bad input: " << e.what();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("ill-conditioned"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("nug("), std::string::npos) << e.what();
  }
  o.model = VariogramModel::parse("gau(sill=0.5,range=5000)+nug(0.001)");
  const FitResult good = fit_compensation_model(sim.nominal(), data, o);
  EXPECT_TRUE(good.warnings.empty());
  ASSERT_TRUE(good.cross_validation.has_value());
  EXPECT_EQ(good.cross_validation->samples, data.id.size());
}

TEST(FitCompensationModel, AnnouncesEachLongStageInOrder) {
  const SimulatedRobot sim(SimulatorConfig::paper_default());
  const MeasurementSet data = simulated_grid(sim);
  std::vector<std::string> stages;
  FitOptions o;
  o.method = CompensationMethod::vector_kriging;
  o.on_stage = [&](const std::string& s) { stages.push_back(s); };
  fit_compensation_model(sim.nominal(), data, o);
  ASSERT_EQ(stages.size(), 4u);
  EXPECT_EQ(stages[0], "estimating the variogram");
  EXPECT_EQ(stages[1].rfind("factoring the 27 x 27 covariance matrix", 0), 0u) << stages[1];
  // an estimated model's variance is calibrated (one more factorization), then the leave-one-out
  EXPECT_EQ(stages[2], "calibrating the predictive variance by leave-one-out");
  EXPECT_EQ(stages[3], "leave-one-out from the factorization");
  stages.clear();
  o.model = VariogramModel::parse("sph(sill=0.02,range=700)+nug(0.001)");  // given: nothing to estimate
  fit_compensation_model(sim.nominal(), data, o);
  EXPECT_EQ(stages.size(), 2u);
}

TEST(KrigingFieldFit, VectorFieldAveragesRepeatedSamples) {
  // (fit --method vector-kriging registers the positions first, and a repeated pose weighs twice in
  // the registration, so the field is compared here on given error vectors.)
  const SimulatedRobot sim(SimulatorConfig::paper_default());
  const MeasurementSet data = simulated_grid(sim);
  FieldSamples samples{data.nominal_mm, data.q_deg};
  std::vector<Eigen::Vector3d> dp;
  for (std::size_t i = 0; i < data.id.size(); ++i) dp.push_back(data.measured_mm[i] - data.nominal_mm[i]);
  // Micro-scale nugget: repeats of a pose share it, so an exact repeat changes nothing.
  FieldSamples samples_repeated = samples;
  std::vector<Eigen::Vector3d> dp_repeated = dp;
  samples_repeated.position_mm.push_back(samples.position_mm[7]);
  samples_repeated.joints_deg.push_back(samples.joints_deg[7]);
  dp_repeated.push_back(dp[7]);
  KrigingFieldOptions o;
  o.model = VariogramModel::parse("sph(sill=0.02,range=700)+nug(0.001)");
  o.nugget_is_measurement_error = false;
  const KrigingFieldFit once = fit_vector_kriging_field(samples, dp, o);
  const KrigingFieldFit twice = fit_vector_kriging_field(samples_repeated, dp_repeated, o);
  EXPECT_EQ(once.merged_duplicates, 0u);
  EXPECT_EQ(twice.merged_duplicates, 1u);
  EXPECT_EQ(twice.leave_one_out.predicted, dp.size());
  EXPECT_NEAR(twice.leave_one_out.rms_error, once.leave_one_out.rms_error, 1e-12);
  EXPECT_GT(once.leave_one_out.rms_error, 0.0);
  const Eigen::Vector3d target = samples.position_mm[7] + Eigen::Vector3d(30.0, -20.0, 10.0);
  const ErrorPrediction p1 = once.field->predict(target, samples.joints_deg[7]);
  const ErrorPrediction p2 = twice.field->predict(target, samples.joints_deg[7]);
  ASSERT_TRUE(p1.inside_region && p2.inside_region);
  EXPECT_LT((p1.position_error_mm - p2.position_error_mm).norm(), 1e-12);
  // Measurement-error nugget: the averaged pose carries nugget/2, so the smoothed field at it moves
  // toward the observation: z - mu = s / (s + v) (z - mu_without_it) with s its noise variance and
  // v (> 0) the signal variance left by the other samples, a ratio that shrinks with s.
  o.nugget_is_measurement_error = true;
  const KrigingFieldFit noisy_once = fit_vector_kriging_field(samples, dp, o);
  const KrigingFieldFit noisy_twice = fit_vector_kriging_field(samples_repeated, dp_repeated, o);
  const ErrorPrediction q1 = noisy_once.field->predict(samples.position_mm[7], samples.joints_deg[7]);
  const ErrorPrediction q2 = noisy_twice.field->predict(samples.position_mm[7], samples.joints_deg[7]);
  ASSERT_TRUE(q1.inside_region && q2.inside_region);
  EXPECT_LT((q2.position_error_mm - dp[7]).norm(), 0.99 * (q1.position_error_mm - dp[7]).norm());
}

}  // namespace
}  // namespace errfield::compensation
