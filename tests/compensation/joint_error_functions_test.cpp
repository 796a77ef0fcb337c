#include "errfield/compensation/model/joint_error_functions.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <Eigen/Eigenvalues>
#include <nlohmann/json.hpp>

#include "errfield/compensation/model/compensation.hpp"
#include "errfield/compensation/fitting/held_out_shift.hpp"
#include "compensation/fitting/fit_checks.hpp"
#include "errfield/compensation/model/kriging_fields.hpp"
#include "errfield/error.hpp"
#include "errfield/robot/builtin_robots.hpp"
#include "errfield/robot/kinematics.hpp"
#include "errfield/robot/simulator.hpp"
#include "errfield/variogram_model.hpp"

namespace errfield::compensation {
using namespace errfield::robot;
namespace joint_error_functions_test {

// A prior so wide it changes nothing: the exact formulas of the ridge and GLS fits underneath it.
const JointFunctionPrior kNoPrior{1e12, 1e12, 0.0};

// KR 16 with a 150 mm tool offset from the flange axis, so that every joint moves the point.
MdhModel robot_with_tool() {
  Eigen::Isometry3d tool = Eigen::Isometry3d::Identity();
  tool.translation() = Eigen::Vector3d(60.0, -30.0, 130.0);
  return find_builtin_robot("kr16")->model.with_tool(tool);
}

std::vector<JointVector> random_poses(std::size_t n, unsigned seed) {
  std::mt19937_64 rng(seed);
  const double lo[6] = {-150, -130, 70, -90, -110, -180}, hi[6] = {150, -30, 150, 90, 110, 180};
  std::vector<JointVector> q(n);
  for (auto& v : q)
    for (int j = 0; j < 6; ++j) v[j] = std::uniform_real_distribution<double>(lo[j], hi[j])(rng);
  return q;
}

// Functions with these coefficients (6 x degree) over the joint box random_poses draws from.
JointErrorFunctions functions_over_the_box(const Eigen::MatrixXd& coefficients_mrad) {
  JointErrorFunctions f;
  f.degree = static_cast<int>(coefficients_mrad.cols());
  f.lo_deg = {-150, -130, 70, -90, -110, -180};
  f.hi_deg = {150, -30, 150, 90, 110, 180};
  f.coefficients_mrad = coefficients_mrad;
  return f;
}

// The truth, written without the library's polynomials: each joint's error in mrad as a plain
// polynomial in u (a combination of Legendre degrees 1..4), e.g. 0.8 u^4 - 0.3 u.
double truth_mrad(int joint, double u) {
  const double a[6][5] = {{0, -0.3, 0, 0, 0.8}, {0, 0.2, 0.4, 0, 0}, {0, 0, 0, -0.5, 0},
                          {0, 0.6, 0, 0, 0},    {0, 0, 1.2, 0, 0.9}, {0, -0.4, 0, 0, 0}};
  double v = 0.0, p = 1.0;
  for (int k = 0; k < 5; ++k, p *= u) v += a[joint][k] * p;
  return v;
}

// What those joint errors do to the tool point: the FK at the perturbed joints, by finite
// difference of positions (no Jacobian involved).
Eigen::Vector3d moved_by(const MdhModel& m, const JointVector& q, const std::array<double, 6>& lo,
                         const std::array<double, 6>& hi) {
  JointVector dq_deg;
  for (int j = 0; j < 6; ++j) {
    const double u = 2.0 * (q[j] - lo[static_cast<std::size_t>(j)]) / (hi[static_cast<std::size_t>(j)] - lo[static_cast<std::size_t>(j)]) - 1.0;
    dq_deg[j] = truth_mrad(j, u) * 1e-3 * 180.0 / M_PI;
  }
  return forward_position(m, q + dq_deg) - forward_position(m, q);
}

// A hand-edited functions member is refused, naming the file and `names` (the member).
void refused(const nlohmann::json& j, const std::string& names) {
  try {
    JointErrorFunctions::from_json(j, "m.json");
    ADD_FAILURE() << "accepted " << j.dump();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(names), std::string::npos) << e.what();
    EXPECT_EQ(e.file(), "m.json");
  }
}

TEST(JointErrorFunctions, PositionErrorIsTheFkOfTheAngleErrors) {
  const MdhModel m = robot_with_tool();
  const JointErrorFunctions f = functions_over_the_box(Eigen::MatrixXd::Random(6, 3));
  for (const JointVector& q : random_poses(20, 3)) {
    const Eigen::Matrix<double, 6, 1> dq = f.angle_error_mrad(q);
    // Legendre P1..P3 written out
    for (int j = 0; j < 6; ++j) {
      const double u = 2.0 * (q[j] - f.lo_deg[static_cast<std::size_t>(j)]) /
                           (f.hi_deg[static_cast<std::size_t>(j)] - f.lo_deg[static_cast<std::size_t>(j)]) - 1.0;
      const double expected = f.coefficients_mrad(j, 0) * u + f.coefficients_mrad(j, 1) * (1.5 * u * u - 0.5) +
                              f.coefficients_mrad(j, 2) * (2.5 * u * u * u - 1.5 * u);
      EXPECT_NEAR(dq[j], expected, 1e-12);
    }
    // Small angles: first order in dq, so compare with the FK difference at 1/1000 of the error
    // and scale back (the second-order remainder is then ~1e-6 relative).
    const Eigen::Vector3d fd = (forward_position(m, q + 1e-3 * dq * 1e-3 * 180.0 / M_PI) - forward_position(m, q)) * 1e3;
    EXPECT_LT((f.position_error_mm(m, q) - fd).norm(), 1e-6 * std::max(1.0, fd.norm())) << q.transpose();
  }
}

TEST(JointErrorFunctions, ClampedBeyondTheFittedRange) {
  JointErrorFunctions f;
  f.degree = 2;
  f.lo_deg = {0, 0, 0, 0, 0, 0};
  f.hi_deg = {10, 10, 10, 10, 10, 10};
  f.coefficients_mrad = Eigen::MatrixXd::Ones(6, 2);
  JointVector at_edge = JointVector::Constant(10.0), beyond = JointVector::Constant(25.0);
  EXPECT_EQ(f.angle_error_mrad(at_edge), f.angle_error_mrad(beyond));
  EXPECT_NEAR(f.angle_error_mrad(at_edge)[0], 2.0, 1e-15);  // P1(1) + P2(1)
}

TEST(JointErrorFunctions, RecoversJointErrorsFromPositionsAlone) {
  const MdhModel m = robot_with_tool();
  const std::vector<JointVector> q = random_poses(300, 5);
  std::array<double, 6> lo, hi;
  lo.fill(1e9);
  hi.fill(-1e9);
  for (const auto& v : q)
    for (std::size_t j = 0; j < 6; ++j) {
      lo[j] = std::min(lo[j], v[static_cast<Eigen::Index>(j)]);
      hi[j] = std::max(hi[j], v[static_cast<Eigen::Index>(j)]);
    }
  // The functions have no constant: that is the joint offset, which the calibration identifies
  // before them. So the residuals are those left after the calibration took each truth's mean over
  // u in [-1, 1] as an offset; the functions then hold the truth minus that mean.
  std::mt19937_64 rng(9);
  std::normal_distribution<double> noise(0.0, 0.005);
  std::vector<Eigen::Vector3d> r(q.size());
  JointVector offset_deg;
  for (int j = 0; j < 6; ++j) {
    double mean = 0.0;
    for (int s = 0; s < 2001; ++s) mean += truth_mrad(j, -1.0 + s / 1000.0) / 2001.0;
    offset_deg[j] = mean * 1e-3 * 180.0 / M_PI;
  }
  for (std::size_t i = 0; i < q.size(); ++i)
    r[i] = moved_by(m, q[i], lo, hi) - (forward_position(m, q[i] + offset_deg) - forward_position(m, q[i])) +
           Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
  const JointErrorFunctionFit fit = fit_joint_error_functions(m, q, r, 4);
  EXPECT_GT(fit.rms_before_mm, 0.3);  // the effect is well above the noise
  // What is left is the noise (3-D RMS 0.005 sqrt(3)) plus the linearization (second order).
  EXPECT_LT(fit.rms_after_mm, 0.0125) << fit.rms_before_mm;
  EXPECT_GE(fit.leave_one_out_inflation, 1.0);
  // The recovered angle errors, compared where they matter (over each joint's range).
  for (int j = 0; j < 6; ++j) {
    double mean = 0.0;
    for (int s = 0; s < 2001; ++s) mean += truth_mrad(j, -1.0 + s / 1000.0) / 2001.0;
    for (double u : {-1.0, -0.5, 0.0, 0.5, 1.0}) {
      JointVector at = JointVector::Zero();
      at[j] = lo[static_cast<std::size_t>(j)] + 0.5 * (u + 1.0) * (hi[static_cast<std::size_t>(j)] - lo[static_cast<std::size_t>(j)]);
      EXPECT_NEAR(fit.functions.angle_error_mrad(at)[j], truth_mrad(j, u) - mean, 0.05) << "joint " << j + 1 << " u " << u;
    }
  }
}

TEST(JointErrorFunctions, HeldOutCoefficientChangeIsTheRidgeRefitWithoutThePose) {
  // beta_-i - beta from the hat matrix's 3 x 3 block against the ridge solved again without pose i
  // at the same penalty (recovered as R^-1 - D'D), written out here.
  const MdhModel m = robot_with_tool();
  const std::vector<JointVector> q = random_poses(60, 11);
  std::mt19937_64 rng(13);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::vector<Eigen::Vector3d> r(q.size());
  for (auto& v : r) v = Eigen::Vector3d(noise(rng), noise(rng), noise(rng)) + Eigen::Vector3d(0.03, -0.01, 0.02);
  const JointErrorFunctionFit fit = fit_joint_error_functions(m, q, r, 3);
  const Eigen::MatrixXd& d = fit.design;
  const Eigen::Index n = static_cast<Eigen::Index>(q.size()), p = d.cols();
  ASSERT_EQ(fit.held_out_coefficient_change_mrad.size(), q.size());
  ASSERT_EQ(fit.ridge_inverse.rows(), p);
  Eigen::VectorXd y(3 * n);
  for (Eigen::Index i = 0; i < n; ++i) y.segment<3>(3 * i) = r[static_cast<std::size_t>(i)];
  const Eigen::VectorXd beta = fit.ridge_inverse * (d.transpose() * y);
  for (Eigen::Index i = 0; i < n; ++i)  // the ridge inverse is the fit's: it leaves what the fit left
    ASSERT_LT((y.segment<3>(3 * i) - d.middleRows<3>(3 * i) * beta - fit.remaining_mm[static_cast<std::size_t>(i)]).norm(), 1e-9);
  const Eigen::MatrixXd normal = fit.ridge_inverse.inverse();  // D'D + penalty
  for (Eigen::Index i = 0; i < n; i += 7) {
    const auto di = d.middleRows<3>(3 * i);
    const Eigen::VectorXd without = (normal - di.transpose() * di).ldlt().solve(d.transpose() * y - di.transpose() * y.segment<3>(3 * i));
    const Eigen::VectorXd change = fit.held_out_coefficient_change_mrad[static_cast<std::size_t>(i)];
    EXPECT_LT((change - (without - beta)).norm(), 1e-6 * std::max(1.0, (without - beta).norm())) << "pose " << i;
  }
}

TEST(JointErrorFunctions, HeldOutShiftMakesTheLeaveOneOutOfFunctionsAndFieldTogether) {
  // The field's leave-one-out residual plus the shift, against leaving the pose out of both by
  // brute force: the ridge solved again without it (same penalty, R^-1 - D'D), then the field kriged
  // on the other poses' residuals and predicted at it. At the functions' own point and at a point
  // 150 mm away whose readings a field of its own krigs (the functions carried there).
  const MdhModel m = robot_with_tool();
  Eigen::Isometry3d moved = m.tool();
  moved.translation() += Eigen::Vector3d(150.0, 0.0, 0.0);
  const MdhModel other_point = m.with_tool(moved);
  const std::vector<JointVector> q = random_poses(50, 17);
  std::mt19937_64 rng(19);
  std::normal_distribution<double> noise(0.0, 0.01);
  // A smooth error over the joints plus noise, at each of the two points.
  auto smooth = [](const JointVector& v, double phase) {
    return Eigen::Vector3d(0.05 * std::sin(v[0] / 60.0 + phase), 0.04 * std::cos(v[1] / 40.0), 0.03 * std::sin(v[2] / 50.0 - phase));
  };
  // ... and joint angle errors the functions can hold, so that the ridge fits something.
  Eigen::MatrixXd coefficients(6, 2);
  coefficients << 0.3, -0.2, 0.1, 0.4, -0.3, 0.1, 0.2, 0.2, -0.1, 0.3, 0.2, -0.2;
  const JointErrorFunctions truth = functions_over_the_box(coefficients);
  std::vector<Eigen::Vector3d> y(q.size()), y_other(q.size());
  for (std::size_t i = 0; i < q.size(); ++i) {
    y[i] = truth.position_error_mm(m, q[i]) + smooth(q[i], 0.0) + Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    y_other[i] = truth.position_error_mm(other_point, q[i]) + smooth(q[i], 0.5) + Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
  }
  const auto fit = std::make_shared<const JointErrorFunctionFit>(fit_joint_error_functions(m, q, y, 2));
  const Eigen::Index n = static_cast<Eigen::Index>(q.size()), p = fit->design.cols();
  ASSERT_GT(p, 0);
  ASSERT_EQ(fit->ridge_inverse.rows(), p) << "GCV fitted no function";
  Eigen::VectorXd stacked(3 * n);
  for (Eigen::Index i = 0; i < n; ++i) stacked.segment<3>(3 * i) = y[static_cast<std::size_t>(i)];
  const Eigen::VectorXd beta = fit->ridge_inverse * (fit->design.transpose() * stacked);
  const Eigen::MatrixXd normal = fit->ridge_inverse.inverse();
  KrigingFieldOptions options;
  options.space = FieldSpace::joint;
  options.model = VariogramModel::parse("exp(sill=0.002,range=120)+nug(0.0001)");
  options.region_margin_deg = 360.0;  // every left-out pose inside the others' region
  for (const MdhModel* at : {&m, &other_point}) {
    const bool own = at == &m;
    const std::vector<Eigen::Vector3d>& readings = own ? y : y_other;
    auto design_at = [&](const JointVector& v) { return own ? fit->functions.design_rows(m, v) : fit->functions.design_rows_at_point(m, *at, v); };
    FieldSamples samples;
    std::vector<Eigen::Vector3d> left_by_functions;
    for (std::size_t i = 0; i < q.size(); ++i) {
      samples.position_mm.push_back(forward_position(*at, q[i]));
      samples.joints_deg.push_back(q[i]);
      left_by_functions.push_back(readings[i] - design_at(q[i]) * beta);
    }
    const auto field = make_vector_kriging_field(samples, left_by_functions, options);
    const std::vector<SampleHoldOut> held_out = leave_one_out_by_sample(*field);
    const std::vector<Eigen::Vector3d> shift = joint_function_held_out_shift(fit, q, m, *at)(*field);
    ASSERT_EQ(held_out.size(), q.size());
    ASSERT_EQ(shift.size(), q.size());
    double largest_shift = 0.0;
    for (Eigen::Index i = 0; i < n; i += 5) {
      const auto di = fit->design.middleRows<3>(3 * i);
      const Eigen::VectorXd without =
          (normal - di.transpose() * di).ldlt().solve(fit->design.transpose() * stacked - di.transpose() * stacked.segment<3>(3 * i));
      FieldSamples rest;
      std::vector<Eigen::Vector3d> rest_values;
      for (Eigen::Index j = 0; j < n; ++j) {
        if (j == i) continue;
        const auto js = static_cast<std::size_t>(j);
        rest.position_mm.push_back(samples.position_mm[js]);
        rest.joints_deg.push_back(q[js]);
        rest_values.push_back(readings[js] - design_at(q[js]) * without);
      }
      const auto is = static_cast<std::size_t>(i);
      const ErrorPrediction e = make_vector_kriging_field(rest, rest_values, options)->predict(samples.position_mm[is], q[is]);
      ASSERT_TRUE(e.inside_region);
      const Eigen::Vector3d brute_force = readings[is] - design_at(q[is]) * without - e.position_error_mm;
      EXPECT_LT((held_out[is].residual_mm + shift[is] - brute_force).norm(), 1e-8) << (own ? "own point" : "other point") << " pose " << i;
      largest_shift = std::max(largest_shift, shift[is].norm());
    }
    EXPECT_GT(largest_shift, 1e-4) << "the functions' leave-one-out moved nothing: the check above checked nothing";
  }
}

TEST(JointErrorFunctions, NoiseAloneLeavesThemNearZero) {
  const MdhModel m = robot_with_tool();
  const std::vector<JointVector> q = random_poses(200, 7);
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::vector<Eigen::Vector3d> r(q.size());
  for (auto& v : r) v = Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
  for (const bool gravity : {false, true}) {
    const JointErrorFunctionFit fit = fit_joint_error_functions(m, q, r, 8, gravity);
    EXPECT_EQ(fit.functions.gravity_terms.empty(), !gravity);
    // Generalized cross-validation does not spend 48 (with the gravity-load terms ~60) parameters on
    // noise: at most a few effective ones, and the residual barely shrinks.
    EXPECT_LT(fit.effective_parameters, 6.0) << gravity;
    EXPECT_GT(fit.rms_after_mm, 0.97 * fit.rms_before_mm) << gravity;
  }
}

TEST(JointErrorFunctions, AJointThatDoesNotMoveThePointHasNone) {
  // No tool: the flange origin lies on joint 6's axis, which then moves nothing.
  const MdhModel m = find_builtin_robot("kr16")->model;
  const std::vector<JointVector> q = random_poses(60, 13);
  std::vector<Eigen::Vector3d> r(q.size(), Eigen::Vector3d(0.01, -0.02, 0.03));
  const JointErrorFunctionFit fit = fit_joint_error_functions(m, q, r, 3);
  EXPECT_EQ(fit.functions.lo_deg[5], fit.functions.hi_deg[5]);
  EXPECT_EQ(fit.functions.coefficients_mrad.row(5).norm(), 0.0);
  EXPECT_LT(fit.functions.lo_deg[0], fit.functions.hi_deg[0]);
}

TEST(JointErrorFunctions, JsonRoundTripAndRefusals) {
  JointErrorFunctions f;
  f.degree = 2;
  f.lo_deg = {-1, -2, -3, -4, -5, -6};
  f.hi_deg = {1, 2, 3, 4, 5, 6};
  f.coefficients_mrad = Eigen::MatrixXd::Random(6, 2);
  const JointErrorFunctions back = JointErrorFunctions::from_json(f.to_json(), "m.json");
  EXPECT_EQ(back.degree, 2);
  EXPECT_EQ(back.lo_deg, f.lo_deg);
  EXPECT_EQ(back.hi_deg, f.hi_deg);
  EXPECT_EQ(back.coefficients_mrad, f.coefficients_mrad);
  nlohmann::json j = f.to_json();
  j["degree"] = 0;
  refused(j, "joint_error_functions.degree");
  j = f.to_json();
  j["coefficients_mrad"][3] = {1.0};
  refused(j, "joint_error_functions.coefficients_mrad\"[3]");
  j = f.to_json();
  j["hi_deg"][2] = -10.0;
  refused(j, "joint_error_functions.hi_deg\"[2]");
  j = f.to_json();
  j["lo_deg"] = "wide";
  refused(j, "joint_error_functions.lo_deg");
  // Issue 35: integers beyond 32 bits were read modulo 2^32 (degree 4294967304 as 8), and joint
  // functions of any size were taken (1e5 mrad moved the tool 297 mm, status ok).
  j = f.to_json();
  j["degree"] = 4294967298ULL;  // 2^32 + 2: would be read as 2, which matches the coefficients
  refused(j, "joint_error_functions.degree\": expected an integer 1..20, got 4294967298");
  j = f.to_json();
  j["degree"] = 2.0;
  refused(j, "joint_error_functions.degree");
  j = f.to_json();
  j["coefficients_mrad"][4] = {600.0, -600.0};  // 600 P1 - 600 P2: 1200 mrad at u = -1 (joint 5)
  refused(j, "joint_error_functions.coefficients_mrad\"[4]: angle errors up to 1200 mrad");
  j = f.to_json();
  j["coefficients_mrad"][4] = {400.0, -400.0};  // 800 mrad: absurd for a robot, but within the limit
  EXPECT_NO_THROW(JointErrorFunctions::from_json(j, "m.json"));
  // Gravity terms: joint and frame read range-checked, the scale and the coefficient credible.
  JointErrorFunctions g = f;
  g.gravity_terms = {GravityLoadTerm{1, 4, 0.8, 0.3}};
  EXPECT_EQ(JointErrorFunctions::from_json(g.to_json(), "m.json").gravity_terms.size(), 1u);
  const std::pair<const char*, nlohmann::json> bad_terms[] = {
      {"joint", 4294967298ULL}, {"frame", 4294967300ULL}, {"scale_m", 1e-300}, {"scale_m", 1e9}, {"coefficient_mrad", 1e5}};
  for (const auto& [key, value] : bad_terms) {
    j = g.to_json();
    j["gravity_terms"][0][key] = value;
    refused(j, std::string("joint_error_functions.gravity_terms\"[0].") + key);
  }
  EXPECT_THROW(fit_joint_error_functions(robot_with_tool(), random_poses(3, 1), std::vector<Eigen::Vector3d>(2), 2),
               ArgumentError);
  EXPECT_THROW(fit_joint_error_functions(robot_with_tool(), random_poses(3, 1), std::vector<Eigen::Vector3d>(3), 0),
               ArgumentError);
}

// The 3N x 3N covariance of the residuals at joints q written out in full under
// sph(sill=0.01,range=200)+nug(0.0004)@ard(1,0.5,2,1,1,0.3): components independent, one covariance
// each, nugget on the diagonal (ard: the range along joint k is range * s_k).
Eigen::MatrixXd full_residual_covariance(const std::vector<JointVector>& q) {
  const auto n = static_cast<Eigen::Index>(q.size());
  const double scale[6] = {1, 0.5, 2, 1, 1, 0.3};
  Eigen::MatrixXd sigma = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < n; ++j) {
      double h2 = 0.0;
      for (int k = 0; k < 6; ++k) h2 += std::pow((q[static_cast<std::size_t>(i)][k] - q[static_cast<std::size_t>(j)][k]) / scale[k], 2);
      const double h = std::sqrt(h2) / 200.0;
      const double c = i == j ? 0.0104 : (h >= 1.0 ? 0.0 : 0.01 * (1.0 - 1.5 * h + 0.5 * h * h * h));
      for (int a = 0; a < 3; ++a) sigma(3 * i + a, 3 * j + a) = c;
    }
  return sigma;
}

TEST(JointErrorFunctions, CoefficientCovarianceIsTheSandwichUnderTheCentredFieldCovariance) {
  const MdhModel m = robot_with_tool();
  const std::vector<JointVector> q = random_poses(40, 17);
  std::vector<Eigen::Vector3d> r(q.size());
  for (std::size_t i = 0; i < q.size(); ++i)  // a smooth joint-1 effect, so that some functions are fitted
    r[i] = Eigen::Vector3d(0.2 * std::sin(q[i][0] / 40.0), 0.1 * std::cos(q[i][4] / 30.0), 0.05);
  JointErrorFunctionFit fit = fit_joint_error_functions(m, q, r, 3, false, kNoPrior);
  ASSERT_GT(fit.ridge_inverse.size(), 0);
  const VariogramModel field = VariogramModel::parse("sph(sill=0.01,range=200)+nug(0.0004)@ard(1,0.5,2,1,1,0.3)");
  set_coefficient_covariance(fit, q, field);
  const auto n = static_cast<Eigen::Index>(q.size());
  Eigen::MatrixXd sigma = full_residual_covariance(q);
  // Less what a constant per component carries (ordinary kriging takes it): P sigma P per component.
  Eigen::MatrixXd centre = Eigen::MatrixXd::Identity(3 * n, 3 * n);
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < n; ++j)
      for (int a = 0; a < 3; ++a) centre(3 * i + a, 3 * j + a) -= 1.0 / static_cast<double>(n);
  sigma = centre * sigma * centre;
  const Eigen::MatrixXd expected = fit.ridge_inverse * fit.design.transpose() * sigma * fit.design * fit.ridge_inverse;
  const Eigen::MatrixXd& got = fit.functions.coefficient_covariance_mrad2;
  ASSERT_EQ(got.rows(), expected.rows());
  EXPECT_LT((got - expected).norm(), 1e-9 * expected.norm());
  // Exactly symmetric, not to rounding: the model file's reader refuses an asymmetric one (CI's
  // ASan build wrote mirror entries 4e-6 apart before the fit symmetrized it).
  EXPECT_EQ(got, got.transpose());
  // A prediction's variance: the design rows at q through that covariance.
  const JointVector at = q[3];
  const Eigen::MatrixXd d = fit.design.middleRows<3>(9);
  EXPECT_LT((fit.functions.axis_variance_mm2(m, at) - (d * got * d.transpose()).diagonal()).norm(),
            1e-12 + 1e-9 * got.norm());
  // Round trip through JSON keeps it; a negative variance is refused.
  const JointErrorFunctions back = JointErrorFunctions::from_json(fit.functions.to_json(), "m.json");
  EXPECT_EQ(back.coefficient_covariance_mrad2, got);
  nlohmann::json j = fit.functions.to_json();
  j["coefficient_covariance_mrad2"][2][2] = -1.0;
  EXPECT_THROW(JointErrorFunctions::from_json(j, "m.json"), InputError);
  // Issue 35: a positive diagonal is not enough. Indefinite (a correlation of 3 between two
  // coefficients: var_mm2 of -823,050 came out with status ok), asymmetric and huge are refused.
  const auto edited = [&](auto change) {
    nlohmann::json e = fit.functions.to_json();
    change(e["coefficient_covariance_mrad2"]);
    return e;
  };
  refused(edited([](nlohmann::json& c) {
            const double s = std::sqrt(c[0][0].get<double>() * c[1][1].get<double>());
            c[0][1] = c[1][0] = 3.0 * s;
          }),
          "coefficient_covariance_mrad2\": not positive semi-definite");
  refused(edited([](nlohmann::json& c) { c[0][1] = c[0][1].get<double>() + 1.0; }),
          "coefficient_covariance_mrad2\": not symmetric: [1][0]");
  refused(edited([](nlohmann::json& c) {
            for (std::size_t r = 0; r < c.size(); ++r)
              for (std::size_t k = 0; k < c.size(); ++k) c[r][k] = c[r][k].get<double>() * 1e18;
          }),
          "coefficient_covariance_mrad2\"[");
  refused(edited([](nlohmann::json& c) { c[3][3] = 1e300; }), "coefficient_covariance_mrad2\"[3][3]: variance 1e+300");
}

// The generalized least squares refit against the GLS written out with the full 3N x 3N covariance:
// an indicator column per component for the constants ordinary kriging takes (profiled out), the
// ridge at the penalty the fit chose, and that penalty a minimum of GCV in the whitened problem.
TEST(JointErrorFunctions, GeneralizedRefitIsTheRidgeGlsUnderTheFieldCovariance) {
  const MdhModel m = robot_with_tool();
  const std::vector<JointVector> q = random_poses(40, 23);
  std::vector<Eigen::Vector3d> r(q.size());
  for (std::size_t i = 0; i < q.size(); ++i)
    r[i] = Eigen::Vector3d(0.2 * std::sin(q[i][0] / 40.0) + 0.03, 0.1 * std::cos(q[i][4] / 30.0), 0.05 * std::sin(q[i][1] / 25.0));
  JointErrorFunctionFit fit = fit_joint_error_functions(m, q, r, 3, false, kNoPrior);
  ASSERT_GT(fit.ridge_inverse.size(), 0);
  const Eigen::MatrixXd design = fit.design;
  const VariogramModel field = VariogramModel::parse("sph(sill=0.01,range=200)+nug(0.0004)@ard(1,0.5,2,1,1,0.3)");
  ASSERT_TRUE(refit_by_generalized_least_squares(fit, q, r, field, kNoPrior));
  EXPECT_TRUE(fit.generalized);
  const auto n = static_cast<Eigen::Index>(q.size());
  const Eigen::MatrixXd si = full_residual_covariance(q).inverse();
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(3 * n, 3);  // one constant per component
  for (Eigen::Index i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) c(3 * i + a, a) = 1.0;
  const Eigen::MatrixXd sp = si - si * c * (c.transpose() * si * c).inverse() * c.transpose() * si;
  Eigen::VectorXd y(3 * n);
  for (Eigen::Index i = 0; i < n; ++i) y.segment<3>(3 * i) = r[static_cast<std::size_t>(i)];
  const Eigen::MatrixXd g = design.transpose() * sp * design;
  const double largest = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(g).eigenvalues().maxCoeff();
  auto solve = [&](double lambda) -> Eigen::MatrixXd {
    return (g + lambda * Eigen::MatrixXd::Identity(g.rows(), g.cols())).inverse();
  };
  const double lambda = fit.ridge * largest;
  const Eigen::MatrixXd rinv = solve(lambda);
  const Eigen::VectorXd beta = rinv * design.transpose() * sp * y;
  const Eigen::VectorXd got = Eigen::Map<const Eigen::VectorXd>(
      Eigen::MatrixXd(fit.functions.coefficients_mrad.transpose()).data(), beta.size());
  EXPECT_LT((got - beta).norm(), 1e-7 * beta.norm());
  const Eigen::MatrixXd cov = rinv * g * rinv;
  EXPECT_LT((fit.functions.coefficient_covariance_mrad2 - cov).norm(), 1e-7 * cov.norm());
  EXPECT_EQ(fit.functions.coefficient_covariance_mrad2, fit.functions.coefficient_covariance_mrad2.transpose());
  const Eigen::VectorXd left = y - design * beta;
  for (Eigen::Index i = 0; i < n; ++i)
    EXPECT_LT((fit.remaining_mm[static_cast<std::size_t>(i)] - left.segment<3>(3 * i)).norm(), 1e-9) << i;
  // GCV in the whitened problem, rows * RSS / (rows - df)^2, is no lower a quarter decade either side.
  auto gcv = [&](double l) {
    const Eigen::MatrixXd ri = solve(l);
    const Eigen::VectorXd e = y - design * (ri * design.transpose() * sp * y);
    const double df = (ri * g).trace(), rows = static_cast<double>(3 * n);
    return rows * e.dot(sp * e) / ((rows - df) * (rows - df));
  };
  EXPECT_LE(gcv(lambda), gcv(lambda * std::pow(10.0, 0.25)) * (1 + 1e-9));
  EXPECT_LE(gcv(lambda), gcv(lambda * std::pow(10.0, -0.25)) * (1 + 1e-9));
  // Nothing to refit without functions.
  JointErrorFunctionFit none = fit_joint_error_functions(m, q, std::vector<Eigen::Vector3d>(q.size(), Eigen::Vector3d::Zero()), 3);
  ASSERT_EQ(none.ridge_inverse.size(), 0);
  EXPECT_FALSE(refit_by_generalized_least_squares(none, q, r, field));
  EXPECT_THROW(refit_by_generalized_least_squares(fit, random_poses(5, 1), r, field), ArgumentError);
}

// The lever is the derivative of the point's height: a unit weight at p loads joint j by
// -d(z_p)/d(q_j) (virtual work), here by central differences of the FK, no cross product involved.
TEST(GravityLoad, LeverIsMinusTheDerivativeOfThePointsHeight) {
  const MdhModel m = robot_with_tool();
  for (const JointVector& q : random_poses(10, 31)) {
    KinematicFrames frames;
    forward_kinematics_all(m, q, frames);
    for (int j = 0; j < 6; ++j)
      for (int frame = j + 2; frame <= 7; ++frame) {
        const double h = 1e-4;  // deg
        KinematicFrames up, down;
        JointVector qu = q, qd = q;
        qu[j] += h;
        qd[j] -= h;
        forward_kinematics_all(m, qu, up);
        forward_kinematics_all(m, qd, down);
        const double dz_per_rad = (up.frames[static_cast<std::size_t>(frame)].translation().z() -
                                   down.frames[static_cast<std::size_t>(frame)].translation().z()) / (2.0 * h * M_PI / 180.0);
        EXPECT_NEAR(gravity_lever_m(frames, j, frame), -1e-3 * dz_per_rad, 1e-9) << "joint " << j + 1 << " frame " << frame;
      }
  }
}

// A simulated arm whose only error is its joints yielding under gravity (the simulator's own
// compliance model: point masses between the frame origins, a payload at the tool point; no
// geometric error, no noise): the gravity-load terms express it, the one-joint functions cannot.
TEST(GravityLoad, RecoversTheSimulatorsComplianceFromPositionsAlone) {
  SimulatorConfig c = SimulatorConfig::paper_default();
  c.nominal = robot_with_tool();
  c.geometry = GeometricDeviation{};
  c.transmission = TransmissionErrorModel{};
  c.end_range = EndRangeErrorModel{};
  c.compliance.stiffness_nm_per_rad = {0, 4e5, 6e5, 2e6, 2e6, 0};
  c.compliance.link_mass_kg = {0, 40, 25, 8, 4, 0};  // link 6's mass sits off the frame origins' lines
  c.compliance.payload_kg = 10;
  c.repeatability_sigma_mm = 0.0;
  const SimulatedRobot sim(c);
  const std::vector<JointVector> q = random_poses(300, 37), held_out = random_poses(100, 41);
  auto residuals = [&](const std::vector<JointVector>& at) {
    std::vector<Eigen::Vector3d> r(at.size());
    for (std::size_t i = 0; i < at.size(); ++i) r[i] = sim.true_position(at[i]) - forward_position(c.nominal, at[i]);
    return r;
  };
  const std::vector<Eigen::Vector3d> r = residuals(q), truth = residuals(held_out);
  const JointErrorFunctionFit with = fit_joint_error_functions(c.nominal, q, r, 4, true);
  const JointErrorFunctionFit without = fit_joint_error_functions(c.nominal, q, r, 4, false);
  ASSERT_FALSE(with.functions.gravity_terms.empty());
  // Joint 1's axis is vertical: no weight loads it.
  for (const GravityLoadTerm& t : with.functions.gravity_terms) EXPECT_NE(t.joint, 0);
  EXPECT_GT(with.rms_before_mm, 0.3);
  // Left: the linearization (second order in ~1 mrad over a ~1.5 m arm, ~0.002 mm) and the
  // ridge's shrinkage; the polynomials alone leave the part that depends on several joints.
  EXPECT_LT(with.rms_after_mm, 0.02 * with.rms_before_mm);
  EXPECT_GT(without.rms_after_mm, 5.0 * with.rms_after_mm);
  // Held-out poses: the terms predict the deflection where nothing was measured.
  double error = 0.0, size = 0.0;
  for (std::size_t i = 0; i < held_out.size(); ++i) {
    error += (with.functions.position_error_mm(c.nominal, held_out[i]) - truth[i]).squaredNorm();
    size += truth[i].squaredNorm();
  }
  EXPECT_LT(std::sqrt(error / size), 0.03);
  // The angle errors are the simulator's deflections (mrad), up to what the joint offsets take
  // (a constant per joint: the functions have none).
  Eigen::Matrix<double, 6, 1> mean_difference = Eigen::Matrix<double, 6, 1>::Zero();
  std::vector<Eigen::Matrix<double, 6, 1>> difference(held_out.size());
  for (std::size_t i = 0; i < held_out.size(); ++i) {
    difference[i] = with.functions.angle_error_mrad(held_out[i], &c.nominal) - sim.joint_deflection_deg(held_out[i]) * M_PI / 0.18;
    mean_difference += difference[i] / static_cast<double>(held_out.size());
  }
  for (std::size_t i = 0; i < held_out.size(); ++i)
    for (int j = 1; j < 3; ++j) EXPECT_NEAR(difference[i][j], mean_difference[j], 0.05) << "joint " << j + 1;
}

TEST(GravityLoad, CovarianceAndPredictionCarryThemAndTheyRoundTrip) {
  const MdhModel m = robot_with_tool();
  const std::vector<JointVector> q = random_poses(200, 43);
  std::vector<Eigen::Vector3d> r(q.size());
  for (std::size_t i = 0; i < q.size(); ++i) r[i] = Eigen::Vector3d(0.2 * std::sin(q[i][1] / 40.0), 0.1 * std::cos(q[i][2] / 30.0), 0.05);
  JointErrorFunctionFit fit = fit_joint_error_functions(m, q, r, 8, true);
  ASSERT_GT(fit.ridge_inverse.size(), 0);
  const VariogramModel field = VariogramModel::parse("sph(sill=0.01,range=200)+nug(0.0004)@ard(1,0.5,2,1,1,0.3)");
  set_coefficient_covariance(fit, q, field);
  EXPECT_EQ(fit.functions.coefficient_covariance_mrad2.rows(), fit.functions.parameter_count());
  for (auto& t : fit.functions.gravity_terms) t.coefficient_mrad = 0.3;
  const JointErrorFunctions back = JointErrorFunctions::from_json(fit.functions.to_json(), "m.json");
  ASSERT_EQ(back.gravity_terms.size(), fit.functions.gravity_terms.size());
  for (const JointVector& at : random_poses(5, 53)) {
    EXPECT_EQ(back.position_error_mm(m, at), fit.functions.position_error_mm(m, at));
    EXPECT_EQ(back.axis_variance_mm2(m, at), fit.functions.axis_variance_mm2(m, at));
    // The position error is the FK of the angle errors (gravity terms included), to first order:
    // a central difference at 1/1000 of them (remainder third order).
    const Eigen::Matrix<double, 6, 1> step = 1e-3 * back.angle_error_mrad(at, &m) * 1e-3 * 180.0 / M_PI;
    const Eigen::Vector3d fd = (forward_position(m, at + step) - forward_position(m, at - step)) * 0.5e3;
    EXPECT_LT((back.position_error_mm(m, at) - fd).norm(), 1e-6 * std::max(1.0, fd.norm()));
  }
  nlohmann::json j = fit.functions.to_json();
  j["gravity_terms"][0]["frame"] = j["gravity_terms"][0]["joint"];  // the joint's own origin: no lever
  refused(j, "gravity_terms\"[0].frame");
  j = fit.functions.to_json();
  j["gravity_terms"][0]["scale_m"] = 0.0;
  refused(j, "gravity_terms\"[0].scale_m");
  j = fit.functions.to_json();
  j["gravity_terms"][1]["joint"] = 7;
  refused(j, "gravity_terms\"[1].joint");
  j = fit.functions.to_json();
  j["gravity_terms"].erase(0);  // the covariance no longer matches the coefficients
  refused(j, "coefficient_covariance_mrad2");
}

TEST(JointErrorFunctions, OnlyKinematicKrigingModelsCarryThem) {
  const MdhModel m = robot_with_tool();
  const JointErrorFunctions f = functions_over_the_box(Eigen::MatrixXd::Constant(6, 1, 0.5));
  const CompensationModel kin(CompensationMethod::kinematic, m, nullptr);
  nlohmann::json j = kin.to_json();
  j["joint_error_functions"] = f.to_json();
  try {
    CompensationModel::from_json(j, "k.json");
    FAIL() << "a kinematic model with joint error functions was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("only kinematic+kriging"), std::string::npos) << e.what();
  }
}

}  // namespace joint_error_functions_test
}  // namespace errfield::compensation

namespace errfield::compensation {
using namespace errfield::robot;
namespace joint_error_functions_test {

// The fit is the maximum a posteriori one: beta = (F'F + lambda I + diag(sigma^2 / sd_k^2))^-1 F'y,
// written out here from the design, the ridge the fit reports (lambda / largest eigenvalue of F'F)
// and sigma^2 read back from the prior's share of the covariance (sigma^2 x sigma^2 / sd^2).
TEST(JointFunctionPrior, TheFitIsTheMaximumAPosterioriOne) {
  const MdhModel m = robot_with_tool();
  const std::vector<JointVector> q = random_poses(40, 17);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::vector<Eigen::Vector3d> r(q.size());
  for (std::size_t i = 0; i < q.size(); ++i)
    r[i] = Eigen::Vector3d(0.2 * std::sin(q[i][0] / 40.0) + noise(rng), 0.1 * std::cos(q[i][4] / 30.0) + noise(rng),
                           0.05 * std::sin(q[i][1] / 25.0) + noise(rng));
  const JointFunctionPrior prior{0.05, 0.02, 0.0};  // tight enough to bind
  const JointErrorFunctionFit fit = fit_joint_error_functions(m, q, r, 3, true, prior);
  ASSERT_GT(fit.ridge_inverse.size(), 0);
  const Eigen::MatrixXd& f = fit.design;
  const Eigen::Index p = f.cols();
  ASSERT_EQ(fit.prior_middle_diagonal.size(), p);
  Eigen::VectorXd y(f.rows());
  for (std::size_t i = 0; i < q.size(); ++i) y.segment<3>(3 * static_cast<Eigen::Index>(i)) = r[i];
  const Eigen::MatrixXd gram = f.transpose() * f;
  const double largest = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(gram).eigenvalues().maxCoeff();
  const int polynomials = 6 * fit.functions.degree;
  Eigen::VectorXd sd(p);
  sd.head(polynomials).setConstant(prior.polynomial_sd_mrad);
  sd.tail(p - polynomials).setConstant(prior.gravity_sd_mrad);
  const double sigma2 = std::sqrt(fit.prior_middle_diagonal[0] * sd[0] * sd[0]);
  Eigen::MatrixXd a = gram;
  a.diagonal().array() += fit.ridge * largest;
  for (Eigen::Index k = 0; k < p; ++k) {
    EXPECT_NEAR(std::sqrt(fit.prior_middle_diagonal[k] * sd[k] * sd[k]), sigma2, 1e-9 * sigma2) << k;
    a(k, k) += sigma2 / (sd[k] * sd[k]);
  }
  const Eigen::VectorXd beta = a.ldlt().solve(f.transpose() * y);
  Eigen::VectorXd fitted(p);
  for (int j = 0; j < 6; ++j)
    for (int k = 0; k < fit.functions.degree; ++k) fitted[j * fit.functions.degree + k] = fit.functions.coefficients_mrad(j, k);
  for (std::size_t t = 0; t < fit.functions.gravity_terms.size(); ++t)
    fitted[polynomials + static_cast<Eigen::Index>(t)] = fit.functions.gravity_terms[t].coefficient_mrad;
  EXPECT_LT((fitted - beta).norm(), 1e-8 * beta.norm()) << fitted.transpose() << "\n" << beta.transpose();
}

// Poses where only q1 turns: every gravity lever is constant (checked here from the levers
// themselves), so each gravity term is a joint offset over these poses and the data cannot tell them
// apart: the fit leaves them out and says which. Over poses that move q2..q5 they stay.
TEST(JointFunctionPrior, GravityTermsWhoseLeverDoesNotVaryAreLeftOut) {
  const MdhModel m = robot_with_tool();
  std::vector<JointVector> q;
  for (int k = 0; k < 25; ++k) q.push_back((JointVector() << -150.0 + 12.5 * k, -80, 110, 20, 40, 30).finished());
  std::vector<Eigen::Vector3d> r(q.size());
  for (std::size_t i = 0; i < q.size(); ++i) r[i] = Eigen::Vector3d(0.1 * std::sin(q[i][0] / 40.0), 0.02, -0.03);
  const JointErrorFunctionFit fit = fit_joint_error_functions(m, q, r, 4, true);
  const JointErrorFunctionFit kept = fit_joint_error_functions(m, random_poses(25, 3), r, 4, true);
  EXPECT_TRUE(kept.undetermined_gravity_terms.empty());
  ASSERT_FALSE(kept.functions.gravity_terms.empty());
  for (int joint = 0; joint < 6; ++joint)
    for (int frame = joint + 2; frame <= 7; ++frame) {
      double lo = 1e300, hi = -1e300;
      for (const JointVector& at : q) {
        KinematicFrames frames;
        forward_kinematics_all(m, at, frames);
        lo = std::min(lo, gravity_lever_m(frames, joint, frame));
        hi = std::max(hi, gravity_lever_m(frames, joint, frame));
      }
      EXPECT_LT(hi - lo, 1e-9) << "joint " << joint + 1 << " frame " << frame << ": the premise, a constant lever";
    }
  EXPECT_TRUE(fit.functions.gravity_terms.empty());
  ASSERT_FALSE(fit.undetermined_gravity_terms.empty());
  EXPECT_EQ(fit.undetermined_gravity_terms.front().rfind("joint ", 0), 0u);
}


// size_over against a computation of its own: the polynomial part from the Legendre P1 = u written
// out, the gravity part from the lever as minus the derivative of the loaded point's height (central
// differences of the FK), and the largest error and opposing pair found by brute force.
TEST(JointErrorFunctions, SizeOverPosesFindsTheLargestErrorAndTheCancellingPair) {
  const MdhModel m = robot_with_tool();
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(6, 1);
  c(1, 0) = -40.0;  // joint 2: -40 u mrad
  c(4, 0) = 3.0;    // joint 5: 3 u mrad, no gravity term
  JointErrorFunctions f = functions_over_the_box(c);
  f.gravity_terms.push_back({1, 7, 0.5, 20.0});  // joint 2, the tool point, 20 mrad per 0.5 m of lever
  const std::vector<JointVector> poses = random_poses(60, 71);
  double largest = 0.0, cancelling = 0.0;
  int largest_joint = -1;
  for (const JointVector& q : poses) {
    const double u2 = 2.0 * (q[1] - f.lo_deg[1]) / (f.hi_deg[1] - f.lo_deg[1]) - 1.0;
    const double u5 = 2.0 * (q[4] - f.lo_deg[4]) / (f.hi_deg[4] - f.lo_deg[4]) - 1.0;
    const double h = 1e-4;  // deg
    JointVector up = q, down = q;
    up[1] += h;
    down[1] -= h;
    const double dz_per_rad = (forward_position(m, up).z() - forward_position(m, down).z()) / (2.0 * h * M_PI / 180.0);
    const double polynomial = -40.0 * u2, gravity = 20.0 * (-1e-3 * dz_per_rad) / 0.5;
    const double joint5 = 3.0 * u5;
    if (std::abs(polynomial + gravity) > largest) largest = std::abs(polynomial + gravity), largest_joint = 1;
    if (std::abs(joint5) > largest) largest = std::abs(joint5), largest_joint = 4;
    if (polynomial * gravity < 0.0) cancelling = std::max(cancelling, std::min(std::abs(polynomial), std::abs(gravity)));
  }
  const JointErrorFunctions::Size size = f.size_over(m, poses);
  EXPECT_NEAR(size.largest_mrad, largest, 1e-5);
  EXPECT_EQ(size.largest_joint, largest_joint);
  EXPECT_NEAR(size.cancelling_mrad, cancelling, 1e-5);
  ASSERT_GT(cancelling, 10.0);  // the draw holds a pair beyond the plausible size: the warning's case
  EXPECT_EQ(size.cancelling_joint, 1);
  EXPECT_NEAR(std::min(std::abs(size.cancelling_polynomial_mrad), std::abs(size.cancelling_gravity_mrad)), cancelling, 1e-5);
  EXPECT_LT(size.cancelling_polynomial_mrad * size.cancelling_gravity_mrad, 0.0);
  const std::optional<std::string> warning = implausible_joint_functions(size);
  ASSERT_TRUE(warning.has_value());
  EXPECT_NE(warning->find("cancel"), std::string::npos) << *warning;
  EXPECT_NE(warning->find("--joint-functions 0"), std::string::npos) << *warning;

  // A tenth of that is a joint's plausible error: no warning, and no pair without gravity terms.
  JointErrorFunctions small = functions_over_the_box(0.1 * c);
  EXPECT_FALSE(implausible_joint_functions(small.size_over(m, poses)).has_value());
  EXPECT_EQ(small.size_over(m, poses).cancelling_joint, -1);
  // Large without cancelling: a warning that names the size and no pair.
  JointErrorFunctions large = functions_over_the_box(c);
  const std::optional<std::string> alone = implausible_joint_functions(large.size_over(m, poses));
  ASSERT_TRUE(alone.has_value());
  EXPECT_EQ(alone->find("cancel"), std::string::npos) << *alone;
  EXPECT_TRUE(f.size_over(m, {}).largest_joint == -1);
}

}  // namespace joint_error_functions_test
}  // namespace errfield::compensation
