// A 6-DoF probe's readings through fit and validate (issue 34): the flange's orientation error the
// model predicts, scored on held-out poses, and its 95 % radius held there. The "before" rotation
// validate reports is checked against one computed here straight from the probe's angles (the
// nominal FK's orientation against the reading's, in the nominal registration) rather than from
// the three points the angles become. SIMULATED data from `errfield simulate --probe`.
#include <cmath>
#include <set>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "errfield/csv_table.hpp"
#include "errfield/robot/kinematics.hpp"
#include "errfield/robot/mdh_model.hpp"
#include "errfield/robot/pose.hpp"
#include "support/cli_harness.hpp"

namespace errfield::compensation {
using namespace errfield::robot;
namespace probe_orientation_cli_test {

using errfield::testing::CliResult;

class ProbeOrientationCli : public errfield::testing::CliTest {
 protected:
  nlohmann::json json(const std::string& name) const { return nlohmann::json::parse(read(name)); }
};

Eigen::Vector3d log_rotation(const Eigen::Matrix3d& r) {
  const Eigen::AngleAxisd a(r);
  return a.angle() * a.axis();
}

TEST_F(ProbeOrientationCli, FitOnProbeReadingsPredictsTheFlangesOrientationWithinItsOwnRadius) {
  ASSERT_EQ(run("simulate --robot kr16 --seed 4 --sample scattered:440 --orientation-spread 30 --measure positions "
                "--systematic realistic --probe 0,0,100,180,0,0 --robot-out kr16.json --out probe.csv")
                .exit_code,
            0);
  nlohmann::json robot = json("kr16.json");
  robot["tool"] = {{"x_mm", 0.0}, {"y_mm", 0.0}, {"z_mm", 100.0}, {"rx_deg", 0.0}, {"ry_deg", 0.0}, {"rz_deg", 0.0}};
  write("kr16_probe.json", robot.dump());
  const CsvTable all = CsvTable::read(path("probe.csv"));
  ASSERT_TRUE(all.has_column("mrx"));
  const std::size_t point = all.column_index("point");
  auto split = [&](const std::string& out, bool training) {
    rewrite("probe.csv", out, [](const CsvTable&, std::size_t, std::vector<std::string>&) {},
            [](const std::string&) { return true; }, [&](std::size_t i) { return (i < 240) == training; });
  };
  split("train.csv", true);
  split("test.csv", false);
  const CliResult fit = run("fit --robot kr16_probe.json --data train.csv --out m.json");
  ASSERT_EQ(fit.exit_code, 0) << fit.output();
  EXPECT_NE(fit.out.find("orientation error is predicted from the fields at 3 points"), std::string::npos) << fit.out;
  const CliResult v = run("validate --model m.json --data test.csv --summary-out s.json --orientation-out o.csv");
  ASSERT_EQ(v.exit_code, 0) << v.output();
  EXPECT_NE(v.out.find("flange orientation error"), std::string::npos) << v.out;
  const nlohmann::json o = json("s.json")["orientation"];
  ASSERT_TRUE(o.is_object()) << json("s.json").dump(2);
  const double before = o["before"]["rms_mdeg"].get<double>(), after = o["after"]["rms_mdeg"].get<double>();
  std::printf("orientation: before %.2f mdeg RMS, after %.2f mdeg, coverage95 %.3f, mean NEES %.3f over %d poses\n",
              before, after, o["coverage95"].get<double>(), o["mean_nees"].get<double>(),
              o["after"]["count"].get<int>());
  EXPECT_EQ(o["poses"].get<std::size_t>(), all.row_count() - 240);
  EXPECT_GE(o["after"]["count"].get<std::size_t>(), 190u);  // a few poses beyond the calibration's data are refused
  EXPECT_LT(after, 0.5 * before);
  // 200 poses: a binomial 95 % has an sd of 1.5 %; the band is 3 sd on either side.
  EXPECT_GE(o["coverage95"].get<double>(), 0.905);
  EXPECT_LE(o["coverage95"].get<double>(), 0.995);

  // "before", computed here from the angles themselves: log(R_read · (R_nominal(q) M)ᵀ), R_read the
  // reading in the robot frame by the nominal registration, M the mean mounting rotation; against
  // validate's, both with their means over the poses removed (the points validate uses are located
  // on the calibrated flange, a constant rotation away from the nominal one).
  const nlohmann::json model = json("m.json");
  Eigen::Matrix3d registration;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) registration(r, c) = model["nominal_registration"]["robot_from_tracker"][r][c].get<double>();
  const MdhModel nominal = MdhModel::from_json(robot);
  const CsvTable test = CsvTable::read(path("test.csv"));
  const CsvTable scored = CsvTable::read(path("o.csv"));
  ASSERT_EQ(scored.row_count(), test.row_count());
  std::vector<Eigen::Matrix3d> read, flange;
  Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < test.row_count(); ++i) {
    JointVector q;
    for (int j = 0; j < kJointCount; ++j) q[j] = test.numeric_cell(i, test.column_index("q" + std::to_string(j + 1)));
    read.push_back(registration * rotation_from_rpy_deg(test.numeric_cell(i, test.column_index("mrx")),
                                                        test.numeric_cell(i, test.column_index("mry")),
                                                        test.numeric_cell(i, test.column_index("mrz"))));
    flange.push_back(forward_kinematics(nominal, q, EndFrame::flange).linear());
    sum += flange.back().transpose() * read.back();
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(sum, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d mounting = svd.matrixU() * svd.matrixV().transpose();
  std::vector<Eigen::Vector3d> direct, reported;
  Eigen::Vector3d direct_mean = Eigen::Vector3d::Zero(), reported_mean = Eigen::Vector3d::Zero();
  const double scored_poses = o["after"]["count"].get<double>();
  for (std::size_t i = 0; i < test.row_count(); ++i) {
    ASSERT_EQ(scored.cell(i, scored.column_index("point")), test.cell(i, point));
    if (scored.cell(i, scored.column_index("status")) != "ok") continue;
    direct.push_back(log_rotation(read[i] * (flange[i] * mounting).transpose()) * 180000.0 / M_PI);
    reported.emplace_back(scored.numeric_cell(i, scored.column_index("before_wx_mdeg")),
                          scored.numeric_cell(i, scored.column_index("before_wy_mdeg")),
                          scored.numeric_cell(i, scored.column_index("before_wz_mdeg")));
    direct_mean += direct.back() / scored_poses;
    reported_mean += reported.back() / scored_poses;
  }
  double worst = 0.0, spread = 0.0;
  for (std::size_t i = 0; i < direct.size(); ++i) {
    worst = std::max(worst, ((direct[i] - direct_mean) - (reported[i] - reported_mean)).norm());
    spread = std::max(spread, (direct[i] - direct_mean).norm());
  }
  std::printf("before rotation: direct vs validate's, largest difference %.3f mdeg (largest rotation %.1f mdeg)\n", worst,
              spread);
  EXPECT_GT(spread, 20.0);  // the comparison means something
  EXPECT_LT(worst, 0.05 * spread);
}

}  // namespace probe_orientation_cli_test
}  // namespace errfield::compensation
