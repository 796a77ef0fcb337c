// ToolPointCorrection (compensation/model/tool_point_correction.hpp): the kriged residual of a located point's
// readings. Checked against simple kriging written out here with a dense solve, the likelihood written out
// here (its optimum in sill and noise), leave-one-out by refitting without each reading, and a known smooth
// turn of the flange at new poses.
#include "errfield/compensation/model/tool_point_correction.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <functional>
#include <nlohmann/json.hpp>
#include <random>
#include <vector>

#include "errfield/error.hpp"

namespace errfield::compensation {
namespace tool_point_correction_test {

using robot::JointVector;

// Readings of a point 150 mm along the flange's y axis while the flange turns by w(q) about its x axis (a
// smooth function of the wrist joints), in the robot frame, with tracker noise.
struct Readings {
  std::vector<JointVector> q;
  std::vector<Eigen::Matrix3d> rotation;
  std::vector<Eigen::Vector3d> truth_mm,
      reading_mm;  // robot frame: the turn's displacement, plus noise
};

Eigen::Vector3d turn_displacement_flange(const JointVector &q) {
  const double w = 1e-3 * (0.6 * std::sin(q[3] / 40.0) + 0.4 * std::cos(q[4] / 35.0) + 0.2 * q[5] / 90.0);  // rad
  return Eigen::Vector3d(w, 0, 0).cross(Eigen::Vector3d(0, 150, 0));
}

Readings draw(int n, std::uint64_t seed, double noise_mm = 0.015) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> z;
  Readings r;
  for (int i = 0; i < n; ++i) {
    JointVector q;
    q << 30 * u(rng), -60 + 20 * u(rng), 90 + 25 * u(rng), 60 * u(rng), 50 + 30 * u(rng), 90 * u(rng);
    const Eigen::Matrix3d rot = (Eigen::AngleAxisd(q[0] * M_PI / 180, Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(q[4] * M_PI / 180, Eigen::Vector3d::UnitY()) *
                                 Eigen::AngleAxisd(q[5] * M_PI / 180, Eigen::Vector3d::UnitZ()))
                                    .toRotationMatrix();
    r.q.push_back(q);
    r.rotation.push_back(rot);
    r.truth_mm.push_back(rot * turn_displacement_flange(q));
    r.reading_mm.push_back(r.truth_mm.back() + noise_mm * Eigen::Vector3d(z(rng), z(rng), z(rng)));
  }
  return r;
}

// A joint-space field model as fit writes one: gau with ARD plus a nugget.
VariogramModel field_model() {
  return VariogramModel::parse("gau(sill=0.002,range=60)+nug(sill=0.0002)@ard(0.5,0.5,0.5,1,1,2)");
}

// ρ(q, q') of the correction's chosen correlation (the library's covariance function of a unit-sill model;
// the kriging and likelihood below are written out here).
double rho(const VariogramModel &m, const JointVector &a, const JointVector &b) {
  JointVector d = a - b, mapped;
  m.anisotropy().apply(d.data(), mapped.data(), 6);
  return m.isotropic_part().covariance(mapped.norm());
}

Eigen::MatrixXd correlation_matrix(const VariogramModel &m, const std::vector<JointVector> &q) {
  const auto n = static_cast<Eigen::Index>(q.size());
  Eigen::MatrixXd r(n, n);
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < n; ++j)
      r(i, j) = rho(m, q[static_cast<std::size_t>(i)], q[static_cast<std::size_t>(j)]);
  return r;
}

// The flange-frame values of axis k.
Eigen::VectorXd axis_values(const Readings &r, int k) {
  Eigen::VectorXd y(static_cast<Eigen::Index>(r.q.size()));
  for (std::size_t i = 0; i < r.q.size(); ++i)
    y[static_cast<Eigen::Index>(i)] = (r.rotation[i].transpose() * r.reading_mm[i])[k];
  return y;
}

// Negative log-likelihood (constant dropped) of y under s R + n I, by Cholesky.
double nll(const Eigen::VectorXd &y, const Eigen::MatrixXd &r, double s, double n) {
  const Eigen::MatrixXd k = s * r + n * Eigen::MatrixXd::Identity(r.rows(), r.cols());
  const Eigen::LLT<Eigen::MatrixXd> llt(k);
  const Eigen::VectorXd a = llt.matrixL().solve(y);
  return llt.matrixL().toDenseMatrix().diagonal().array().log().sum() + 0.5 * a.squaredNorm();
}

std::vector<Eigen::Vector3d> robot_frame_residuals(const Readings &r) { return r.reading_mm; }

TEST(ToolPointCorrection, PredictsTheSimpleKrigingOfItsReadingsInTheFlangeFrame) {
  const Readings r = draw(40, 5);
  const auto c =
      ToolPointCorrection::fit(Eigen::Vector3d(0, 150, 100), r.q, r.rotation, robot_frame_residuals(r), field_model());
  ASSERT_TRUE(c.has_value());
  EXPECT_EQ(c->readings(), 40u);
  const Eigen::MatrixXd rr = correlation_matrix(c->correlation(), r.q);
  const Readings targets = draw(25, 6);
  const std::vector<ToolPointCorrectionPrediction> p = c->predict(targets.q, targets.rotation);
  ASSERT_EQ(p.size(), 25u);
  for (std::size_t t = 0; t < targets.q.size(); ++t) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero(), variance = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) {
      const double s = c->sill_mm2()[k];
      if (s == 0.0) continue;
      Eigen::VectorXd kv(rr.rows());
      for (Eigen::Index i = 0; i < rr.rows(); ++i)
        kv[i] = s * rho(c->correlation(), targets.q[t], r.q[static_cast<std::size_t>(i)]);
      const Eigen::MatrixXd big = s * rr + c->noise_mm2() * Eigen::MatrixXd::Identity(rr.rows(), rr.cols());
      const Eigen::VectorXd w = big.ldlt().solve(kv);
      mean[k] = w.dot(axis_values(r, k));
      variance[k] = c->variance_factor() * (s - w.dot(kv));
    }
    const Eigen::Matrix3d &rot = targets.rotation[t];
    EXPECT_LT((p[t].error_mm - rot * mean).norm(), 1e-9) << t;
    EXPECT_LT((p[t].axis_variance_mm2 - rot.cwiseAbs2() * variance).norm(), 1e-10) << t;
    // One pose at a time gives the same.
    EXPECT_LT((c->predict(targets.q[t], rot).error_mm - p[t].error_mm).norm(), 1e-12);
  }
  // The turn about the flange's x axis moves a point on its y axis along z only: the likelihood puts the sill
  // there, and next to none on x and y.
  EXPECT_GT(c->sill_mm2().z(), 10.0 * (c->sill_mm2().x() + c->sill_mm2().y())) << c->sill_mm2().transpose();
}

TEST(ToolPointCorrection, ItsSillsAndNoiseAreTheMostLikelyAtTheChosenCorrelation) {
  const Readings r = draw(40, 7);
  const auto c =
      ToolPointCorrection::fit(Eigen::Vector3d(0, 150, 100), r.q, r.rotation, robot_frame_residuals(r), field_model());
  ASSERT_TRUE(c.has_value());
  const Eigen::MatrixXd rr = correlation_matrix(c->correlation(), r.q);
  auto total = [&](const Eigen::Vector3d &s, double n) {
    double v = 0.0;
    for (int k = 0; k < 3; ++k) v += nll(axis_values(r, k), rr, s[k], n);
    return v;
  };
  const double at_fit = total(c->sill_mm2(), c->noise_mm2());
  // Every parameter moved by 10 % either way (a sill of 0 only up) makes the data less likely; the noise is
  // searched on a grid of 10^(1/10) steps, so it is optimal within half a step.
  for (int k = 0; k < 3; ++k)
    for (double f : {0.9, 1.1}) {
      Eigen::Vector3d s = c->sill_mm2();
      s[k] = s[k] == 0.0 ? (f > 1.0 ? 1e-6 : 0.0) : s[k] * f;
      EXPECT_GE(total(s, c->noise_mm2()), at_fit - 1e-9) << "axis " << k << " x" << f;
    }
  for (double f : {std::pow(10.0, -0.1), std::pow(10.0, 0.1)}) {
    // The noise's neighbours on its grid, each with its own best sills (profiled here by a fine scan).
    const double n = c->noise_mm2() * f;
    double best = 0.0;
    for (int k = 0; k < 3; ++k) {
      double axis_best = nll(axis_values(r, k), rr, 0.0, n);
      for (int g = 0; g <= 400; ++g)
        axis_best = std::min(axis_best, nll(axis_values(r, k), rr, 1e-8 * std::pow(10.0, 8.0 * g / 400), n));
      best += axis_best;
    }
    EXPECT_GE(best, at_fit - 1e-6 * std::abs(at_fit)) << "noise x" << f;
  }
}

TEST(ToolPointCorrection, TheVarianceFactorMaximizesTheReadingsLeaveOneOutScore) {
  int interior = 0;
  for (std::uint64_t seed : {11, 12, 13, 14}) {
    const Readings r = draw(30, seed);
    const auto c = ToolPointCorrection::fit(Eigen::Vector3d(0, 150, 100), r.q, r.rotation, robot_frame_residuals(r),
                                            field_model());
    ASSERT_TRUE(c.has_value());
    const Eigen::MatrixXd rr = correlation_matrix(c->correlation(), r.q);
    const std::vector<Eigen::Vector3d> loo = c->leave_one_out_residual_mm();
    ASSERT_EQ(loo.size(), 30u);
    // The leave-one-out log score at variance factor f, written out from the refits below.
    std::vector<std::pair<double, double>> terms;  // residual², kriging variance
    for (int k = 0; k < 3; ++k) {
      const double s = c->sill_mm2()[k];
      if (s == 0.0) continue;
      const Eigen::VectorXd y = axis_values(r, k);
      for (Eigen::Index i = 0; i < y.size(); ++i) {
        // Kriging without reading i, written out.
        std::vector<Eigen::Index> keep;
        for (Eigen::Index j = 0; j < y.size(); ++j)
          if (j != i) keep.push_back(j);
        const auto m = static_cast<Eigen::Index>(keep.size());
        Eigen::MatrixXd big(m, m);
        Eigen::VectorXd kv(m), yk(m);
        for (Eigen::Index a = 0; a < m; ++a) {
          kv[a] = s * rr(i, keep[static_cast<std::size_t>(a)]);
          yk[a] = y[keep[static_cast<std::size_t>(a)]];
          for (Eigen::Index b = 0; b < m; ++b)
            big(a, b) = s * rr(keep[static_cast<std::size_t>(a)], keep[static_cast<std::size_t>(b)]);
          big(a, a) += c->noise_mm2();
        }
        const Eigen::VectorXd w = big.ldlt().solve(kv);
        const double residual = y[i] - w.dot(yk);
        EXPECT_NEAR(loo[static_cast<std::size_t>(i)][k], residual, 1e-9) << "reading " << i << " axis " << k;
        terms.emplace_back(residual * residual, s - w.dot(kv));
      }
    }
    ASSERT_FALSE(terms.empty());
    auto score = [&](double f) {
      double v = 0.0;
      for (const auto &[r2, var] : terms)
        v -= 0.5 * (std::log(f * var + c->noise_mm2()) + r2 / (f * var + c->noise_mm2()));
      return v;
    };
    // The factor is the score's maximum within its bounds (at a bound, the score falls inward).
    const double f = c->variance_factor();
    for (double step : {0.97, 1.03, 0.8, 1.25}) {
      const double g =
          std::clamp(f * step, ToolPointCorrection::kMinVarianceFactor, ToolPointCorrection::kMaxVarianceFactor);
      EXPECT_GE(score(f), score(g) - 1e-12) << "seed " << seed << ": factor " << f << " against " << g;
    }
    interior += f > ToolPointCorrection::kMinVarianceFactor && f < ToolPointCorrection::kMaxVarianceFactor ? 1 : 0;
  }
  EXPECT_GE(interior, 1) << "at least one of the draws has its factor inside the bounds";
}

TEST(ToolPointCorrection, RecoversASmoothTurnOfTheFlangeAtNewPoses) {
  const Readings r = draw(40, 21);
  const auto c =
      ToolPointCorrection::fit(Eigen::Vector3d(0, 150, 100), r.q, r.rotation, robot_frame_residuals(r), field_model());
  ASSERT_TRUE(c.has_value());
  const Readings held_out = draw(300, 22);
  const std::vector<ToolPointCorrectionPrediction> p = c->predict(held_out.q, held_out.rotation);
  double truth2 = 0.0, miss2 = 0.0, z2 = 0.0;
  for (std::size_t t = 0; t < p.size(); ++t) {
    truth2 += held_out.truth_mm[t].squaredNorm();
    miss2 += (held_out.truth_mm[t] - p[t].error_mm).squaredNorm();
    // A new reading's error: the correction's miss plus the reading's noise (the model beside the correction
    // states that noise at a real point; here it is the correction's own estimate).
    const Eigen::Vector3d e = held_out.reading_mm[t] - p[t].error_mm;
    for (int a = 0; a < 3; ++a) z2 += e[a] * e[a] / (p[t].axis_variance_mm2[a] + c->noise_mm2());
  }
  const double n = static_cast<double>(p.size());
  // The turn moves the point by 0.1 mm RMS; 40 readings leave a small part of it (0.2x here).
  EXPECT_LT(std::sqrt(miss2 / n), 0.3 * std::sqrt(truth2 / n))
      << std::sqrt(miss2 / n) << " of " << std::sqrt(truth2 / n);
  // Its stated variance holds at the new poses: mean z² per axis near 1 (300 x 3 terms, each chi-square-like;
  // the band is wide for the noise the 40-reading estimate carries).
  EXPECT_GT(z2 / (3 * n), 0.6);
  EXPECT_LT(z2 / (3 * n), 1.6);
}

TEST(ToolPointCorrection, PureNoiseIsNotKrigedIntoACorrection) {
  Readings r = draw(40, 31, 0.02);
  for (std::size_t i = 0; i < r.q.size(); ++i) r.reading_mm[i] -= r.truth_mm[i];  // noise only
  const auto c =
      ToolPointCorrection::fit(Eigen::Vector3d(0, 150, 100), r.q, r.rotation, robot_frame_residuals(r), field_model());
  ASSERT_TRUE(c.has_value());
  const Readings held_out = draw(100, 32);
  double pred2 = 0.0;
  for (const ToolPointCorrectionPrediction &p : c->predict(held_out.q, held_out.rotation))
    pred2 += p.error_mm.squaredNorm();
  // Against noise of 0.02 mm per axis (0.035 mm 3-D), what it predicts stays a small fraction.
  EXPECT_LT(std::sqrt(pred2 / 100.0), 0.01);
  EXPECT_NEAR(std::sqrt(c->noise_mm2()), 0.02, 0.006);
}

TEST(ToolPointCorrection, TooFewReadingsOrNonFiniteInputGiveNone) {
  const Readings r = draw(static_cast<int>(kMinToolPointCorrectionReadings) - 1, 41);
  EXPECT_FALSE(ToolPointCorrection::fit(Eigen::Vector3d(0, 150, 100), r.q, r.rotation, r.reading_mm, field_model()));
  Readings bad = draw(30, 42);
  bad.reading_mm[3].x() = std::nan("");
  EXPECT_FALSE(
      ToolPointCorrection::fit(Eigen::Vector3d(0, 150, 100), bad.q, bad.rotation, bad.reading_mm, field_model()));
  // A field model with no bounded structure gives no correlation of its own; the isotropic ones remain, so a
  // correction is still fitted.
  const Readings ok = draw(30, 43);
  EXPECT_TRUE(ToolPointCorrection::fit(Eigen::Vector3d(0, 150, 100), ok.q, ok.rotation, ok.reading_mm,
                                       VariogramModel::parse("lin(sill=0.001,range=1)+nug(sill=0.0001)")));
}

TEST(ToolPointCorrection, JsonRoundTripsAndRefusesEdits) {
  const Readings r = draw(30, 51);
  const auto c = ToolPointCorrection::fit(Eigen::Vector3d(0, 150, 100), r.q, r.rotation, r.reading_mm, field_model());
  ASSERT_TRUE(c.has_value());
  const nlohmann::json j = c->to_json();
  const ToolPointCorrection back = ToolPointCorrection::from_json(nlohmann::json::parse(j.dump()), "m.json");
  const Readings targets = draw(10, 52);
  const auto a = c->predict(targets.q, targets.rotation), b = back.predict(targets.q, targets.rotation);
  for (std::size_t t = 0; t < a.size(); ++t) {
    EXPECT_LT((a[t].error_mm - b[t].error_mm).norm(), 1e-12);
    EXPECT_LT((a[t].axis_variance_mm2 - b[t].axis_variance_mm2).norm(), 1e-14);
  }
  auto refused = [&](const std::function<void(nlohmann::json &)> &edit, const std::string &named) {
    nlohmann::json e = j;
    edit(e);
    try {
      (void)ToolPointCorrection::from_json(e, "m.json");
      ADD_FAILURE() << "accepted: " << named;
    } catch (const InputError &err) {
      EXPECT_NE(std::string(err.what()).find(named), std::string::npos) << err.what();
      EXPECT_NE(std::string(err.what()).find("m.json"), std::string::npos) << err.what();
    }
  };
  refused([](nlohmann::json &e) { e["sill_mm2"][1] = -0.001; }, "sill_mm2");
  refused([](nlohmann::json &e) { e["noise_mm2"] = 0.0; }, "noise_mm2");
  refused([](nlohmann::json &e) { e["variance_factor"] = 1000.0; }, "variance_factor");
  refused([](nlohmann::json &e) { e["correlation"] = "gau(sill=1,range=60)+nug(sill=0.1)"; }, "correlation");
  refused([](nlohmann::json &e) { e["correlation"] = "gau(sill=2,range=60)"; }, "correlation");
  refused([](nlohmann::json &e) { e["residual_flange_mm"].erase(0); }, "residual_flange_mm");
  refused([](nlohmann::json &e) { e["joints_deg"][2][4] = "x"; }, "joints_deg");
  refused([](nlohmann::json &e) { e.erase("point_mm"); }, "point_mm");
}

TEST(ToolPointCorrection, AGrossReadingIsLeftOutNotKrigedIntoASpike) {
  const Readings clean = draw(40, 61);
  Readings bumped = clean;
  bumped.reading_mm[7] += Eigen::Vector3d(0.0, 0.0, 0.6);  // one reading 0.6 mm off (a bumped nest)
  const auto a = ToolPointCorrection::fit(Eigen::Vector3d(0, 150, 100), clean.q, clean.rotation, clean.reading_mm,
                                          field_model());
  const auto b = ToolPointCorrection::fit(Eigen::Vector3d(0, 150, 100), bumped.q, bumped.rotation, bumped.reading_mm,
                                          field_model());
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a->excluded_readings(), 0u);
  EXPECT_EQ(b->excluded_readings(), 1u);
  EXPECT_EQ(b->readings(), 39u);
  // Without the bumped reading the correction is the one kriged from the other 39 readings by hand.
  std::vector<JointVector> q;
  std::vector<Eigen::Matrix3d> rot;
  std::vector<Eigen::Vector3d> res;
  for (std::size_t i = 0; i < clean.q.size(); ++i)
    if (i != 7) q.push_back(clean.q[i]), rot.push_back(clean.rotation[i]), res.push_back(clean.reading_mm[i]);
  const auto by_hand = ToolPointCorrection::fit(Eigen::Vector3d(0, 150, 100), q, rot, res, field_model());
  ASSERT_TRUE(by_hand);
  const Readings held_out = draw(200, 62);
  const auto pb = b->predict(held_out.q, held_out.rotation), ph = by_hand->predict(held_out.q, held_out.rotation);
  double miss2 = 0.0, truth2 = 0.0;
  for (std::size_t t = 0; t < pb.size(); ++t) {
    EXPECT_LT((pb[t].error_mm - ph[t].error_mm).norm(), 1e-12) << t;
    miss2 += (held_out.truth_mm[t] - pb[t].error_mm).squaredNorm();
    truth2 += held_out.truth_mm[t].squaredNorm();
  }
  EXPECT_LT(std::sqrt(miss2 / 200.0), 0.3 * std::sqrt(truth2 / 200.0));
}

}  // namespace tool_point_correction_test
}  // namespace errfield::compensation
