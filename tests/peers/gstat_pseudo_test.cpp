// Cross-check of `errfield variogram --pseudo` and `fit-variogram --lmc` on its output against R
// gstat (tests/peers/gstat_pseudo.R, one R run for the suite), through the CLI:
//  - fulmar (gstat's data: 1998 and 1999 surveys, never co-located) with gstat's default bins
//    (each variogram its own: a direct one its variable's, the pseudo cross-variogram f98.f99 the
//    later variable's) and with cutoff 100000, width 7500 (cutoff not a multiple of width: the last
//    bin ends at the cutoff): the same non-empty bins per id, np exactly, dist and gamma to 1e-12
//    relative (the issue asks 1e-9);
//  - a SIMULATED set whose second variable shares 5 locations with the first: gstat's separate
//    estimate at lag 0 (np 5, dist 0) and the other bins;
//  - fit.lmc(cw, g, vgm(1, "Sph", 60000, 1)) against fit-variogram --lmc --lmc-method gstat on our
//    CSV: every partial sill to 1e-8 of the largest.
// Skipped with a message when Rscript, gstat or sp is missing.

#include <cmath>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "errfield/csv_table.hpp"
#include "support/cli_harness.hpp"
#include "support/gstat_peer.hpp"

namespace errfield {
namespace gstat_pseudo_test {

using errfield::testing::run_errfield;

class GstatPseudo : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { gstat_.start(ERRFIELD_SOURCE_DIR "/tests/peers/gstat_pseudo.R", "errfield_gstat_pseudo"); }
  static void TearDownTestSuite() { gstat_.finish(); }
  void SetUp() override {
    if (!gstat_.available()) GTEST_SKIP() << errfield::testing::kGstatMissing;
    ASSERT_TRUE(gstat_.succeeded()) << "tests/peers/gstat_pseudo.R failed";
  }
  static std::string file(const std::string& name) { return gstat_.file(name); }
  static void run(std::vector<std::string> args) {
    const auto r = run_errfield(args, gstat_.root());
    ASSERT_EQ(r.exit_code, 0) << r.output();
  }
  static inline errfield::testing::GstatScriptRun gstat_;
};

struct Bin {
  double np, dist, gamma;
};

// id -> non-empty bins, the lag-0 row first (gstat writes it after the others).
std::map<std::string, std::vector<Bin>> by_id(const std::string& path, const char* np, const char* dist) {
  const CsvTable t = CsvTable::read(path);
  std::map<std::string, std::vector<Bin>> out;
  for (std::size_t r = 0; r < t.row_count(); ++r) {
    const double n = t.numeric_cell(r, t.column_index(np));
    if (n == 0.0) continue;
    const Bin b{n, t.numeric_cell(r, t.column_index(dist)), t.numeric_cell(r, t.column_index("gamma"))};
    auto& v = out[t.row(r)[t.column_index("id")]];
    if (b.dist == 0.0) v.insert(v.begin(), b);
    else v.push_back(b);
  }
  return out;
}

void expect_same_variograms(const std::string& ours, const std::string& theirs, std::size_t ids) {
  const auto o = by_id(ours, "pairs", "lag_mean"), t = by_id(theirs, "np", "dist");
  ASSERT_EQ(o.size(), ids);
  ASSERT_EQ(t.size(), ids);
  for (const auto& [id, bins] : t) {
    ASSERT_TRUE(o.count(id)) << id;
    const auto& mine = o.at(id);
    ASSERT_EQ(mine.size(), bins.size()) << id;
    for (std::size_t k = 0; k < bins.size(); ++k) {
      SCOPED_TRACE(id + " bin " + std::to_string(k));
      EXPECT_EQ(mine[k].np, bins[k].np);
      EXPECT_NEAR(mine[k].dist, bins[k].dist, 1e-12 * bins[k].dist);
      EXPECT_NEAR(mine[k].gamma, bins[k].gamma, 1e-12 * std::fabs(bins[k].gamma));
    }
  }
}

TEST_F(GstatPseudo, DefaultBinsMatchGstatsPseudoVariogramOnFulmar) {
  run({"variogram", "--input", file("fulmar.csv"), "--coords", "x,y", "--value", "f98,f99", "--pseudo", "--out",
       file("ours_default.csv")});
  expect_same_variograms(file("ours_default.csv"), file("default.csv"), 3);
}

TEST_F(GstatPseudo, CutoffAndWidthMatchGstatsBins) {
  run({"variogram", "--input", file("fulmar.csv"), "--coords", "x,y", "--value", "f98,f99", "--pseudo", "--cutoff", "100000",
       "--width", "7500", "--out", file("ours_cw.csv")});
  expect_same_variograms(file("ours_cw.csv"), file("cw.csv"), 3);
  // The last bin ends at the cutoff, not at 14 x 7500 = 105000.
  const CsvTable t = CsvTable::read(file("ours_cw.csv"));
  EXPECT_EQ(t.numeric_cell(t.row_count() - 1, t.column_index("lag_hi")), 100000.0);
}

TEST_F(GstatPseudo, LagZeroPairsGetGstatsSeparateEstimate) {
  run({"variogram", "--input", file("mixed.csv"), "--coords", "x,y", "--value", "a,b", "--pseudo", "--cutoff", "60", "--width",
       "20", "--out", file("ours_mixed.csv")});
  expect_same_variograms(file("ours_mixed.csv"), file("mixed_vario.csv"), 3);
  const auto o = by_id(file("ours_mixed.csv"), "pairs", "lag_mean");
  ASSERT_FALSE(o.at("a.b").empty());
  EXPECT_EQ(o.at("a.b").front().dist, 0.0);
  EXPECT_EQ(o.at("a.b").front().np, 5.0);
}

TEST_F(GstatPseudo, LmcFitOfPseudoVariogramsMatchesFitLmc) {
  run({"variogram", "--input", file("fulmar.csv"), "--coords", "x,y", "--value", "f98,f99", "--pseudo", "--cutoff", "100000",
       "--width", "7500", "--out", file("ours_cw_fit.csv")});
  run({"fit-variogram", "--lmc", "--lmc-method", "gstat", "--input", file("ours_cw_fit.csv"), "--value", "f98,f99", "--model",
       "nug(1)+sph(1,60000)", "--out", file("lmc.json")});
  nlohmann::json j;
  std::ifstream(file("lmc.json")) >> j;
  const CsvTable g = CsvTable::read(file("fit.csv"));
  ASSERT_EQ(g.row_count(), 6u);
  double largest = 0.0;
  for (const auto& s : j["structures"])
    for (const auto& row : s["sills"])
      for (const auto& v : row) largest = std::max(largest, std::fabs(v.get<double>()));
  for (std::size_t r = 0; r < g.row_count(); ++r) {
    const std::string id = g.row(r)[g.column_index("id")];
    const auto k = static_cast<std::size_t>(g.numeric_cell(r, g.column_index("structure")));
    const int a = id == "f99" ? 1 : 0, b = id == "f98" ? 0 : 1;
    EXPECT_NEAR(j["structures"][k]["sills"][a][b].get<double>(), g.numeric_cell(r, g.column_index("psill")), 1e-8 * largest)
        << id << " structure " << k;
  }
  // gstat's own data frame (id, np, dist, gamma) is read the same way.
  run({"fit-variogram", "--lmc", "--lmc-method", "gstat", "--input", file("cw.csv"), "--value", "f98,f99", "--model",
       "nug(1)+sph(1,60000)", "--out", file("lmc_gstat.json")});
  nlohmann::json k;
  std::ifstream(file("lmc_gstat.json")) >> k;
  for (std::size_t s = 0; s < 2; ++s)
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 2; ++b)
        EXPECT_NEAR(k["structures"][s]["sills"][a][b].get<double>(), j["structures"][s]["sills"][a][b].get<double>(),
                    1e-10 * largest);
}

}  // namespace gstat_pseudo_test
}  // namespace errfield
