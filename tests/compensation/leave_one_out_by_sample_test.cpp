// leave_one_out_by_sample (what fit's outlier screen judges rows by) against the brute force: for
// each sample, a field fitted on all the others, predicting at the sample's joints.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "errfield/compensation/model/kriging_fields.hpp"
#include "errfield/variogram_model.hpp"

namespace errfield::compensation {
namespace leave_one_out_by_sample_test {

TEST(LeaveOneOutBySample, EqualsRefittingWithoutEachSample) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> joint(-60.0, 60.0);
  std::normal_distribution<double> noise(0.0, 0.01);
  FieldSamples samples;
  std::vector<Eigen::Vector3d> values;
  for (int i = 0; i < 25; ++i) {
    robot::JointVector q;
    for (int j = 0; j < robot::kJointCount; ++j) q[j] = joint(rng);
    samples.joints_deg.push_back(q);
    samples.position_mm.emplace_back(q[0], q[1], q[2]);  // unused in joint space
    values.emplace_back(0.1 * std::sin(q[0] / 20.0) + noise(rng), 0.05 * std::cos(q[1] / 30.0) + noise(rng),
                        0.002 * q[2] + noise(rng));
  }
  KrigingFieldOptions o;
  o.space = FieldSpace::joint;
  o.model = VariogramModel::parse("gau(sill=0.01,range=60)+nug(0.0001)");
  o.region_margin_deg = 90.0;  // the left-out sample may lie outside the others' box
  const auto field = make_vector_kriging_field(samples, values, o);
  const std::vector<SampleHoldOut> loo = leave_one_out_by_sample(*field);
  ASSERT_EQ(loo.size(), values.size());
  for (std::size_t k = 0; k < values.size(); ++k) {
    FieldSamples others;
    std::vector<Eigen::Vector3d> other_values;
    for (std::size_t i = 0; i < values.size(); ++i) {
      if (i == k) continue;
      others.joints_deg.push_back(samples.joints_deg[i]);
      others.position_mm.push_back(samples.position_mm[i]);
      other_values.push_back(values[i]);
    }
    const auto without = make_vector_kriging_field(others, other_values, o);
    const ErrorPrediction p = without->predict(samples.position_mm[k], samples.joints_deg[k]);
    ASSERT_TRUE(p.inside_region) << k;
    const Eigen::Vector3d residual = values[k] - p.position_error_mm;
    EXPECT_LT((loo[k].residual_mm - residual).norm(), 1e-8) << "sample " << k;
    // per component: a new reading's variance (field + nugget) of one axis
    EXPECT_NEAR(loo[k].variance_mm2, p.predictive_variance_mm2() / 3.0, 1e-9 + 1e-7 * loo[k].variance_mm2)
        << "sample " << k;
  }
}

TEST(LeaveOneOutBySample, EmptyForAFieldThatIsNotAVectorKrigingField) {
  FieldSamples samples;
  std::vector<double> values;
  for (int i = 0; i < 10; ++i) {
    robot::JointVector q = robot::JointVector::Constant(3.0 * i);
    samples.joints_deg.push_back(q);
    samples.position_mm.emplace_back(100.0 * i, 10.0 * (i % 3), 5.0 * (i % 2));
    values.push_back(0.01 * i);
  }
  KrigingFieldOptions o;
  o.model = VariogramModel::parse("exp(sill=0.01,range=200)+nug(0.0001)");
  const auto field = make_distance_kriging_field(samples, values, Eigen::Vector3d(-500, 0, 0), o);
  EXPECT_TRUE(leave_one_out_by_sample(*field).empty());
}

}  // namespace leave_one_out_by_sample_test
}  // namespace errfield::compensation
