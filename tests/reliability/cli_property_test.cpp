// Property-based tests over the CLI (issue 12, "Beyond the list"): random valid and invalid
// command lines and input files from a fixed seed, each run through the real `errfield`, each
// checked against the promises the tool makes whatever the input:
//   1. the exit status is one --help documents (0, 1, 2, 3), never 70 or a signal; a defect put
//      into a valid input gives exactly its class (2 for bad input or usage, 1 for an output that
//      cannot be written);
//   2. a failed run leaves the previous output byte-for-byte and no temporary file;
//   3. no output (file or standard output) holds a non-finite number: no nan/inf cell in a CSV,
//      no null or non-finite number in a JSON;
//   4. a successful run gives byte-identical outputs and console output with 1 and 2 threads.
// The cases are small (tens of rows), so the whole suite stays within seconds; a failing case is
// printed as the command line and its input files are kept in the failure message's directory.
// The data are SIMULATED (random, from the seed).

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "support/cli_test_common.hpp"

namespace errfield {
namespace cli_property_test {

using namespace testing::cli_common;
namespace fs = std::filesystem;

constexpr const char* kOld = "previous output\n";
constexpr std::uint64_t kSeed = 20261123;
constexpr int kCases = 60;

std::string num(double v) {
  std::ostringstream s;
  s.precision(9);
  s << v;
  return s.str();
}

// One generated case: the files to write, the command, what must happen.
struct Case {
  std::vector<std::pair<std::string, std::string>> files;
  std::vector<std::string> args;
  std::string out;           // output file the command writes ("" = standard output)
  int expected_exit = 0;     // -1: any documented status (0..3)
  std::string defect;        // what was broken, for the failure message
};

class Generator {
 public:
  explicit Generator(std::uint64_t seed) : rng_(seed) {}

  double uniform(double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng_); }
  int integer(int a, int b) { return std::uniform_int_distribution<int>(a, b)(rng_); }
  bool chance(double p) { return uniform(0, 1) < p; }
  template <class T>
  const T& pick(const std::vector<T>& v) { return v[static_cast<std::size_t>(integer(0, static_cast<int>(v.size()) - 1))]; }

  // Scattered 3-D samples x,y,z,v (distinct locations), a smooth field plus noise.
  std::string samples(int n) {
    std::string s = "x,y,z,v\n";
    for (int i = 0; i < n; ++i) {
      const double x = uniform(0, 1000), y = uniform(0, 1000), z = uniform(0, 1000);
      s += num(x) + "," + num(y) + "," + num(z) + "," + num(std::sin(x / 300) + 0.001 * y + uniform(-0.05, 0.05)) + "\n";
    }
    return s;
  }
  // A complete regular grid k^3 with spacing h (idw-grid's input).
  std::string grid(int k, double h) {
    std::string s = "x,y,z,v\n";
    for (int c = 0; c < k; ++c)
      for (int b = 0; b < k; ++b)
        for (int a = 0; a < k; ++a) s += num(a * h) + "," + num(b * h) + "," + num(c * h) + "," + num(uniform(-1, 1)) + "\n";
    return s;
  }
  std::string targets(int n, double hi) {
    std::string s = "x,y,z\n";
    for (int i = 0; i < n; ++i) s += num(uniform(0, hi)) + "," + num(uniform(0, hi)) + "," + num(uniform(0, hi)) + "\n";
    return s;
  }
  std::string joints(int n) {
    std::string s = "q1,q2,q3,q4,q5,q6\n";
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < 6; ++j) s += (j ? "," : "") + num(uniform(-30, 30));
      s += "\n";
    }
    return s;
  }

  Case valid_case() {
    Case c;
    const int kind = integer(0, 7);
    const std::string model = pick<std::string>({"sph", "exp", "gau"}) + "(sill=" + num(uniform(0.2, 2)) +
                              ",range=" + num(uniform(200, 1500)) + ")+nug(" + num(uniform(0.001, 0.05)) + ")";
    switch (kind) {
      case 0: {  // variogram
        c.files = {{"s.csv", samples(integer(5, 40))}};
        const double w = uniform(50, 400);
        c.args = {"variogram", "--input", "s.csv", "--coords", "x,y,z", "--value", "v",
                  "--bins", "0:" + num(w * integer(2, 8)) + ":" + num(w)};
        if (chance(0.3)) c.args.insert(c.args.end(), {"--estimator", "cressie"});
        if (chance(0.3)) c.args.insert(c.args.end(), {"--subsample", num(uniform(0.3, 1)), "--seed", std::to_string(integer(0, 99))});
        break;
      }
      case 1: {  // interpolate idw
        c.files = {{"s.csv", samples(integer(3, 40))}, {"t.csv", targets(integer(1, 30), 1000)}};
        c.args = {"interpolate", "--method", "idw", "--samples", "s.csv", "--targets", "t.csv", "--coords", "x,y,z",
                  "--value", "v"};
        if (chance(0.5)) c.args.insert(c.args.end(), {"--neighbors", std::to_string(integer(1, 8))});
        if (chance(0.5)) c.args.insert(c.args.end(), {"--power", num(uniform(0.5, 4))});
        break;
      }
      case 2: {  // interpolate idw-grid
        const int k = integer(2, 5);
        const double h = uniform(10, 300);
        c.files = {{"s.csv", grid(k, h)}, {"t.csv", targets(integer(1, 30), (k - 1) * h)}};
        c.args = {"interpolate", "--method", "idw-grid", "--samples", "s.csv", "--targets", "t.csv", "--coords", "x,y,z",
                  "--value", "v"};
        break;
      }
      case 3: {  // interpolate kriging (dense or local)
        c.files = {{"s.csv", samples(integer(6, 40))}, {"t.csv", targets(integer(1, 30), 1000)}};
        c.args = {"interpolate", "--method", "kriging", "--samples", "s.csv", "--targets", "t.csv", "--coords", "x,y,z",
                  "--value", "v", "--model", model};
        if (chance(0.4)) c.args.insert(c.args.end(), {"--backend", "local", "--neighbors", std::to_string(integer(4, 10))});
        break;
      }
      case 4: {  // cv
        c.files = {{"s.csv", samples(integer(6, 40))}};
        c.args = {"cv", "--samples", "s.csv", "--coords", "x,y,z", "--value", "v"};
        if (chance(0.5)) c.args.insert(c.args.end(), {"--method", "kriging", "--model", model});
        else c.args.insert(c.args.end(), {"--method", "idw"});
        if (chance(0.5)) c.args.insert(c.args.end(), {"--folds", std::to_string(integer(2, 5)), "--seed", std::to_string(integer(0, 9))});
        break;
      }
      case 5: {  // fit-variogram on a synthetic empirical variogram
        // Only the columns fit-variogram reads: a defect put into an unread column would rightly pass.
        std::string v = "lag_mean,gamma,pairs\n";
        const double sill = uniform(0.2, 2), range = uniform(200, 1500), w = uniform(50, 200);
        for (int b = 0; b < integer(4, 12); ++b) {
          const double h = (b + 0.5) * w;
          const double g = sill * (1 - std::exp(-3 * h / range)) + uniform(0, 0.05);
          v += num(h) + "," + num(g) + "," + std::to_string(integer(5, 200)) + "\n";
        }
        c.files = {{"v.csv", v}};
        c.args = {"fit-variogram", "--input", "v.csv", "--model", pick<std::string>({"sph", "exp", "gau"})};
        c.out = "m.json";
        c.args.insert(c.args.end(), {"--out", c.out});
        return c;
      }
      case 6: {  // fk
        c.files = {{"q.csv", joints(integer(1, 20))}};
        c.args = {"fk", "--input", "q.csv"};
        break;
      }
      default: {  // simulate (a small cube)
        c.args = {"simulate", "--seed", std::to_string(integer(0, 999)), "--cube", "750,-250,350,500", "--step",
                  pick<std::string>({"250", "500"})};
        if (chance(0.5)) c.args.insert(c.args.end(), {"--measure", "distances"});
        break;
      }
    }
    c.out = "o.csv";
    c.args.insert(c.args.end(), {"--out", c.out});
    return c;
  }

  // A valid case with one defect; its expected exit status.
  Case invalid_case() {
    Case c = valid_case();
    const int defect = integer(0, 8);  // 6, 7, 8: an option value
    auto input = [&]() -> std::pair<std::string, std::string>& { return c.files[static_cast<std::size_t>(integer(0, static_cast<int>(c.files.size()) - 1))]; };
    if (c.files.empty() && defect <= 2) {
      c.args.insert(c.args.end(), {"--step", "-5"});
      c.defect = "--step -5";
      c.expected_exit = 2;
      return c;
    }
    switch (defect) {
      case 0:
      case 1: {  // one cell of a data row (not the header) replaced by something that is no number
        auto& f = input();
        std::vector<std::string> lines;
        std::istringstream in(f.second);
        for (std::string l; std::getline(in, l);) lines.push_back(l);
        const std::size_t row = static_cast<std::size_t>(integer(1, static_cast<int>(lines.size()) - 1));
        std::vector<std::string> cells;
        std::istringstream cs(lines[row]);
        for (std::string cell; std::getline(cs, cell, ',');) cells.push_back(cell);
        const std::string bad = pick<std::string>({"abc", "nan", "1e999", "-inf", ""});
        cells[static_cast<std::size_t>(integer(0, static_cast<int>(cells.size()) - 1))] = bad;
        lines[row].clear();
        for (std::size_t k = 0; k < cells.size(); ++k) lines[row] += (k ? "," : "") + cells[k];
        f.second.clear();
        for (const auto& l : lines) f.second += l + "\n";
        c.defect = f.first + ":" + std::to_string(row + 1) + ": cell '" + bad + "'";
        c.expected_exit = 2;
        break;
      }
      case 2: {  // a row with one cell too many
        auto& f = input();
        const std::size_t first = f.second.find('\n') + 1;
        f.second += f.second.substr(first, f.second.find('\n', first) - first) + ",7\n";
        c.defect = f.first + ": a row with an extra cell";
        c.expected_exit = 2;
        break;
      }
      case 3: {  // an input that does not exist
        for (std::size_t i = 1; i < c.args.size(); ++i)
          if (!c.files.empty() && c.args[i] == c.files.front().first) {
            c.args[i] = "missing.csv";
            break;
          }
        if (c.files.empty()) c.args.insert(c.args.end(), {"--robot", "missing.json"});
        c.defect = "missing input";
        c.expected_exit = 2;
        break;
      }
      case 4: {  // an output in a directory that does not exist
        c.args.back() = "no_dir/" + c.out;
        c.defect = "output directory missing";
        c.expected_exit = 1;
        break;
      }
      case 5: {  // an option that does not exist
        c.args.insert(c.args.end(), {"--frobnicate", "1"});
        c.defect = "unknown option";
        c.expected_exit = 2;
        break;
      }
      default: {  // an option value out of its domain (several were accepted silently before issue 12)
        const std::string cmd = c.args[0];
        std::vector<std::vector<std::string>> choices;
        if (cmd == "interpolate" || cmd == "cv")
          choices = {{"--neighbors", "-3"}, {"--neighbors", "0"}, {"--neighbors", "x"}, {"--power", "-1"}};
        else if (cmd == "variogram")
          choices = {{"--subsample", "0"}, {"--subsample", "1.5"}, {"--subsample", "nan"}, {"--seed", "-1"},
                     {"--bins", "5:1:1"}};
        else if (cmd == "fit-variogram")
          choices = {{"--range-max", "0"}, {"--range-max", "-5"}, {"--range-max", "nan"}, {"--nu", "1.5"}};
        else if (cmd == "simulate")
          choices = {{"--seed", "-1"}, {"--step", "7"}, {"--step", "-5"}};
        else
          choices = {{"--frame", "nowhere"}, {"--robot", "q.csv"}};
        const auto& extra = pick(choices);
        c.args.insert(c.args.end(), extra.begin(), extra.end());
        c.defect = "option value " + extra[0] + " " + extra[1];
        c.expected_exit = 2;
        break;
      }
    }
    return c;
  }

 private:
  std::mt19937_64 rng_;
};

// Promise 3 for a CSV text: no cell reads as NaN or infinity.
std::string non_finite_cell(const std::string& csv) {
  std::istringstream in(csv);
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    std::istringstream cells(line);
    std::string cell;
    while (std::getline(cells, cell, ',')) {
      std::string lower;
      for (char ch : cell) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
      if (lower.find("nan") != std::string::npos || lower.find("inf") != std::string::npos)
        return "line " + std::to_string(n) + ": '" + cell + "'";
    }
  }
  return {};
}

// Promise 3 for JSON: every number finite, no null.
std::string non_finite_json(const nlohmann::json& j, const std::string& path = "") {
  if (j.is_null()) return path + " is null";
  if (j.is_number_float() && !std::isfinite(j.get<double>())) return path + " is not finite";
  if (j.is_object())
    for (auto it = j.begin(); it != j.end(); ++it)
      if (auto e = non_finite_json(it.value(), path + "." + it.key()); !e.empty()) return e;
  if (j.is_array())
    for (std::size_t i = 0; i < j.size(); ++i)
      if (auto e = non_finite_json(j[i], path + "[" + std::to_string(i) + "]"); !e.empty()) return e;
  return {};
}

// Runs one case in a fresh directory with `threads` OpenMP threads; returns the result and the
// output's bytes.
struct Outcome {
  CliResult result;
  std::string output;
  std::vector<std::string> entries;
};

Outcome run_case(const Case& c, int threads, const std::string& tag) {
  ScratchDir dir;
  const fs::path sub = dir.path() / tag;
  fs::create_directory(sub);
  for (const auto& [name, text] : c.files) {
    std::ofstream(sub / name, std::ios::binary) << text;
  }
  if (!c.out.empty()) std::ofstream(sub / c.out, std::ios::binary) << kOld;
  Outcome o;
  o.result = run_errfield(c.args, sub, {"OMP_NUM_THREADS=" + std::to_string(threads)});
  if (!c.out.empty()) o.output = ScratchDir::slurp(sub / c.out);
  for (const auto& e : fs::directory_iterator(sub)) o.entries.push_back(e.path().filename().string());
  std::sort(o.entries.begin(), o.entries.end());
  return o;
}

TEST(CliProperties, RandomValidAndInvalidCommandLinesKeepThePromises) {
  Generator gen(kSeed);
  int valid = 0, invalid = 0;
  for (int i = 0; i < kCases; ++i) {
    const bool bad = gen.chance(0.45);
    const Case c = bad ? gen.invalid_case() : gen.valid_case();
    (bad ? invalid : valid)++;
    const std::string what = "case " + std::to_string(i) + ": " + testing::command_line(c.args) +
                             (c.defect.empty() ? "" : "  [defect: " + c.defect + "]");
    const Outcome one = run_case(c, 1, "t1");
    const CliResult& r = one.result;
    if (std::getenv("ERRFIELD_PROPERTY_VERBOSE")) std::cout << "exit " << r.exit_code << "  " << what << "\n";
    // 1. a documented exit status, and the one the defect calls for
    ASSERT_EQ(r.signal, 0) << what << "\nkilled by signal " << r.signal << "\n" << r.err;
    ASSERT_TRUE(r.exit_code >= 0 && r.exit_code <= 3) << what << "\nexit " << r.exit_code << "\n" << r.err;
    if (c.expected_exit >= 0) {
      EXPECT_EQ(r.exit_code, c.expected_exit) << what << "\n" << r.err;
    }
    // 2. a failure leaves the previous output and nothing else
    std::vector<std::string> expected_entries;
    for (const auto& f : c.files) expected_entries.push_back(f.first);
    if (!c.out.empty()) expected_entries.push_back(c.out);
    std::sort(expected_entries.begin(), expected_entries.end());
    EXPECT_EQ(one.entries, expected_entries) << what;
    if (r.exit_code != 0) {
      if (!c.out.empty()) {
        EXPECT_EQ(one.output, kOld) << what << ": a failed run changed the output";
      }
      EXPECT_FALSE(r.err.empty()) << what << ": failed without a message";
      continue;
    }
    // 3. finite numbers only
    if (c.out.size() > 5 && c.out.substr(c.out.size() - 5) == ".json") {
      const auto j = nlohmann::json::parse(one.output, nullptr, false);
      ASSERT_FALSE(j.is_discarded()) << what << ": output is not JSON";
      EXPECT_EQ(non_finite_json(j), "") << what;
    } else if (!c.out.empty()) {
      EXPECT_NE(one.output, kOld) << what << ": exit 0 but the output was not written";
      EXPECT_EQ(non_finite_cell(one.output), "") << what;
    }
    EXPECT_EQ(non_finite_cell(r.out), "") << what << " (standard output)";
    // 4. the same bytes with 2 threads
    const Outcome two = run_case(c, 2, "t2");
    EXPECT_EQ(two.result.exit_code, 0) << what;
    EXPECT_TRUE(one.output == two.output) << what << ": output differs between 1 and 2 threads";
    EXPECT_TRUE(r.out == two.result.out) << what << ": console output differs between 1 and 2 threads";
  }
  std::cout << "[ property ] " << valid << " valid and " << invalid << " invalid command lines (seed " << kSeed
            << ")\n";
  // The generator must produce both kinds (a silent change to it would otherwise test nothing).
  EXPECT_GE(valid, kCases / 4);
  EXPECT_GE(invalid, kCases / 4);
}

}  // namespace
}  // namespace errfield
