// The flange's small rotation from several points (flange_rotation.hpp) and a 6-DoF probe's rows as
// three points (probe_readings.hpp), against closed forms written here: a rigid motion applied to
// points, the least-squares covariance σ²(AᵀA)⁻¹ built from its own design matrix, and the rotation
// between two probe orientations.
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "errfield/compensation/model/flange_rotation.hpp"
#include "errfield/compensation/tools/probe_readings.hpp"
#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"
#include "errfield/robot/pose.hpp"

namespace errfield::compensation {
namespace flange_rotation_test {

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

TEST(FlangeRotation, RecoversTheRotationOfAnExactRigidMotion) {
  std::mt19937 gen(5);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<Eigen::Vector3d> points;
    const Eigen::Vector3d flange(1200 + 100 * n(gen), 300 * n(gen), 800 + 100 * n(gen));
    const std::size_t k = 3 + static_cast<std::size_t>(trial % 3);
    for (std::size_t j = 0; j < k; ++j) points.push_back(flange + 120.0 * Eigen::Vector3d(n(gen), n(gen), n(gen)));
    const Eigen::Vector3d t(0.3 * n(gen), 0.3 * n(gen), 0.3 * n(gen)), w(1e-3 * n(gen), 1e-3 * n(gen), 1e-3 * n(gen));
    const Eigen::Vector3d about(1000 * n(gen), 1000 * n(gen), 1000 * n(gen));  // any centre: w is the same
    std::vector<Eigen::Vector3d> errors;
    for (const Eigen::Vector3d& p : points) errors.push_back(t + w.cross(p - about));
    const auto op = FlangeRotationOperator::of(points);
    ASSERT_TRUE(op.has_value());
    EXPECT_LT((op->rotation_rad(errors) - w).norm(), 1e-12 * (1.0 + w.norm() * 1e3));
  }
}

TEST(FlangeRotation, PointsOnALineOrTooFewDetermineNoRotation) {
  const Eigen::Vector3d a(1000, 0, 500), u = Eigen::Vector3d(1, 2, 3).normalized();
  EXPECT_FALSE(FlangeRotationOperator::of({a, a + 150 * u}).has_value());
  EXPECT_FALSE(FlangeRotationOperator::of({a, a + 150 * u, a + 300 * u}).has_value());
  // 5 mm off the line: below kMinPointSpreadOffLineMm.
  const Eigen::Vector3d off = u.cross(Eigen::Vector3d::UnitX()).normalized();
  EXPECT_FALSE(FlangeRotationOperator::of({a, a + 150 * u, a + 300 * u + 5 * off}).has_value());
  EXPECT_TRUE(FlangeRotationOperator::of({a, a + 150 * u, a + 150 * u + 100 * off}).has_value());
}

TEST(FlangeRotation, CovarianceIsTheLeastSquaresOneBuiltFromTheDesign) {
  const std::vector<Eigen::Vector3d> points = {{1000, 0, 500}, {1150, 0, 500}, {1000, 150, 500}, {1060, 40, 620}};
  const auto op = FlangeRotationOperator::of(points);
  ASSERT_TRUE(op.has_value());
  // Equal variances: σ² (AᵀA)⁻¹'s rotation block, A = [I, −[p]×] over the points (about the origin).
  const double s2 = 0.0004;
  Eigen::MatrixXd a(3 * points.size(), 6);
  for (std::size_t j = 0; j < points.size(); ++j) {
    a.block<3, 3>(3 * static_cast<Eigen::Index>(j), 0).setIdentity();
    a.block<3, 3>(3 * static_cast<Eigen::Index>(j), 3) = -skew(points[j]);
  }
  const Eigen::MatrixXd expected = s2 * (a.transpose() * a).inverse();
  const Eigen::Matrix3d c = op->covariance_rad2(std::vector<Eigen::Vector3d>(points.size(), Eigen::Vector3d::Constant(s2)));
  const Eigen::Matrix3d rotation_block = expected.bottomRightCorner(3, 3);
  EXPECT_LT((c - rotation_block).norm(), 1e-9 * rotation_block.norm());
  // Unequal variances: the sum of each point's block, B_j Σ_j B_jᵀ, against perturbing one point.
  std::vector<Eigen::Vector3d> v(points.size(), Eigen::Vector3d::Zero());
  v[1] = Eigen::Vector3d(1.0, 0.0, 0.0);
  std::vector<Eigen::Vector3d> unit(points.size(), Eigen::Vector3d::Zero());
  unit[1] = Eigen::Vector3d::UnitX();
  const Eigen::Vector3d column = op->rotation_rad(unit);  // dw / de_1x
  EXPECT_LT((op->covariance_rad2(v) - column * column.transpose()).norm(), 1e-15);
}

TEST(FlangeRotation, RadiusAndNeesOfAPrediction) {
  RotationPrediction p;
  p.covariance_rad2 = Eigen::Vector3d(4e-8, 1e-8, 9e-8).asDiagonal();
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix();
  RotationPrediction turned = p;
  turned.covariance_rad2 = turn * p.covariance_rad2 * turn.transpose();
  EXPECT_NEAR(turned.radius95_rad(), p.radius95_rad(), 1e-12);
  // Equal variances: the closed form sqrt(l chi2_3(0.95)).
  RotationPrediction equal;
  equal.covariance_rad2 = 1e-8 * Eigen::Matrix3d::Identity();
  EXPECT_NEAR(equal.radius95_rad(), std::sqrt(1e-8 * 7.814727903251178), 1e-9 * 1e-4);
  const Eigen::Vector3d e(2e-4, -1e-4, 3e-4);
  EXPECT_NEAR(p.nees(e), 4e-8 / 4e-8 + 1e-8 / 1e-8 + 9e-8 / 9e-8, 1e-12);
}

CsvTable probe_table(const std::string& text) { return CsvTable::parse(text, "probe.csv"); }

TEST(ProbeReadings, EachRowBecomesThreePointsAlongTheProbesAxes) {
  const CsvTable t = probe_table(
      "point,q1,q2,q3,q4,q5,q6,mx,my,mz,mrx,mry,mrz\n"
      "p1,0,-90,90,0,45,0,1000,200,300,0,0,90\n"
      "p2,1,-80,85,2,40,3,1100,-50,400,30,-20,10\n");
  const CsvTable e = expand_probe_readings(t);
  ASSERT_EQ(e.row_count(), 6u);
  EXPECT_FALSE(e.has_column("mrx"));
  const std::size_t label = e.column_index("reflector");
  EXPECT_EQ(e.cell(0, label), "probe");
  EXPECT_EQ(e.cell(1, label), "probe+x");
  EXPECT_EQ(e.cell(2, label), "probe+y");
  EXPECT_EQ(e.cell(1, e.column_index("point")), "p1");
  EXPECT_EQ(e.line_of_row(5), t.line_of_row(1));  // messages name the line the user wrote
  // rz = 90 deg: the probe's x axis is the tracker's y, its y axis the tracker's −x.
  const Eigen::Matrix<double, 3, 1> x1(e.numeric_cell(1, e.column_index("mx")), e.numeric_cell(1, e.column_index("my")),
                                       e.numeric_cell(1, e.column_index("mz")));
  const Eigen::Matrix<double, 3, 1> y1(e.numeric_cell(2, e.column_index("mx")), e.numeric_cell(2, e.column_index("my")),
                                       e.numeric_cell(2, e.column_index("mz")));
  EXPECT_LT((x1 - Eigen::Vector3d(1000, 200 + kProbeLeverMm, 300)).norm(), 1e-9);
  EXPECT_LT((y1 - Eigen::Vector3d(1000 - kProbeLeverMm, 200, 300)).norm(), 1e-9);
  // The same rows as quaternions (w first) give the same points.
  std::string text = "point,q1,q2,q3,q4,q5,q6,mx,my,mz,mqw,mqx,mqy,mqz\n";
  const double angles[2][3] = {{0, 0, 90}, {30, -20, 10}};
  const double at[2][3] = {{1000, 200, 300}, {1100, -50, 400}};
  for (int r = 0; r < 2; ++r) {
    const Eigen::Quaterniond q(robot::rotation_from_rpy_deg(angles[r][0], angles[r][1], angles[r][2]));
    char line[256];
    std::snprintf(line, sizeof line, "p%d,0,-90,90,0,45,0,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", r + 1, at[r][0],
                  at[r][1], at[r][2], q.w(), q.x(), q.y(), q.z());
    text += line;
  }
  const CsvTable eq = expand_probe_readings(probe_table(text));
  for (std::size_t r = 0; r < 6; ++r)
    for (const char* c : {"mx", "my", "mz"})
      EXPECT_NEAR(eq.numeric_cell(r, eq.column_index(c)), e.numeric_cell(r, e.column_index(c)), 1e-9) << r << c;
}

TEST(ProbeReadings, ThePointsTurnByTheRotationBetweenTwoOrientations) {
  // Two readings at the same probe point, orientations R1 and R2 = exp([w]x) R1: the rotation the
  // three points imply is w (to first order in |w|; 0.3 mrad leaves 1e-4 relative).
  const Eigen::Matrix3d r1 = robot::rotation_from_rpy_deg(170, 10, -35);
  const Eigen::Vector3d w(2e-4, -1e-4, 1.5e-4);
  const Eigen::Matrix3d r2 = Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix() * r1;
  std::string text = "point,q1,q2,q3,q4,q5,q6,mx,my,mz,mrx,mry,mrz\n";
  for (const Eigen::Matrix3d* r : {&r1, &r2}) {
    const Eigen::Vector3d a = robot::rpy_deg_from_rotation(*r);
    char line[256];
    std::snprintf(line, sizeof line, "p,0,0,0,0,0,0,900,100,700,%.17g,%.17g,%.17g\n", a.x(), a.y(), a.z());
    text += line;
  }
  const CsvTable e = expand_probe_readings(probe_table(text));
  std::vector<Eigen::Vector3d> first, error;
  for (std::size_t k = 0; k < 3; ++k) {
    auto at = [&](std::size_t r) {
      return Eigen::Vector3d(e.numeric_cell(r, e.column_index("mx")), e.numeric_cell(r, e.column_index("my")),
                             e.numeric_cell(r, e.column_index("mz")));
    };
    first.push_back(at(k));
    error.push_back(at(3 + k) - at(k));
  }
  const auto op = FlangeRotationOperator::of(first);
  ASSERT_TRUE(op.has_value());
  EXPECT_LT((op->rotation_rad(error) - w).norm(), 1e-4 * w.norm());
}

TEST(ProbeReadings, PartialOrBadOrientationsAreRefusedNamingTheLine) {
  auto fails = [](const std::string& text, const std::string& expected) {
    try {
      (void)expand_probe_readings(probe_table(text));
      ADD_FAILURE() << "accepted: " << text;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  };
  fails("point,q1,q2,q3,q4,q5,q6,mx,my,mz,mrx,mry\np,0,0,0,0,0,0,1,2,3,4,5\n", "missing mrz");
  fails("point,q1,q2,q3,q4,q5,q6,mx,my,mz,mrx,mry,mrz\np,0,0,0,0,0,0,1,2,3,4,,6\n", "probe.csv:2: the probe's orientation is given in part");
  fails("point,q1,q2,q3,q4,q5,q6,mx,my,mz,mqw,mqx,mqy,mqz\np,0,0,0,0,0,0,1,2,3,1,0.1,0,0\n", "probe.csv:2: the quaternion");
  fails("point,q1,q2,q3,q4,q5,q6,mx,my,mz,mrx,mry,mrz,mqw,mqx,mqy,mqz\np,0,0,0,0,0,0,1,2,3,0,0,0,1,0,0,0\n", "one way");
  fails("point,q1,q2,q3,q4,q5,q6,mx,my,mz,mrx,mry,mrz\np,0,0,0,0,0,0,,,,4,5,6\n", "probe.csv:2: an orientation without a position");
  // A table without orientation columns is returned as it is.
  const CsvTable plain = probe_table("point,mx,my,mz\np,1,2,3\n");
  EXPECT_EQ(expand_probe_readings(plain).header(), plain.header());
}

}  // namespace flange_rotation_test
}  // namespace errfield::compensation
