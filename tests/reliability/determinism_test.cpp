// Determinism: every command's output files are byte-identical for the same input and seed, with
// OMP_NUM_THREADS=1 and 2, run after run (three runs: 1 thread, 2 threads, 2 threads again).
// Inputs are generated here (simulated data, seeded), small enough to keep the suite fast but
// large enough that the parallel loops split the work.

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "support/cli_harness.hpp"

namespace errfield {
namespace determinism_test {

using testing::ScratchDir;

// Random 3-D samples with a smooth field plus noise (simulated), seeded.
std::string samples_csv(std::size_t n, unsigned seed, double extent = 1000.0) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, extent);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::string s = "x,y,z,v,w\n";
  for (std::size_t i = 0; i < n; ++i) {
    const double x = u(rng), y = u(rng), z = u(rng);
    const double v = std::sin(x / 150) * std::cos(y / 210) + 0.0004 * z + noise(rng);
    const double w = std::cos(z / 170) + noise(rng);
    s += std::to_string(x) + "," + std::to_string(y) + "," + std::to_string(z) + "," + std::to_string(v) + "," +
         std::to_string(w) + "\n";
  }
  return s;
}

std::string targets_csv(std::size_t n, unsigned seed, double extent = 1000.0) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, extent);
  std::string s = "x,y,z\n";
  for (std::size_t i = 0; i < n; ++i)
    s += std::to_string(u(rng)) + "," + std::to_string(u(rng)) + "," + std::to_string(u(rng)) + "\n";
  return s;
}

std::string grid_csv(int nodes_per_axis, double step) {
  std::string s = "x,y,z,v\n";
  for (int i = 0; i < nodes_per_axis; ++i)
    for (int j = 0; j < nodes_per_axis; ++j)
      for (int k = 0; k < nodes_per_axis; ++k) {
        const double x = i * step, y = j * step, z = k * step;
        s += std::to_string(x) + "," + std::to_string(y) + "," + std::to_string(z) + "," +
             std::to_string(std::sin(x / 300) + std::cos(y / 400) * z / 1000) + "\n";
      }
  return s;
}

struct Case {
  std::string name;
  std::function<void(const ScratchDir&)> setup;  // writes the inputs
  std::vector<std::string> args;                 // the command; outputs named below
  std::vector<std::string> outputs;
  bool same_stdout = false;  // also compare what it prints (not for commands that print a run time)
};

void PrintTo(const Case& c, std::ostream* os) { *os << c.name; }

class Determinism : public ::testing::TestWithParam<Case> {};

TEST_P(Determinism, SameBytesForOneAndTwoThreadsRunAfterRun) {
  const Case& c = GetParam();
  ScratchDir dir;
  c.setup(dir);
  std::vector<std::vector<std::string>> runs;
  for (const char* threads : {"OMP_NUM_THREADS=1", "OMP_NUM_THREADS=2", "OMP_NUM_THREADS=2"}) {
    const auto r = testing::run_errfield(c.args, dir.path(), {threads});
    ASSERT_EQ(r.exit_code, 0) << testing::command_line(c.args) << " with " << threads << ":\n" << r.err;
    std::vector<std::string> files;
    if (c.same_stdout) files.push_back(r.out);
    for (const auto& o : c.outputs) {
      files.push_back(dir.read(o));
      ASSERT_FALSE(files.back().empty()) << o;
      std::filesystem::remove(dir.path() / o);  // the next run must write it again
    }
    runs.push_back(std::move(files));
  }
  std::vector<std::string> names = c.outputs;
  if (c.same_stdout) names.insert(names.begin(), "stdout");
  for (std::size_t k = 0; k < names.size(); ++k) {
    EXPECT_TRUE(runs[0][k] == runs[1][k]) << names[k] << " differs between 1 and 2 threads";
    EXPECT_TRUE(runs[1][k] == runs[2][k]) << names[k] << " differs between two runs with 2 threads";
  }
}

std::vector<Case> cases() {
  auto scattered = [](std::size_t n) {
    return [n](const ScratchDir& d) {
      d.write("s.csv", samples_csv(n, 11));
      d.write("t.csv", targets_csv(400, 12));
    };
  };
  const std::vector<std::string> interp{"interpolate", "--samples", "s.csv", "--targets", "t.csv",
                                        "--coords",    "x,y,z",     "--value", "v", "--out", "p.csv"};
  auto with = [](std::vector<std::string> base, std::vector<std::string> extra) {
    base.insert(base.end(), extra.begin(), extra.end());
    return base;
  };
  std::vector<Case> cs{
      {"variogram", scattered(4000),
       {"variogram", "--input", "s.csv", "--coords", "x,y,z", "--value", "v", "--bins", "0:1000:50", "--out", "g.csv"},
       {"g.csv"}},
      {"variogram_vector_cressie", scattered(3000),
       {"variogram", "--input", "s.csv", "--coords", "x,y,z", "--value", "v,w", "--bins", "0:1000:100", "--estimator",
        "cressie", "--per-component", "--out", "g.csv"},
       {"g.csv"}},
      {"variogram_subsample", scattered(4000),
       {"variogram", "--input", "s.csv", "--coords", "x,y", "--value", "v", "--bins", "0:1000:100", "--subsample",
        "0.3", "--seed", "5", "--out", "g.csv"},
       {"g.csv"}},
      {"interpolate_idw_grid",
       [](const ScratchDir& d) {
         d.write("s.csv", grid_csv(6, 200));
         d.write("t.csv", targets_csv(5000, 3, 1000));
       },
       with(interp, {"--method", "idw-grid"}),
       {"p.csv"}},
      {"interpolate_idw", scattered(3000), with(interp, {"--method", "idw", "--neighbors", "12"}), {"p.csv"}},
      {"interpolate_kriging_dense", scattered(600),
       with(interp, {"--method", "kriging", "--model", "sph(sill=0.5,range=400)+nug(0.0001)"}),
       {"p.csv"}},
      {"interpolate_kriging_universal", scattered(600),
       with(interp, {"--method", "kriging", "--kind", "universal1", "--model", "exp(sill=0.5,range=200)+nug(0.0001)"}),
       {"p.csv"}},
      {"interpolate_kriging_local", scattered(3000),
       with(interp, {"--method", "kriging", "--backend", "local", "--neighbors", "24", "--model",
                     "sph(sill=0.5,range=400)+nug(0.0001)"}),
       {"p.csv"}},
      {"interpolate_kriging_sparse", scattered(2000),
       with(interp, {"--method", "kriging", "--backend", "sparse", "--model", "wen(sill=0.5,range=150)+nug(0.0001)"}),
       {"p.csv"}},
      // Conditional simulation: random numbers in one order, parallel loops over independent items.
      {"interpolate_kriging_simulations_sequential", scattered(300),
       with(interp, {"--method", "kriging", "--model", "sph(sill=0.5,range=400)+nug(0.0001)", "--simulations", "4",
                     "--seed", "9", "--simulation-method", "sequential", "--simulation-neighbours", "20"}),
       {"p.csv"}},
      {"interpolate_kriging_simulations_local", scattered(600),
       with(interp, {"--method", "kriging", "--backend", "local", "--neighbors", "16", "--model",
                     "exp(sill=0.5,range=200)+nug(0.0001)", "--simulations", "3", "--seed", "9"}),
       {"p.csv"}},
      {"interpolate_kriging_auto", scattered(200), with(interp, {"--method", "kriging", "--model", "auto"}), {"p.csv"}},
      // Universal kriging with a quadratic drift (10 terms) and N >= 1000 differed between 1 and
      // 2 threads (Eigen's own parallel products, blocked by thread count): dense and sparse,
      // interpolate and cv.
      {"interpolate_kriging_universal2_dense", scattered(1000),
       with(interp, {"--method", "kriging", "--kind", "universal2", "--model", "exp(sill=0.5,range=200)+nug(0.0001)"}),
       {"p.csv"}},
      {"interpolate_kriging_universal2_sparse", scattered(1200),
       with(interp, {"--method", "kriging", "--kind", "universal2", "--backend", "sparse", "--model",
                     "wen(sill=0.5,range=200)+nug(0.0001)"}),
       {"p.csv"}},
      {"cv_kfold_kriging_universal2", scattered(1250),
       {"cv", "--method", "kriging", "--kind", "universal2", "--samples", "s.csv", "--coords", "x,y,z", "--value", "v",
        "--folds", "5", "--seed", "7", "--model", "exp(sill=0.5,range=200)+nug(0.0001)", "--out", "cv.csv"},
       {"cv.csv"}},
      {"cv_kfold_kriging", scattered(500),
       {"cv", "--method", "kriging", "--samples", "s.csv", "--coords", "x,y,z", "--value", "v", "--folds", "5",
        "--seed", "7", "--model", "sph(sill=0.5,range=400)+nug(0.0001)", "--out", "cv.csv"},
       {"cv.csv"}},
      {"simulate", [](const ScratchDir&) {},
       {"simulate", "--seed", "42", "--step", "250", "--out", "m.csv", "--truth-out", "truth.json"},
       {"m.csv", "truth.json"}},
      {"calibrate",
       [](const ScratchDir& d) {
         // robot.json: the simulated nominal robot with its ball, whose FK the data's x,y,z are.
         const auto r = testing::run_errfield(
             {"simulate", "--seed", "42", "--step", "250", "--out", "data.csv", "--robot-out", "robot.json"}, d.path());
         ASSERT_EQ(r.exit_code, 0) << r.err;
       },
       {"calibrate", "--robot", "robot.json", "--data", "data.csv", "--out", "cal.json", "--report", "cal.txt"},
       {"cal.json", "cal.txt"}},
  };
  // fit-variogram on the variogram of simulated samples; fk and ik on the plan's joints and poses.
  cs.push_back({"fit_variogram",
                [](const ScratchDir& d) {
                  d.write("s.csv", samples_csv(1500, 21));
                  const auto r = testing::run_errfield({"variogram", "--input", "s.csv", "--coords", "x,y,z", "--value",
                                                        "v", "--bins", "0:1000:50", "--out", "g.csv"},
                                                       d.path());
                  ASSERT_EQ(r.exit_code, 0) << r.err;
                },
                {"fit-variogram", "--input", "g.csv", "--model", "sph", "--nugget", "free", "--out", "fit.json"},
                {"fit.json"},
                true});
  auto planned = [](const ScratchDir& d) {
    const auto r = testing::run_errfield(
        {"plan", "--cube", "750,-250,350,250", "--step", "25", "--out", "p.csv"}, d.path());
    ASSERT_EQ(r.exit_code, 0) << r.err;
  };
  cs.push_back({"fk", planned, {"fk", "--input", "p.csv", "--out", "fk.csv"}, {"fk.csv"}, true});
  cs.push_back({"ik", planned, {"ik", "--input", "p.csv", "--out", "ik.csv"}, {"ik.csv"}, true});
  // The pipeline: plan, then fit (every method) and compensate on simulated measurements.
  cs.push_back({"plan", [](const ScratchDir&) {},
                {"plan", "--cube", "750,-250,350,250", "--step", "25", "--samples-out", "s.csv", "--seed", "4", "--out",
                 "p.csv"},
                {"p.csv", "s.csv"},
                true});
  auto measured = [](const ScratchDir& d) {
    for (const std::vector<std::string>& a :
         {std::vector<std::string>{"simulate", "--seed", "42", "--step", "125", "--out", "g.csv", "--robot-out", "robot.json"},
          std::vector<std::string>{"simulate", "--seed", "43", "--sample", "cells", "--step", "125", "--out", "t.csv"}}) {
      const auto r = testing::run_errfield(a, d.path());
      ASSERT_EQ(r.exit_code, 0) << r.err;
    }
  };
  for (const std::string method :
       {"distance-idw", "position-idw", "distance-kriging", "vector-kriging", "kinematic", "kinematic+kriging"}) {
    std::string name = "fit_" + method;
    std::replace(name.begin(), name.end(), '-', '_');
    std::replace(name.begin(), name.end(), '+', '_');
    cs.push_back({name, measured, {"fit", "--robot", "robot.json", "--data", "g.csv", "--method", method, "--out", "m.json"},
                  {"m.json"}, true});
  }
  for (const std::string method : {"vector-kriging", "kinematic+kriging"}) {
    std::string name = "compensate_" + method;
    std::replace(name.begin(), name.end(), '-', '_');
    std::replace(name.begin(), name.end(), '+', '_');
    cs.push_back({name,
                  [measured, method](const ScratchDir& d) {
                    measured(d);
                    const auto r = testing::run_errfield(
                        {"fit", "--robot", "robot.json", "--data", "g.csv", "--method", method, "--out", "m.json"}, d.path());
                    ASSERT_EQ(r.exit_code, 0) << r.err;
                  },
                  {"compensate", "--robot", "robot.json", "--model", "m.json", "--targets", "t.csv", "--out", "j.csv"},
                  {"j.csv"},
                  true});
  }
  // Every file of reproduce, report.html included (it carries no date, run time or thread count);
  // --runs 2 so that the parallel loop over runs splits. Its console summary ends with the run time.
  cs.push_back({"reproduce", [](const ScratchDir&) {},
                {"reproduce", "--runs", "2", "--seed", "5", "--out", "rep"},
                {"rep/table3.csv", "rep/table4.csv", "rep/fig5.csv", "rep/table6.csv", "rep/table6_spread.csv",
                 "rep/table6_points.csv", "rep/table8.csv", "rep/beyond_orientation.csv", "rep/report.html"},
                false});
  return cs;
}

INSTANTIATE_TEST_SUITE_P(Commands, Determinism, ::testing::ValuesIn(cases()),
                         [](const auto& info) { return info.param.name; });

}  // namespace
}  // namespace errfield
