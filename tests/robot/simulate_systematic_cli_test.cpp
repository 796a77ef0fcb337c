// `errfield simulate --systematic / --compliance / --end-range-error` (issue 19, item 7): systematic
// joint effects a kinematic model cannot express, through the real executable. Each is checked
// against an independent computation: the end-of-travel error against its formula pushed through
// FK of the written true geometry, the compliance against its linearity in the compliance, and the
// preset against the effects it names.

#include <cmath>

#include <gtest/gtest.h>

#include "errfield/csv_table.hpp"
#include "errfield/robot/builtin_robots.hpp"
#include "errfield/robot/kinematics.hpp"
#include "support/cli_harness.hpp"

namespace errfield::robot {
namespace simulate_systematic_cli_test {

class SimulateSystematic : public errfield::testing::CliTest {
 protected:
  // Commanded joints of the test rows: inside every onset, q1 beyond 90 deg, q5 beyond 60 deg.
  static std::vector<JointVector> test_joints() {
    std::vector<JointVector> q(3);
    q[0] << 20, -60, 90, 0, 30, 0;
    q[1] << 150, -60, 90, 0, 30, 0;
    q[2] << -20, -60, 90, 0, -110, 0;
    return q;
  }
  // Runs simulate on test_joints() with `options`; returns the true positions of the target rows.
  std::vector<Eigen::Vector3d> truth(const std::string& options, const std::string& name) {
    write("q.csv", "q1,q2,q3,q4,q5,q6\n20,-60,90,0,30,0\n150,-60,90,0,30,0\n-20,-60,90,0,-110,0\n");
    const auto r = run("simulate --robot kr16 --seed 7 --joints " + path("q.csv") + " --truth-columns " + options +
                       " --truth-out " + path(name + ".json") + " --out " + path(name + ".csv"));
    EXPECT_EQ(r.exit_code, 0) << r.err;
    const CsvTable t = CsvTable::read(path(name + ".csv"));
    std::vector<Eigen::Vector3d> out;
    for (std::size_t i = 0; i < t.row_count(); ++i) {
      if (t.row(i)[t.column_index("kind")] != "target") continue;
      out.emplace_back(t.numeric_cell(i, t.column_index("true_x")), t.numeric_cell(i, t.column_index("true_y")),
                       t.numeric_cell(i, t.column_index("true_z")));
    }
    return out;
  }
};

TEST_F(SimulateSystematic, EndRangeErrorFollowsItsFormulaBeyondTheOnsetOnly) {
  // Rigid joints, no transmission error: the truth is the FK of the true geometry (+ the same
  // repeatability noise in both runs, which cancels), so the difference is the end-range error's alone.
  const auto plain = truth("--systematic none", "plain");
  const auto bent = truth("--systematic none --end-range-error q1:90:0.2 --end-range-error q5:60:1.0", "bent");
  ASSERT_EQ(plain.size(), 3u);
  ASSERT_EQ(bent.size(), 3u);
  const MdhModel true_robot = MdhModel::load(path("plain.json"));
  const MdhModel kr = kr16();
  const auto q = test_joints();
  for (std::size_t i = 0; i < q.size(); ++i) {
    JointVector dq = JointVector::Zero();
    const double q1 = q[i][0], q5 = q[i][4];
    const double limit1 = q1 >= 0 ? kr.link(0).q_max_deg : -kr.link(0).q_min_deg;
    const double limit5 = q5 >= 0 ? kr.link(4).q_max_deg : -kr.link(4).q_min_deg;
    if (std::abs(q1) > 90) dq[0] = std::copysign(0.2 * std::pow((std::abs(q1) - 90) / (limit1 - 90), 2), q1);
    if (std::abs(q5) > 60) dq[4] = std::copysign(1.0 * std::pow((std::abs(q5) - 60) / (limit5 - 60), 2), q5);
    const Eigen::Vector3d expected = forward_position(true_robot, q[i] + dq) - forward_position(true_robot, q[i]);
    EXPECT_LT((bent[i] - plain[i] - expected).norm(), 1e-6) << "row " << i;
    if (i == 0) EXPECT_EQ((bent[i] - plain[i]).norm(), 0.0) << "inside both onsets nothing changes";
    else EXPECT_GT((bent[i] - plain[i]).norm(), 0.05) << "row " << i << " is beyond an onset";
  }
  EXPECT_NE(read("bent.csv").find("# SIMULATED like real data:"), std::string::npos);
  EXPECT_NE(read("bent.csv").find("q1 error growing beyond |q1| = 90 deg to 0.2 deg"), std::string::npos);
}

TEST_F(SimulateSystematic, ComplianceIsLinearInTheComplianceAndZeroIsRigid) {
  const auto rigid = truth("--systematic none", "rigid");
  const auto zero = truth("--systematic none --compliance 0", "zero");
  const auto one = truth("--systematic none --compliance 1", "one");
  const auto two = truth("--systematic none --compliance 2", "two");
  for (std::size_t i = 0; i < rigid.size(); ++i) {
    EXPECT_EQ((zero[i] - rigid[i]).norm(), 0.0) << "row " << i;
    const Eigen::Vector3d d1 = one[i] - rigid[i], d2 = two[i] - rigid[i];
    // ~1 mrad of deflection: sub-mm and linear to well within 1 % (second order ~1e-3 relative).
    EXPECT_GT(d1.norm(), 0.05) << "row " << i << ": gravity bends joints 2-3";
    EXPECT_LT(d1.norm(), 5.0) << "row " << i;
    EXPECT_LT((d2 - 2.0 * d1).norm(), 0.01 * d2.norm()) << "row " << i;
  }
}

TEST_F(SimulateSystematic, MassOffsetMovesTheGravityLoadAndIsWrittenToTheConfig) {
  const auto compliant = truth("--systematic none --compliance 1", "compliant");
  const auto offset = truth("--systematic none --compliance 1 --mass-offset 0,150,0 --config-out " + path("c.json"), "offset");
  const auto rigid = truth("--systematic none --compliance 0 --mass-offset 0,150,0", "rigid");
  const auto plain_rigid = truth("--systematic none --compliance 0", "plain_rigid");
  for (std::size_t i = 0; i < compliant.size(); ++i) {
    EXPECT_GT((offset[i] - compliant[i]).norm(), 0.005) << "row " << i << ": the load moved";
    EXPECT_EQ((rigid[i] - plain_rigid[i]).norm(), 0.0) << "row " << i << ": rigid joints do not feel it";
  }
  EXPECT_NE(read("offset.csv").find("0,150,0 mm off the frame origins"), std::string::npos);
  const std::string config = read("c.json");
  EXPECT_NE(config.find("mass_offset_mm"), std::string::npos);
}

TEST_F(SimulateSystematic, RealisticPresetNamesItsEffectsAndAddsThemToTheGeometry) {
  const auto none = truth("--systematic none", "none");
  const auto realistic = truth("--systematic realistic", "realistic");
  const auto smooth = truth("--systematic realistic --end-range-error q1:110:0 --end-range-error q5:95:0", "smooth");
  const std::string text = read("realistic.csv");
  EXPECT_NE(text.find("# SIMULATED"), std::string::npos);
  EXPECT_NE(text.find("realistic systematic effects"), std::string::npos);
  // The preset's end-of-travel errors set in beyond |q1| = 110 and |q5| = 95 deg: row 0 is inside
  // both, row 1 has q1 = 150, row 2 has q5 = -110.
  EXPECT_EQ((realistic[0] - smooth[0]).norm(), 0.0);
  EXPECT_GT((realistic[1] - smooth[1]).norm(), 0.05);
  EXPECT_GT((realistic[2] - smooth[2]).norm(), 0.05);
  // Compliance and cyclic errors act everywhere.
  for (std::size_t i = 0; i < none.size(); ++i) EXPECT_GT((smooth[i] - none[i]).norm(), 0.05) << "row " << i;
  // The geometry is the same with every preset: the effects are on top of it.
  EXPECT_EQ(read("none.json"), read("realistic.json"));
}

TEST_F(SimulateSystematic, BadSystematicOptionsAreUsageErrors) {
  const std::pair<const char*, const char*> cases[] = {
      {"--systematic rough", "--systematic"},
      {"--compliance -1", "--compliance"},
      {"--end-range-error q7:90:0.1", "--end-range-error"},
      {"--end-range-error q1:90", "--end-range-error"},
      {"--end-range-error q1:400:0.1", "below the joint's limit"},
      {"--end-range-error q1:x:0.1", "ONSET_DEG"},
      {"--mass-offset 1,2", "--mass-offset"},
  };
  for (const auto& [opt, word] : cases) {
    const auto r = run(std::string("simulate --robot kr16 ") + opt + " --out " + path("x.csv"));
    EXPECT_EQ(r.exit_code, 2) << opt << "\n" << r.err;
    EXPECT_NE(r.err.find(word), std::string::npos) << opt << "\n" << r.err;
  }
}

}  // namespace simulate_systematic_cli_test
}  // namespace errfield::robot
