#include "errfield/variogram_fit.hpp"

#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "errfield/error.hpp"

namespace errfield {
namespace variogram_fit_test {

struct Bins {
  std::vector<double> h, g;
  std::vector<std::uint64_t> n;
};

// Semivariances taken exactly from a known model at given lags: the fit must recover it.
Bins from_model(const VariogramModel& m, double max_lag, int bins) {
  Bins b;
  for (int j = 0; j < bins; ++j) {
    const double h = max_lag * (j + 0.5) / bins;
    b.h.push_back(h);
    b.g.push_back(m.gamma(h));
    b.n.push_back(static_cast<std::uint64_t>(100 + 37 * j));
  }
  return b;
}

std::vector<ModelComponent> structure(ModelKind k, double nu = 0.5) { return {{k, 0.0, 0.0, nu}}; }

TEST(VariogramFit, RecoversExactModelsAtLargeAndSmallScales) {
  struct Case {
    const char* model;
    double max_lag;
  };
  // Lags in the thousands (mm) and semivariances around 1e-6 (mm^2 of a very accurate robot):
  // the internal scaling must make these as easy as order-1 data.
  const Case cases[] = {
      {"sph(sill=0.3,range=400)+nug(sill=0.002)", 1000.0},
      {"exp(sill=2e-6,range=1500)+nug(sill=1e-7)", 12000.0},
      {"gau(sill=5,range=30)+nug(sill=0.5)", 80.0},
      {"mat(sill=0.8,range=200,nu=1.5)+nug(sill=0.05)", 1500.0},
      {"pow(sill=0.003,exponent=1.4)+nug(sill=0.01)", 2000.0},
      {"lin(slope=0.0005)+nug(sill=0.01)", 2000.0},
  };
  for (const auto& c : cases)
    for (auto w : {FitWeighting::Nj, FitWeighting::NjOverH2, FitWeighting::Cressie}) {
      SCOPED_TRACE(std::string(c.model) + " weights " + std::string(weighting_name(w)));
      const auto truth = VariogramModel::parse(c.model);
      const Bins b = from_model(truth, c.max_lag, 15);
      auto st = truth.components();
      st.pop_back();  // structure without the nugget, parameters unknown:
      for (auto& comp : st) comp.sill = comp.range = 0.0;
      if (truth.components()[0].kind == ModelKind::Matern) st[0].nu = 1.5;
      VariogramFitOptions o;
      o.weighting = w;
      const auto r = fit_variogram(b.h, b.g, b.n, st, o);
      EXPECT_EQ(r.status, FitStatus::Converged) << r.message;
      ASSERT_EQ(r.model.components().size(), 2u);
      const auto& got = r.model.components();
      const auto& want = truth.components();
      // An exact model is the global minimum with SSE 0; parameters come back to the optimizer's
      // relative tolerance amplified by the conditioning of the problem: 1e-5 relative.
      EXPECT_NEAR(got[0].sill, want[0].sill, 1e-5 * want[0].sill);
      if (want[0].kind != ModelKind::Linear) {
        EXPECT_NEAR(got[0].range, want[0].range, 1e-5 * want[0].range);
      }
      EXPECT_NEAR(got[1].sill, want[1].sill, 1e-5 * want[0].sill);
      auto off = want;
      off[0].sill *= 1.01;  // a model 1% off in sill, for scale
      EXPECT_LT(r.weighted_sse, 1e-6 * weighted_sse(b.h, b.g, b.n, VariogramModel(off), w));
    }
}

TEST(VariogramFit, NuggetFixedAndNone) {
  const auto truth = VariogramModel::parse("exp(sill=1,range=100)+nug(sill=0.25)");
  const Bins b = from_model(truth, 500.0, 12);
  VariogramFitOptions o;
  o.nugget = NuggetMode::Fixed;
  o.nugget_value = 0.25;
  auto r = fit_variogram(b.h, b.g, b.n, structure(ModelKind::Exponential), o);
  ASSERT_EQ(r.model.components().size(), 2u);
  EXPECT_EQ(r.model.nugget(), 0.25);
  EXPECT_NEAR(r.model.components()[0].range, 100.0, 1e-4);
  o.nugget = NuggetMode::None;
  r = fit_variogram(b.h, b.g, b.n, structure(ModelKind::Exponential), o);
  ASSERT_EQ(r.model.components().size(), 1u);
  EXPECT_EQ(r.model.nugget(), 0.0);
  EXPECT_GT(r.weighted_sse, 0.0);  // the nugget is missing, so the fit cannot be exact
}

TEST(VariogramFit, NoisyFitIsALocalMinimumOfTheWeightedSse) {
  // Simulated noisy bins around a spherical model: the fitted parameters must not be improvable
  // by small moves in any parameter (checked by direct evaluation of the criterion).
  const auto truth = VariogramModel::parse("sph(sill=0.3,range=400)+nug(sill=0.02)");
  Bins b = from_model(truth, 900.0, 18);
  std::mt19937_64 rng(4);
  std::normal_distribution<double> noise(0.0, 0.01);
  for (auto& g : b.g) g = std::max(0.0, g + noise(rng));
  for (auto w : {FitWeighting::Nj, FitWeighting::NjOverH2, FitWeighting::Cressie}) {
    VariogramFitOptions o;
    o.weighting = w;
    const auto r = fit_variogram(b.h, b.g, b.n, structure(ModelKind::Spherical), o);
    const double f0 = weighted_sse(b.h, b.g, b.n, r.model, w);
    EXPECT_DOUBLE_EQ(f0, r.weighted_sse);
    for (int p = 0; p < 3; ++p)
      for (double d : {-1e-4, 1e-4}) {
        auto comps = r.model.components();
        if (p == 0) comps[0].sill *= 1 + d;
        if (p == 1) comps[0].range *= 1 + d;
        if (p == 2) comps[1].sill = comps[1].sill * (1 + d) + (d > 0 ? 1e-9 : 0.0);
        EXPECT_GE(weighted_sse(b.h, b.g, b.n, VariogramModel(comps), w), f0 * (1 - 1e-12))
            << "parameter " << p << " step " << d << " weights " << weighting_name(w);
      }
  }
}

TEST(VariogramFit, WeightedSseUsesGstatWeights) {
  const std::vector<double> h{10, 20};
  const std::vector<double> g{1.0, 2.0};
  const std::vector<std::uint64_t> n{3, 5};
  const auto m = VariogramModel::parse("lin(slope=0.05)");  // model values 0.5 and 1.0
  EXPECT_DOUBLE_EQ(weighted_sse(h, g, n, m, FitWeighting::Nj), 3 * 0.25 + 5 * 1.0);
  EXPECT_DOUBLE_EQ(weighted_sse(h, g, n, m, FitWeighting::NjOverH2), 3 * 0.25 / 100 + 5 * 1.0 / 400);
  EXPECT_DOUBLE_EQ(weighted_sse(h, g, n, m, FitWeighting::Cressie), 3 * 0.25 / 0.25 + 5 * 1.0 / 1.0);
  EXPECT_EQ(weighting_from_name("7"), FitWeighting::NjOverH2);
  EXPECT_EQ(weighting_from_name("cressie"), FitWeighting::Cressie);
  EXPECT_THROW(weighting_from_name("ols"), ArgumentError);
}

TEST(VariogramFit, RejectsBadInput) {
  const std::vector<double> h{10, 20, 30};
  const std::vector<double> g{1.0, 2.0, 2.5};
  const std::vector<std::uint64_t> n{3, 5, 4};
  EXPECT_THROW(fit_variogram(h, g, std::vector<std::uint64_t>{1, 2}, structure(ModelKind::Spherical)),
               ArgumentError);
  EXPECT_THROW(fit_variogram(h, g, n, {{ModelKind::Nugget, 1, 0, 0.5}}), ArgumentError);
  // 3 bins, 3 parameters is fine; 2 bins is not.
  EXPECT_NO_THROW(fit_variogram(h, g, n, structure(ModelKind::Spherical)));
  EXPECT_THROW(fit_variogram(std::span(h).first(2), std::span(g).first(2), std::span(n).first(2),
                             structure(ModelKind::Spherical)),
               ArgumentError);
  const std::vector<double> bad{1.0, std::nan(""), 2.5};
  EXPECT_THROW(fit_variogram(h, bad, n, structure(ModelKind::Spherical)), InputError);
  VariogramFitOptions o;
  o.nugget = NuggetMode::Fixed;
  o.nugget_value = -1;
  EXPECT_THROW(fit_variogram(h, g, n, structure(ModelKind::Spherical), o), ArgumentError);
  o = {};
  o.starts = 0;
  EXPECT_THROW(fit_variogram(h, g, n, structure(ModelKind::Spherical), o), ArgumentError);
}


// A nested template (gstat's vgm(..., add.to = ...)): two spherical structures and a nugget, from
// starting values near but not at the truth, on bins taken from the nested model itself.
TEST(VariogramFit, NestedStructuresFromATemplateRecoverTheModel) {
  const VariogramModel truth = VariogramModel::parse("nug(sill=2e4)+sph(sill=3e4,range=25)+sph(sill=4e4,range=80)");
  const Bins b = from_model(truth, 120.0, 24);
  const std::vector<ModelComponent> tmpl = {{ModelKind::Spherical, 2e4, 15.0, 0.5}, {ModelKind::Spherical, 6e4, 100.0, 0.5}};
  VariogramFitOptions o;
  o.nugget_start = 1e4;
  const VariogramFitResult r = fit_variogram(b.h, b.g, b.n, tmpl, o);
  ASSERT_EQ(r.status, FitStatus::Converged) << r.message;
  // The weighted SSE of the truth is 0: the fit must reach (nearly) that, and the model's values.
  double sse_scale = 0.0;
  for (std::size_t j = 0; j < b.h.size(); ++j) sse_scale += b.n[j] / (b.h[j] * b.h[j]) * b.g[j] * b.g[j];
  EXPECT_LT(r.weighted_sse, 1e-10 * sse_scale) << r.model.to_string();
  for (double h : {1.0, 10.0, 25.0, 50.0, 80.0, 110.0})
    EXPECT_NEAR(r.model.gamma(h), truth.gamma(h), 1e-4 * truth.sill()) << "h = " << h << ", " << r.model.to_string();
}

// With every range held, gamma(h) is linear in the sills and the nugget: the weighted least squares
// has a closed form, written out here (normal equations), which the fit must reproduce.
TEST(VariogramFit, HeldRangesGiveTheLinearLeastSquaresSills) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 0.03);
  const VariogramModel truth = VariogramModel::parse("nug(sill=0.2)+sph(sill=1,range=30)+exp(sill=0.5,range=200)");
  Bins b = from_model(truth, 400.0, 30);
  for (double& g : b.g) g *= 1.0 + noise(rng);
  const std::vector<ModelComponent> tmpl = {{ModelKind::Spherical, 0.7, 30.0, 0.5},
                                            {ModelKind::Exponential, 0.7, 200.0, 0.5}};
  for (const FitWeighting w : {FitWeighting::Nj, FitWeighting::NjOverH2}) {
    VariogramFitOptions o;
    o.weighting = w;
    o.hold_range = {true, true};
    const VariogramFitResult r = fit_variogram(b.h, b.g, b.n, tmpl, o);
    ASSERT_EQ(r.status, FitStatus::Converged) << r.message;
    // Columns: unit-sill sph(30), unit-sill exp(200), nugget.
    Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
    Eigen::Vector3d atb = Eigen::Vector3d::Zero();
    for (std::size_t j = 0; j < b.h.size(); ++j) {
      const Eigen::Vector3d a(ModelComponent{ModelKind::Spherical, 1.0, 30.0, 0.5}.gamma(b.h[j]),
                              ModelComponent{ModelKind::Exponential, 1.0, 200.0, 0.5}.gamma(b.h[j]), 1.0);
      const double wj = w == FitWeighting::Nj ? double(b.n[j]) : double(b.n[j]) / (b.h[j] * b.h[j]);
      ata += wj * a * a.transpose();
      atb += wj * b.g[j] * a;
    }
    const Eigen::Vector3d sills = ata.ldlt().solve(atb);
    ASSERT_TRUE((sills.array() > 0.0).all()) << "the test's data must keep the unconstrained optimum feasible";
    const auto& c = r.model.components();
    ASSERT_EQ(c.size(), 3u);
    EXPECT_EQ(c[0].range, 30.0);  // held: exactly as given
    EXPECT_EQ(c[1].range, 200.0);
    EXPECT_NEAR(c[0].sill, sills[0], 1e-6 * sills[0]);
    EXPECT_NEAR(c[1].sill, sills[1], 1e-6 * sills[1]);
    EXPECT_NEAR(c[2].sill, sills[2], 1e-6 * sills[2]);
  }
}

// Held sills: only the ranges move; the held values come back bit for bit and the SSE is no worse
// than any other range on a fine scan (a one-parameter brute force).
TEST(VariogramFit, HeldSillLeavesTheRangeToTheFit) {
  const VariogramModel truth = VariogramModel::parse("sph(sill=2,range=50)");
  const Bins b = from_model(truth, 100.0, 20);
  VariogramFitOptions o;
  o.nugget = NuggetMode::None;
  o.hold_sill = {true};
  const VariogramFitResult r = fit_variogram(b.h, b.g, b.n, {{ModelKind::Spherical, 1.5, 20.0, 0.5}}, o);
  ASSERT_EQ(r.status, FitStatus::Converged) << r.message;
  ASSERT_EQ(r.model.components().size(), 1u);
  EXPECT_EQ(r.model.components()[0].sill, 1.5);
  double best_scan = 1e300;
  for (double range = 1.0; range <= 200.0; range += 0.01) {
    const VariogramModel m({{ModelKind::Spherical, 1.5, range, 0.5}});
    best_scan = std::min(best_scan, weighted_sse(b.h, b.g, b.n, m, o.weighting));
  }
  EXPECT_LE(r.weighted_sse, best_scan * (1 + 1e-9));
}

TEST(VariogramFit, HoldsAreChecked) {
  const Bins b = from_model(VariogramModel::parse("sph(sill=2,range=50)"), 100.0, 20);
  VariogramFitOptions o;
  o.hold_range = {true};
  EXPECT_THROW(fit_variogram(b.h, b.g, b.n, {{ModelKind::Spherical, 1.0, 0.0, 0.5}}, o), ArgumentError);  // no value
  o.hold_range = {true, false};
  EXPECT_THROW(fit_variogram(b.h, b.g, b.n, {{ModelKind::Spherical, 1.0, 10.0, 0.5}}, o), ArgumentError);  // size
  o.hold_range = {true};
  o.hold_sill = {true};
  o.nugget = NuggetMode::None;
  EXPECT_THROW(fit_variogram(b.h, b.g, b.n, {{ModelKind::Spherical, 1.0, 10.0, 0.5}}, o), ArgumentError);  // all held
}

}  // namespace
}  // namespace errfield
