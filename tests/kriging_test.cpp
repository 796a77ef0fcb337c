// Kriging against independent ground truth: the textbook bordered system / GP posterior solved
// with a full-pivot LU of explicitly built matrices, brute-force leave-one-out, and the back ends
// against each other. All data are simulated (random locations, smooth field + noise).

#include "errfield/kriging.hpp"
#include "errfield/indicator_kriging.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>

#include <Eigen/Dense>
#include <gtest/gtest.h>

namespace errfield {
namespace kriging_test {

using P3 = Eigen::Vector3d;

struct Data {
  std::vector<P3> points;
  std::vector<double> values;
};

// Simulated: uniform locations in [0, 100]^3, a smooth trend + sinusoid + small noise.
Data make_data(std::size_t n, unsigned seed, double noise = 0.05) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 100.0);
  std::normal_distribution<double> e(0.0, noise);
  Data d;
  for (std::size_t i = 0; i < n; ++i) {
    P3 p(u(rng), u(rng), u(rng));
    d.points.push_back(p);
    d.values.push_back(0.01 * p.x() - 0.02 * p.z() + std::sin(p.x() / 20.0) * std::cos(p.y() / 25.0) + e(rng));
  }
  return d;
}

std::vector<P3> make_targets(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-10.0, 110.0);
  std::vector<P3> t;
  for (std::size_t i = 0; i < n; ++i) t.emplace_back(u(rng), u(rng), u(rng));
  return t;
}

// Independent reference: builds K, c0, F, f0 directly from VariogramModel::covariance and solves
// the bordered (universal kriging) system [K F; F' 0] [lambda; mu] = [c0; f0] by full-pivot LU.
struct Reference {
  double mean, variance;
  Eigen::VectorXd weights;
};
Reference reference(const Data& d, const P3& target, const VariogramModel& model, int drift_order /* -1 simple */,
                    double simple_mean = 0.0, bool measurement_error = false,
                    const std::vector<double>& meas = {}) {
  const auto n = static_cast<Eigen::Index>(d.points.size());
  auto drift = [&](const P3& x) {
    std::vector<double> f;
    if (drift_order >= 0) f.push_back(1.0);
    if (drift_order >= 1)
      for (int k = 0; k < 3; ++k) f.push_back(x[k] / 100.0);
    if (drift_order >= 2)
      for (int k = 0; k < 3; ++k)
        for (int l = k; l < 3; ++l) f.push_back(x[k] * x[l] / 1e4);
    return f;
  };
  const auto p = static_cast<Eigen::Index>(drift(target).size());
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n + p, n + p);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n + p);
  const double nug = model.nugget();
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index j = 0; j < n; ++j)
      a(i, j) = model.covariance((d.points[i] - d.points[j]).norm());
    if (!meas.empty()) a(i, i) += meas[i];
    const double h = (d.points[i] - target).norm();
    b[i] = model.covariance(h);
    if (measurement_error && h == 0.0) b[i] -= nug;
    const auto f = drift(d.points[i]);
    for (Eigen::Index k = 0; k < p; ++k) a(i, n + k) = a(n + k, i) = f[k];
  }
  const auto f0 = drift(target);
  for (Eigen::Index k = 0; k < p; ++k) b[n + k] = f0[k];
  const Eigen::VectorXd sol = a.fullPivLu().solve(b);
  Reference r;
  r.weights = sol.head(n);
  r.mean = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) r.mean += r.weights[i] * (d.values[i] - (drift_order < 0 ? simple_mean : 0.0));
  if (drift_order < 0) r.mean += simple_mean;
  const double c00 = model.sill() - (measurement_error ? nug : 0.0);
  r.variance = c00 - sol.dot(b);
  return r;
}

KrigingOptions options_for(int drift_order) {
  KrigingOptions o;
  if (drift_order < 0) o.kind = KrigingKind::Simple;
  else if (drift_order == 0) o.kind = KrigingKind::Ordinary;
  else {
    o.kind = KrigingKind::Universal;
    o.drift_order = drift_order;
  }
  return o;
}

// The reference solves an (N+p) system with a full-pivot LU in raw coordinates; agreement is
// limited by that system's conditioning (~1e8 here for quadratic drift), so 1e-7 of the sill.
constexpr double kTol = 1e-7;

class KrigingVariants : public ::testing::TestWithParam<int> {};

TEST_P(KrigingVariants, DenseEqualsBorderedSystem) {
  const int order = GetParam();
  const Data d = make_data(60, 7);
  const auto model = VariogramModel::parse("sph(sill=0.5,range=60)+nug(0.01)");
  auto opt = options_for(order);
  opt.simple_mean = {0.1};
  opt.keep_weights = true;
  const Kriging<P3, double> k(d.points, d.values, model, opt);
  ASSERT_EQ(k.report().status, KrigingStatus::Ok) << k.report().message;
  const auto targets = make_targets(25, 3);
  const auto pred = k.predict(targets);
  ASSERT_TRUE(pred.usable());
  for (std::size_t t = 0; t < targets.size(); ++t) {
    const auto ref = reference(d, targets[t], model, order, 0.1);
    EXPECT_NEAR(pred.mean[t], ref.mean, kTol) << "target " << t;
    EXPECT_NEAR(pred.variance[t], ref.variance, kTol) << "target " << t;
    for (std::size_t i = 0; i < d.points.size(); ++i)
      EXPECT_NEAR(pred.weights.weight[pred.weights.offset[t] + i], ref.weights[static_cast<Eigen::Index>(i)], 1e-7);
  }
}

TEST_P(KrigingVariants, LocalWithAllNeighboursEqualsDense) {
  const int order = GetParam();
  const Data d = make_data(80, 11);
  const auto model = VariogramModel::parse("exp(sill=0.4,range=30)+nug(0.02)");
  auto opt = options_for(order);
  const Kriging<P3, double> dense(d.points, d.values, model, opt);
  opt.backend = KrigingBackend::Local;
  opt.neighbors = d.points.size();
  const Kriging<P3, double> local(d.points, d.values, model, opt);
  const auto targets = make_targets(40, 5);
  const auto a = dense.predict(targets), b = local.predict(targets);
  ASSERT_TRUE(a.usable() && b.usable()) << a.message << b.message;
  // Same system, different elimination order: agreement to rounding of a ~1e4-conditioned solve.
  for (std::size_t t = 0; t < targets.size(); ++t) {
    EXPECT_NEAR(a.mean[t], b.mean[t], 1e-9);
    EXPECT_NEAR(a.variance[t], b.variance[t], 1e-9);
  }
}

TEST_P(KrigingVariants, LocalKNearestEqualsReferenceOnTheseNeighbours) {
  const int order = GetParam();
  const Data d = make_data(150, 13);
  const auto model = VariogramModel::parse("gau(sill=0.4,range=25)+nug(0.01)");
  auto opt = options_for(order);
  opt.backend = KrigingBackend::Local;
  opt.neighbors = 20;
  const Kriging<P3, double> local(d.points, d.values, model, opt);
  const auto targets = make_targets(10, 9);
  const auto pred = local.predict(targets);
  ASSERT_TRUE(pred.usable()) << pred.message;
  for (std::size_t t = 0; t < targets.size(); ++t) {
    std::vector<std::size_t> idx(d.points.size());
    std::iota(idx.begin(), idx.end(), 0);
    std::sort(idx.begin(), idx.end(), [&](auto a, auto b) {
      return (d.points[a] - targets[t]).norm() < (d.points[b] - targets[t]).norm();
    });  // brute force neighbour search
    Data sub;
    for (std::size_t i = 0; i < 20; ++i) {
      sub.points.push_back(d.points[idx[i]]);
      sub.values.push_back(d.values[idx[i]]);
    }
    const auto ref = reference(sub, targets[t], model, order);
    EXPECT_NEAR(pred.mean[t], ref.mean, kTol);
    EXPECT_NEAR(pred.variance[t], ref.variance, kTol);
  }
}

TEST_P(KrigingVariants, SparseEqualsDenseOnCompactModels) {
  const int order = GetParam();
  const Data d = make_data(200, 17);
  for (const char* text : {"sph(sill=0.5,range=35)", "sph(sill=0.5,range=35)+nug(0.02)", "wen(sill=0.3,range=40)+nug(0.01)"}) {
    const auto model = VariogramModel::parse(text);
    auto opt = options_for(order);
    const Kriging<P3, double> dense(d.points, d.values, model, opt);
    opt.backend = KrigingBackend::Sparse;
    const Kriging<P3, double> sparse(d.points, d.values, model, opt);
    ASSERT_TRUE(sparse.report().usable()) << sparse.report().message;
    const auto targets = make_targets(30, 21);
    const auto a = dense.predict(targets), b = sparse.predict(targets);
    for (std::size_t t = 0; t < targets.size(); ++t) {
      EXPECT_NEAR(a.mean[t], b.mean[t], 1e-9) << text;
      EXPECT_NEAR(a.variance[t], b.variance[t], 1e-9) << text;
    }
  }
}

TEST_P(KrigingVariants, ExactWithZeroVarianceAtDataWithoutNugget) {
  const int order = GetParam();
  const Data d = make_data(50, 23);
  const auto model = VariogramModel::parse("sph(sill=0.5,range=70)");
  for (auto backend : {KrigingBackend::Dense, KrigingBackend::Local, KrigingBackend::Sparse}) {
    auto opt = options_for(order);
    opt.backend = backend;
    opt.neighbors = 30;
    const Kriging<P3, double> k(d.points, d.values, model, opt);
    const auto pred = k.predict(d.points);
    ASSERT_TRUE(pred.usable()) << pred.message;
    for (std::size_t i = 0; i < d.points.size(); ++i) {
      EXPECT_NEAR(pred.mean[i], d.values[i], 1e-9) << kriging_backend_name(backend) << " sample " << i;
      EXPECT_NEAR(pred.variance[i], 0.0, 1e-9);
      EXPECT_GE(pred.variance[i], 0.0);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(SimpleOrdinaryUniversal, KrigingVariants, ::testing::Values(-1, 0, 1, 2),
                         [](const auto& info) {
                           return std::string(info.param < 0 ? "simple" : info.param == 0 ? "ordinary"
                                                                          : info.param == 1 ? "universal1"
                                                                                            : "universal2");
                         });

// Simulated: an 11 x 11 integer grid (z = 0) with a smooth field + a deterministic wiggle, so that
// many samples lie at exactly the same distance from an integer or half-integer target. The grid
// points kIntegerTargets are left out: a target on a sample would be predicted exactly whatever
// its neighbours.
const std::vector<P3> kIntegerTargets{{5, 5, 0}, {0, 3, 0}, {7, 2, 0}, {3, 7, 0}, {8, 1, 0}};
Data integer_grid() {
  Data d;
  for (int x = 0; x <= 10; ++x)
    for (int y = 0; y <= 10; ++y) {
      if (std::find(kIntegerTargets.begin(), kIntegerTargets.end(), P3(x, y, 0)) != kIntegerTargets.end()) continue;
      d.points.emplace_back(x, y, 0.0);
      d.values.push_back(std::sin(0.4 * x) + 0.3 * y + 0.05 * ((x * 7 + y * 13) % 5));
    }
  return d;
}

// The brute-force neighbourhood: samples at squared distance <= r * r (the same sum of squares
// gstat forms), the k nearest of them by (squared distance, index) when k > 0.
Data brute_force_neighbours(const Data& d, const P3& target, double r, std::size_t k) {
  std::vector<std::pair<double, std::size_t>> ranked;
  for (std::size_t i = 0; i < d.points.size(); ++i) {
    const double dx = d.points[i].x() - target.x(), dy = d.points[i].y() - target.y(), dz = d.points[i].z() - target.z();
    const double d2 = dx * dx + dy * dy + dz * dz;
    if (d2 <= r * r) ranked.emplace_back(d2, i);
  }
  std::sort(ranked.begin(), ranked.end());
  if (k > 0 && ranked.size() > k) ranked.resize(k);
  Data sub;
  for (const auto& [d2, i] : ranked) {
    sub.points.push_back(d.points[i]);
    sub.values.push_back(d.values[i]);
  }
  return sub;
}

TEST(Kriging, LocalRadiusIncludesSamplesAtExactlyTheRadius) {
  const Data d = integer_grid();
  const auto model = VariogramModel::parse("sph(sill=1,range=6)+nug(0.05)");
  // Integer targets: ties at 2 (up to 4 samples) and 5 (up to 12: 5-0 and 3-4); (x + 0.5, y)
  // targets: ties at 1.5 (2) and 2.5 (6: 2.5-0 and 1.5-2). Inside, at the border, at a corner.
  std::vector<P3> targets = kIntegerTargets;
  for (const P3& t : {P3(4.5, 6, 0), P3(0.5, 0, 0), P3(9.5, 10, 0), P3(2.5, 3, 0)}) targets.push_back(t);
  for (double r : {1.5, 2.0, 2.5, 5.0}) {
    KrigingOptions opt;
    opt.backend = KrigingBackend::Local;
    opt.radius = r;
    const auto pred = Kriging<P3, double>(d.points, d.values, model, opt).predict(targets);
    ASSERT_TRUE(pred.usable()) << pred.message;
    for (std::size_t t = 0; t < targets.size(); ++t) {
      const Data sub = brute_force_neighbours(d, targets[t], r, 0);
      const auto ref = reference(sub, targets[t], model, 0);
      // Both solve the same well-conditioned (< 100 unknowns) system: rounding only.
      EXPECT_NEAR(pred.mean[t], ref.mean, 1e-10) << "radius " << r << ", target " << t << ", " << sub.points.size()
                                                 << " samples within";
      EXPECT_NEAR(pred.variance[t], ref.variance, 1e-10) << "radius " << r << ", target " << t;
    }
  }
}

TEST(Kriging, LocalNearestTiesAreBrokenBySampleOrder) {
  // With k = 6 at an integer target (off the samples) the cut falls among the 4 samples at sqrt(2)
  // (at the border: among those at 2): which of them the kd-tree returns first is its internal
  // order; the selection must not depend on it.
  const Data d = integer_grid();
  const auto model = VariogramModel::parse("exp(sill=1,range=4)+nug(0.02)");
  const std::vector<P3>& targets = kIntegerTargets;
  for (double r : {std::numeric_limits<double>::infinity(), 1.5}) {
    KrigingOptions opt;
    opt.backend = KrigingBackend::Local;
    opt.neighbors = 6;
    opt.radius = r;
    const auto pred = Kriging<P3, double>(d.points, d.values, model, opt).predict(targets);
    ASSERT_TRUE(pred.usable()) << pred.message;
    for (std::size_t t = 0; t < targets.size(); ++t) {
      const Data sub = brute_force_neighbours(d, targets[t], r, 6);
      const auto ref = reference(sub, targets[t], model, 0);
      EXPECT_NEAR(pred.mean[t], ref.mean, 1e-10) << "radius " << r << ", target " << t;
      EXPECT_NEAR(pred.variance[t], ref.variance, 1e-10) << "radius " << r << ", target " << t;
    }
  }
}

// gstat's quadrant of sample p around target q (its which_octant, 2-D): a sample on a dividing axis
// goes to the quadrant that the axis starts when turning counter-clockwise around the target.
int quadrant_around(const P3& p, const P3& q) {
  const double dx = p.x() - q.x(), dy = p.y() - q.y();
  const int x = dy < 0 ? dx > 0 : dx >= 0;
  const int y = dx < 0 ? dy >= 0 : dy > 0;
  return x + 2 * y;
}

TEST(Kriging, LocalMinimumAndOctantSearchAreGstatsNminAndOmax) {
  const Data d = integer_grid();
  const auto model = VariogramModel::parse("sph(sill=1,range=6)+nug(0.05)");
  std::vector<P3> targets = kIntegerTargets;
  for (const P3& t : {P3(4.5, 6, 0), P3(0.5, 0, 0), P3(9.5, 10, 0), P3(2.5, 3, 0)}) targets.push_back(t);
  for (const std::size_t k : {std::size_t{0}, std::size_t{12}})
    for (const std::size_t min_count : {std::size_t{0}, std::size_t{14}})
      for (const std::size_t omax : {std::size_t{0}, std::size_t{1}, std::size_t{2}, std::size_t{3}}) {
        const double r = 2.5;
        KrigingOptions opt;
        opt.backend = KrigingBackend::Local;
        opt.radius = r;
        opt.neighbors = k;
        opt.min_neighbours = min_count;
        opt.octant_max = omax;
        const auto pred = Kriging<P3, double>(d.points, d.values, model, opt).predict(targets);
        std::size_t refused = 0;
        for (std::size_t t = 0; t < targets.size(); ++t) {
          // Brute force: the k nearest within r by (squared distance, index); none if fewer than
          // min_count; then per quadrant the omax nearest.
          std::vector<std::pair<double, std::size_t>> ranked;
          for (std::size_t i = 0; i < d.points.size(); ++i) {
            const double dx = d.points[i].x() - targets[t].x(), dy = d.points[i].y() - targets[t].y();
            if (dx * dx + dy * dy <= r * r) ranked.emplace_back(dx * dx + dy * dy, i);
          }
          std::sort(ranked.begin(), ranked.end());
          if (k > 0 && ranked.size() > k) ranked.resize(k);
          const std::string where = "k " + std::to_string(k) + ", min " + std::to_string(min_count) + ", omax " +
                                    std::to_string(omax) + ", target " + std::to_string(t);
          if (ranked.size() < min_count) {
            ++refused;
            EXPECT_TRUE(std::isnan(pred.mean[t]) && std::isnan(pred.variance[t])) << where;
            continue;
          }
          Data sub;
          std::size_t per_quadrant[4] = {};
          for (const auto& [d2, i] : ranked)
            if (omax == 0 || per_quadrant[quadrant_around(d.points[i], targets[t])]++ < omax) {
              sub.points.push_back(d.points[i]);
              sub.values.push_back(d.values[i]);
            }
          const auto ref = reference(sub, targets[t], model, 0);
          EXPECT_NEAR(pred.mean[t], ref.mean, 1e-10) << where << ", " << sub.points.size() << " neighbours";
          EXPECT_NEAR(pred.variance[t], ref.variance, 1e-10) << where;
        }
        EXPECT_EQ(pred.failed_targets, refused);
        if (refused > 0) {
          EXPECT_EQ(pred.status, KrigingStatus::TooFewSamples);
          EXPECT_NE(pred.message.find("min_neighbours = 14"), std::string::npos) << pred.message;
        }
      }
  // Octant search needs at most 3 coordinates, and both need the local back end.
  KrigingOptions dense;
  dense.octant_max = 2;
  EXPECT_THROW(dense.validate(), ArgumentError);
  dense.octant_max = 0;
  dense.min_neighbours = 3;
  EXPECT_THROW(dense.validate(), ArgumentError);
}

TEST(Kriging, OrdinaryWeightsSumToOne) {
  const Data d = make_data(70, 31);
  const auto model = VariogramModel::parse("exp(sill=1,range=20)+nug(0.1)");
  for (auto backend : {KrigingBackend::Dense, KrigingBackend::Local}) {
    KrigingOptions opt;
    opt.backend = backend;
    opt.neighbors = 16;
    opt.keep_weights = true;
    const Kriging<P3, double> k(d.points, d.values, model, opt);
    const auto pred = k.predict(make_targets(30, 1));
    for (std::size_t t = 0; t + 1 < pred.weights.offset.size(); ++t) {
      double s = 0.0;
      for (auto i = pred.weights.offset[t]; i < pred.weights.offset[t + 1]; ++i) s += pred.weights.weight[i];
      EXPECT_NEAR(s, 1.0, 1e-12);
    }
  }
}

TEST(Kriging, WeightsOnRequestAreThoseKeepWeightsGives) {
  const Data d = make_data(70, 33);
  const auto model = VariogramModel::parse("exp(sill=1,range=20)+nug(0.1)");
  const auto targets = make_targets(12, 5);
  for (auto backend : {KrigingBackend::Dense, KrigingBackend::Local}) {
    KrigingOptions opt;
    opt.backend = backend;
    opt.neighbors = 16;
    const Kriging<P3, double> asked(d.points, d.values, model, opt);
    opt.keep_weights = true;
    const Kriging<P3, double> kept(d.points, d.values, model, opt);
    EXPECT_TRUE(asked.predict(targets).weights.weight.empty());  // not paid for unless asked
    const auto a = asked.predict_with_weights(targets), k = kept.predict(targets);
    EXPECT_EQ(a.weights.offset, k.weights.offset);
    EXPECT_EQ(a.weights.sample, k.weights.sample);
    EXPECT_EQ(a.weights.weight, k.weights.weight);
    EXPECT_EQ(a.mean, k.mean);
    EXPECT_EQ(a.variance, k.variance);
    // and they are the prediction's: the weighted sum of the values is the mean
    for (std::size_t t = 0; t < targets.size(); ++t) {
      double sum = 0.0;
      for (auto i = a.weights.offset[t]; i < a.weights.offset[t + 1]; ++i) sum += a.weights.weight[i] * d.values[a.weights.sample[i]];
      EXPECT_NEAR(sum, a.mean[t], 1e-10);
    }
  }
  KrigingOptions sparse;
  sparse.backend = KrigingBackend::Sparse;
  const auto compact = VariogramModel::parse("sph(sill=1,range=20)+nug(0.1)");
  const Kriging<P3, double> k(d.points, d.values, compact, sparse);
  EXPECT_THROW(k.predict_with_weights(targets), ArgumentError);
}

TEST(Kriging, SimpleKrigingIsTheGaussianProcessPosterior) {
  // GP posterior with explicit inverse: m + k*' K^-1 (z - m), C(0) - k*' K^-1 k*.
  const Data d = make_data(40, 37);
  const auto model = VariogramModel::parse("gau(sill=0.8,range=30)+nug(0.05)");
  const auto n = static_cast<Eigen::Index>(d.points.size());
  Eigen::MatrixXd kmat(n, n);
  Eigen::VectorXd z(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    z[i] = d.values[i] - 0.3;
    for (Eigen::Index j = 0; j < n; ++j) kmat(i, j) = model.covariance((d.points[i] - d.points[j]).norm());
  }
  const Eigen::MatrixXd kinv = kmat.inverse();
  KrigingOptions opt;
  opt.kind = KrigingKind::Simple;
  opt.simple_mean = {0.3};
  const Kriging<P3, double> k(d.points, d.values, model, opt);
  const auto targets = make_targets(20, 2);
  const auto pred = k.predict(targets);
  for (std::size_t t = 0; t < targets.size(); ++t) {
    Eigen::VectorXd ks(n);
    for (Eigen::Index i = 0; i < n; ++i) ks[i] = model.covariance((d.points[i] - targets[t]).norm());
    EXPECT_NEAR(pred.mean[t], 0.3 + ks.dot(kinv * z), 1e-9);
    EXPECT_NEAR(pred.variance[t], model.sill() - ks.dot(kinv * ks), 1e-9);
  }
}

TEST(Kriging, FarTargetVarianceReachesTheSill) {
  const Data d = make_data(30, 41);
  const auto model = VariogramModel::parse("sph(sill=0.5,range=50)+nug(0.1)");
  const std::vector<P3> far{P3(1e4, 1e4, 1e4)};
  KrigingOptions simple;
  simple.kind = KrigingKind::Simple;
  EXPECT_DOUBLE_EQ((Kriging<P3, double>(d.points, d.values, model, simple).predict(far).variance[0]), 0.6);
  // Ordinary: the sill plus the variance of the estimated mean, 1 / (1'K^-1 1).
  const auto n = static_cast<Eigen::Index>(d.points.size());
  Eigen::MatrixXd kmat(n, n);
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < n; ++j) kmat(i, j) = model.covariance((d.points[i] - d.points[j]).norm());
  const Eigen::VectorXd ones = Eigen::VectorXd::Ones(n);
  const double extra = 1.0 / ones.dot(kmat.ldlt().solve(ones));
  EXPECT_NEAR((Kriging<P3, double>(d.points, d.values, model).predict(far).variance[0]), 0.6 + extra, 1e-12);
  KrigingOptions me;
  me.kind = KrigingKind::Simple;
  me.nugget = NuggetTreatment::MeasurementError;
  EXPECT_NEAR((Kriging<P3, double>(d.points, d.values, model, me).predict(far).variance[0]), 0.5, 1e-15);
}

TEST(Kriging, NuggetAsMeasurementErrorSmoothsAndMatchesReference) {
  const Data d = make_data(40, 43);
  const auto model = VariogramModel::parse("exp(sill=0.5,range=30)+nug(0.05)");
  KrigingOptions opt;
  opt.nugget = NuggetTreatment::MeasurementError;
  const Kriging<P3, double> k(d.points, d.values, model, opt);
  const auto at_data = k.predict(d.points);
  double max_diff = 0.0;
  for (std::size_t i = 0; i < d.points.size(); ++i) {
    const auto ref = reference(d, d.points[i], model, 0, 0.0, true);
    EXPECT_NEAR(at_data.mean[i], ref.mean, 1e-9);
    EXPECT_NEAR(at_data.variance[i], ref.variance, 1e-9);
    EXPECT_GT(at_data.variance[i], 0.0);
    max_diff = std::max(max_diff, std::abs(at_data.mean[i] - d.values[i]));
  }
  EXPECT_GT(max_diff, 1e-3);  // smoothing: not an exact interpolator
  // micro-scale (default) stays exact at the data despite the nugget
  const auto exact = Kriging<P3, double>(d.points, d.values, model).predict(d.points);
  for (std::size_t i = 0; i < d.points.size(); ++i) EXPECT_NEAR(exact.mean[i], d.values[i], 1e-9);
}

TEST(Kriging, PerPointMeasurementVarianceMatchesReference) {
  const Data d = make_data(40, 47);
  std::vector<double> meas;
  for (std::size_t i = 0; i < d.points.size(); ++i) meas.push_back(1e-3 * (1.0 + d.points[i].norm() / 50.0));
  const auto model = VariogramModel::parse("sph(sill=0.5,range=60)");
  const Kriging<P3, double> k(d.points, d.values, model, {}, {}, meas);
  const auto targets = make_targets(10, 4);
  const auto pred = k.predict(targets);
  for (std::size_t t = 0; t < targets.size(); ++t) {
    const auto ref = reference(d, targets[t], model, 0, 0.0, false, meas);
    EXPECT_NEAR(pred.mean[t], ref.mean, 1e-9);
    EXPECT_NEAR(pred.variance[t], ref.variance, 1e-9);
  }
}

TEST(Kriging, VectorValuesEqualComponentwiseScalarKriging) {
  const Data d = make_data(60, 53);
  std::vector<Eigen::Vector3d> vals;
  std::vector<std::vector<double>> comp(3);
  for (std::size_t i = 0; i < d.points.size(); ++i) {
    const Eigen::Vector3d v(d.values[i], 2.0 * d.values[i] + d.points[i].y() * 0.01, std::cos(d.points[i].z() / 10));
    vals.push_back(v);
    for (int c = 0; c < 3; ++c) comp[c].push_back(v[c]);
  }
  const auto model = VariogramModel::parse("sph(sill=0.5,range=50)+nug(0.01)");
  for (auto backend : {KrigingBackend::Dense, KrigingBackend::Local, KrigingBackend::Sparse}) {
    KrigingOptions opt;
    opt.kind = KrigingKind::Universal;
    opt.backend = backend;
    opt.neighbors = 25;
    const Kriging<P3, Eigen::Vector3d> kv(d.points, vals, model, opt);
    const auto targets = make_targets(15, 8);
    const auto pv = kv.predict(targets);
    for (int c = 0; c < 3; ++c) {
      const auto ps = Kriging<P3, double>(d.points, comp[c], model, opt).predict(targets);
      for (std::size_t t = 0; t < targets.size(); ++t) {
        EXPECT_NEAR(pv.mean[t][c], ps.mean[t], 1e-12);
        EXPECT_NEAR(pv.variance[t], ps.variance[t], 1e-12);
      }
    }
  }
}

TEST(Kriging, WeightedMetricEqualsScaledCoordinates) {
  const Data d = make_data(40, 59);
  const auto model = VariogramModel::parse("exp(sill=1,range=40)");
  const WeightedEuclideanMetric metric({4.0, 1.0, 0.25});
  const Kriging<P3, double, WeightedEuclideanMetric> kw(d.points, d.values, model, {}, metric);
  std::vector<P3> scaled;
  for (const auto& p : d.points) scaled.emplace_back(2.0 * p.x(), p.y(), 0.5 * p.z());
  const Kriging<P3, double> ks(scaled, d.values, model);
  const auto targets = make_targets(10, 6);
  std::vector<P3> scaled_targets;
  for (const auto& p : targets) scaled_targets.emplace_back(2.0 * p.x(), p.y(), 0.5 * p.z());
  const auto a = kw.predict(targets), b = ks.predict(scaled_targets);
  for (std::size_t t = 0; t < targets.size(); ++t) {
    EXPECT_NEAR(a.mean[t], b.mean[t], 1e-12);
    EXPECT_NEAR(a.variance[t], b.variance[t], 1e-12);
  }
}

TEST(Kriging, UserDriftFunctionEqualsPolynomialDrift) {
  // A user drift x*y added to order-1 drift must equal the bordered reference with that term.
  const Data d = make_data(50, 61);
  const auto model = VariogramModel::parse("sph(sill=0.5,range=60)+nug(0.01)");
  KrigingOptions opt;
  opt.kind = KrigingKind::Universal;
  opt.drift_order = 2;
  const auto full = Kriging<P3, double>(d.points, d.values, model, opt).predict(make_targets(10, 3));
  // Quadratic drift rebuilt as order 1 + the six quadratic monomials as user functions.
  opt.drift_order = 1;
  for (int k = 0; k < 3; ++k)
    for (int l = k; l < 3; ++l)
      opt.drift_functions.push_back([k, l](std::span<const double> x) { return x[k] * x[l] / 1e4; });
  const auto user = Kriging<P3, double>(d.points, d.values, model, opt).predict(make_targets(10, 3));
  for (std::size_t t = 0; t < 10; ++t) {
    EXPECT_NEAR(full.mean[t], user.mean[t], 1e-8);
    EXPECT_NEAR(full.variance[t], user.variance[t], 1e-8);
  }
}

TEST(Kriging, LeaveOneOutClosedFormEqualsBruteForce) {
  const Data d = make_data(35, 67);
  const auto model = VariogramModel::parse("sph(sill=0.5,range=60)+nug(0.02)");
  for (int order : {-1, 0, 1}) {
    auto opt = options_for(order);
    const auto cv = Kriging<P3, double>(d.points, d.values, model, opt).leave_one_out();
    auto lopt = opt;
    lopt.backend = KrigingBackend::Local;
    lopt.neighbors = d.points.size();
    const auto cv_local = Kriging<P3, double>(d.points, d.values, model, lopt).leave_one_out();
    ASSERT_EQ(cv.status, KrigingStatus::Ok);
    for (std::size_t i = 0; i < d.points.size(); ++i) {
      Data rest = d;
      rest.points.erase(rest.points.begin() + static_cast<long>(i));
      rest.values.erase(rest.values.begin() + static_cast<long>(i));
      const auto ref = reference(rest, d.points[i], model, order);
      EXPECT_NEAR(cv.prediction[i], ref.mean, 1e-8) << "order " << order << " sample " << i;
      EXPECT_NEAR(cv.residual[i], d.values[i] - ref.mean, 1e-8);
      EXPECT_NEAR(cv.variance[i], ref.variance, 1e-8);
      EXPECT_NEAR(cv_local.prediction[i], ref.mean, 1e-8);
      EXPECT_NEAR(cv_local.variance[i], ref.variance, 1e-8);
    }
    EXPECT_GT(cv.rms_error, 0.0);
  }
}

TEST(Kriging, LeaveOneOutResidualsOfOtherValuesEqualBruteForce) {
  // The leave-one-out weights applied to other values at the same samples: each column against a
  // kriging of that column without the sample (ordinary, universal, and simple kriging, whose mean
  // the operator leaves out: it acts on deviations). Wrong row counts are refused.
  const Data d = make_data(40, 83);
  const auto model = VariogramModel::parse("sph(sill=0.5,range=60)+nug(0.02)");
  std::mt19937 rng(5);
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::MatrixXd other(static_cast<Eigen::Index>(d.points.size()), 2);
  for (Eigen::Index i = 0; i < other.rows(); ++i)
    other.row(i) << normal(rng), d.points[static_cast<std::size_t>(i)].x() / 50.0 + 0.1 * normal(rng);
  for (int order : {-1, 0, 1}) {
    auto opt = options_for(order);
    if (order < 0) opt.simple_mean = {0.3};  // not in the operator: the reference below has mean 0
    const Eigen::MatrixXd left = Kriging<P3, double>(d.points, d.values, model, opt).leave_one_out_residuals_of(other);
    ASSERT_EQ(left.rows(), other.rows());
    ASSERT_EQ(left.cols(), 2);
    for (Eigen::Index c = 0; c < 2; ++c) {
      Data column = d;
      for (std::size_t i = 0; i < d.points.size(); ++i) column.values[i] = other(static_cast<Eigen::Index>(i), c);
      for (std::size_t i = 0; i < d.points.size(); ++i) {
        Data rest = column;
        rest.points.erase(rest.points.begin() + static_cast<long>(i));
        rest.values.erase(rest.values.begin() + static_cast<long>(i));
        const auto ref = reference(rest, d.points[i], model, order, 0.0);
        EXPECT_NEAR(left(static_cast<Eigen::Index>(i), c), column.values[i] - ref.mean, 1e-8)
            << "order " << order << " column " << c << " sample " << i;
      }
    }
  }
  const Kriging<P3, double> k(d.points, d.values, model);
  EXPECT_THROW((void)k.leave_one_out_residuals_of(other.topRows(10)), ArgumentError);
}

TEST(Kriging, LeaveOneOutClosedFormSpanningSeveralColumnBlocksEqualsBruteForce) {
  // diag(K^-1) is computed in blocks of 64 columns over shrinking trailing triangles: 150 samples
  // give two full blocks and a partial one. Bit-identical for 1 and 2 threads.
  const Data d = make_data(150, 73);
  const auto model = VariogramModel::parse("exp(sill=0.5,range=40)+nug(0.02)");
  auto opt = options_for(0);
  opt.threads = 1;
  const auto cv = Kriging<P3, double>(d.points, d.values, model, opt).leave_one_out();
  opt.threads = 2;
  const auto cv2 = Kriging<P3, double>(d.points, d.values, model, opt).leave_one_out();
  ASSERT_EQ(cv.status, KrigingStatus::Ok);
  for (std::size_t i = 0; i < d.points.size(); ++i) {
    EXPECT_EQ(cv.variance[i], cv2.variance[i]) << "sample " << i;
    EXPECT_EQ(cv.prediction[i], cv2.prediction[i]) << "sample " << i;
  }
  for (std::size_t i = 0; i < d.points.size(); i += 7) {  // samples in every block
    Data rest = d;
    rest.points.erase(rest.points.begin() + static_cast<long>(i));
    rest.values.erase(rest.values.begin() + static_cast<long>(i));
    const auto ref = reference(rest, d.points[i], model, 0);
    EXPECT_NEAR(cv.prediction[i], ref.mean, 1e-8) << "sample " << i;
    EXPECT_NEAR(cv.variance[i], ref.variance, 1e-8) << "sample " << i;
  }
}

TEST(Kriging, KFoldPredictsEverySampleFromTheOtherFolds) {
  const Data d = make_data(40, 71);
  const auto model = VariogramModel::parse("sph(sill=0.5,range=60)+nug(0.02)");
  const auto cv = Kriging<P3, double>(d.points, d.values, model).k_fold(5, 3);
  ASSERT_EQ(cv.status, KrigingStatus::Ok) << cv.message;
  ASSERT_EQ(cv.prediction.size(), d.points.size());
  for (std::size_t i = 0; i < d.points.size(); ++i) {
    EXPECT_TRUE(std::isfinite(cv.prediction[i]));
    EXPECT_DOUBLE_EQ(cv.residual[i], d.values[i] - cv.prediction[i]);
    EXPECT_GT(cv.variance[i], 0.0);  // never predicted from itself
  }
  // k-fold with one sample per fold is leave-one-out.
  const auto loo = Kriging<P3, double>(d.points, d.values, model).leave_one_out();
  const auto kn = Kriging<P3, double>(d.points, d.values, model).k_fold(40, 1);
  for (std::size_t i = 0; i < d.points.size(); ++i) {
    EXPECT_NEAR(loo.prediction[i], kn.prediction[i], 1e-9);
    EXPECT_NEAR(loo.variance[i], kn.variance[i], 1e-9);
  }
}

TEST(Kriging, DuplicatesAreNamedOrMerged) {
  Data d = make_data(20, 73);
  d.points.push_back(d.points[4]);
  d.values.push_back(d.values[4] + 0.2);
  const auto model = VariogramModel::parse("sph(sill=0.5,range=60)");
  try {
    Kriging<P3, double> k(d.points, d.values, model);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("samples 4 and 20"), std::string::npos) << e.what();
  }
  KrigingOptions opt;
  opt.duplicates = DuplicatePolicy::Average;
  const Kriging<P3, double> k(d.points, d.values, model, opt);
  EXPECT_EQ(k.report().merged_duplicates, 1u);
  EXPECT_EQ(k.report().samples_used, 20u);
  EXPECT_NEAR(k.predict(std::vector<P3>{d.points[4]}).mean[0], d.values[4] + 0.1, 1e-9);  // mean of v and v + 0.2
  // near-duplicates within a tolerance
  Data n2 = make_data(20, 73);
  n2.points.push_back(n2.points[7] + P3(1e-4, 0, 0));
  n2.values.push_back(0.0);
  KrigingOptions tol;
  tol.duplicate_distance = 1e-3;
  EXPECT_THROW((Kriging<P3, double>(n2.points, n2.values, model, tol)), InputError);
}

// Independent ground truth for merged duplicates: ordinary kriging written as generalized least
// squares (not the bordered system), each observation a separate sample. K_ij = Cs(h_ij) +
// delta_ij noise_i with Cs the covariance of the predicted signal, Cs(0) = c00;
// m = (1'K^-1 z) / (1'K^-1 1), mean = m + c0'K^-1 (z - 1 m),
// var = c00 - c0'K^-1 c0 + (1 - 1'K^-1 c0)^2 / (1'K^-1 1).
struct GlsPrediction {
  Eigen::RowVectorXd mean;
  double variance;
};
GlsPrediction ordinary_kriging_gls(const std::vector<P3>& points, const Eigen::MatrixXd& z,
                                   const std::vector<double>& noise, const P3& target, const VariogramModel& model,
                                   double c00) {
  const auto n = static_cast<Eigen::Index>(points.size());
  auto cs = [&](double h) { return h == 0.0 ? c00 : model.covariance(h); };
  Eigen::MatrixXd k(n, n);
  Eigen::VectorXd c0(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index j = 0; j < n; ++j) k(i, j) = cs((points[i] - points[j]).norm()) + (i == j ? noise[i] : 0.0);
    c0[i] = cs((points[i] - target).norm());
  }
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(k);
  const Eigen::VectorXd one = Eigen::VectorXd::Ones(n);
  const Eigen::VectorXd kinv_one = ldlt.solve(one), kinv_c = ldlt.solve(c0);
  const double s = one.dot(kinv_one);
  const Eigen::RowVectorXd m = kinv_one.transpose() * z / s;
  GlsPrediction r;
  r.mean = m + kinv_c.transpose() * (z - one * m);
  r.variance = c00 - c0.dot(kinv_c) + std::pow(1.0 - one.dot(kinv_c), 2) / s;
  return r;
}

// Repeats at one location merged by DuplicatePolicy::Average must predict exactly as ordinary
// kriging with every repeat kept (the GLS above): measurement error nugget -> nugget/k on the
// merged sample, micro-scale nugget -> kept whole (only measurement variances are divided).
// Scalar and 3-vector values, every back end; leave-one-out and k-fold of a merged sample.
template <class V>
void expect_merged_equals_repeats(NuggetTreatment treatment, V (*make_value)(const P3&, double)) {
  const Data base = make_data(25, 91);
  const auto model = VariogramModel::parse("sph(sill=0.5,range=60)+nug(0.05)");  // compact: sparse too
  const bool micro = treatment == NuggetTreatment::MicroScale;
  std::vector<P3> points = base.points;
  std::vector<double> raw = base.values, meas;
  for (std::size_t i = 0; i < base.points.size(); ++i) meas.push_back(0.002 * static_cast<double>(1 + i % 3));
  // simulated repeats: location 3 three times in all, location 10 twice, other values
  const std::vector<std::pair<std::size_t, double>> repeats = {{3, 0.07}, {3, -0.11}, {10, 0.05}};
  for (const auto& [at, offset] : repeats) {
    points.push_back(base.points[at]);
    raw.push_back(base.values[at] + offset);
    meas.push_back(meas[at]);  // equal within a group: the plain mean is then the optimal one
  }
  std::vector<V> values;
  for (std::size_t i = 0; i < points.size(); ++i) values.push_back(make_value(points[i], raw[i]));
  constexpr int kC = ValueTraits<V>::kComponents;
  auto rows = [&](const std::vector<std::size_t>& idx) {
    Eigen::MatrixXd z(static_cast<Eigen::Index>(idx.size()), kC);
    for (std::size_t r = 0; r < idx.size(); ++r)
      for (int c = 0; c < kC; ++c) z(static_cast<Eigen::Index>(r), c) = ValueTraits<V>::component(values[idx[r]], c);
    return z;
  };
  const double nug = model.nugget();
  const double c00 = micro ? model.sill() : model.sill() - nug;
  auto noise_of = [&](std::size_t i) { return meas[i] + (micro ? 0.0 : nug); };  // one observation
  // ground truth on all observations except those at `skip` (a location index, or none)
  auto truth = [&](const P3& target, std::size_t skip) {
    std::vector<std::size_t> idx;
    std::vector<P3> pts;
    std::vector<double> noise;
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (skip < points.size() && points[i] == base.points[skip]) continue;
      idx.push_back(i);
      pts.push_back(points[i]);
      noise.push_back(noise_of(i));
    }
    return ordinary_kriging_gls(pts, rows(idx), noise, target, model, c00);
  };
  std::vector<P3> targets = make_targets(6, 12);
  targets.push_back(base.points[3]);
  targets.push_back(base.points[10]);
  for (auto backend : {KrigingBackend::Dense, KrigingBackend::Local, KrigingBackend::Sparse}) {
    SCOPED_TRACE(std::string(kriging_backend_name(backend)) + (micro ? " micro-scale" : " measurement error"));
    KrigingOptions opt;
    opt.nugget = treatment;
    opt.backend = backend;
    opt.neighbors = points.size();
    opt.duplicates = DuplicatePolicy::Average;
    opt.threads = 1;  // 27 samples: threads would cost more than they save
    const Kriging<P3, V> k(points, values, model, opt, {}, meas);
    ASSERT_EQ(k.report().merged_duplicates, 3u);
    const auto pred = k.predict(targets);
    ASSERT_EQ(pred.status, KrigingStatus::Ok) << pred.message;
    for (std::size_t t = 0; t < targets.size(); ++t) {
      const GlsPrediction ref = truth(targets[t], points.size());
      for (int c = 0; c < kC; ++c) EXPECT_NEAR(ValueTraits<V>::component(pred.mean[t], c), ref.mean[c], 1e-10) << t;
      EXPECT_NEAR(pred.variance[t], ref.variance, 1e-10) << t;
    }
    // Cross-validation of merged sample 3 (3 repeats): predicted from every other location, its
    // residual variance carries the merged sample's own noise, noise/3.
    const GlsPrediction ref = truth(base.points[3], 3);
    const double merged_noise = (meas[3] + (micro ? 0.0 : nug)) / 3.0;
    std::vector<KrigingCrossValidation<V>> cvs = {k.k_fold(static_cast<int>(base.points.size()), 5)};
    if (backend != KrigingBackend::Sparse) cvs.push_back(k.leave_one_out());
    for (const auto& cv : cvs) {
      ASSERT_EQ(cv.prediction.size(), base.points.size());
      for (int c = 0; c < kC; ++c) {
        const double observed = (rows({3, 25, 26}).col(c).mean());
        EXPECT_NEAR(ValueTraits<V>::component(cv.prediction[3], c), ref.mean[c], 1e-10);
        EXPECT_NEAR(ValueTraits<V>::component(cv.residual[3], c), observed - ref.mean[c], 1e-10);
      }
      EXPECT_NEAR(cv.variance[3], ref.variance + merged_noise, 1e-10);
    }
  }
}

TEST(Kriging, AveragedDuplicatesEqualKeepingEveryRepeat) {
  auto scalar = [](const P3&, double v) { return v; };
  auto vector = [](const P3& p, double v) { return Eigen::Vector3d(v, 2.0 * v + 0.01 * p.y(), std::cos(p.z() / 10.0) + v); };
  for (auto treatment : {NuggetTreatment::MeasurementError, NuggetTreatment::MicroScale}) {
    expect_merged_equals_repeats<double>(treatment, +scalar);
    expect_merged_equals_repeats<Eigen::Vector3d>(treatment, +vector);
  }
}

TEST(Kriging, NumericalOutcomesAreStatusesNotNaN) {
  const auto model = VariogramModel::parse("sph(sill=0.5,range=60)");
  // Fewer samples than drift terms: 3 samples, quadratic drift in 3-D has 10 terms.
  Data few = make_data(3, 79);
  KrigingOptions uk2;
  uk2.kind = KrigingKind::Universal;
  uk2.drift_order = 2;
  const Kriging<P3, double> k1(few.points, few.values, model, uk2);
  EXPECT_EQ(k1.report().status, KrigingStatus::TooFewSamples);
  const auto p1 = k1.predict(make_targets(2, 1));
  EXPECT_EQ(p1.status, KrigingStatus::TooFewSamples);
  EXPECT_TRUE(p1.mean.empty());
  // Samples on the plane z = 50 with a linear drift in z: the drift is singular.
  Data flat = make_data(30, 83);
  for (auto& p : flat.points) p.z() = 50.0;
  KrigingOptions uk1;
  uk1.kind = KrigingKind::Universal;
  const Kriging<P3, double> k2(flat.points, flat.values, model, uk1);
  EXPECT_EQ(k2.report().status, KrigingStatus::SingularDrift) << k2.report().message;
  // A Gaussian model with a range far beyond the spacing: hopelessly ill-conditioned.
  Data dense_pts;
  for (int i = 0; i < 40; ++i) {
    dense_pts.points.emplace_back(i * 0.5, 0.0, 0.0);
    dense_pts.values.push_back(std::sin(i * 0.1));
  }
  KrigingOptions strict;
  strict.max_jitter_retries = 0;
  const Kriging<P3, double> k3(dense_pts.points, dense_pts.values, VariogramModel::parse("gau(sill=1,range=1000)"), strict);
  EXPECT_TRUE(k3.report().status == KrigingStatus::IllConditioned ||
              k3.report().status == KrigingStatus::NotPositiveDefinite);
  EXPECT_FALSE(k3.report().message.empty());
  if (k3.report().status == KrigingStatus::IllConditioned) {
    EXPECT_GT(k3.report().condition_number, 1e12);
    for (double m : k3.predict(make_targets(5, 2)).mean) EXPECT_TRUE(std::isfinite(m));
  }
  // Local: a radius with no samples inside is reported per target.
  KrigingOptions loc;
  loc.backend = KrigingBackend::Local;
  loc.radius = 1.0;
  const Data d = make_data(30, 89);
  const auto p4 = Kriging<P3, double>(d.points, d.values, model, loc).predict(std::vector<P3>{P3(1e3, 0, 0), d.points[0]});
  EXPECT_EQ(p4.status, KrigingStatus::TooFewSamples);
  EXPECT_EQ(p4.failed_targets, 1u);
  EXPECT_NE(p4.message.find("first: target 0"), std::string::npos) << p4.message;
  EXPECT_TRUE(std::isnan(p4.mean[0]));
  EXPECT_NEAR(p4.mean[1], d.values[0], 1e-12);
}

TEST(Kriging, DenseMemoryBudgetNamesTheOtherBackEnds) {
  const Data d = make_data(300, 97);
  KrigingOptions opt;
  opt.dense_memory_budget_bytes = 1 << 20;
  try {
    Kriging<P3, double> k(d.points, d.values, VariogramModel::parse("exp(1,10)"), opt);
    FAIL() << "expected ResourceError";
  } catch (const ResourceError& e) {
    EXPECT_NE(std::string(e.what()).find("local"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("sparse"), std::string::npos);
  }
}

TEST(Kriging, OptionsAndInputAreValidated) {
  const Data d = make_data(10, 101);
  const auto model = VariogramModel::parse("exp(1,10)");
  KrigingOptions bad;
  bad.backend = KrigingBackend::Local;  // neither k nor radius
  EXPECT_THROW(bad.validate(), ArgumentError);
  bad = {};
  bad.kind = KrigingKind::Universal;
  bad.drift_order = 3;
  EXPECT_THROW(bad.validate(), ArgumentError);
  bad = {};
  bad.backend = KrigingBackend::Sparse;
  EXPECT_THROW((Kriging<P3, double>(d.points, d.values, model, bad)), ArgumentError);  // exp is not compact
  EXPECT_THROW((Kriging<P3, double>(d.points, d.values, VariogramModel::parse("lin(1)"))), ArgumentError);
  auto vals = d.values;
  vals[3] = std::nan("");
  EXPECT_THROW((Kriging<P3, double>(d.points, vals, model)), InputError);
  KrigingOptions k2;
  k2.backend = KrigingBackend::Local;
  k2.kind = KrigingKind::Universal;
  k2.neighbors = 3;  // < 4 drift terms
  EXPECT_THROW((Kriging<P3, double>(d.points, d.values, model, k2)), ArgumentError);
}

TEST(Kriging, ThreadCountDoesNotChangeResults) {
  const Data d = make_data(300, 103);
  const auto model = VariogramModel::parse("sph(sill=0.5,range=40)+nug(0.01)");
  const auto targets = make_targets(700, 7);
  for (auto backend : {KrigingBackend::Dense, KrigingBackend::Local, KrigingBackend::Sparse}) {
    KrigingOptions one;
    one.backend = backend;
    one.neighbors = 24;
    one.threads = 1;
    one.target_batch = 64;
    auto two = one;
    two.threads = 2;
    const auto a = Kriging<P3, double>(d.points, d.values, model, one).predict(targets);
    const auto b = Kriging<P3, double>(d.points, d.values, model, two).predict(targets);
    EXPECT_EQ(a.mean, b.mean);
    EXPECT_EQ(a.variance, b.variance);
  }
}

static_assert(EmbeddableMetric<EuclideanMetric> && EmbeddableMetric<WeightedEuclideanMetric>);
struct NotEmbeddable {
  double operator()(const P3& a, const P3& b) const { return (a - b).lpNorm<1>(); }
};
static_assert(!EmbeddableMetric<NotEmbeddable>);

// Indicator kriging of one threshold is the kriging of the 0/1 indicators I(z < T) (strict: a
// sample equal to T is 0); the order correction equals the correction written another way here
// (u_k the maximum of the clipped p_j over j <= k, d_k the minimum over j >= k), leaves monotone rows
// in [0, 1] alone and NaN rows untouched.
TEST(IndicatorKriging, KrigesTheStrictIndicatorsAndCorrectsOrderAsGslib) {
  std::mt19937_64 rng(3606);
  std::uniform_real_distribution<double> u(0.0, 10.0);
  std::vector<Eigen::VectorXd> pts, targets;
  std::vector<double> z;
  for (int i = 0; i < 40; ++i) {
    pts.push_back(Eigen::Vector2d(u(rng), u(rng)));
    z.push_back(std::round(u(rng)));  // integers: samples equal to a threshold
  }
  for (int i = 0; i < 25; ++i) targets.push_back(Eigen::Vector2d(u(rng), u(rng)));
  const std::vector<double> thresholds{3.0, 5.0, 7.0};
  const std::vector<VariogramModel> models{VariogramModel::parse("sph(sill=0.15,range=4)+nug(0.05)"),
                                           VariogramModel::parse("exp(sill=0.2,range=1)+nug(0.02)"),
                                           VariogramModel::parse("gau(sill=0.1,range=3)+nug(0.08)")};
  KrigingOptions o;
  IndicatorKrigingOptions keep;
  keep.correct_order = false;
  const auto raw = indicator_kriging<Eigen::VectorXd>(pts, z, targets, thresholds, models, o, keep);
  const auto ik = indicator_kriging<Eigen::VectorXd>(pts, z, targets, thresholds, models, o);
  ASSERT_TRUE(ik.usable()) << ik.message;
  for (std::size_t k = 0; k < thresholds.size(); ++k) {
    std::vector<double> ind;
    for (double v : z) ind.push_back(v < thresholds[k] ? 1.0 : 0.0);
    const Kriging<Eigen::VectorXd, double> plain(pts, ind, models[k], o);
    const auto p = plain.predict(targets);
    for (std::size_t t = 0; t < targets.size(); ++t) {
      EXPECT_EQ(raw.raw(static_cast<Eigen::Index>(t), static_cast<Eigen::Index>(k)), p.mean[t]);
      EXPECT_EQ(ik.variance(static_cast<Eigen::Index>(t), static_cast<Eigen::Index>(k)), p.variance[t]);
    }
  }
  EXPECT_EQ(raw.probability, raw.raw);
  std::size_t changed = 0;
  for (Eigen::Index t = 0; t < ik.raw.rows(); ++t) {
    const Eigen::RowVector3d q = ik.raw.row(t).cwiseMax(0.0).cwiseMin(1.0);
    bool row_changed = false;
    for (int k = 0; k < 3; ++k) {
      const double expected = 0.5 * (q.head(k + 1).maxCoeff() + q.tail(3 - k).minCoeff());
      EXPECT_NEAR(ik.probability(t, k), expected, 1e-15);
      row_changed |= ik.probability(t, k) != ik.raw(t, k);
    }
    changed += row_changed;
  }
  EXPECT_EQ(ik.correction.rows_changed, changed);
  EXPECT_GT(changed, 0u);
  Eigen::MatrixXd cdf(2, 3);
  cdf << 0.1, 0.4, 0.9, std::nan(""), 2.0, -1.0;
  const Eigen::MatrixXd before = cdf;
  const auto c = correct_order_relations(cdf);
  EXPECT_EQ(c.rows_changed, 0u);
  EXPECT_EQ(cdf.row(0), before.row(0));
  EXPECT_TRUE(std::isnan(cdf(1, 0)) && cdf(1, 1) == 2.0);
  const std::vector<double> unsorted{5.0, 3.0};
  EXPECT_THROW(indicator_kriging<Eigen::VectorXd>(pts, z, targets, unsorted, models, o), ArgumentError);
}

}  // namespace
}  // namespace errfield
