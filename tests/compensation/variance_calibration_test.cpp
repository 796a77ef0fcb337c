// The leave-one-out calibration of a kriging field's predictive variance (VarianceCalibration,
// kriging_fields.hpp): its factor against a leave-one-out computed here by refitting without each
// sample, the predictions it must leave alone, and on SIMULATED Gaussian fields whose model states
// a variance 4x too small, that it is what brings the 95 % region back to holding 95 % of held-out
// readings.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "errfield/compensation/model/error_ball.hpp"
#include "errfield/compensation/model/kriging_fields.hpp"
#include "errfield/variogram_model.hpp"

namespace errfield::compensation {
namespace variance_calibration_test {

/// Readings of a SIMULATED 3-component Gaussian field at `n` random points in a 1000 mm cube:
/// covariance sill exp(-h/range) per component, a constant mean, independent noise of variance
/// `nugget` on every reading.
struct FieldDraw {
  std::vector<Eigen::Vector3d> x, reading;
};

FieldDraw draw_field(unsigned seed, int n, double sill, double range, double nugget) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1000.0);
  std::normal_distribution<double> z;
  FieldDraw d;
  d.x.resize(static_cast<std::size_t>(n));
  for (auto& p : d.x) p = Eigen::Vector3d(u(rng), u(rng), u(rng));
  Eigen::MatrixXd k(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      k(i, j) = sill * std::exp(-(d.x[static_cast<std::size_t>(i)] - d.x[static_cast<std::size_t>(j)]).norm() / range);
  const Eigen::MatrixXd l = Eigen::LLT<Eigen::MatrixXd>(k).matrixL();
  Eigen::MatrixXd white(n, 3);
  for (int i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) white(i, c) = z(rng);
  const Eigen::MatrixXd field = l * white;
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3d r = field.row(i).transpose() + Eigen::Vector3d(0.3, -0.2, 0.1);
    for (int c = 0; c < 3; ++c) r[c] += std::sqrt(nugget) * z(rng);
    d.reading.push_back(r);
  }
  return d;
}

FieldSamples samples_of(const std::vector<Eigen::Vector3d>& x) {
  FieldSamples s;
  for (const auto& p : x) {
    s.position_mm.push_back(p);
    s.joints_deg.push_back(robot::JointVector::Zero());
  }
  return s;
}

KrigingFieldOptions options_with(const std::string& model, bool calibrate) {
  KrigingFieldOptions o;
  o.space = FieldSpace::task;
  o.model = VariogramModel::parse(model);
  o.region_margin_mm = 1000.0;  // every point of the cube is predicted
  o.calibrate_variance = calibrate;
  return o;
}

/// Per sample, z² of a leave-one-out by refitting: a field on the other samples (model `given`, not
/// calibrated) predicts the left-out one; its variance is that of a new reading.
std::vector<double> refitted_squared_z(const FieldDraw& d, const std::string& given) {
  std::vector<double> z2;
  for (std::size_t i = 0; i < d.x.size(); ++i) {
    std::vector<Eigen::Vector3d> x, v;
    for (std::size_t j = 0; j < d.x.size(); ++j)
      if (j != i) x.push_back(d.x[j]), v.push_back(d.reading[j]);
    const auto field = make_vector_kriging_field(samples_of(x), v, options_with(given, false));
    const ErrorPrediction p = field->predict(d.x[i], robot::JointVector::Zero());
    if (!p.inside_region) return {};
    z2.push_back((d.reading[i] - p.position_error_mm).squaredNorm() / p.axis_variance_mm2[0]);
  }
  return z2;
}

TEST(VarianceCalibration, OneFarOutSampleEntersTheMeanAtTheCap) {
  // The model is right, but one reading is 1 mm off (sd 0.11 mm per axis). The mean takes each z² up to tail · χ²₃(0.999) = tail · 16.266 (R qchisq(0.999, 3)).
  FieldDraw d = draw_field(5, 60, 0.01, 300.0, 0.0025);
  d.reading[17] += Eigen::Vector3d(1.0, 0.0, 0.0);
  const std::string given = "exp(sill=0.01,range=300)+nug(0.0025)";
  std::vector<double> z2 = refitted_squared_z(d, given);
  ASSERT_EQ(z2.size(), d.x.size());
  std::sort(z2.begin(), z2.end());
  const double tail = z2[static_cast<std::size_t>(std::ceil(0.95 * 60)) - 1] / 7.814727903251178;
  const double cap = tail * 16.266236196238129;
  double capped_mean = 0.0, plain_mean = 0.0;
  std::size_t capped = 0;
  for (double z : z2) {
    capped_mean += std::min(z, cap) / 3.0 / 60.0;
    plain_mean += z / 3.0 / 60.0;
    capped += z > cap ? 1 : 0;
  }
  ASSERT_GE(capped, 1u);
  const KrigingFieldFit fit = fit_vector_kriging_field(samples_of(d.x), d.reading, options_with(given, true));
  ASSERT_TRUE(fit.variance_calibration.has_value());
  const VarianceCalibration& c = *fit.variance_calibration;
  EXPECT_EQ(c.capped_samples, capped);
  EXPECT_NEAR(c.mean_squared_z_before, capped_mean, 1e-8 * capped_mean);
  EXPECT_NEAR(c.factor, std::max(capped_mean, tail), 1e-8 * c.factor);
  // The cap took something off (the neighbours that lean on the reading keep theirs: they are the
  // tail, not one sample).
  EXPECT_LT(c.mean_squared_z_before, plain_mean - 0.1);
  const nlohmann::json j = fit.field->to_json();
  EXPECT_EQ(j["variance_calibration"]["capped_samples"].get<std::size_t>(), capped);
  const auto back = kriging_field_from_json(j, "m.json");
  ASSERT_NE(back, nullptr);
  EXPECT_EQ(back->to_json()["variance_calibration"], j["variance_calibration"]);
}

TEST(VarianceCalibration, FactorIsTheLargerOfMeanAndTailOfALeaveOneOutByRefitting) {
  // 40 samples; the model's variance 4x too small. Independent leave-one-out: a field on the other
  // 39 samples (same model, not calibrated) predicts the left-out one; its variance is that of a
  // new reading (field + nugget per axis). z² = |residual|² / variance is χ²₃ when the model is
  // right; factor = max(mean z² / 3, the 95 % quantile of z² (the ceil(0.95 n)-th smallest) /
  // χ²₃(0.95) = 7.8147).
  const FieldDraw d = draw_field(3, 40, 0.04, 300.0, 0.01);
  const std::string given = "exp(sill=0.01,range=300)+nug(0.0025)";
  std::vector<double> z2 = refitted_squared_z(d, given);
  ASSERT_EQ(z2.size(), d.x.size());
  double mean = 0.0;
  for (double z : z2) mean += z / 3.0 / static_cast<double>(z2.size());
  std::sort(z2.begin(), z2.end());
  const double tail = z2[static_cast<std::size_t>(std::ceil(0.95 * 40)) - 1] / 7.814727903251178;
  const double want = std::max(mean, tail);

  const KrigingFieldFit fit = fit_vector_kriging_field(samples_of(d.x), d.reading, options_with(given, true));
  ASSERT_TRUE(fit.variance_calibration.has_value());
  const VarianceCalibration& c = *fit.variance_calibration;
  EXPECT_NEAR(c.mean_squared_z_before, mean, 1e-8 * mean);
  EXPECT_NEAR(c.tail_factor, tail, 1e-8 * tail);
  EXPECT_NEAR(c.factor, want, 1e-8 * want);
  EXPECT_EQ(c.samples, 40u);
  EXPECT_EQ(c.model_before, VariogramModel::parse(given).to_string());
  // The variance was 4x too small: the factor says so (loosely: 40 samples).
  EXPECT_GT(c.factor, 2.0);
  // The calibrated model is the given one scaled, and so the field's leave-one-out says mean z² <= 1.
  EXPECT_NEAR(fit.model.sill(), c.factor * 0.0125, 1e-12);
  EXPECT_NEAR(fit.model.nugget(), c.factor * 0.0025, 1e-12);
  ASSERT_TRUE(fit.leave_one_out.mean_squared_z.has_value());
  EXPECT_NEAR(*fit.leave_one_out.mean_squared_z, mean / c.factor, 1e-8);
  // The model file says what was done, and reads back to the same calibration.
  const nlohmann::json j = fit.field->to_json();
  ASSERT_TRUE(j.contains("variance_calibration")) << j.dump();
  EXPECT_EQ(j["variance_calibration"]["method"], "leave-one-out");
  EXPECT_NEAR(j["variance_calibration"]["factor"].get<double>(), c.factor, 1e-15);
  const auto back = kriging_field_from_json(j, "m.json");
  ASSERT_NE(back, nullptr);
  EXPECT_EQ(back->to_json()["variance_calibration"], j["variance_calibration"]);
}

TEST(VarianceCalibration, LeavesPredictionsAndScalesVariances) {
  // Ordinary kriging weights do not depend on the covariance's scale: the calibrated field predicts
  // the same errors, and every variance (field and nugget) times the factor.
  const FieldDraw d = draw_field(5, 60, 0.04, 300.0, 0.01);
  const std::string given = "exp(sill=0.01,range=300)+nug(0.0025)";
  const KrigingFieldFit plain = fit_vector_kriging_field(samples_of(d.x), d.reading, options_with(given, false));
  const KrigingFieldFit calibrated = fit_vector_kriging_field(samples_of(d.x), d.reading, options_with(given, true));
  ASSERT_FALSE(plain.variance_calibration.has_value());
  ASSERT_TRUE(calibrated.variance_calibration.has_value());
  const double c = calibrated.variance_calibration->factor;
  for (const Eigen::Vector3d& x : {Eigen::Vector3d(100, 200, 300), Eigen::Vector3d(500, 500, 500),
                                   Eigen::Vector3d(900, 50, 700)}) {
    const ErrorPrediction a = plain.field->predict(x, robot::JointVector::Zero());
    const ErrorPrediction b = calibrated.field->predict(x, robot::JointVector::Zero());
    EXPECT_LT((a.position_error_mm - b.position_error_mm).norm(), 1e-9) << x.transpose();
    EXPECT_NEAR(b.variance_mm2, c * a.variance_mm2, 1e-9 * b.variance_mm2);
    EXPECT_NEAR(b.axis_variance_mm2[0], c * a.axis_variance_mm2[0], 1e-9 * b.axis_variance_mm2[0]);
  }
  EXPECT_NEAR(calibrated.leave_one_out.rms_error, plain.leave_one_out.rms_error, 1e-9);
}

TEST(VarianceCalibration, BringsTheNinetyFivePercentRegionBackWhenTheModelUnderstatesTheVariance) {
  // 4 SIMULATED fields x (150 training + 200 held-out readings), the model's sill and nugget 4x too
  // small. Pooled 800 held-out readings: binomial standard error of coverage95
  // sqrt(0.95 * 0.05 / 800) = 0.0077; pass band 4 standard errors (0.919-0.981). Uncalibrated the
  // region's radius is half what it should be: P(χ²₃ <= 7.81 / 4) = 0.42 expected, far outside.
  const std::string given = "exp(sill=0.01,range=300)+nug(0.0025)";
  double points = 0, within = 0, within_uncalibrated = 0;
  for (unsigned seed = 11; seed <= 14; ++seed) {
    const FieldDraw d = draw_field(seed, 350, 0.04, 300.0, 0.01);
    const std::vector<Eigen::Vector3d> x(d.x.begin(), d.x.begin() + 150), v(d.reading.begin(), d.reading.begin() + 150);
    const KrigingFieldFit calibrated = fit_vector_kriging_field(samples_of(x), v, options_with(given, true));
    const KrigingFieldFit plain = fit_vector_kriging_field(samples_of(x), v, options_with(given, false));
    for (std::size_t i = 150; i < d.x.size(); ++i) {
      const ErrorPrediction a = calibrated.field->predict(d.x[i], robot::JointVector::Zero());
      const ErrorPrediction b = plain.field->predict(d.x[i], robot::JointVector::Zero());
      ASSERT_TRUE(a.inside_region && b.inside_region);
      points += 1;
      within += (d.reading[i] - a.position_error_mm).norm() <= radius_with_probability(0.95, a.axis_variance_mm2);
      within_uncalibrated += (d.reading[i] - b.position_error_mm).norm() <= radius_with_probability(0.95, b.axis_variance_mm2);
    }
  }
  const double se = std::sqrt(0.95 * 0.05 / points);
  std::cout << "SIMULATED, model variance 4x too small: coverage95 " << within / points << " calibrated, "
            << within_uncalibrated / points << " not, on " << points << " held-out readings\n";
  EXPECT_NEAR(within / points, 0.95, 4.0 * se);
  EXPECT_LT(within_uncalibrated / points, 0.95 - 4.0 * se);
}

}  // namespace variance_calibration_test
}  // namespace errfield::compensation
