#include "errfield/compensation/model/calibration_leverage.hpp"

#include <gtest/gtest.h>

#include <random>

#include <nlohmann/json.hpp>

#include "errfield/error.hpp"
#include "errfield/robot/builtin_robots.hpp"
#include "errfield/robot/kinematics.hpp"

namespace errfield::compensation {
using namespace errfield::robot;
namespace calibration_leverage_test {

/// The KR 16 with a reflector 100 mm out on the flange's axis.
MdhModel arm() {
  Eigen::Isometry3d tool = Eigen::Isometry3d::Identity();
  tool.translation() = Eigen::Vector3d(0, 0, 100);
  return kr16().with_tool(tool);
}

/// Joints of a KR 16-like arm with the tool pointing down within `tilt_deg` (q5 near -90 + tilt,
/// q4 and q6 small), in a box of the first three joints.
std::vector<JointVector> poses(std::size_t n, double wrist_spread_deg, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<JointVector> q(n);
  for (auto& v : q)
    v << 40 * u(rng), -90 + 25 * u(rng), 100 + 25 * u(rng), wrist_spread_deg * u(rng), 60 + wrist_spread_deg * u(rng),
        wrist_spread_deg * u(rng);
  return q;
}

/// An identification Jacobian by central differences of apply_parameter_increment: independent of
/// identification_jacobian's analytic form.
Eigen::Matrix<double, 3, Eigen::Dynamic> numerical_columns(const MdhModel& m, const JointVector& q, const std::vector<int>& p) {
  Eigen::Matrix<double, 3, Eigen::Dynamic> j(3, static_cast<Eigen::Index>(p.size()));
  for (std::size_t c = 0; c < p.size(); ++c) {
    ParameterVector d = ParameterVector::Zero();
    const double h = parameter_is_angle(p[c]) ? 1e-6 : 1e-4;
    d[p[c]] = h;
    j.col(static_cast<Eigen::Index>(c)) =
        (forward_position(apply_parameter_increment(m, d), q) - forward_position(apply_parameter_increment(m, -d), q)) / (2 * h);
  }
  return j;
}

// v(q) is the calibrated prediction's variance under the readings' noise and the parameters' prior:
// equal to the one built explicitly from a finite-difference Jacobian (a second implementation),
// and at a training pose at most the readings' own variance (the hat matrix's diagonal is <= 1).
TEST(CalibrationLeverage, IsThePosteriorVarianceOfTheCalibratedPrediction) {
  const MdhModel m = arm();
  const double noise = 0.02 * 0.02;  // mm² per component
  const std::vector<JointVector> q = poses(60, 60.0, 3);
  const std::optional<CalibrationLeverage> lev = CalibrationLeverage::of(m, q, noise);
  ASSERT_TRUE(lev);
  std::vector<int> all;
  for (int k = 0; k < param::kCount; ++k) all.push_back(k);
  Eigen::MatrixXd information = Eigen::MatrixXd::Zero(param::kCount, param::kCount);
  for (int k = 0; k < param::kCount; ++k) {
    const bool base = k >= param::kBaseTranslation && k < param::kToolTranslation;
    const double sd = base ? (k < param::kBaseRotation ? kFreeBaseSdMm : kFreeBaseSdRad)
                           : (parameter_is_angle(k) ? kGeometricErrorSdRad : kGeometricErrorSdMm);
    information(k, k) = 1.0 / (sd * sd);
  }
  for (const JointVector& v : q) {
    const Eigen::Matrix<double, 3, Eigen::Dynamic> j = numerical_columns(m, v, all);
    information += j.transpose() * j / noise;
  }
  const Eigen::MatrixXd covariance = information.inverse();
  double largest = 0.0;
  for (const JointVector& v : q) {
    const double at = lev->at(m, v);
    EXPECT_LE(at, 3.0 * noise * (1 + 1e-9));
    largest = std::max(largest, at);
  }
  EXPECT_NEAR(lev->largest_training, largest, 1e-9 * largest);
  for (const JointVector& v : poses(5, 90.0, 9)) {
    const Eigen::Matrix<double, 3, Eigen::Dynamic> j = numerical_columns(m, v, all);
    const double independent = (j * covariance * j.transpose()).trace();
    EXPECT_NEAR(lev->at(m, v), independent, 1e-4 * independent);
  }
}

// Poses of one tool orientation leave the wrist's parameters determined only in the combinations
// they move: poses of other orientations in the same box of the first three joints lie far beyond
// the training poses' variance, while new poses like the training ones do not.
TEST(CalibrationLeverage, OneOrientationsPosesDoNotCoverATiltedTool) {
  const MdhModel m = arm();
  const std::optional<CalibrationLeverage> lev = CalibrationLeverage::of(m, poses(40, 2.0, 5), 0.03 * 0.03);
  ASSERT_TRUE(lev);
  std::size_t like_training_beyond = 0, tilted_beyond = 0;
  for (const JointVector& v : poses(100, 2.0, 6)) like_training_beyond += lev->ratio(m, v) > kMaxCalibrationLeverageRatio;
  for (const JointVector& v : poses(100, 45.0, 7)) tilted_beyond += lev->ratio(m, v) > kMaxCalibrationLeverageRatio;
  EXPECT_LE(like_training_beyond, 5u);
  EXPECT_GE(tilted_beyond, 90u);
}

TEST(CalibrationLeverage, JsonRoundTripsAndHandEditsAreRefused) {
  const MdhModel m = arm();
  const std::optional<CalibrationLeverage> lev = CalibrationLeverage::of(m, poses(20, 30.0, 1), 1e-3);
  ASSERT_TRUE(lev);
  const nlohmann::json j = lev->to_json();
  const CalibrationLeverage back = CalibrationLeverage::from_json(j, "m.json");
  const JointVector q = poses(1, 30.0, 2)[0];
  EXPECT_DOUBLE_EQ(back.at(m, q), lev->at(m, q));
  auto refused = [&](nlohmann::json e, const std::string& expected) {
    try {
      (void)CalibrationLeverage::from_json(e, "m.json");
      ADD_FAILURE() << "accepted " << e.dump();
    } catch (const InputError& x) {
      EXPECT_NE(std::string(x.what()).find(expected), std::string::npos) << x.what();
      EXPECT_NE(std::string(x.what()).find("m.json"), std::string::npos) << x.what();
    }
  };
  nlohmann::json e = j;
  e["parameters"][0] = "link9.a";
  refused(e, "unknown parameter");
  e = j;
  e["inverse_information"][0][1] = 1.0;
  refused(e, "not symmetric");
  e = j;
  e["inverse_information"][0][0] = -1.0;
  refused(e, "positive semi-definite");
  e = j;
  e["largest_training"] = 0.0;
  refused(e, "largest_training");
  e = j;
  e["inverse_information"].erase(0);
  refused(e, "square matrix");
}

}  // namespace calibration_leverage_test
}  // namespace errfield::compensation
