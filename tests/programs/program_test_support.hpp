#pragma once
// What the compensate-program tests of every format share: a SIMULATED robot with a kinematic
// model fitted on its readings, where the simulated robot lands in the model's base frame, and a
// program's numbers split from the text between them.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

#include <unistd.h>

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "errfield/csv_table.hpp"
#include "errfield/programs/program_text.hpp"
#include "errfield/robot/inverse_kinematics.hpp"
#include "errfield/robot/kinematics.hpp"
#include "errfield/robot/mdh_model.hpp"
#include "errfield/robot/pose.hpp"
#include "support/cli_harness.hpp"

namespace errfield::programs::program_test_support {

// The numbers of a text and the text between them: two files that differ only in numbers have
// equal "between" parts.
struct Numbers {
  std::vector<std::string> between, numbers;
  std::vector<std::size_t> lines;
};

inline Numbers split_numbers(const std::string& s) {
  static const std::regex number(R"(-?[0-9]+(\.[0-9]*)?([eE][-+]?[0-9]+)?)");
  Numbers n;
  std::size_t at = 0;
  for (auto it = std::sregex_iterator(s.begin(), s.end(), number); it != std::sregex_iterator(); ++it) {
    const auto pos = static_cast<std::size_t>(it->position());
    n.between.push_back(s.substr(at, pos - at));
    n.numbers.push_back(it->str());
    n.lines.push_back(line_of_offset(s, pos));
    at = pos + static_cast<std::size_t>(it->length());
  }
  n.between.push_back(s.substr(at));
  return n;
}

// Simulates `simulate_options` (SIMULATED readings, robot.json, truth.json, config.json, train.csv)
// and fits a kinematic model.json on them in `dir`; returns the first failure, or "".
inline std::string simulate_and_fit(const std::filesystem::path& dir, const std::string& simulate_options) {
  std::filesystem::create_directories(dir);
  for (const std::string& line : {"simulate " + simulate_options +
                                     " --robot-out robot.json --truth-out truth.json --config-out config.json --out train.csv",
                                 std::string("fit --robot robot.json --data train.csv --method kinematic --out model.json")}) {
    const errfield::testing::CliResult r = errfield::testing::run_errfield_line(line, dir);
    if (r.exit_code != 0) return line + ": " + r.output();
  }
  return {};
}

// The commanded joints of the target rows of a simulated readings file.
inline std::vector<robot::JointVector> training_joints(const std::string& csv) {
  const CsvTable t = CsvTable::read(csv);
  std::vector<robot::JointVector> q;
  for (std::size_t i = 0; i < t.row_count(); ++i) {
    if (t.has_column("kind") && t.cell(i, t.column_index("kind")) != "target") continue;
    robot::JointVector v;
    for (int k = 0; k < 6; ++k) v[k] = t.numeric_cell(i, t.column_index("q" + std::to_string(k + 1)));
    q.push_back(v);
  }
  return q;
}

// Where the SIMULATED robot lands, in the frame the model calls the robot base: the simulator's
// world -> tracker (config.json), then the model's registration tracker -> base. (The true base
// error and the tracker's pose are one rigid motion to the readings; only their product is known.)
inline Eigen::Isometry3d base_from_world(const std::filesystem::path& dir) {
  const nlohmann::json config = nlohmann::json::parse(std::ifstream(dir / "config.json"));
  const nlohmann::json& tw = config.at("tracker").at("tracker_from_world");
  const Eigen::Isometry3d tracker_from_world = robot::to_isometry(
      robot::PoseXyzRpy{tw.at("x_mm"), tw.at("y_mm"), tw.at("z_mm"), tw.at("rx_deg"), tw.at("ry_deg"), tw.at("rz_deg")});
  const nlohmann::json model_json = nlohmann::json::parse(std::ifstream(dir / "model.json"));
  const nlohmann::json& rt = model_json.at("registration").at("robot_from_tracker");
  Eigen::Isometry3d robot_from_tracker = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) robot_from_tracker.matrix()(r, c) = rt.at(static_cast<std::size_t>(r)).at(static_cast<std::size_t>(c));
  return robot_from_tracker * tracker_from_world;
}

// `v` with `decimals` digits after the point (how the tests write a program's numbers).
inline std::string fixed(double v, int decimals) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", decimals, v);
  return b;
}

// A suite sharing one SIMULATED robot and a kinematic model fitted on its readings (fitted once per
// suite): `Setup::kDirectory` names the scratch folder, `Setup::kSimulate` the simulate options.
template <class Setup>
class FittedRobotTest : public errfield::testing::CliTest {
 protected:
  static void SetUpTestSuite() {
    shared_ = std::filesystem::temp_directory_path() / (std::string(Setup::kDirectory) + "_" + std::to_string(::getpid()));
    setup_error_ = simulate_and_fit(shared_, Setup::kSimulate);
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(shared_); }
  void SetUp() override { ASSERT_TRUE(setup_error_.empty()) << setup_error_; }
  std::string shared(const std::string& name) const { return (shared_ / name).string(); }
  robot::MdhModel nominal() const { return robot::MdhModel::load(shared("robot.json")); }
  robot::MdhModel truth() const { return robot::MdhModel::load(shared("truth.json")); }
  std::vector<robot::JointVector> training_joints() const { return program_test_support::training_joints(shared("train.csv")); }
  static inline std::filesystem::path shared_;
  static inline std::string setup_error_;
};

// The indices of the numbers that differ between `before` and `after`, which must be equal outside
// their numbers (a test failure names the first piece that is not).
inline std::vector<std::size_t> changed_numbers(const std::string& before, const std::string& after) {
  const Numbers a = split_numbers(before), b = split_numbers(after);
  std::vector<std::size_t> changed;
  if (a.between.size() != b.between.size()) {
    ADD_FAILURE() << "the texts have " << a.numbers.size() << " and " << b.numbers.size() << " numbers";
    return changed;
  }
  for (std::size_t i = 0; i < a.between.size(); ++i)
    if (a.between[i] != b.between[i]) {
      ADD_FAILURE() << "text between numbers changed at piece " << i << ": '" << a.between[i] << "' -> '" << b.between[i] << "'";
      return changed;
    }
  for (std::size_t i = 0; i < a.numbers.size(); ++i)
    if (a.numbers[i] != b.numbers[i]) changed.push_back(i);
  return changed;
}

// Runs each target as written before and after compensation through the controller (nominal IK
// with the program's tool, from the joints it was made from) and the SIMULATED true robot, in the
// model's base frame (base_from_world), and expects every compensated target to land nearer its
// intended position, with an RMS below `max_ratio` of the uncompensated one. Poses in the robot base.
inline void expect_lands_nearer(const robot::MdhModel& controller, const robot::MdhModel& true_robot,
                                const Eigen::Isometry3d& base_from_world, const std::vector<Eigen::Isometry3d>& before,
                                const std::vector<Eigen::Isometry3d>& after, const std::vector<Eigen::Isometry3d>& intended,
                                const std::vector<robot::JointVector>& joints, double max_ratio = 0.2) {
  ASSERT_EQ(before.size(), intended.size());
  ASSERT_EQ(after.size(), intended.size());
  double ss_before = 0, ss_after = 0;
  for (std::size_t i = 0; i < intended.size(); ++i) {
    auto reached = [&](const Eigen::Isometry3d& pose) {
      const robot::IkResult ik = robot::inverse_kinematics(controller, pose, joints[i]);
      EXPECT_TRUE(ik.ok());
      return Eigen::Vector3d(base_from_world * robot::forward_position(true_robot, ik.q_deg));
    };
    const double e0 = (reached(before[i]) - intended[i].translation()).norm();
    const double e1 = (reached(after[i]) - intended[i].translation()).norm();
    ss_before += e0 * e0;
    ss_after += e1 * e1;
    EXPECT_LT(e1, e0) << "target " << i;
  }
  const double n = static_cast<double>(intended.size());
  const double rms_before = std::sqrt(ss_before / n), rms_after = std::sqrt(ss_after / n);
  EXPECT_GT(rms_before, 0.3) << "the simulated robot must have errors to correct";
  EXPECT_LT(rms_after, max_ratio * rms_before) << rms_before << " -> " << rms_after;
}

// The text of 1-based line `line` of `text` (without its line end).
inline std::string line_text(const std::string& text, std::size_t line) {
  std::size_t s = 0;
  for (std::size_t l = 1; l < line; ++l) s = text.find('\n', s) + 1;
  std::string out = text.substr(s, text.find('\n', s) - s);
  if (!out.empty() && out.back() == '\r') out.pop_back();
  return out;
}

}  // namespace errfield::programs::program_test_support
