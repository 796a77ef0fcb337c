// Kriging with external drift (KrigingOptions::covariates) against independent computations
// written here: the bordered system [K F; F' 0] solved by full-pivot LU, the identity "a
// covariate that is an exact linear function of a coordinate spans the same drift as that
// coordinate", and the unbiasedness constraints on the weights. Also the statuses and errors
// (SingularDrift naming the covariate, TooFewSamples, non-finite values naming row and column).
// All data are simulated (random locations, a smooth field plus a covariate trend).

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "errfield/error.hpp"
#include "errfield/kriging.hpp"
#include "errfield/kriging_likelihood.hpp"

namespace errfield {
namespace kriging_external_drift_test {

using P2 = Eigen::Vector2d;

struct Data {
  std::vector<P2> points;
  std::vector<double> values;
  Eigen::MatrixXd covariates;  // N x 2: a smooth "elevation" and a noisy "distance"
};

double elevation(const P2& p) { return std::sin(p.x() / 30.0) + 0.02 * p.y(); }
double distance(const P2& p) { return std::sqrt((p.x() - 20.0) * (p.x() - 20.0) + 1.0); }

// Simulated: uniform locations in [0, 100]^2; value = 2 elevation - 0.05 distance + a sinusoid.
Data make_data(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 100.0);
  std::normal_distribution<double> e(0.0, 0.05);
  Data d;
  d.covariates.resize(static_cast<Eigen::Index>(n), 2);
  for (std::size_t i = 0; i < n; ++i) {
    const P2 p(u(rng), u(rng));
    d.points.push_back(p);
    d.covariates(static_cast<Eigen::Index>(i), 0) = elevation(p);
    d.covariates(static_cast<Eigen::Index>(i), 1) = distance(p);
    d.values.push_back(2.0 * elevation(p) - 0.05 * distance(p) + std::sin(p.y() / 15.0) + e(rng));
  }
  return d;
}

std::vector<P2> make_targets(std::size_t n, unsigned seed, Eigen::MatrixXd& covariates) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-5.0, 105.0);
  std::vector<P2> t;
  covariates.resize(static_cast<Eigen::Index>(n), 2);
  for (std::size_t i = 0; i < n; ++i) {
    t.emplace_back(u(rng), u(rng));
    covariates(static_cast<Eigen::Index>(i), 0) = elevation(t.back());
    covariates(static_cast<Eigen::Index>(i), 1) = distance(t.back());
  }
  return t;
}

// The textbook system of kriging with external drift, built from VariogramModel::covariance:
// [K F; F' 0] [w; mu] = [c0; f0], F = [1, covariates]; mean = w'z, variance = C(0) - w'c0 - mu'f0.
struct Reference {
  double mean, variance;
};
Reference reference(const Data& d, const P2& target, const Eigen::RowVectorXd& target_cov, const VariogramModel& model) {
  const auto n = static_cast<Eigen::Index>(d.points.size()), p = 1 + d.covariates.cols();
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n + p, n + p);
  Eigen::VectorXd b(n + p);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index j = 0; j < n; ++j)
      a(i, j) = model.covariance((d.points[static_cast<std::size_t>(i)] - d.points[static_cast<std::size_t>(j)]).norm());
    a(i, n) = a(n, i) = 1.0;
    for (Eigen::Index c = 0; c < d.covariates.cols(); ++c) a(i, n + 1 + c) = a(n + 1 + c, i) = d.covariates(i, c);
    b[i] = model.covariance((d.points[static_cast<std::size_t>(i)] - target).norm());
  }
  b[n] = 1.0;
  for (Eigen::Index c = 0; c < d.covariates.cols(); ++c) b[n + 1 + c] = target_cov[c];
  const Eigen::VectorXd x = a.fullPivLu().solve(b);
  const Eigen::VectorXd z = Eigen::Map<const Eigen::VectorXd>(d.values.data(), n);
  return {x.head(n).dot(z), model.covariance(0.0) - x.dot(b)};
}

const VariogramModel kModel = VariogramModel::parse("sph(sill=0.5,range=60)+nug(0.01)");

TEST(KrigingExternalDrift, MatchesTheBorderedSystemInEveryBackEnd) {
  const Data d = make_data(80, 3);
  Eigen::MatrixXd tc;
  const auto targets = make_targets(25, 4, tc);
  for (auto backend : {KrigingBackend::Dense, KrigingBackend::Local, KrigingBackend::Sparse}) {
    KrigingOptions o;
    o.covariates = {"elevation", "distance"};
    o.backend = backend;
    if (backend == KrigingBackend::Local) o.neighbors = 80;  // all samples: the global system
    const Kriging<P2, double> k(d.points, d.values, d.covariates, kModel, o);
    ASSERT_TRUE(k.report().usable()) << k.report().message;
    EXPECT_EQ(k.report().drift_terms, 3u);
    const auto pred = k.predict(targets, tc);
    ASSERT_TRUE(pred.usable()) << pred.message;
    for (std::size_t t = 0; t < targets.size(); ++t) {
      const Reference r = reference(d, targets[t], tc.row(static_cast<Eigen::Index>(t)), kModel);
      EXPECT_NEAR(pred.mean[t], r.mean, 1e-9 * std::max(1.0, std::abs(r.mean))) << kriging_backend_name(backend) << " " << t;
      EXPECT_NEAR(pred.variance[t], r.variance, 1e-9) << kriging_backend_name(backend) << " " << t;
    }
  }
}

TEST(KrigingExternalDrift, LeaveOneOutMatchesRefittingWithoutTheSample) {
  const Data d = make_data(40, 5);
  for (auto backend : {KrigingBackend::Dense, KrigingBackend::Local}) {
    KrigingOptions o;
    o.covariates = {"elevation", "distance"};
    o.backend = backend;
    if (backend == KrigingBackend::Local) o.neighbors = 40;
    const Kriging<P2, double> k(d.points, d.values, d.covariates, kModel, o);
    const auto cv = k.leave_one_out();
    ASSERT_EQ(cv.prediction.size(), d.points.size()) << cv.message;
    // k-fold with one sample per fold refits without each sample, covariates carried along.
    const auto folds = k.k_fold(static_cast<int>(d.points.size()));
    ASSERT_EQ(folds.prediction.size(), d.points.size()) << folds.message;
    for (std::size_t i = 0; i < d.points.size(); ++i) {
      EXPECT_NEAR(folds.prediction[i], cv.prediction[i], 1e-9) << kriging_backend_name(backend) << " sample " << i;
      EXPECT_NEAR(folds.variance[i], cv.variance[i], 1e-9) << kriging_backend_name(backend) << " sample " << i;
    }
    for (std::size_t i = 0; i < d.points.size(); i += 7) {
      Data rest;
      rest.covariates.resize(static_cast<Eigen::Index>(d.points.size() - 1), 2);
      for (std::size_t j = 0, r = 0; j < d.points.size(); ++j) {
        if (j == i) continue;
        rest.points.push_back(d.points[j]);
        rest.values.push_back(d.values[j]);
        rest.covariates.row(static_cast<Eigen::Index>(r++)) = d.covariates.row(static_cast<Eigen::Index>(j));
      }
      const Reference r = reference(rest, d.points[i], d.covariates.row(static_cast<Eigen::Index>(i)), kModel);
      EXPECT_NEAR(cv.prediction[i], r.mean, 1e-9) << kriging_backend_name(backend) << " sample " << i;
      EXPECT_NEAR(cv.variance[i], r.variance, 1e-9) << kriging_backend_name(backend) << " sample " << i;
    }
  }
}

// A covariate c = 3 x + 2 spans, with the constant, what the linear drift in x spans: ordinary
// kriging with it equals universal kriging with the drift function x (and, in 1-D, universal1).
TEST(KrigingExternalDrift, CovariateLinearInACoordinateEqualsThatLinearDrift) {
  const Data d = make_data(60, 7);
  Eigen::MatrixXd tc;
  const auto targets = make_targets(20, 8, tc);
  auto linear_in_x = [](const std::vector<P2>& pts) {
    Eigen::MatrixXd c(static_cast<Eigen::Index>(pts.size()), 1);
    for (std::size_t i = 0; i < pts.size(); ++i) c(static_cast<Eigen::Index>(i), 0) = 3.0 * pts[i].x() + 2.0;
    return c;
  };
  for (auto backend : {KrigingBackend::Dense, KrigingBackend::Local, KrigingBackend::Sparse}) {
    KrigingOptions ked;
    ked.covariates = {"three_x_plus_2"};
    ked.backend = backend;
    ked.neighbors = backend == KrigingBackend::Local ? 15 : 0;
    KrigingOptions uk = ked;
    uk.covariates.clear();
    uk.kind = KrigingKind::Universal;
    uk.drift_order = 0;
    uk.drift_functions = {[](std::span<const double> x) { return x[0]; }};
    const Kriging<P2, double> a(d.points, d.values, linear_in_x(d.points), kModel, ked);
    const Kriging<P2, double> b(d.points, d.values, kModel, uk);
    const auto pa = a.predict(targets, linear_in_x(targets));
    const auto pb = b.predict(targets);
    ASSERT_TRUE(pa.usable() && pb.usable()) << pa.message << pb.message;
    for (std::size_t t = 0; t < targets.size(); ++t) {
      EXPECT_NEAR(pa.mean[t], pb.mean[t], 1e-10 * std::max(1.0, std::abs(pb.mean[t]))) << kriging_backend_name(backend);
      EXPECT_NEAR(pa.variance[t], pb.variance[t], 1e-10) << kriging_backend_name(backend);
    }
  }
  // 1-D locations: the covariate equals universal kriging of order 1.
  std::vector<double> x1, t1;
  for (const auto& p : d.points) x1.push_back(p.x());
  for (const auto& p : targets) t1.push_back(p.x() + 0.5 * p.y() / 100.0);
  Eigen::MatrixXd c1(static_cast<Eigen::Index>(x1.size()), 1), ct(static_cast<Eigen::Index>(t1.size()), 1);
  for (std::size_t i = 0; i < x1.size(); ++i) c1(static_cast<Eigen::Index>(i), 0) = 3.0 * x1[i] + 2.0;
  for (std::size_t i = 0; i < t1.size(); ++i) ct(static_cast<Eigen::Index>(i), 0) = 3.0 * t1[i] + 2.0;
  KrigingOptions ked;
  ked.covariates = {"c"};
  KrigingOptions uk;
  uk.kind = KrigingKind::Universal;
  uk.drift_order = 1;
  const Kriging<double, double> a(x1, d.values, c1, kModel, ked);
  const Kriging<double, double> b(x1, d.values, kModel, uk);
  const auto pa = a.predict(t1, ct);
  const auto pb = b.predict(t1);
  for (std::size_t t = 0; t < t1.size(); ++t) {
    EXPECT_NEAR(pa.mean[t], pb.mean[t], 1e-10 * std::max(1.0, std::abs(pb.mean[t])));
    EXPECT_NEAR(pa.variance[t], pb.variance[t], 1e-10);
  }
  // The likelihoods agree too: the same F after centring and scaling.
  Eigen::MatrixXd xs(static_cast<Eigen::Index>(x1.size()), 1);
  for (std::size_t i = 0; i < x1.size(); ++i) xs(static_cast<Eigen::Index>(i), 0) = x1[i];
  const Eigen::VectorXd z = Eigen::Map<const Eigen::VectorXd>(d.values.data(), static_cast<Eigen::Index>(d.values.size()));
  for (bool restricted : {true, false}) {
    LikelihoodFitOptions lk;
    lk.restricted = restricted;
    lk.covariates = c1;
    LikelihoodFitOptions lu;
    lu.restricted = restricted;
    lu.kind = KrigingKind::Universal;
    lu.drift_order = 1;
    const double a_nll = negative_log_likelihood(xs, z, kModel, lk);
    const double b_nll = negative_log_likelihood(xs, z, kModel, lu);
    // REML is the textbook value without nlme's + 0.5 log det F'F (docs/kriging.md): a basis change
    // F -> F T of the drift shifts it by log |det T| per value column; the covariate 3x + 2 against
    // the coordinate x is det T = 3. ML does not depend on the basis.
    const double basis_shift = restricted ? std::log(3.0) : 0.0;
    EXPECT_NEAR(a_nll - basis_shift, b_nll, 1e-9 * std::abs(b_nll)) << (restricted ? "REML" : "ML");
    LikelihoodFitOptions plain;
    plain.restricted = restricted;
    EXPECT_GT(std::abs(negative_log_likelihood(xs, z, kModel, plain) - a_nll), 1e-6) << "the covariate must enter F";
  }
}

// The weights reproduce the drift at the target: sum w_i = 1 and sum w_i cov_i = cov_0.
TEST(KrigingExternalDrift, WeightsSatisfyTheUnbiasednessConstraints) {
  const Data d = make_data(50, 11);
  Eigen::MatrixXd tc;
  const auto targets = make_targets(10, 12, tc);
  for (auto backend : {KrigingBackend::Dense, KrigingBackend::Local}) {
    KrigingOptions o;
    o.covariates = {"elevation", "distance"};
    o.backend = backend;
    o.neighbors = backend == KrigingBackend::Local ? 12 : 0;
    o.keep_weights = true;
    const Kriging<P2, double> k(d.points, d.values, d.covariates, kModel, o);
    const auto pred = k.predict(targets, tc);
    ASSERT_TRUE(pred.usable()) << pred.message;
    const auto& w = pred.weights;
    for (std::size_t t = 0; t < targets.size(); ++t) {
      double sum = 0.0, mean = 0.0;
      Eigen::RowVector2d cov = Eigen::RowVector2d::Zero();
      for (std::size_t e = w.offset[t]; e < w.offset[t + 1]; ++e) {
        sum += w.weight[e];
        cov += w.weight[e] * d.covariates.row(static_cast<Eigen::Index>(w.sample[e]));
        mean += w.weight[e] * d.values[w.sample[e]];
      }
      EXPECT_NEAR(sum, 1.0, 1e-10) << kriging_backend_name(backend) << " target " << t;
      EXPECT_NEAR(cov[0], tc(static_cast<Eigen::Index>(t), 0), 1e-9) << kriging_backend_name(backend);
      EXPECT_NEAR(cov[1], tc(static_cast<Eigen::Index>(t), 1), 1e-8 * std::abs(tc(static_cast<Eigen::Index>(t), 1)))
          << kriging_backend_name(backend);
      EXPECT_NEAR(mean, pred.mean[t], 1e-9) << kriging_backend_name(backend);
    }
  }
}

TEST(KrigingExternalDrift, CollinearCovariateIsNamedInSingularDrift) {
  const Data d = make_data(30, 13);
  Eigen::MatrixXd cov(30, 2);
  for (Eigen::Index i = 0; i < 30; ++i) {
    cov(i, 0) = d.covariates(i, 1);
    cov(i, 1) = 2.0 * d.points[static_cast<std::size_t>(i)].y() - 1.0;  // linear in y: the drift has y already
  }
  KrigingOptions o;
  o.kind = KrigingKind::Universal;
  o.drift_order = 1;
  o.covariates = {"distance", "twice_y"};
  for (auto backend : {KrigingBackend::Dense, KrigingBackend::Sparse}) {
    o.backend = backend;
    const Kriging<P2, double> k(d.points, d.values, cov, kModel, o);
    EXPECT_EQ(k.report().status, KrigingStatus::SingularDrift);
    EXPECT_NE(k.report().message.find("covariate 'twice_y'"), std::string::npos) << k.report().message;
    EXPECT_EQ(k.report().message.find("covariate 'distance' is"), std::string::npos) << k.report().message;
  }
  // A constant covariate is what the mean term already is.
  Eigen::MatrixXd constant = Eigen::MatrixXd::Constant(30, 1, 4.5);
  KrigingOptions ked;
  ked.covariates = {"flat"};
  const Kriging<P2, double> k(d.points, d.values, constant, kModel, ked);
  EXPECT_EQ(k.report().status, KrigingStatus::SingularDrift);
  EXPECT_NE(k.report().message.find("covariate 'flat' is constant (4.5)"), std::string::npos) << k.report().message;
  // Local back end: per target, the message names the drift with its covariates.
  ked.backend = KrigingBackend::Local;
  ked.neighbors = 10;
  const Kriging<P2, double> local(d.points, d.values, constant, kModel, ked);
  const auto pred = local.predict(std::vector<P2>{P2(50, 50)}, Eigen::MatrixXd::Constant(1, 1, 4.5));
  EXPECT_EQ(pred.status, KrigingStatus::SingularDrift);
  EXPECT_NE(pred.message.find("'flat'"), std::string::npos) << pred.message;
}

TEST(KrigingExternalDrift, TooFewSamplesForTheDriftTerms) {
  const Data d = make_data(3, 17);
  KrigingOptions o;
  o.kind = KrigingKind::Universal;
  o.drift_order = 1;
  o.covariates = {"elevation", "distance"};  // 1 + 2 + 2 = 5 terms for 3 samples
  const Kriging<P2, double> k(d.points, d.values, d.covariates, kModel, o);
  EXPECT_EQ(k.report().status, KrigingStatus::TooFewSamples);
  EXPECT_EQ(k.report().drift_terms, 5u);
  EXPECT_NE(k.report().message.find("'distance'"), std::string::npos) << k.report().message;
}

TEST(KrigingExternalDrift, NonFiniteCovariatesNameRowAndColumn) {
  Data d = make_data(20, 19);
  KrigingOptions o;
  o.covariates = {"elevation", "distance"};
  d.covariates(7, 1) = std::nan("");
  try {
    const Kriging<P2, double> k(d.points, d.values, d.covariates, kModel, o);
    FAIL() << "a NaN covariate was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("covariate 'distance' of sample 7 is nan"), std::string::npos) << e.what();
    EXPECT_EQ(e.column(), "distance");
  }
  d.covariates(7, 1) = 1.0;
  const Kriging<P2, double> k(d.points, d.values, d.covariates, kModel, o);
  Eigen::MatrixXd tc;
  const auto targets = make_targets(4, 20, tc);
  tc(2, 0) = std::numeric_limits<double>::infinity();
  RowLabels labels{"T.csv", {2, 3, 4, 5}, "target"};
  try {
    (void)k.predict(targets, tc, labels);
    FAIL() << "an infinite target covariate was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("T.csv:4: kriging: covariate 'elevation' is inf"), std::string::npos) << e.what();
    EXPECT_EQ(e.file(), "T.csv");
    EXPECT_EQ(e.row(), 4u);
  }
  // The targets must come with their covariates, one column per name.
  EXPECT_THROW((void)k.predict(targets), ArgumentError);
  EXPECT_THROW((void)k.predict(targets, Eigen::MatrixXd::Zero(4, 1)), ArgumentError);
  // Simple kriging has no drift to extend.
  o.kind = KrigingKind::Simple;
  EXPECT_THROW((Kriging<P2, double>(d.points, d.values, d.covariates, kModel, o)), ArgumentError);
}

}  // namespace kriging_external_drift_test
}  // namespace errfield
