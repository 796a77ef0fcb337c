// Block kriging (Kriging::predict_blocks), against an independent computation written here: the
// bordered ordinary/universal kriging system built explicitly with the block-averaged covariances
// and drift, solved by full-pivot LU. Also: the block mean is the weighted mean of the point
// predictions at the discretization points (the weights are linear in the right-hand side), the
// Gauss-Legendre rule integrates polynomials exactly, and misuse is refused. The gstat cross-check
// is tests/peers/gstat_block_test.cpp.

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <Eigen/LU>
#include <gtest/gtest.h>

#include "errfield/error.hpp"
#include "errfield/kriging.hpp"

namespace errfield {
namespace kriging_block_test {

using Point = Eigen::Vector2d;

struct Field {
  std::vector<Point> samples, centres;
  std::vector<double> values;
};

Field make_field(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 100.0);
  Field f;
  for (int i = 0; i < 40; ++i) {
    f.samples.emplace_back(u(rng), u(rng));
    f.values.push_back(std::sin(f.samples.back()[0] / 20.0) + 0.01 * f.samples.back()[1]);
  }
  for (int t = 0; t < 8; ++t) f.centres.emplace_back(u(rng), u(rng));
  return f;
}

// Independent block kriging: bordered system [K F; F' 0] [w; mu] = [c_B; f_B], variance
// C_BB - w'c_B - mu'f_B, with drift 1 (ordinary) or 1, x, y (universal, order 1).
std::pair<double, double> brute_force_block(const Field& f, const VariogramModel& model, const Point& centre,
                                            const Eigen::MatrixXd& offsets, const Eigen::VectorXd& weights, bool linear) {
  const int n = static_cast<int>(f.samples.size()), p = linear ? 3 : 1;
  auto cov = [&](const Point& a, const Point& b) { return (a - b).norm() > 0 ? model.covariance((a - b).norm()) : model.sill(); };
  // A sample and a point of the block: the nugget averages out over the block (gstat: C(0+)).
  const double structured = model.sill() - model.nugget();
  auto cov_block = [&](const Point& a, const Point& b) {
    return (a - b).norm() > 0 ? model.covariance((a - b).norm()) : structured;
  };
  auto drift = [&](const Point& x) {
    Eigen::VectorXd d(p);
    d[0] = 1.0;
    if (linear) d[1] = x[0], d[2] = x[1];
    return d;
  };
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n + p, n + p);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n + p);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) a(i, j) = cov(f.samples[i], f.samples[j]);
    a.block(i, n, 1, p) = drift(f.samples[i]).transpose();
    a.block(n, i, p, 1) = drift(f.samples[i]);
  }
  double cbb = 0.0;
  for (Eigen::Index j = 0; j < offsets.cols(); ++j) {
    const Point pj = centre + offsets.col(j);
    for (int i = 0; i < n; ++i) rhs[i] += weights[j] * cov_block(f.samples[i], pj);
    rhs.tail(p) += weights[j] * drift(pj);
    for (Eigen::Index k = 0; k < offsets.cols(); ++k) {
      const Point pk = centre + offsets.col(k);
      cbb += weights[j] * weights[k] * ((pj - pk).norm() > 0 ? model.covariance((pj - pk).norm()) : structured);
    }
  }
  const Eigen::VectorXd sol = a.fullPivLu().solve(rhs);
  double mean = 0.0;
  for (int i = 0; i < n; ++i) mean += sol[i] * f.values[static_cast<std::size_t>(i)];
  return {mean, cbb - sol.dot(rhs)};
}

TEST(BlockKriging, MatchesTheBorderedSystemWithBlockAveragedCovariances) {
  const Field f = make_field(1);
  const VariogramModel model = VariogramModel::parse("sph(sill=1,range=40)+nug(sill=0.1)");
  for (const bool linear : {false, true})
    for (const auto rule : {BlockDiscretization::Rule::GaussLegendre, BlockDiscretization::Rule::Regular}) {
      KrigingOptions o;
      o.kind = linear ? KrigingKind::Universal : KrigingKind::Ordinary;
      BlockDiscretization block{{12.0, 6.0}, 3, rule};
      const auto got = Kriging<Point, double>(f.samples, f.values, model, o).predict_blocks(f.centres, block);
      ASSERT_TRUE(got.usable()) << got.message;
      for (std::size_t t = 0; t < f.centres.size(); ++t) {
        const auto [mean, variance] = brute_force_block(f, model, f.centres[t], block.offsets(2), block.weights(2), linear);
        EXPECT_NEAR(got.mean[t], mean, 1e-10);
        EXPECT_NEAR(got.variance[t], variance, 1e-10);
      }
    }
}

TEST(BlockKriging, OddRegularRuleIsContinuousWhereAPointMeetsASample) {
  // Samples on an integer grid, blocks centred on samples: with an odd regular rule the centre point
  // (and with a 3-wide block of 3 points, its neighbours too) falls exactly on a sample. Moving the
  // blocks by 1e-7 must move the results by O(1e-7): with the covariance's slope (~ sill * 1.5 /
  // range = 0.25 per unit here) far below 1e-5. Adding the nugget (0.1) at the coincident point
  // instead jumps by ~0.1 / 9 in the covariance and ~1e-2 in the results.
  Field f;
  for (int x = 0; x < 7; ++x)
    for (int y = 0; y < 7; ++y) {
      f.samples.emplace_back(x, y);
      f.values.push_back(std::sin(0.7 * x) + 0.2 * y + 0.1 * ((3 * x + 5 * y) % 4));
    }
  f.centres = {{3, 3}, {1, 4}, {5, 2}, {0, 0}};
  const VariogramModel model = VariogramModel::parse("sph(sill=1,range=6)+nug(sill=0.1)");
  for (const auto backend : {KrigingBackend::Dense, KrigingBackend::Local})
    for (const int points : {3, 5})
      for (const double size : {2.0, 3.0}) {
        KrigingOptions o;
        o.backend = backend;
        // (a radius between the grid's distances sqrt(5) and sqrt(8): the same neighbours after the move)
        if (backend == KrigingBackend::Local) o.radius = 2.5;
        const BlockDiscretization block{{size, size}, points, BlockDiscretization::Rule::Regular};
        const Kriging<Point, double> k(f.samples, f.values, model, o);
        std::vector<Point> moved;
        for (const Point& c : f.centres) moved.push_back(c + Point(1e-7, 1e-7));
        const auto at = k.predict_blocks(f.centres, block), near = k.predict_blocks(moved, block);
        ASSERT_TRUE(at.usable() && near.usable()) << at.message << near.message;
        for (std::size_t t = 0; t < f.centres.size(); ++t) {
          const std::string where = std::string(backend == KrigingBackend::Dense ? "dense" : "local") + ", " +
                                    std::to_string(points) + " points, size " + std::to_string(size) + ", block " +
                                    std::to_string(t);
          EXPECT_NEAR(at.mean[t], near.mean[t], 1e-5) << where;
          EXPECT_NEAR(at.variance[t], near.variance[t], 1e-5) << where;
          if (backend == KrigingBackend::Dense) {
            const auto [mean, variance] = brute_force_block(f, model, f.centres[t], block.offsets(2), block.weights(2), false);
            EXPECT_NEAR(at.mean[t], mean, 1e-10) << where;
            EXPECT_NEAR(at.variance[t], variance, 1e-10) << where;
          }
        }
      }
}

TEST(BlockKriging, MeanIsTheWeightedMeanOfThePointPredictions) {
  const Field f = make_field(2);
  const VariogramModel model = VariogramModel::parse("exp(sill=1,range=15)+nug(sill=0.05)");
  const Kriging<Point, double> k(f.samples, f.values, model);
  const BlockDiscretization block{{10.0, 10.0}};
  const Eigen::MatrixXd offsets = block.offsets(2);
  const Eigen::VectorXd weights = block.weights(2);
  const auto blocks = k.predict_blocks(f.centres, block);
  for (std::size_t t = 0; t < f.centres.size(); ++t) {
    std::vector<Point> points;
    for (Eigen::Index j = 0; j < offsets.cols(); ++j) points.push_back(f.centres[t] + offsets.col(j));
    const auto at_points = k.predict(points);
    double mean = 0.0;
    for (std::size_t j = 0; j < points.size(); ++j) mean += weights[static_cast<Eigen::Index>(j)] * at_points.mean[j];
    EXPECT_NEAR(blocks.mean[t], mean, 1e-12);
    // Averaging removes the nugget and part of the structured variance: a block is known better.
    EXPECT_LT(blocks.variance[t], at_points.variance[0]);
  }
}

TEST(BlockKriging, LocalBackEndWithEveryNeighbourIsTheDenseOne) {
  const Field f = make_field(3);
  const VariogramModel model = VariogramModel::parse("gau(sill=1,range=20)+nug(sill=0.02)");
  KrigingOptions local;
  local.backend = KrigingBackend::Local;
  local.neighbors = f.samples.size();
  const BlockDiscretization block{{8.0, 8.0}, 4};
  const auto dense = Kriging<Point, double>(f.samples, f.values, model).predict_blocks(f.centres, block);
  const auto loc = Kriging<Point, double>(f.samples, f.values, model, local).predict_blocks(f.centres, block);
  for (std::size_t t = 0; t < f.centres.size(); ++t) {
    EXPECT_NEAR(loc.mean[t], dense.mean[t], 1e-9);
    EXPECT_NEAR(loc.variance[t], dense.variance[t], 1e-9);
  }
}

TEST(BlockKriging, GaussLegendreIntegratesPolynomialsExactly) {
  // n points per axis integrate degree 2n - 1 exactly: the mean of x^6 y^2 over a 3 x 5 block.
  const BlockDiscretization block{{3.0, 5.0}, 4};
  const Eigen::MatrixXd o = block.offsets(2);
  const Eigen::VectorXd w = block.weights(2);
  EXPECT_NEAR(w.sum(), 1.0, 1e-15);
  double mean = 0.0;
  for (Eigen::Index j = 0; j < o.cols(); ++j) mean += w[j] * std::pow(o(0, j), 6) * std::pow(o(1, j), 2);
  const double exact = (std::pow(1.5, 6) / 7.0) * (std::pow(2.5, 2) / 3.0);  // mean of x^6 on [-1.5,1.5], y^2 on [-2.5,2.5]
  EXPECT_NEAR(mean, exact, 1e-12 * exact);
}

TEST(BlockKriging, MisuseIsRefusedWithTheCause) {
  const Field f = make_field(4);
  const VariogramModel model = VariogramModel::parse("sph(sill=1,range=40)");
  const Kriging<Point, double> k(f.samples, f.values, model);
  EXPECT_THROW(k.predict_blocks(f.centres, BlockDiscretization{{10.0}}), ArgumentError);         // one size in 2-D
  EXPECT_THROW(k.predict_blocks(f.centres, BlockDiscretization{{10.0, -1.0}}), ArgumentError);   // negative
  EXPECT_THROW(k.predict_blocks(f.centres, BlockDiscretization{{10.0, 10.0}, 0}), ArgumentError);
  KrigingOptions sparse;
  sparse.backend = KrigingBackend::Sparse;
  const Kriging<Point, double> s(f.samples, f.values, VariogramModel::parse("sph(sill=1,range=40)+nug(0.01)"), sparse);
  EXPECT_THROW(s.predict_blocks(f.centres, BlockDiscretization{{10.0, 10.0}}), ArgumentError);
}

}  // namespace kriging_block_test
}  // namespace errfield
