// Cross-check against R gstat's krige() (tests/peers/gstat_krige.R), run at test time on simulated
// data: simple, ordinary and universal (order 1 and 2) kriging, global and with nmax (our local
// back end), for sph, exp and gau with and without nugget. Predictions and variances must agree
// to 1e-6 relative. Skipped with a message when Rscript or gstat is missing.

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "errfield/kriging.hpp"

namespace errfield {
namespace gstat_krige_test {

namespace fs = std::filesystem;
using P3 = Eigen::Vector3d;

bool gstat_available() {
  return std::system("Rscript -e 'suppressPackageStartupMessages(library(gstat))' >/dev/null 2>&1") == 0;
}

struct Case {
  std::string name, model, vgm;
  int order;          // -1 simple, 0 ordinary, 1/2 universal
  std::size_t nmax;   // 0 = global
};

std::string formula(int order) {
  if (order <= 0) return "v ~ 1";
  if (order == 1) return "v ~ x + y + z";
  return "v ~ x + y + z + I(x^2) + I(y^2) + I(z^2) + I(x*y) + I(x*z) + I(y*z)";
}

TEST(GstatKrige, PredictionsAndVariancesAgree) {
  if (!gstat_available()) GTEST_SKIP() << "Rscript with the gstat package not found; install r-cran-gstat to run this cross-check";
  // Simulated data: 80 uniform points in [0,100]^3, smooth trend + sinusoid + noise.
  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> u(0.0, 100.0);
  std::normal_distribution<double> e(0.0, 0.05);
  std::vector<P3> pts, targets;
  std::vector<double> vals;
  for (int i = 0; i < 80; ++i) {
    pts.emplace_back(u(rng), u(rng), u(rng));
    vals.push_back(0.01 * pts.back().x() + std::sin(pts.back().y() / 15.0) + e(rng));
  }
  for (int i = 0; i < 20; ++i) targets.emplace_back(u(rng), u(rng), u(rng));

  const fs::path dir = fs::temp_directory_path() / ("errfield_gstat_krige_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  {
    std::ofstream s(dir / "samples.csv"), t(dir / "targets.csv");
    s.precision(17);
    t.precision(17);
    s << "x,y,z,v\n";
    for (std::size_t i = 0; i < pts.size(); ++i) s << pts[i].x() << ',' << pts[i].y() << ',' << pts[i].z() << ',' << vals[i] << '\n';
    t << "x,y,z\n";
    for (const auto& p : targets) t << p.x() << ',' << p.y() << ',' << p.z() << '\n';
  }
  const double simple_mean = 0.4;
  struct M { const char* ours; const char* gstat; };
  const M models[] = {
      {"sph(sill=0.5,range=60)", "vgm(0.5, 'Sph', 60)"},
      {"sph(sill=0.5,range=60)+nug(0.03)", "vgm(0.5, 'Sph', 60, 0.03)"},
      {"exp(sill=0.5,range=25)", "vgm(0.5, 'Exp', 25)"},
      {"exp(sill=0.5,range=25)+nug(0.03)", "vgm(0.5, 'Exp', 25, 0.03)"},
      {"gau(sill=0.5,range=20)", "vgm(0.5, 'Gau', 20)"},
      {"gau(sill=0.5,range=20)+nug(0.03)", "vgm(0.5, 'Gau', 20, 0.03)"},
  };
  std::vector<Case> cases;
  for (const auto& m : models)
    for (int order : {-1, 0, 1, 2})
      for (std::size_t nmax : {std::size_t{0}, std::size_t{15}}) {
        if (order == 2 && nmax > 0) continue;  // 10 drift terms in 15 neighbours: too few to matter
        cases.push_back({std::string(m.ours) + " order " + std::to_string(order) + " nmax " + std::to_string(nmax),
                         m.ours, m.gstat, order, nmax});
      }
  {
    std::ofstream c(dir / "cases.tsv");
    c << "case\tmodel\tformula\tnmax\tbeta\n";
    for (std::size_t k = 0; k < cases.size(); ++k)
      c << k << '\t' << cases[k].vgm << '\t' << formula(cases[k].order) << '\t'
        << (cases[k].nmax ? std::to_string(cases[k].nmax) : std::string("Inf")) << '\t'
        << (cases[k].order < 0 ? std::to_string(simple_mean) : std::string("NA")) << '\n';
  }
  const std::string cmd = "Rscript '" ERRFIELD_SOURCE_DIR "/tests/peers/gstat_krige.R' '" + (dir / "samples.csv").string() +
                          "' '" + (dir / "targets.csv").string() + "' '" + (dir / "cases.tsv").string() + "' '" +
                          (dir / "out.csv").string() + "'";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  std::map<std::pair<int, int>, std::pair<double, double>> ref;
  {
    std::ifstream in(dir / "out.csv");
    std::string line;
    std::getline(in, line);
    while (std::getline(in, line)) {
      std::stringstream ss(line);
      std::string a, b, c, d;
      std::getline(ss, a, ',');
      std::getline(ss, b, ',');
      std::getline(ss, c, ',');
      std::getline(ss, d, ',');
      ref[{std::stoi(a), std::stoi(b)}] = {std::stod(c), std::stod(d)};
    }
  }
  fs::remove_all(dir);
  ASSERT_EQ(ref.size(), cases.size() * targets.size());

  for (std::size_t k = 0; k < cases.size(); ++k) {
    const auto& cs = cases[k];
    KrigingOptions opt;
    if (cs.order < 0) {
      opt.kind = KrigingKind::Simple;
      opt.simple_mean = {simple_mean};
    } else if (cs.order == 0) {
      opt.kind = KrigingKind::Ordinary;
    } else {
      opt.kind = KrigingKind::Universal;
      opt.drift_order = cs.order;
    }
    if (cs.nmax) {
      opt.backend = KrigingBackend::Local;
      opt.neighbors = cs.nmax;
    }
    const Kriging<P3, double> kr(pts, vals, VariogramModel::parse(cs.model), opt);
    const auto pred = kr.predict(targets);
    ASSERT_TRUE(pred.usable()) << cs.name << ": " << pred.message;
    for (std::size_t t = 0; t < targets.size(); ++t) {
      const auto [gp, gv] = ref.at({static_cast<int>(k), static_cast<int>(t)});
      // 1e-6 relative; predictions near 0 are compared relative to the data's scale (0.1).
      EXPECT_NEAR(pred.mean[t], gp, 1e-6 * std::max(std::abs(gp), 0.1)) << cs.name << ", target " << t;
      EXPECT_NEAR(pred.variance[t], gv, 1e-6 * gv) << cs.name << ", target " << t;
    }
  }
}

}  // namespace
}  // namespace errfield
