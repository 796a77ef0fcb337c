#include "errfield/variogram_model.hpp"

#include <cmath>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "errfield/error.hpp"

namespace errfield {
namespace variogram_model_test {

TEST(VariogramModel, ClosedFormsAtZeroRangeAndBeyond) {
  const auto sph = VariogramModel::parse("sph(sill=2,range=100)");
  EXPECT_EQ(sph.gamma(0.0), 0.0);
  EXPECT_DOUBLE_EQ(sph.gamma(50.0), 2.0 * (0.75 - 0.0625));
  EXPECT_DOUBLE_EQ(sph.gamma(100.0), 2.0);
  EXPECT_DOUBLE_EQ(sph.gamma(1e6), 2.0);
  const auto ex = VariogramModel::parse("exp(1,10)");
  EXPECT_DOUBLE_EQ(ex.gamma(10.0), 1.0 - std::exp(-1.0));
  const auto ga = VariogramModel::parse("gau(1,10)");
  EXPECT_DOUBLE_EQ(ga.gamma(20.0), 1.0 - std::exp(-4.0));
  // Matérn with nu = 0.5 is the exponential model (same scale a).
  const auto m = VariogramModel::parse("mat(sill=1,range=10,nu=0.5)");
  for (double h : {0.5, 3.0, 10.0, 40.0}) EXPECT_NEAR(m.gamma(h), ex.gamma(h), 1e-12);
  const auto nug = VariogramModel::parse("nug(0.3)");
  EXPECT_EQ(nug.gamma(0.0), 0.0);
  EXPECT_EQ(nug.gamma(1e-9), 0.3);
  EXPECT_DOUBLE_EQ(VariogramModel::parse("pow(sill=2,exponent=1.5)").gamma(4.0), 16.0);
  EXPECT_DOUBLE_EQ(VariogramModel::parse("lin(slope=0.5)").gamma(4.0), 2.0);
  const auto w = VariogramModel::parse("wen(1,10)");
  EXPECT_DOUBLE_EQ(w.gamma(10.0), 1.0);
  EXPECT_NEAR(w.gamma(1e-8), 0.0, 1e-12);
}

TEST(VariogramModel, SumsTextAndJsonRoundTrip) {
  const auto m = VariogramModel::parse("sph(sill=0.3,range=400)+nug(0.002)");
  EXPECT_DOUBLE_EQ(m.sill(), 0.302);
  EXPECT_DOUBLE_EQ(m.nugget(), 0.002);
  EXPECT_TRUE(m.compact());
  EXPECT_DOUBLE_EQ(m.support(), 400.0);
  const auto back = VariogramModel::parse(m.to_string());
  EXPECT_EQ(back.to_string(), m.to_string());
  nlohmann::json j = m;
  const auto from = j.get<VariogramModel>();
  EXPECT_EQ(from.to_string(), m.to_string());
  EXPECT_DOUBLE_EQ(VariogramModel::parse("exp(sill=1e+0,range=2.5e+2)").components()[0].range, 250.0);
}

TEST(VariogramModel, RejectsBadTextAndParameters) {
  EXPECT_THROW(VariogramModel::parse("xyz(1,2)"), ArgumentError);
  EXPECT_THROW(VariogramModel::parse("sph(sill=1)"), ArgumentError);
  EXPECT_THROW(VariogramModel::parse("sph(sill=-1,range=3)"), ArgumentError);
  EXPECT_THROW(VariogramModel::parse("sph(sill=1,range=0)"), ArgumentError);
  EXPECT_THROW(VariogramModel::parse("sph(sill=1,range=3"), ArgumentError);
  EXPECT_THROW(VariogramModel::parse("sph(1,3)+"), ArgumentError);
  EXPECT_THROW(VariogramModel::parse("pow(1,2.5)"), ArgumentError);
  EXPECT_THROW(VariogramModel::parse("mat(1,3)"), ArgumentError);
  EXPECT_THROW(VariogramModel::parse("sph(sill=1,sill=2,range=3)"), ArgumentError);
}

}  // namespace
}  // namespace errfield
