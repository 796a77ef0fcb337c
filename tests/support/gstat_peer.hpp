#pragma once
// The R gstat cross-checks in tests/peers/ (gstat_block, gstat_external_drift, gstat_cokriging,
// gstat_lmc): each suite runs its R script once into a temporary folder and compares errfield with
// the CSVs the script wrote there; without Rscript, gstat or sp the suite is skipped with a message.

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include <Eigen/Core>

#include "errfield/csv_table.hpp"

namespace errfield::testing {

/// Why a gstat suite is skipped.
inline constexpr const char* kGstatMissing =
    "Rscript with gstat and sp not found; install r-cran-gstat to run this cross-check";

/// One gstat peer script's run: start() in SetUpTestSuite, finish() in TearDownTestSuite, and in
/// SetUp: `if (!run.available()) GTEST_SKIP() << kGstatMissing; ASSERT_TRUE(run.succeeded())`.
class GstatScriptRun {
 public:
  /// Runs `Rscript <script> <folder>` into a fresh temporary folder named `<name>_<pid>` when
  /// Rscript with gstat and sp is installed.
  void start(const std::string& script, const std::string& name) {
    available_ = std::system("Rscript -e 'suppressPackageStartupMessages({library(gstat); library(sp)})' "
                             ">/dev/null 2>&1") == 0;
    if (!available_) return;
    root_ = std::filesystem::temp_directory_path() / (name + "_" + std::to_string(::getpid()));
    std::filesystem::remove_all(root_);
    std::filesystem::create_directories(root_);
    const std::string cmd = "Rscript '" + script + "' '" + root_.string() + "'";
    succeeded_ = std::system(cmd.c_str()) == 0;
  }
  /// Removes the folder.
  void finish() {
    std::error_code ec;
    if (!root_.empty()) std::filesystem::remove_all(root_, ec);
  }
  bool available() const { return available_; }
  bool succeeded() const { return succeeded_; }
  const std::filesystem::path& root() const { return root_; }
  /// The path of a file in the folder.
  std::string file(const std::string& name) const { return (root_ / name).string(); }

 private:
  bool available_ = false, succeeded_ = false;
  std::filesystem::path root_;
};

/// The named numeric columns of a CSV file, in that order.
inline Eigen::MatrixXd csv_columns(const std::string& path, const std::vector<std::string>& names) {
  return CsvTable::read(path).numeric_columns(names);
}

/// Per target (rows of `targets`), whether its nmax-th and (nmax+1)-th nearest samples (rows of
/// `samples`) are at the same distance (relative 1e-9): the neighbourhood is then a tie that gstat
/// and errfield may break differently, so a comparison leaves the target out. Brute force.
inline std::vector<bool> tied_neighbourhoods(const Eigen::MatrixXd& samples, const Eigen::MatrixXd& targets,
                                             std::size_t nmax) {
  std::vector<bool> tied(static_cast<std::size_t>(targets.rows()), false);
  for (Eigen::Index t = 0; t < targets.rows(); ++t) {
    std::vector<double> d;
    for (Eigen::Index i = 0; i < samples.rows(); ++i) d.push_back((samples.row(i) - targets.row(t)).norm());
    std::sort(d.begin(), d.end());
    tied[static_cast<std::size_t>(t)] = std::abs(d[nmax] - d[nmax - 1]) <= 1e-9 * d[nmax];
  }
  return tied;
}

}  // namespace errfield::testing
