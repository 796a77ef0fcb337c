// `errfield compensate-program` on KUKA KRL programs written to look like real ones (SIMULATED
// KR 16 and data): A,B,C and Status/Turn against independent computations, bytes kept outside the
// rewritten numbers in the .src and the .dat, the report's rows, and a round trip through the
// simulated true robot.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <regex>

#include <Eigen/Dense>

#include "errfield/csv_table.hpp"
#include "errfield/programs/krl_program.hpp"
#include "errfield/robot/builtin_robots.hpp"
#include "errfield/robot/inverse_kinematics.hpp"
#include "errfield/robot/kinematics.hpp"
#include "program_test_support.hpp"
#include "support/cli_harness.hpp"

namespace errfield::programs {
namespace krl_program_test {

using namespace errfield::robot;
namespace fs = std::filesystem;
using program_test_support::split_numbers;

constexpr double kDeg = M_PI / 180.0;

// KUKA's definition written out: A about z, then B about the turned y, then C about the twice
// turned x (intrinsic Z-Y'-X'').
Eigen::Matrix3d abc_by_hand(double a, double b, double c) {
  return (Eigen::AngleAxisd(a * kDeg, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(b * kDeg, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(c * kDeg, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

TEST(KukaAbc, AgreesWithTheIntrinsicZYXProductAndRoundTrips) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> angle(-180.0, 180.0), pitch(-89.0, 89.0);
  for (int i = 0; i < 200; ++i) {
    const double a = angle(rng), b = pitch(rng), c = angle(rng);
    const Eigen::Matrix3d r = abc_by_hand(a, b, c);
    ASSERT_LT((kuka_abc_rotation(a, b, c) - r).norm(), 1e-12) << a << " " << b << " " << c;
    const Eigen::Vector3d back = kuka_abc_of(r);
    EXPECT_NEAR(back[0], a, 1e-9);
    EXPECT_NEAR(back[1], b, 1e-9);
    EXPECT_NEAR(back[2], c, 1e-9);
  }
  // By hand: A = 90 turns x onto y; B = 90 turns x onto -z; C = 90 turns y onto z.
  EXPECT_LT((kuka_abc_rotation(90, 0, 0) * Eigen::Vector3d::UnitX() - Eigen::Vector3d::UnitY()).norm(), 1e-12);
  EXPECT_LT((kuka_abc_rotation(0, 90, 0) * Eigen::Vector3d::UnitX() + Eigen::Vector3d::UnitZ()).norm(), 1e-12);
  EXPECT_LT((kuka_abc_rotation(0, 0, 90) * Eigen::Vector3d::UnitY() - Eigen::Vector3d::UnitZ()).norm(), 1e-12);
}

TEST(KrlBits, ReadsDecimalsAndBitLiteralsAndRefusesTheRest) {
  EXPECT_EQ(krl_bits("6"), 6);
  EXPECT_EQ(krl_bits("'B010'"), 2);
  EXPECT_EQ(krl_bits("'B00110010'"), 50);
  EXPECT_EQ(krl_bits("'b110'"), 6);
  EXPECT_EQ(krl_bits("'H1A'"), 26);
  EXPECT_EQ(krl_bits("'B012'"), -1);
  EXPECT_EQ(krl_bits("6.5"), -1);
  EXPECT_EQ(krl_bits("XP1"), -1);
  JointVector q;
  q << -10, -90, 80, 0, -30, 5;  // axes 1, 2 and 5 negative: Turn 'B010011' = 19
  EXPECT_TRUE(krl_turn_matches(19, q));
  EXPECT_FALSE(krl_turn_matches(18, q));
  EXPECT_FALSE(krl_turn_matches(51, q));
}

// Status bit 0 by hand on the KR 16: the wrist centre (158 mm behind the flange along its z) in the
// A1 coordinate system (the base turned by q1 about z) has x < 0: KUKA's overhead area.
bool overhead_by_hand(const MdhModel& m, const JointVector& q) {
  const Eigen::Isometry3d flange = forward_kinematics(m.with_tool(Eigen::Isometry3d::Identity()), q);
  const Eigen::Vector3d wc = flange.translation() - 158.0 * flange.linear().col(2);
  return wc.x() * std::cos(q[0] * kDeg) + wc.y() * std::sin(q[0] * kDeg) < 0.0;
}

TEST(KrlStatusTurn, PtpTargetsAskForTurnAndOverheadAsKukaDefinesThem) {
  const MdhModel m = find_builtin_robot("kr16")->model;
  // A PTP with S 'B011' T 'B010011' (Status bits 1 and 2 are not checked, see krl_program.hpp).
  const ProgramFile src{"t.src", "DEF t( )\n$TOOL=$NULLFRAME\n$BASE=$NULLFRAME\nPTP {X 900,Y 0,Z 600,A 0,B 90,C 0,S 'B011',T 'B010011'}\n"
                                 "LIN {X 900,Y 0,Z 600,A 0,B 90,C 0,S 'B011',T 'B010011'}\nEND\n"};
  const auto targets = read_krl_targets(src, {}, {}, m);
  ASSERT_EQ(targets.size(), 2u);
  const ProgramTarget& ptp = targets[0];
  ASSERT_TRUE(ptp.refusal.empty()) << ptp.refusal;
  ASSERT_TRUE(ptp.configuration.matches);
  EXPECT_FALSE(ptp.configuration.ignored);
  EXPECT_TRUE(targets[1].configuration.ignored) << "LIN ignores Status and Turn";
  std::mt19937 rng(5);
  int seen[2] = {0, 0};
  for (int i = 0; i < 4000; ++i) {
    JointVector q;
    for (int k = 0; k < 6; ++k) q[k] = std::uniform_real_distribution<double>(m.q_min_deg()[k], m.q_max_deg()[k])(rng);
    const bool turn = q[0] < 0 && q[1] < 0 && q[2] >= 0 && q[3] >= 0 && q[4] < 0 && q[5] >= 0;
    const bool overhead = overhead_by_hand(m, q);
    ASSERT_EQ(ptp.configuration.matches(q), turn && overhead) << q.transpose();
    if (turn) ++seen[overhead];
  }
  EXPECT_GT(seen[0], 0);
  EXPECT_GT(seen[1], 0) << "no overhead posture drawn with the Turn";
}

TEST(KrlRewrite, WritesTheAnglesOfTheNewRotationNearestTheWrittenOnes) {
  // A = 179.99 turned by +0.02 deg about the tool's z is A = 180.01 (not -179.99), C stays 180.0.
  const ProgramFile src{"r.src", "DEF r( )\r\n$TOOL=$NULLFRAME\r\n$BASE=$NULLFRAME\r\nLIN {X 1000.0,Y 0.0,Z 500.0,A 179.99,B 0.0,C 180.0}\r\nEND\r\n"};
  const auto targets = read_krl_targets(src, {}, {}, find_builtin_robot("kr16")->model);
  ASSERT_EQ(targets.size(), 1u);
  ASSERT_TRUE(targets[0].rewrite);
  const Eigen::Isometry3d old = targets[0].pose_in_frame;
  EXPECT_LT((old.linear() - abc_by_hand(179.99, 0.0, 180.0)).norm(), 1e-12);
  Eigen::Isometry3d now = old;
  now.translation() += Eigen::Vector3d(0.25, -0.5, 0.0);
  now.linear() = abc_by_hand(180.01, 0.0, 180.0);
  const std::string out = apply_replacements(src.bytes, targets[0].rewrite(now));
  EXPECT_EQ(out, "DEF r( )\r\n$TOOL=$NULLFRAME\r\n$BASE=$NULLFRAME\r\nLIN {X 1000.25,Y -0.5,Z 500.0,A 180.01,B 0.0,C 180.0}\r\nEND\r\n");
}

// ---- the CLI on a SIMULATED KR 16 and a kinematic model fitted on its SIMULATED readings.

using program_test_support::fixed;

struct KrlSetup {
  static constexpr const char* kDirectory = "errfield_programs_krl";
  static constexpr const char* kSimulate = "--robot kr16 --seed 2 --sample grid --step 125";
};
using CompensateKrl = program_test_support::FittedRobotTest<KrlSetup>;

// A KRL cell as a KSS writes one: inline-form folds naming PDAT/FDAT data in the .dat, E6POS points
// in the .dat, inline aggregates in the .src, TOOL_DATA/BASE_DATA in a $config.dat, an axis home,
// a frame product, a point assigned at run time, an undeclared tool. CRLF line ends.
struct Cell {
  std::string src, dat, config;
  std::vector<Eigen::Isometry3d> intended;  // robot base frame, point i
  std::vector<JointVector> joints;          // the nominal joints they were made from
  Eigen::Isometry3d tool, base;
};

std::string abc_text(const Eigen::Matrix3d& r) {
  // Independent of kuka_abc_of: Eigen's Z-Y-X Euler angles (R = Rz(A) Ry(B) Rx(C)).
  const Eigen::Vector3d e = r.eulerAngles(2, 1, 0) / kDeg;
  return "A " + fixed(e[0], 4) + ",B " + fixed(e[1], 4) + ",C " + fixed(e[2], 4);
}

std::string bits(int v, int width) {
  std::string s;
  for (int i = width - 1; i >= 0; --i) s += ((v >> i) & 1) ? '1' : '0';
  return s;
}

Cell make_cell(const MdhModel& nominal, const std::vector<JointVector>& training, int count) {
  Cell c;
  c.tool = nominal.tool();
  c.tool.linear() = c.tool.linear() * Eigen::AngleAxisd(M_PI / 6, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  c.base = Eigen::Isometry3d::Identity();
  c.base.translation() << 150.0, -80.0, 30.0;
  c.base.linear() = Eigen::AngleAxisd(0.25, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const MdhModel with_tool = nominal.with_tool(c.tool);
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> jitter(-2.0, 2.0);
  const std::string nl = "\r\n";
  std::string src = "&ACCESS RVP" + nl + "&REL 3" + nl + "DEF zelle( )" + nl + ";FOLD INI;%{PE}" + nl + "  ;FOLD BASISTECH INI" + nl +
                    "    BAS (#INITMOV,0 )" + nl + "  ;ENDFOLD (BASISTECH INI)" + nl + ";ENDFOLD (INI)" + nl + nl +
                    ";FOLD PTP HOME  Vel= 100 % DEFAULT;%{PE}%MKUKATPBASIS,%CMOVE,%VPTP,%P 1:PTP, 2:HOME, 3:, 5:100, 7:DEFAULT" + nl +
                    "$BWDSTART = FALSE" + nl + "PDAT_ACT=PDEFAULT" + nl + "FDAT_ACT=FHOME" + nl + "BAS (#PTP_PARAMS,100 )" + nl +
                    "$H_POS=XHOME" + nl + "PTP  XHOME" + nl + ";ENDFOLD" + nl;
  std::string dat = "&ACCESS RVP" + nl + "DEFDAT  zelle" + nl + ";FOLD EXTERNAL DECLARATIONS;%{PE}%MKUKATPBASIS,%CEXT,%VCOMMON,%P" + nl +
                    ";ENDFOLD (EXTERNAL DECLARATIONS)" + nl + "DECL E6AXIS XHOME={A1 0.0,A2 -90.0,A3 90.0,A4 0.0,A5 0.0,A6 0.0,E1 0.0,E2 0.0}" + nl +
                    "DECL FDAT FHOME={TOOL_NO 0,BASE_NO 0,IPO_FRAME #BASE,POINT2[] \" \"}" + nl;
  for (int i = 0; i < count; ++i) {
    JointVector q = training[static_cast<std::size_t>(i * 11 + 5) % training.size()];
    for (int k = 0; k < 6; ++k) q[k] += jitter(rng);
    // Turn holds the axes' signs: keep them clear of 0, where a correction could flip one.
    for (int k = 0; k < 6; ++k)
      if (std::abs(q[k]) < 1.5) q[k] = q[k] < 0 ? -1.5 : 1.5;
    const Eigen::Isometry3d pose = forward_kinematics(with_tool, q);
    c.intended.push_back(pose);
    c.joints.push_back(q);
    const Eigen::Isometry3d in_base = c.base.inverse() * pose;
    int turn = 0;
    for (int k = 0; k < 6; ++k) turn |= (q[k] < 0 ? 1 : 0) << k;
    const int status = 2 + (overhead_by_hand(nominal, q) ? 1 : 0);
    const std::string xyz = "X " + fixed(in_base.translation().x(), 3) + ",Y " + fixed(in_base.translation().y(), 3) + ",Z " +
                            fixed(in_base.translation().z(), 3) + "," + abc_text(in_base.linear());
    const std::string p = "P" + std::to_string(i);
    const std::string motion = i % 3 == 1 ? "LIN" : "PTP";
    if (i % 2 == 0) {
      // The inline form: a fold naming the tool and base, the point in the .dat (Status/Turn as bits).
      src += ";FOLD " + motion + " " + p + " Vel=100 % PDAT" + std::to_string(i) + " Tool[1] Base[2];%{PE}%R 8.3.40,%MKUKATPBASIS" + nl +
             "$BWDSTART=FALSE" + nl + "PDAT_ACT=PPDAT" + std::to_string(i) + nl + "FDAT_ACT=F" + p + nl + "BAS(#PTP_PARAMS,100)" + nl +
             motion + " X" + p + (motion == "LIN" ? " C_DIS" : "") + nl + ";ENDFOLD" + nl;
      dat += "DECL E6POS X" + p + "={" + xyz + ",S 'B" + bits(status, 3) + "',T 'B" + bits(turn, 6) + "',E1 0.0,E2 0.0}" + nl;
      dat += "DECL FDAT F" + p + "={TOOL_NO 1,BASE_NO 2,IPO_FRAME #BASE,POINT2[] \" \"}" + nl;
    } else {
      // An expert-mode line with an inline aggregate (Status/Turn in decimal) after $TOOL/$BASE.
      src += "$TOOL = TOOL_DATA[1]" + nl + "$BASE=BASE_DATA[2]" + nl + motion + " {" + xyz + ",S " + std::to_string(status) + ",T " +
             std::to_string(turn) + "} ; Punkt " + std::to_string(i) + " \xFC" "ber dem Teil" + nl;
    }
  }
  src += "LIN XP0 : {X 0,Y 0,Z 50,A 0,B 0,C 0} C_DIS ; 50 mm above" + nl;
  src += "XPROBE.Z = XPROBE.Z + 10" + nl + "LIN XPROBE" + nl;  // a run-time value: computed
  src += ";FOLD LIN P9 Vel=2 m/s CPDAT9 Tool[3] Base[2];%{PE}" + nl + "LIN {X 500,Y 0,Z 500,A 0,B 90,C 0}" + nl + ";ENDFOLD" + nl;
  src += "PTP {A1 0,A2 -90,A3 90,A4 0,A5 30,A6 0}" + nl + "END" + nl;
  dat += "DECL E6POS XPROBE={X 1000.0,Y 0.0,Z 800.0,A 0.0,B 90.0,C 0.0,S 'B010',T 'B000000',E1 0.0,E2 0.0}" + nl + "ENDDAT" + nl;
  const Eigen::Vector3d tabc = c.tool.linear().eulerAngles(2, 1, 0) / kDeg, babc = c.base.linear().eulerAngles(2, 1, 0) / kDeg;
  c.config = "DEFDAT  $CONFIG" + nl + "DECL FRAME TOOL_DATA[16]" + nl + "TOOL_DATA[1]={X " + fixed(c.tool.translation().x(), 4) + ",Y " +
             fixed(c.tool.translation().y(), 4) + ",Z " + fixed(c.tool.translation().z(), 4) + ",A " + fixed(tabc[0], 6) + ",B " +
             fixed(tabc[1], 6) + ",C " + fixed(tabc[2], 6) + "}" + nl + "BASE_DATA[2]={X 150.0,Y -80.0,Z 30.0,A " + fixed(babc[0], 8) +
             ",B " + fixed(babc[1], 8) + ",C " + fixed(babc[2], 8) + "}" + nl + "ENDDAT" + nl;
  c.src = src;
  c.dat = dat;
  return c;
}

// Point i's pose (base frame of the program, mm) as written: from the .dat's XPi or the .src's
// "; Punkt i" line, with A,B,C turned into a rotation by the intrinsic Z-Y-X product.
std::map<int, Eigen::Isometry3d> points_of(const std::string& src, const std::string& dat) {
  static const std::regex point(
      R"(XP(\d+)=\{X (-?[0-9.]+),Y (-?[0-9.]+),Z (-?[0-9.]+),A (-?[0-9.]+),B (-?[0-9.]+),C (-?[0-9.]+),)");
  static const std::regex inline_point(
      R"(\{X (-?[0-9.]+),Y (-?[0-9.]+),Z (-?[0-9.]+),A (-?[0-9.]+),B (-?[0-9.]+),C (-?[0-9.]+),S [0-9]+,T [0-9]+\} ; Punkt (\d+))");
  std::map<int, Eigen::Isometry3d> out;
  auto pose = [](const std::smatch& m, int first) {
    Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
    p.translation() << std::stod(m[first]), std::stod(m[first + 1]), std::stod(m[first + 2]);
    p.linear() = abc_by_hand(std::stod(m[first + 3]), std::stod(m[first + 4]), std::stod(m[first + 5]));
    return p;
  };
  for (auto it = std::sregex_iterator(dat.begin(), dat.end(), point); it != std::sregex_iterator(); ++it)
    out[std::stoi((*it)[1])] = pose(*it, 2);
  for (auto it = std::sregex_iterator(src.begin(), src.end(), inline_point); it != std::sregex_iterator(); ++it)
    out[std::stoi((*it)[7])] = pose(*it, 1);
  return out;
}

TEST_F(CompensateKrl, RoundTripThroughTheSimulatedRobotLandsNearerAndKeepsEveryOtherByte) {
  const MdhModel nom = nominal(), tru = truth();
  constexpr int kPoints = 10;
  const Cell c = make_cell(nom, training_joints(), kPoints);
  write("zelle.src", c.src);
  write("zelle.dat", c.dat);
  write("$config.dat", c.config);
  const auto r = run("compensate-program --model " + shared("model.json") +
                     " --program zelle.src --include $config.dat --out zelle_out.src --report r.csv");
  ASSERT_EQ(r.exit_code, 0) << r.output();
  EXPECT_EQ(read("zelle.src"), c.src);
  EXPECT_EQ(read("zelle.dat"), c.dat);
  const std::string out_src = read("zelle_out.src"), out_dat = read("zelle_out.dat");
  // Every byte outside numbers kept; the numbers that change are X, Y, Z, A, B or C of a point.
  std::size_t changed = 0;
  for (const auto& [before, after] : {std::pair{c.src, out_src}, std::pair{c.dat, out_dat}}) {
    const auto a = split_numbers(before);
    static const std::regex field(R"([{,][XYZABC] $)");
    for (std::size_t i : program_test_support::changed_numbers(before, after)) {
      ++changed;
      EXPECT_TRUE(std::regex_search(a.between[i], field)) << program_test_support::line_text(before, a.lines[i]);
    }
  }
  EXPECT_GT(changed, 2u * kPoints);

  // The report: one row per target occurrence, in program order.
  const CsvTable rep = CsvTable::read(path("r.csv"));
  // HOME, the points, the frame product, XPROBE, the Tool[3] move, the axis PTP.
  ASSERT_EQ(rep.row_count(), 1u + kPoints + 4u) << read("r.csv");
  auto row = [&](std::size_t i, std::size_t col) { return std::string(rep.cell(i, col)); };
  EXPECT_EQ(row(0, 3), "unchanged") << row(0, 4);
  EXPECT_EQ(row(0, 2), "XHOME");
  std::map<std::string, int> status;
  for (std::size_t i = 1; i <= kPoints; ++i) ++status[row(i, 3)];
  EXPECT_EQ(status["ok"], kPoints) << read("r.csv");
  EXPECT_EQ(row(kPoints + 1, 3), "computed");
  EXPECT_NE(row(kPoints + 1, 4).find("XP0"), std::string::npos) << "the frame product names what it depends on";
  EXPECT_EQ(row(kPoints + 2, 3), "computed");
  EXPECT_NE(row(kPoints + 2, 4).find("assigned at run time"), std::string::npos) << row(kPoints + 2, 4);
  EXPECT_EQ(row(kPoints + 3, 3), "refused");
  EXPECT_NE(row(kPoints + 3, 4).find("TOOL_DATA[3]"), std::string::npos) << row(kPoints + 3, 4);
  EXPECT_EQ(row(kPoints + 4, 3), "unchanged");
  EXPECT_EQ(row(1, 0), "zelle.src");
  EXPECT_NE(r.out.find("positionally accurate"), std::string::npos) << r.out;

  // Through the controller (nominal IK from the taught joints) and the SIMULATED true robot.
  const auto before = points_of(c.src, c.dat), after = points_of(out_src, out_dat);
  ASSERT_EQ(before.size(), static_cast<std::size_t>(kPoints));
  ASSERT_EQ(after.size(), static_cast<std::size_t>(kPoints));
  const MdhModel controller = nom.with_tool(c.tool), robot = tru.with_tool(tru.tool() * nom.tool().inverse() * c.tool);
  std::vector<Eigen::Isometry3d> before_base, after_base;
  for (int i = 0; i < kPoints; ++i) {
    before_base.push_back(c.base * before.at(i));
    after_base.push_back(c.base * after.at(i));
  }
  // A third, not RAPID's fifth: the KR 16 model is fitted on one tool-down orientation and these
  // points turn every joint by up to 2 deg from the grid's (measured: 1.17 -> 0.34 mm RMS, each
  // point nearer; the ER20 and UR5 suites reach a fifth).
  program_test_support::expect_lands_nearer(controller, robot, program_test_support::base_from_world(shared_), before_base,
                                            after_base, c.intended, c.joints, 1.0 / 3.0);
}

TEST_F(CompensateKrl, AToolDeclaredNowhereIsRefusedByNameAndGivenByOption) {
  const MdhModel nom = nominal();
  const Eigen::Isometry3d pose = forward_kinematics(nom, training_joints()[10]);
  const std::string src = "DEF t( )\r\n$TOOL=TOOL_DATA[4]\r\n$BASE=$NULLFRAME\r\nPTP {A1 0,A2 -90,A3 90,A4 0,A5 30,A6 0}\r\n"
                          "LIN {X " + fixed(pose.translation().x(), 3) + ",Y " + fixed(pose.translation().y(), 3) + ",Z " +
                          fixed(pose.translation().z(), 3) + "," + abc_text(pose.linear()) + "} ; probe\r\nEND\r\n";
  write("t.src", src);
  auto r = run("compensate-program --model " + shared("model.json") + " --program t.src --out o.src --report r.csv");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output().find("TOOL_DATA[4]"), std::string::npos) << r.output();
  EXPECT_FALSE(fs::exists(path("o.src"))) << "a failed run writes nothing";
  // Given by --tool in KUKA's X,Y,Z,A,B,C: the simulated tool.
  const Eigen::Isometry3d t = nom.tool();
  const Eigen::Vector3d abc = t.linear().eulerAngles(2, 1, 0) / kDeg;
  r = run("compensate-program --model " + shared("model.json") + " --program t.src --out o.src --report r.csv --tool TOOL_DATA[4]=" +
          fixed(t.translation().x(), 4) + "," + fixed(t.translation().y(), 4) + "," + fixed(t.translation().z(), 4) + "," + fixed(abc[0], 6) +
          "," + fixed(abc[1], 6) + "," + fixed(abc[2], 6));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  const CsvTable rep = CsvTable::read(path("r.csv"));
  ASSERT_EQ(rep.row_count(), 2u);
  EXPECT_EQ(std::string(rep.cell(0, 3)), "unchanged");
  EXPECT_EQ(std::string(rep.cell(1, 3)), "ok") << std::string(rep.cell(1, 4));
  const std::string out = read("o.src");
  EXPECT_NE(out.find(" ; probe\r\nEND\r\n"), std::string::npos);
  EXPECT_EQ(out.substr(0, 90), src.substr(0, 90));
}

TEST_F(CompensateKrl, TheDatAloneIsRefusedAndFormatsComeFromTheExtensionOrFormat) {
  write("cell.dat", "DEFDAT cell\r\nDECL E6POS XP1={X 1000.0,Y 0.0,Z 500.0,A 0.0,B 0.0,C 180.0}\r\nENDDAT\r\n");
  auto r = run("compensate-program --model " + shared("model.json") + " --program cell.dat --out o.dat");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output().find("give the .src"), std::string::npos) << r.output();
  write("cell.txt", "DEF cell( )\n$TOOL=TOOL_DATA[7]\n$BASE=$NULLFRAME\nLIN {X 1000.0,Y 0.0,Z 500.0,A 0.0,B 0.0,C 180.0}\nEND\n");
  r = run("compensate-program --model " + shared("model.json") + " --program cell.txt --out o.txt");
  EXPECT_NE(r.output().find("give --format"), std::string::npos) << r.output();
  r = run("compensate-program --model " + shared("model.json") + " --program cell.txt --out o.txt --format krl");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output().find("TOOL_DATA[7]"), std::string::npos) << "read as KRL: " << r.output();
  EXPECT_FALSE(fs::exists(path("o.txt")));
}

}  // namespace krl_program_test
}  // namespace errfield::programs
