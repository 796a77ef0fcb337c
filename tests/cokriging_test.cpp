// Cokriging under a linear model of coregionalization (errfield/cokriging.hpp): against the
// bordered cokriging system written out in the test, against Kriging for an intrinsic model,
// exactness at the data, back ends against each other, thread invariance, and on simulated fields
// the use of the cross-covariances and the calibration of the variances.

#include "errfield/cokriging.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <gtest/gtest.h>

#include "errfield/error.hpp"
#include "errfield/kriging.hpp"

namespace errfield {
namespace cokriging_test {

using Point = Eigen::Vector2d;

// A small deterministic generator (splitmix64 + Box-Muller), so the simulated data are the same
// with every standard library.
struct Gaussian {
  std::uint64_t state;
  double uniform() {
    std::uint64_t z = (state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    z ^= z >> 31;
    return (static_cast<double>(z >> 11) + 0.5) / 9007199254740992.0;
  }
  double operator()() { return std::sqrt(-2.0 * std::log(uniform())) * std::cos(6.283185307179586 * uniform()); }
};

std::vector<Point> scattered_points(std::size_t n, double extent, std::uint64_t seed) {
  Gaussian g{seed};
  std::vector<Point> p;
  for (std::size_t i = 0; i < n; ++i) p.emplace_back(extent * g.uniform(), extent * g.uniform());
  return p;
}

Eigen::MatrixXd symmetric(std::initializer_list<double> upper, int p) {
  Eigen::MatrixXd m(p, p);
  auto it = upper.begin();
  for (int i = 0; i < p; ++i)
    for (int j = i; j < p; ++j) m(i, j) = m(j, i) = *it++;
  return m;
}

// Nugget + spherical + exponential with cross-correlations of different signs per structure.
CoregionalizationModel heterogeneous_model(int p) {
  if (p == 2)
    return CoregionalizationModel({{.kind = ModelKind::Nugget, .range = 0.0, .nu = 0.5, .sills = symmetric({0.05, 0.01, 0.08}, 2)},
                                   {.kind = ModelKind::Spherical, .range = 40.0, .nu = 0.5, .sills = symmetric({1.0, 0.7, 0.8}, 2)},
                                   {.kind = ModelKind::Exponential, .range = 15.0, .nu = 0.5, .sills = symmetric({0.3, -0.2, 0.5}, 2)}},
                                  {}, {"a", "b"});
  return CoregionalizationModel(
      {{.kind = ModelKind::Nugget, .range = 0.0, .nu = 0.5, .sills = symmetric({0.05, 0.01, 0.0, 0.08, 0.02, 0.06}, 3)},
       {.kind = ModelKind::Spherical, .range = 40.0, .nu = 0.5, .sills = symmetric({1.0, 0.7, 0.3, 0.8, 0.1, 0.6}, 3)},
       {.kind = ModelKind::Exponential, .range = 15.0, .nu = 0.5, .sills = symmetric({0.3, -0.2, 0.1, 0.5, 0.0, 0.4}, 3)}},
      {}, {"a", "b", "c"});
}

template <class V>
std::vector<V> some_values(const std::vector<Point>& x) {
  std::vector<V> v;
  for (const Point& p : x) {
    V value;
    for (int c = 0; c < ValueTraits<V>::kComponents; ++c)
      value[c] = std::sin(0.07 * p.x() + c) + 0.5 * std::cos(0.05 * p.y() * (c + 1)) + 0.1 * c;
    v.push_back(value);
  }
  return v;
}

// The cokriging system written out, ordered component-major (row a*N + i: component a at sample
// i; the engine orders sample-major), with the drift as explicit columns of a bordered matrix,
// solved by LU. Returns the mean (P) and the prediction error covariance (P x P). A NaN in z (a
// component not measured at a sample) removes that row and column from the system.
struct Reference {
  Eigen::VectorXd mean;
  Eigen::MatrixXd cov;
};
Reference bordered_cokriging(const std::vector<Point>& x, const Eigen::MatrixXd& z, const CoregionalizationModel& model,
                             const Point& x0, KrigingKind kind, int drift_order, const Eigen::VectorXd& simple_mean,
                             bool nugget_is_noise) {
  const int n = static_cast<int>(x.size()), p = model.components();
  auto drift = [&](const Point& q) {
    std::vector<double> f;
    if (kind == KrigingKind::Simple) return f;
    f.push_back(1.0);
    if (kind == KrigingKind::Universal && drift_order >= 1) {
      f.push_back(q.x());
      f.push_back(q.y());
    }
    if (kind == KrigingKind::Universal && drift_order >= 2) {
      f.push_back(q.x() * q.x());
      f.push_back(q.x() * q.y());
      f.push_back(q.y() * q.y());
    }
    return f;
  };
  const int t = static_cast<int>(drift(x0).size());
  const int size = n * p + t * p;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(size, size), rhs = Eigen::MatrixXd::Zero(size, p);
  const Eigen::MatrixXd signal_zero = nugget_is_noise ? Eigen::MatrixXd(model.sill() - model.nugget()) : model.sill();
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const Eigen::MatrixXd c = i == j ? model.sill() : model.covariance_matrix((x[i] - x[j]).norm());
      for (int u = 0; u < p; ++u)
        for (int v = 0; v < p; ++v) a(u * n + i, v * n + j) = c(u, v);
    }
    const double h0 = (x[i] - x0).norm();
    const Eigen::MatrixXd c0 = h0 == 0.0 ? signal_zero : model.covariance_matrix(h0);
    for (int u = 0; u < p; ++u)
      for (int v = 0; v < p; ++v) rhs(u * n + i, v) = c0(u, v);
    const std::vector<double> f = drift(x[i]);
    for (int u = 0; u < p; ++u)
      for (int k = 0; k < t; ++k) a(u * n + i, n * p + u * t + k) = a(n * p + u * t + k, u * n + i) = f[static_cast<std::size_t>(k)];
  }
  const std::vector<double> f0 = drift(x0);
  for (int v = 0; v < p; ++v)
    for (int k = 0; k < t; ++k) rhs(n * p + v * t + k, v) = f0[static_cast<std::size_t>(k)];
  std::vector<int> keep;
  for (int u = 0; u < p; ++u)
    for (int i = 0; i < n; ++i)
      if (!std::isnan(z(i, u))) keep.push_back(u * n + i);
  const auto measured = static_cast<Eigen::Index>(keep.size());
  for (int k = n * p; k < size; ++k) keep.push_back(k);
  const Eigen::MatrixXd kept_rhs = rhs(keep, Eigen::all);
  const Eigen::MatrixXd sol = Eigen::MatrixXd(a(keep, keep)).fullPivLu().solve(kept_rhs);
  Eigen::VectorXd zz(measured);
  for (Eigen::Index k = 0; k < measured; ++k) {
    const int u = keep[static_cast<std::size_t>(k)] / n, i = keep[static_cast<std::size_t>(k)] % n;
    zz[k] = z(i, u) - (kind == KrigingKind::Simple ? simple_mean[u] : 0.0);
  }
  Reference r;
  r.mean = sol.topRows(measured).transpose() * zz;
  if (kind == KrigingKind::Simple) r.mean += simple_mean;
  r.cov = signal_zero - sol.transpose() * kept_rhs;
  return r;
}

template <class V>
Eigen::MatrixXd as_matrix(const std::vector<V>& v) {
  Eigen::MatrixXd m(static_cast<Eigen::Index>(v.size()), ValueTraits<V>::kComponents);
  for (std::size_t i = 0; i < v.size(); ++i)
    for (int c = 0; c < ValueTraits<V>::kComponents; ++c) m(static_cast<Eigen::Index>(i), c) = v[i][c];
  return m;
}

template <class V>
void expect_matches_bordered_system(KrigingKind kind, int drift_order, bool nugget_is_noise, KrigingBackend backend) {
  constexpr int P = ValueTraits<V>::kComponents;
  const auto x = scattered_points(12, 100.0, 7);
  const auto values = some_values<V>(x);
  const CoregionalizationModel model = heterogeneous_model(P);
  KrigingOptions o;
  o.kind = kind;
  o.drift_order = drift_order;
  o.backend = backend;
  o.neighbors = backend == KrigingBackend::Local ? 12 : 0;
  o.nugget = nugget_is_noise ? NuggetTreatment::MeasurementError : NuggetTreatment::MicroScale;
  Eigen::VectorXd mean(P);
  for (int c = 0; c < P; ++c) mean[c] = 0.3 * c - 0.2;
  if (kind == KrigingKind::Simple) o.simple_mean.assign(mean.data(), mean.data() + P);
  const Cokriging<Point, V> ck(x, values, model, o);
  ASSERT_TRUE(ck.report().usable()) << ck.report().message;
  // Targets in between, outside, and on a sample.
  std::vector<Point> targets{{50, 50}, {10, 90}, {120, -10}, x[3]};
  const auto pred = ck.predict(targets);
  ASSERT_TRUE(pred.usable()) << pred.message;
  ASSERT_EQ(pred.covariance.size(), targets.size());
  for (std::size_t t = 0; t < targets.size(); ++t) {
    const Reference r = bordered_cokriging(x, as_matrix(values), model, targets[t], kind, drift_order, mean, nugget_is_noise);
    for (int a = 0; a < P; ++a) {
      // The values and sills are O(1); both solutions are backward stable on a 12P-unknown system.
      EXPECT_NEAR(pred.mean[t][a], r.mean[a], 1e-10) << "target " << t << ", component " << a;
      for (int b = 0; b < P; ++b)
        EXPECT_NEAR(pred.covariance[t](a, b), r.cov(a, b), 1e-10) << "target " << t << ", entry " << a << "," << b;
    }
  }
}

TEST(Cokriging, OrdinaryMatchesTheBorderedSystemForTwoComponents) {
  expect_matches_bordered_system<Eigen::Vector2d>(KrigingKind::Ordinary, 0, false, KrigingBackend::Dense);
}
TEST(Cokriging, OrdinaryMatchesTheBorderedSystemForThreeComponents) {
  expect_matches_bordered_system<Eigen::Vector3d>(KrigingKind::Ordinary, 0, false, KrigingBackend::Dense);
}
TEST(Cokriging, SimpleMatchesTheBorderedSystem) {
  expect_matches_bordered_system<Eigen::Vector2d>(KrigingKind::Simple, 0, false, KrigingBackend::Dense);
  expect_matches_bordered_system<Eigen::Vector3d>(KrigingKind::Simple, 0, false, KrigingBackend::Local);
}
TEST(Cokriging, UniversalMatchesTheBorderedSystem) {
  expect_matches_bordered_system<Eigen::Vector2d>(KrigingKind::Universal, 1, false, KrigingBackend::Dense);
  expect_matches_bordered_system<Eigen::Vector3d>(KrigingKind::Universal, 2, false, KrigingBackend::Dense);
  expect_matches_bordered_system<Eigen::Vector2d>(KrigingKind::Universal, 1, false, KrigingBackend::Local);
}
TEST(Cokriging, MeasurementErrorNuggetMatchesTheBorderedSystem) {
  expect_matches_bordered_system<Eigen::Vector2d>(KrigingKind::Simple, 0, true, KrigingBackend::Dense);
  expect_matches_bordered_system<Eigen::Vector3d>(KrigingKind::Ordinary, 0, true, KrigingBackend::Dense);
  expect_matches_bordered_system<Eigen::Vector2d>(KrigingKind::Ordinary, 0, true, KrigingBackend::Local);
}

// Heterotopic data: each component missing at its own samples (about 40 % of the second's, 25 %
// of the third's), never all at one sample.
template <class V>
std::vector<V> with_gaps(std::vector<V> values, std::uint64_t seed) {
  Gaussian g{seed};
  for (V& v : values)
    for (int c = 1; c < ValueTraits<V>::kComponents; ++c)
      if (g.uniform() < (c == 1 ? 0.4 : 0.25)) v[c] = std::numeric_limits<double>::quiet_NaN();
  return values;
}

TEST(Cokriging, HeterotopicMatchesTheBorderedSystemWithoutTheMissingRows) {
  const auto x = scattered_points(14, 100.0, 21);
  const std::vector<Point> targets{{50, 50}, {10, 90}, {120, -10}, x[3], x[5]};
  const auto check = [&]<class V>(KrigingKind kind, int drift_order, KrigingBackend backend) {
    constexpr int P = ValueTraits<V>::kComponents;
    const auto values = with_gaps(some_values<V>(x), 22);
    const CoregionalizationModel model = heterogeneous_model(P);
    KrigingOptions o;
    o.kind = kind;
    o.drift_order = drift_order;
    o.backend = backend;
    o.neighbors = backend == KrigingBackend::Local ? x.size() : 0;
    const Eigen::VectorXd mean = Eigen::VectorXd::LinSpaced(P, -0.2, 0.4);
    if (kind == KrigingKind::Simple) o.simple_mean.assign(mean.data(), mean.data() + P);
    const auto pred = Cokriging<Point, V>(x, values, model, o).predict(targets);
    ASSERT_TRUE(pred.usable()) << pred.message;
    for (std::size_t t = 0; t < targets.size(); ++t) {
      const Reference r = bordered_cokriging(x, as_matrix(values), model, targets[t], kind, drift_order, mean, false);
      // O(1) values and sills, backward-stable solves of systems of ~30 unknowns: rounding only.
      EXPECT_LT((pred.mean[t] - r.mean).cwiseAbs().maxCoeff(), 1e-10) << kriging_kind_name(kind) << ", target " << t;
      EXPECT_LT((pred.covariance[t] - r.cov).cwiseAbs().maxCoeff(), 1e-10) << kriging_kind_name(kind) << ", target " << t;
    }
  };
  for (KrigingBackend backend : {KrigingBackend::Dense, KrigingBackend::Local}) {
    check.template operator()<Eigen::Vector2d>(KrigingKind::Ordinary, 0, backend);
    check.template operator()<Eigen::Vector3d>(KrigingKind::Ordinary, 0, backend);
    check.template operator()<Eigen::Vector3d>(KrigingKind::Simple, 0, backend);
    check.template operator()<Eigen::Vector2d>(KrigingKind::Universal, 1, backend);
  }
}

// With the secondary everywhere the data are isotopic, and the engine builds the same rows for
// them (the bordered-system tests above); with the secondary nowhere, ordinary cokriging of the
// primary is ordinary kriging with the primary's direct variogram.
TEST(Cokriging, HeterotopicWithTheSecondaryNowhereIsKrigingOfThePrimary) {
  const auto x = scattered_points(30, 100.0, 31);
  const auto targets = scattered_points(12, 110.0, 32);
  const CoregionalizationModel lmc = heterogeneous_model(2);
  const auto full = some_values<Eigen::Vector2d>(x);
  // The primary's own variogram: the (0, 0) entries of the LMC's structures.
  const VariogramModel primary = VariogramModel::parse("nug(0.05)+sph(sill=1,range=40)+exp(sill=0.3,range=15)");
  std::vector<double> primary_values;
  auto alone = full;
  for (std::size_t i = 0; i < x.size(); ++i) {
    primary_values.push_back(full[i][0]);
    alone[i][1] = std::numeric_limits<double>::quiet_NaN();
  }
  for (KrigingBackend backend : {KrigingBackend::Dense, KrigingBackend::Local}) {
    KrigingOptions o;
    o.backend = backend;
    o.neighbors = backend == KrigingBackend::Local ? 12 : 0;
    const auto none = Cokriging<Point, Eigen::Vector2d>(x, alone, lmc, o).predict(targets);
    const auto ok = Kriging<Point, double>(x, primary_values, primary, o).predict(targets);
    ASSERT_TRUE(none.usable() && ok.usable()) << none.message;
    for (std::size_t t = 0; t < targets.size(); ++t) {
      EXPECT_NEAR(none.mean[t][0], ok.mean[t], 1e-10) << "target " << t;
      EXPECT_NEAR(none.variance(t, 0), ok.variance[t], 1e-10) << "target " << t;
      // No secondary anywhere: ordinary cokriging has no unbiased predictor of it.
      EXPECT_TRUE(std::isnan(none.mean[t][1])) << "target " << t;
      EXPECT_TRUE(std::isnan(none.covariance[t](1, 1))) << "target " << t;
    }
  }
  // Simple cokriging (known means) predicts the secondary from the primary alone: the simple
  // kriging of the secondary by the cross-covariance, whose variance is sill - c' K^-1 c.
  KrigingOptions simple;
  simple.kind = KrigingKind::Simple;
  const auto s = Cokriging<Point, Eigen::Vector2d>(x, alone, lmc, simple).predict(targets);
  ASSERT_TRUE(s.usable());
  for (std::size_t t = 0; t < targets.size(); ++t) EXPECT_TRUE(std::isfinite(s.mean[t][1]) && s.variance(t, 1) > 0.0);
}

TEST(Cokriging, HeterotopicLeaveOneOutEqualsRefittingWithoutTheSample) {
  const auto x = scattered_points(20, 100.0, 41);
  const auto values = with_gaps(some_values<Eigen::Vector2d>(x), 42);
  const CoregionalizationModel model = heterogeneous_model(2);
  KrigingOptions o;
  const auto cv = Cokriging<Point, Eigen::Vector2d>(x, values, model, o).leave_one_out();
  KrigingOptions local = o;
  local.backend = KrigingBackend::Local;
  local.neighbors = x.size();
  const auto lcv = Cokriging<Point, Eigen::Vector2d>(x, values, model, local).leave_one_out();
  std::size_t gaps = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    std::vector<Point> xs = x;
    std::vector<Eigen::Vector2d> vs = values;
    xs.erase(xs.begin() + static_cast<std::ptrdiff_t>(i));
    vs.erase(vs.begin() + static_cast<std::ptrdiff_t>(i));
    const auto p = Cokriging<Point, Eigen::Vector2d>(xs, vs, model, o).predict(std::vector<Point>{x[i]});
    for (int a = 0; a < 2; ++a) {
      if (std::isnan(values[i][a])) {
        ++gaps;
        EXPECT_TRUE(std::isnan(cv.residual[i][a]) && std::isnan(lcv.residual[i][a])) << "sample " << i;
        continue;
      }
      EXPECT_NEAR(cv.prediction[i][a], p.mean[0][a], 1e-9) << "sample " << i << ", component " << a;
      EXPECT_NEAR(lcv.prediction[i][a], p.mean[0][a], 1e-9) << "sample " << i << ", component " << a;
      EXPECT_NEAR(cv.covariance[i](a, a), p.covariance[0](a, a), 1e-9) << "sample " << i << ", component " << a;
    }
  }
  EXPECT_GT(gaps, 3u);
  EXPECT_TRUE(std::isfinite(cv.rms_error) && cv.rms_error > 0.0);
}

TEST(Cokriging, HeterotopicRefusesASampleWithNothingMeasured) {
  const auto x = scattered_points(10, 100.0, 51);
  auto values = some_values<Eigen::Vector2d>(x);
  values[6].setConstant(std::numeric_limits<double>::quiet_NaN());
  try {
    Cokriging<Point, Eigen::Vector2d>(x, values, heterogeneous_model(2));
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("sample 6 has no measured component"), std::string::npos) << e.what();
  }
  values[6][0] = 1.0;
  values[6][1] = std::numeric_limits<double>::infinity();
  EXPECT_THROW((Cokriging<Point, Eigen::Vector2d>(x, values, heterogeneous_model(2))), InputError);
}

TEST(Cokriging, IntrinsicModelGivesKrigingWithTheSharedModel) {
  const auto x = scattered_points(30, 100.0, 11);
  const auto values = some_values<Eigen::Vector3d>(x);
  const VariogramModel shared = VariogramModel::parse("nug(0.05)+sph(sill=1,range=40)+exp(sill=0.3,range=15)");
  const CoregionalizationModel lmc = CoregionalizationModel::intrinsic(shared, Eigen::MatrixXd::Identity(3, 3));
  const auto targets = scattered_points(20, 110.0, 12);
  for (KrigingKind kind : {KrigingKind::Simple, KrigingKind::Ordinary, KrigingKind::Universal}) {
    KrigingOptions o;
    o.kind = kind;
    o.simple_mean = {0.2};
    const auto k = Kriging<Point, Eigen::Vector3d>(x, values, shared, o).predict(targets);
    const auto c = Cokriging<Point, Eigen::Vector3d>(x, values, lmc, o).predict(targets);
    ASSERT_TRUE(k.usable() && c.usable());
    for (std::size_t t = 0; t < targets.size(); ++t)
      for (int a = 0; a < 3; ++a) {
        EXPECT_NEAR(c.mean[t][a], k.mean[t][a], 1e-10) << kriging_kind_name(kind) << ", target " << t;
        EXPECT_NEAR(c.variance(t, a), k.variance[t], 1e-10) << kriging_kind_name(kind) << ", target " << t;
        for (int b = 0; b < a; ++b) EXPECT_NEAR(c.covariance[t](a, b), 0.0, 1e-10);
      }
  }
}

TEST(Cokriging, MeansWithoutVariancesAreTheSame) {
  const auto x = scattered_points(30, 100.0, 17);
  const auto values = some_values<Eigen::Vector3d>(x);
  const auto targets = scattered_points(70, 100.0, 18);
  for (KrigingKind kind : {KrigingKind::Simple, KrigingKind::Ordinary, KrigingKind::Universal}) {
    KrigingOptions o;
    o.kind = kind;
    const auto with = Cokriging<Point, Eigen::Vector3d>(x, values, heterogeneous_model(3), o).predict(targets);
    o.compute_variance = false;
    const auto without = Cokriging<Point, Eigen::Vector3d>(x, values, heterogeneous_model(3), o).predict(targets);
    EXPECT_TRUE(without.covariance.empty());
    for (std::size_t t = 0; t < targets.size(); ++t)
      EXPECT_LT((with.mean[t] - without.mean[t]).cwiseAbs().maxCoeff(), 1e-12) << "target " << t;
  }
}

TEST(Cokriging, ExactAtTheDataWithoutNugget) {
  const auto x = scattered_points(25, 100.0, 3);
  const auto values = some_values<Eigen::Vector2d>(x);
  const CoregionalizationModel model(
      {{.kind = ModelKind::Spherical, .range = 50.0, .nu = 0.5, .sills = symmetric({1.0, 0.6, 0.9}, 2)},
       {.kind = ModelKind::Exponential, .range = 10.0, .nu = 0.5, .sills = symmetric({0.2, -0.1, 0.3}, 2)}});
  for (KrigingBackend backend : {KrigingBackend::Dense, KrigingBackend::Local}) {
    KrigingOptions o;
    o.backend = backend;
    o.neighbors = 10;
    const auto p = Cokriging<Point, Eigen::Vector2d>(x, values, model, o).predict(x);
    ASSERT_TRUE(p.usable()) << p.message;
    for (std::size_t i = 0; i < x.size(); ++i)
      for (int a = 0; a < 2; ++a) {
        // Interpolation of O(1) values through a system of condition ~1e3: rounding only.
        EXPECT_NEAR(p.mean[i][a], values[i][a], 1e-10) << "sample " << i;
        for (int b = 0; b < 2; ++b) EXPECT_NEAR(p.covariance[i](a, b), 0.0, 1e-10) << "sample " << i;
      }
  }
}

TEST(Cokriging, LocalWithAllSamplesEqualsDense) {
  const auto x = scattered_points(40, 100.0, 5);
  const auto values = some_values<Eigen::Vector3d>(x);
  const CoregionalizationModel model = heterogeneous_model(3);
  const auto targets = scattered_points(15, 100.0, 6);
  for (KrigingKind kind : {KrigingKind::Simple, KrigingKind::Ordinary, KrigingKind::Universal}) {
    KrigingOptions dense;
    dense.kind = kind;
    dense.simple_mean = {0.1, -0.2, 0.3};
    // Simple: the nugget as measurement error, whose leave-one-out residuals carry it.
    if (kind == KrigingKind::Simple) dense.nugget = NuggetTreatment::MeasurementError;
    KrigingOptions local = dense;
    local.backend = KrigingBackend::Local;
    for (std::size_t k : {std::size_t{40}, std::size_t{45}}) {
      local.neighbors = k;
      const auto d = Cokriging<Point, Eigen::Vector3d>(x, values, model, dense).predict(targets);
      const auto l = Cokriging<Point, Eigen::Vector3d>(x, values, model, local).predict(targets);
      for (std::size_t t = 0; t < targets.size(); ++t) {
        EXPECT_LT((d.mean[t] - l.mean[t]).cwiseAbs().maxCoeff(), 1e-10) << "target " << t;
        EXPECT_LT((d.covariance[t] - l.covariance[t]).cwiseAbs().maxCoeff(), 1e-10) << "target " << t;
      }
      const auto dc = Cokriging<Point, Eigen::Vector3d>(x, values, model, dense).leave_one_out();
      const auto lc = Cokriging<Point, Eigen::Vector3d>(x, values, model, local).leave_one_out();
      for (std::size_t i = 0; i < x.size(); ++i) {
        EXPECT_LT((dc.residual[i] - lc.residual[i]).cwiseAbs().maxCoeff(), 1e-9) << "sample " << i;
        EXPECT_LT((dc.covariance[i] - lc.covariance[i]).cwiseAbs().maxCoeff(), 1e-9) << "sample " << i;
      }
    }
  }
}

TEST(Cokriging, LocalRadiusIncludesSamplesAtExactlyTheRadius) {
  // An 8 x 8 integer grid without the integer targets (a target on a sample is predicted exactly
  // whatever its neighbours): they have up to 4 samples at exactly 2, (x + 0.5, y) targets up to 6
  // at exactly 2.5. The local back end must equal the bordered system on the samples at distance
  // <= R (chosen by brute force here, with the sum of squares gstat's maxdist compares).
  const std::vector<Point> integer_targets{{3, 4}, {0, 2}, {7, 7}};
  std::vector<Point> x;
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 8; ++j)
      if (std::find(integer_targets.begin(), integer_targets.end(), Point(i, j)) == integer_targets.end()) x.emplace_back(i, j);
  const auto values = some_values<Eigen::Vector2d>(x);
  const CoregionalizationModel model = heterogeneous_model(2);
  std::vector<Point> targets = integer_targets;
  targets.insert(targets.end(), {Point(2.5, 5), Point(0.5, 0), Point(4.5, 3)});
  for (double r : {2.0, 2.5}) {
    KrigingOptions o;
    o.backend = KrigingBackend::Local;
    o.radius = r;
    const auto pred = Cokriging<Point, Eigen::Vector2d>(x, values, model, o).predict(targets);
    ASSERT_TRUE(pred.usable()) << pred.message;
    for (std::size_t t = 0; t < targets.size(); ++t) {
      std::vector<Point> near;
      std::vector<Eigen::Vector2d> near_values;
      for (std::size_t i = 0; i < x.size(); ++i) {
        const double dx = x[i].x() - targets[t].x(), dy = x[i].y() - targets[t].y();
        if (dx * dx + dy * dy <= r * r) {
          near.push_back(x[i]);
          near_values.push_back(values[i]);
        }
      }
      const Reference ref = bordered_cokriging(near, as_matrix(near_values), model, targets[t], KrigingKind::Ordinary, 0,
                                               Eigen::VectorXd::Zero(2), false);
      // O(1) values and sills, systems of at most 2 x 13 unknowns: rounding only.
      EXPECT_LT((pred.mean[t] - ref.mean).cwiseAbs().maxCoeff(), 1e-10) << "radius " << r << ", target " << t;
      EXPECT_LT((pred.covariance[t] - ref.cov).cwiseAbs().maxCoeff(), 1e-10) << "radius " << r << ", target " << t;
    }
  }
}

TEST(Cokriging, DenseLeaveOneOutEqualsRefittingWithoutTheSample) {
  const auto x = scattered_points(20, 100.0, 9);
  const auto values = some_values<Eigen::Vector2d>(x);
  const CoregionalizationModel model = heterogeneous_model(2);
  KrigingOptions o;
  o.kind = KrigingKind::Universal;
  const auto cv = Cokriging<Point, Eigen::Vector2d>(x, values, model, o).leave_one_out();
  for (std::size_t i : {std::size_t{0}, std::size_t{7}, std::size_t{19}}) {
    std::vector<Point> xs = x;
    std::vector<Eigen::Vector2d> vs = values;
    xs.erase(xs.begin() + static_cast<std::ptrdiff_t>(i));
    vs.erase(vs.begin() + static_cast<std::ptrdiff_t>(i));
    const auto p = Cokriging<Point, Eigen::Vector2d>(xs, vs, model, o).predict(std::vector<Point>{x[i]});
    EXPECT_LT((cv.prediction[i] - p.mean[0]).cwiseAbs().maxCoeff(), 1e-9) << "sample " << i;
    EXPECT_LT((cv.covariance[i] - p.covariance[0]).cwiseAbs().maxCoeff(), 1e-9) << "sample " << i;
  }
}

TEST(Cokriging, ResultsAreBitIdenticalForAnyThreadCount) {
  const auto x = scattered_points(60, 100.0, 13);
  const auto values = some_values<Eigen::Vector2d>(x);
  const CoregionalizationModel model = heterogeneous_model(2);
  const auto targets = scattered_points(200, 100.0, 14);
  for (KrigingBackend backend : {KrigingBackend::Dense, KrigingBackend::Local}) {
    KrigingOptions o;
    o.backend = backend;
    o.neighbors = 15;
    o.threads = 1;
    const auto one = Cokriging<Point, Eigen::Vector2d>(x, values, model, o).predict(targets);
    const auto loo_one = Cokriging<Point, Eigen::Vector2d>(x, values, model, o).leave_one_out();
    for (int threads : {2, 3}) {
      o.threads = threads;
      const auto many = Cokriging<Point, Eigen::Vector2d>(x, values, model, o).predict(targets);
      const auto loo_many = Cokriging<Point, Eigen::Vector2d>(x, values, model, o).leave_one_out();
      for (std::size_t t = 0; t < targets.size(); ++t) {
        EXPECT_EQ(one.mean[t], many.mean[t]) << "target " << t;
        EXPECT_EQ(one.covariance[t], many.covariance[t]) << "target " << t;
      }
      for (std::size_t i = 0; i < x.size(); ++i) EXPECT_EQ(loo_one.residual[i], loo_many.residual[i]) << "sample " << i;
    }
  }
}

// A simulated Gaussian field with P components from the LMC: z = chol(Sigma) e over all samples
// and components (the covariance written out with the model's covariance_matrix).
Eigen::MatrixXd simulate(const std::vector<Point>& x, const CoregionalizationModel& model, std::uint64_t seed) {
  const int n = static_cast<int>(x.size()), p = model.components();
  Eigen::MatrixXd sigma(n * p, n * p);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      sigma.block(i * p, j * p, p, p) = i == j ? model.sill() : model.covariance_matrix((x[i] - x[j]).norm());
  const Eigen::LLT<Eigen::MatrixXd> llt(sigma);
  Gaussian g{seed};
  Eigen::VectorXd e(n * p);
  for (int k = 0; k < n * p; ++k) e[k] = g();
  const Eigen::VectorXd z = llt.matrixL() * e;
  Eigen::MatrixXd out(n, p);
  for (int i = 0; i < n; ++i) out.row(i) = z.segment(i * p, p).transpose();
  return out;
}

std::vector<Eigen::Vector2d> rows_of(const Eigen::MatrixXd& m) {
  std::vector<Eigen::Vector2d> v;
  for (Eigen::Index i = 0; i < m.rows(); ++i) v.emplace_back(m(i, 0), m(i, 1));
  return v;
}

// SIMULATED data: the cross-covariance carries the information. a = S + L + noise and
// b = S - L + noise, S a short-range field (exp, range 2: nearly independent from sample to
// sample) and L a long-range one (sph, range 60). Kriging a alone sees S as noise on L at every
// neighbour; cokriging sees L = (a - b) / 2 at the neighbours free of S, so it must predict better
// in leave-one-out (all components of a sample left out together).
TEST(Cokriging, CrossCorrelationImprovesLeaveOneOutOnSimulatedData) {
  const CoregionalizationModel model(
      {{.kind = ModelKind::Nugget, .range = 0.0, .nu = 0.5, .sills = symmetric({0.01, 0.0, 0.01}, 2)},
       {.kind = ModelKind::Exponential, .range = 2.0, .nu = 0.5, .sills = symmetric({1.0, 1.0, 1.0}, 2)},
       {.kind = ModelKind::Spherical, .range = 60.0, .nu = 0.5, .sills = symmetric({1.0, -1.0, 1.0}, 2)}},
      {}, {"a", "b"});
  const auto x = scattered_points(80, 100.0, 21);
  const Eigen::MatrixXd z = simulate(x, model, 22);
  const auto cv = Cokriging<Point, Eigen::Vector2d>(x, rows_of(z), model).leave_one_out();
  double co = 0.0, separate = 0.0, co_var = 0.0, separate_var = 0.0;
  for (int a = 0; a < 2; ++a) {
    std::vector<double> za(z.col(a).data(), z.col(a).data() + z.rows());
    const auto k = Kriging<Point, double>(x, za, model.direct_model(a)).leave_one_out();
    for (std::size_t i = 0; i < x.size(); ++i) {
      separate += k.residual[i] * k.residual[i];
      co += cv.residual[i][a] * cv.residual[i][a];
      separate_var += k.variance[i];
      co_var += cv.covariance[i](a, a);
    }
  }
  const double n = 2.0 * static_cast<double>(x.size());
  const double rms_co = std::sqrt(co / n), rms_separate = std::sqrt(separate / n);
  std::cout << "leave-one-out RMS: cokriging " << rms_co << ", separate kriging " << rms_separate
            << "; expected from the model's variances " << std::sqrt(co_var / n) << ", " << std::sqrt(separate_var / n) << "\n";
  // Most of the error is S, which nothing predicts (variance 1 of about 1.3): the model expects a
  // gain of a few per cent, and the realized errors must show it.
  EXPECT_LT(co_var, separate_var);
  EXPECT_LT(rms_co, rms_separate);
}

// SIMULATED data from a known LMC: the leave-one-out residuals whitened by their covariance are
// standard normal, so their mean square is 1 and 95 % of the component residuals lie within 1.96
// standard deviations. 300 samples x 2 components: the mean square of 600 chi2(1) values has a
// standard deviation of sqrt(2/600) = 0.058, the tolerance 0.2 is 3.5 of them; a coverage
// estimated from 300 residuals has a standard deviation of 0.0126, the band 0.95 +- 0.04 is 3.2 of them.
TEST(Cokriging, LeaveOneOutVariancesAreCalibratedOnSimulatedData) {
  const CoregionalizationModel model = heterogeneous_model(2);
  const auto x = scattered_points(300, 100.0, 31);
  const Eigen::MatrixXd z = simulate(x, model, 32);
  const auto cv = Cokriging<Point, Eigen::Vector2d>(x, rows_of(z), model).leave_one_out();
  ASSERT_EQ(cv.residual.size(), x.size());
  double sum_sq = 0.0;
  int covered[2] = {0, 0};
  for (std::size_t i = 0; i < x.size(); ++i) {
    const Eigen::LLT<Eigen::MatrixXd> llt(cv.covariance[i]);
    ASSERT_EQ(llt.info(), Eigen::Success) << "sample " << i;
    const Eigen::VectorXd e = cv.residual[i];
    sum_sq += llt.matrixL().solve(e).squaredNorm();
    for (int a = 0; a < 2; ++a) covered[a] += std::abs(e[a]) <= 1.96 * std::sqrt(cv.covariance[i](a, a)) ? 1 : 0;
  }
  const double mean_square = sum_sq / (2.0 * x.size());
  std::cout << "mean squared whitened residual " << mean_square << ", coverage " << covered[0] / 300.0 << ", "
            << covered[1] / 300.0 << "\n";
  EXPECT_NEAR(mean_square, 1.0, 0.2);
  for (int a = 0; a < 2; ++a) EXPECT_NEAR(covered[a] / 300.0, 0.95, 0.04) << "component " << a;
}

TEST(Cokriging, RefusesWhatItDoesNotSupport) {
  const auto x = scattered_points(10, 100.0, 1);
  const auto v2 = some_values<Eigen::Vector2d>(x);
  const auto v3 = some_values<Eigen::Vector3d>(x);
  const CoregionalizationModel model = heterogeneous_model(2);
  auto message = [](auto&& f) {
    try {
      f();
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  {
    const std::string m = message([&] { Cokriging<Point, Eigen::Vector3d>(x, v3, model); });
    EXPECT_NE(m.find("model has 2 component(s) but the values have 3"), std::string::npos) << m;
  }
  KrigingOptions o;
  o.backend = KrigingBackend::Sparse;
  EXPECT_NE(message([&] { Cokriging<Point, Eigen::Vector2d>(x, v2, model, o); }).find("sparse back end"), std::string::npos);
  o = {};
  o.covariates = {"dist"};
  EXPECT_NE(message([&] { Cokriging<Point, Eigen::Vector2d>(x, v2, model, o); }).find("covariates"), std::string::npos);
  o = {};
  o.duplicates = DuplicatePolicy::Average;
  EXPECT_NE(message([&] { Cokriging<Point, Eigen::Vector2d>(x, v2, model, o); }).find("Average"), std::string::npos);
  o = {};
  o.simple_mean = {1.0, 2.0, 3.0};
  o.kind = KrigingKind::Simple;
  EXPECT_NE(message([&] { Cokriging<Point, Eigen::Vector2d>(x, v2, model, o); }).find("simple_mean has 3 entries"),
            std::string::npos);
  auto dup = x;
  dup[4] = dup[2];
  const std::string m = message([&] { Cokriging<Point, Eigen::Vector2d>(dup, v2, model); });
  EXPECT_NE(m.find("samples 2 and 4 are duplicates"), std::string::npos) << m;
  EXPECT_THROW(CoregionalizationModel({{.kind = ModelKind::Power, .range = 1.0, .nu = 0.5, .sills = symmetric({1, 0, 1}, 2)}}),
               ArgumentError);
}

TEST(Cokriging, MemoryBudgetIsCheckedBeforeAllocating) {
  const auto x = scattered_points(100, 100.0, 51);
  const auto values = some_values<Eigen::Vector3d>(x);
  KrigingOptions o;
  o.dense_memory_budget_bytes = 1 << 20;  // the 300 x 300 system needs 2 * 300^2 * 8 bytes = 1.4 MB
  try {
    Cokriging<Point, Eigen::Vector3d>(x, values, heterogeneous_model(3), o);
    ADD_FAILURE() << "no ResourceError";
  } catch (const ResourceError& e) {
    EXPECT_NE(std::string(e.what()).find("300 x 300 system"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("local back end"), std::string::npos) << e.what();
  }
  o.backend = KrigingBackend::Local;
  o.neighbors = 20;  // 60 x 60 per target: fits
  const auto p = Cokriging<Point, Eigen::Vector3d>(x, values, heterogeneous_model(3), o).predict(x);
  EXPECT_TRUE(p.usable());
  o.neighbors = 100;
  o.threads = 4;  // 4 x (300^2 + ...) doubles > 1 MiB
  const Cokriging<Point, Eigen::Vector3d> too_many(x, values, heterogeneous_model(3), o);
  EXPECT_THROW(too_many.predict(x), ResourceError);
}

TEST(Cokriging, AnisotropyIsTheModelsLagMap) {
  // ARD with range multiplier 2 along y equals the isotropic model on y / 2.
  const auto x = scattered_points(20, 100.0, 41);
  const auto values = some_values<Eigen::Vector2d>(x);
  const CoregionalizationModel iso = heterogeneous_model(2);
  std::vector<CoregionalizationStructure> s = iso.structures();
  const CoregionalizationModel ard(s, Anisotropy::ard({1.0, 2.0}));
  std::vector<Point> squeezed = x;
  for (Point& p : squeezed) p.y() /= 2.0;
  const std::vector<Point> targets{{30, 60}, {70, 20}};
  std::vector<Point> targets_squeezed = targets;
  for (Point& p : targets_squeezed) p.y() /= 2.0;
  const auto a = Cokriging<Point, Eigen::Vector2d>(x, values, ard).predict(targets);
  const auto b = Cokriging<Point, Eigen::Vector2d>(squeezed, values, iso).predict(targets_squeezed);
  for (std::size_t t = 0; t < targets.size(); ++t) {
    EXPECT_LT((a.mean[t] - b.mean[t]).cwiseAbs().maxCoeff(), 1e-10);
    EXPECT_LT((a.covariance[t] - b.covariance[t]).cwiseAbs().maxCoeff(), 1e-10);
  }
}

}  // namespace cokriging_test
}  // namespace errfield
