// Anisotropy: the linear map against its definition (lags along the principal axes), text and JSON
// round trips, and kriging with an anisotropic model against kriging of coordinates mapped by hand
// (dense, local with neighbours chosen in the mapped space, sparse).

#include "errfield/anisotropy.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include <Eigen/Dense>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "errfield/error.hpp"
#include "errfield/kriging.hpp"
#include "errfield/variogram_model.hpp"

namespace errfield {
namespace anisotropy_test {

Eigen::VectorXd mapped(const Anisotropy& a, const Eigen::VectorXd& v) {
  Eigen::VectorXd out(v.size());
  a.apply(v.data(), out.data(), static_cast<int>(v.size()));
  return out;
}

TEST(Anisotropy, ArdDividesEachCoordinateByItsMultiplier) {
  const Anisotropy a = Anisotropy::ard({2.0, 0.5, 4.0});
  const Eigen::VectorXd m = mapped(a, Eigen::Vector3d(2.0, 1.0, -8.0));
  EXPECT_DOUBLE_EQ(m[0], 1.0);
  EXPECT_DOUBLE_EQ(m[1], 2.0);
  EXPECT_DOUBLE_EQ(m[2], -2.0);
  EXPECT_THROW(Anisotropy::ard({1.0, 0.0}), ArgumentError);
  EXPECT_THROW(Anisotropy::ard({}), ArgumentError);
}

TEST(Anisotropy, TwoDimensionalGstatAnisStretchesAcrossTheMajorAxis) {
  // gstat: the major axis `angle` degrees clockwise from +y; range across it = ratio * range.
  const double angle = 30.0, ratio = 0.25;
  const Anisotropy a = Anisotropy::rotated({angle, ratio});
  const double t = angle * std::numbers::pi / 180.0;
  const Eigen::Vector2d major(std::sin(t), std::cos(t)), minor(std::cos(t), -std::sin(t));
  EXPECT_NEAR(mapped(a, major).norm(), 1.0, 1e-15);
  EXPECT_NEAR(mapped(a, minor).norm(), 1.0 / ratio, 1e-14);
  // A lag along +y (north) at angle 0 is along the major axis.
  EXPECT_NEAR(mapped(Anisotropy::rotated({0.0, 0.5}), Eigen::Vector2d(0.0, 3.0)).norm(), 3.0, 1e-15);
  EXPECT_NEAR(mapped(Anisotropy::rotated({0.0, 0.5}), Eigen::Vector2d(3.0, 0.0)).norm(), 6.0, 1e-15);
}

TEST(Anisotropy, ThreeDimensionalGstatAnisFollowsAzimuthDipAndRatios) {
  const double s = 0.5, t = 0.2;
  // Azimuth 0, no dip: the major axis is +y, minor 1 is x, minor 2 is z.
  const Anisotropy flat = Anisotropy::rotated({0.0, 0.0, 0.0, s, t});
  EXPECT_NEAR(mapped(flat, Eigen::Vector3d(0, 1, 0)).norm(), 1.0, 1e-15);
  EXPECT_NEAR(mapped(flat, Eigen::Vector3d(1, 0, 0)).norm(), 1.0 / s, 1e-14);
  EXPECT_NEAR(mapped(flat, Eigen::Vector3d(0, 0, 1)).norm(), 1.0 / t, 1e-14);
  // Azimuth 90: the major axis is +x.
  EXPECT_NEAR(mapped(Anisotropy::rotated({90.0, 0.0, 0.0, s, t}), Eigen::Vector3d(1, 0, 0)).norm(), 1.0, 1e-15);
  // Azimuth 0, dip 90 (up from horizontal): the major axis is vertical.
  EXPECT_NEAR(mapped(Anisotropy::rotated({0.0, 90.0, 0.0, s, t}), Eigen::Vector3d(0, 0, 1)).norm(), 1.0, 1e-15);
  // Any angles: A'A has eigenvalues 1, 1/s^2, 1/t^2 (a rotation, then the scaling).
  const Anisotropy a = Anisotropy::rotated({37.0, 21.0, -14.0, s, t});
  const Eigen::Matrix3d m = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(a.matrix().data());
  Eigen::Vector3d ev = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(m.transpose() * m).eigenvalues();
  std::sort(ev.data(), ev.data() + 3);
  EXPECT_NEAR(ev[0], 1.0, 1e-12);
  EXPECT_NEAR(ev[1], 1.0 / (s * s), 1e-12);
  EXPECT_NEAR(ev[2], 1.0 / (t * t), 1e-10);
  EXPECT_THROW(Anisotropy::rotated({1.0, 2.0, 3.0}), ArgumentError);
}

TEST(Anisotropy, ModelTextAndJsonRoundTrip) {
  for (const char* text : {"mat(sill=1.5,range=40,nu=2.5)+nug(sill=0.01)@ard(1,0.5,0.25)",
                           "sph(sill=1,range=100)@anis(30,0.5)", "exp(sill=2,range=7)@anis(10,20,30,0.5,0.25)",
                           "gau(sill=1,range=3)"}) {
    const VariogramModel m = VariogramModel::parse(text);
    EXPECT_EQ(m.to_string(), text);
    const nlohmann::json j = m;
    EXPECT_EQ(j.get<VariogramModel>().to_string(), text) << j.dump();
  }
  EXPECT_TRUE(VariogramModel::parse("sph(1,2)").anisotropy().isotropic());
  EXPECT_THROW(VariogramModel::parse("sph(1,2)@ard(1,-1)"), ArgumentError);
  EXPECT_THROW(VariogramModel::parse("sph(1,2)@iso(1)"), ArgumentError);
  EXPECT_THROW(VariogramModel::parse("sph(1,2)@ard(1,x)"), ArgumentError);
}

struct Data {
  std::vector<Eigen::VectorXd> samples, targets;
  std::vector<double> values;
};

Data random_data(int dims, int n, int m) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 10.0);
  Data d;
  for (int i = 0; i < n + m; ++i) {
    Eigen::VectorXd p(dims);
    for (auto& x : p) x = u(rng);
    (i < n ? d.samples : d.targets).push_back(p);
    if (i < n) d.values.push_back(std::sin(p[0]) + 0.3 * p[1]);
  }
  return d;
}

std::vector<Eigen::VectorXd> map_all(const Anisotropy& a, const std::vector<Eigen::VectorXd>& p) {
  std::vector<Eigen::VectorXd> out;
  for (const auto& v : p) out.push_back(mapped(a, v));
  return out;
}

void expect_same_as_mapped_by_hand(const char* model_text, int dims, KrigingOptions o) {
  const VariogramModel model = VariogramModel::parse(model_text);
  const Data d = random_data(dims, 60, 25);
  const Kriging<Eigen::VectorXd, double> aniso(d.samples, d.values, model, o);
  const auto mapped_samples = map_all(model.anisotropy(), d.samples);
  const Kriging<Eigen::VectorXd, double> by_hand(mapped_samples, d.values, model.isotropic_part(), o);
  const auto p = aniso.predict(d.targets);
  const auto q = by_hand.predict(map_all(model.anisotropy(), d.targets));
  ASSERT_TRUE(p.usable()) << p.message;
  ASSERT_EQ(p.mean.size(), q.mean.size());
  for (std::size_t t = 0; t < p.mean.size(); ++t) {
    EXPECT_NEAR(p.mean[t], q.mean[t], 1e-12 * (1.0 + std::abs(q.mean[t]))) << model_text << " target " << t;
    EXPECT_NEAR(p.variance[t], q.variance[t], 1e-12) << model_text << " target " << t;
  }
}

TEST(AnisotropicKriging, EveryBackEndEqualsKrigingOfMappedCoordinates) {
  KrigingOptions dense;
  expect_same_as_mapped_by_hand("mat(sill=1,range=4,nu=1.5)+nug(0.01)@ard(1,0.3,2)", 3, dense);
  expect_same_as_mapped_by_hand("exp(sill=1,range=4)+nug(0.01)@anis(30,0.4)", 2, dense);
  expect_same_as_mapped_by_hand("gau(sill=1,range=4)+nug(0.05)@anis(20,10,5,0.5,0.3)", 3, dense);
  KrigingOptions local;
  local.backend = KrigingBackend::Local;
  local.neighbors = 12;  // neighbours must be the 12 nearest in the mapped space to agree
  expect_same_as_mapped_by_hand("mat(sill=1,range=4,nu=2.5)+nug(0.01)@ard(1,0.1,5)", 3, local);
  KrigingOptions sparse;
  sparse.backend = KrigingBackend::Sparse;
  expect_same_as_mapped_by_hand("sph(sill=1,range=3)+nug(0.01)@ard(1,0.5,2)", 3, sparse);
}

TEST(AnisotropicKriging, LocalNeighboursAreTheNearestInTheMappedSpace) {
  // Along y the range is 100 times shorter: a sample 0.5 away in y is "farther" than one 10 away
  // in x, so with one neighbour the prediction at the origin is the x-sample's value.
  const VariogramModel model = VariogramModel::parse("exp(sill=1,range=50)@ard(1,0.01)");
  const std::vector<Eigen::VectorXd> s{Eigen::Vector2d(10.0, 0.0), Eigen::Vector2d(0.0, 0.5)};
  const std::vector<double> v{1.0, 2.0};
  KrigingOptions o;
  o.backend = KrigingBackend::Local;
  o.neighbors = 1;
  const Kriging<Eigen::VectorXd, double> k(s, v, model, o);
  const auto p = k.predict(std::vector<Eigen::VectorXd>{Eigen::Vector2d(0.0, 0.0)});
  ASSERT_TRUE(p.usable());
  EXPECT_DOUBLE_EQ(p.mean[0], 1.0);
}

TEST(AnisotropicKriging, DimensionMismatchIsAnArgumentError) {
  const Data d = random_data(2, 10, 1);
  EXPECT_THROW((Kriging<Eigen::VectorXd, double>(d.samples, d.values, VariogramModel::parse("exp(1,2)@ard(1,2,3)"))),
               ArgumentError);
}

}  // namespace
}  // namespace errfield
