// `errfield validate` and `errfield predict` against computations written here: a quaternion (Horn
// 1987) registration, ordinary kriging solved directly, and the summary statistics (numpy's
// percentile). SIMULATED data from `errfield simulate`.
#include <set>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "errfield/csv_table.hpp"
#include "errfield/robot/inverse_kinematics.hpp"
#include "errfield/robot/kinematics.hpp"
#include "errfield/robot/pose.hpp"
#include "errfield/robot/mdh_model.hpp"
#include "support/cli_harness.hpp"

namespace errfield::compensation {
using namespace errfield::robot;
namespace validate_cli_test {

using errfield::testing::CliResult;

class ValidateCli : public errfield::testing::CliTest {
 protected:
  nlohmann::json json(const std::string& name) const { return nlohmann::json::parse(read(name)); }
};

/// Horn's quaternion solution of min sum |R a + t - b|^2 (not the SVD the library uses).
Eigen::Isometry3d horn(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b) {
  Eigen::Vector3d ca = Eigen::Vector3d::Zero(), cb = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < a.size(); ++i) {
    ca += a[i];
    cb += b[i];
  }
  ca /= static_cast<double>(a.size());
  cb /= static_cast<double>(b.size());
  Eigen::Matrix3d s = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < a.size(); ++i) s += (a[i] - ca) * (b[i] - cb).transpose();
  Eigen::Matrix4d n;
  n << s(0, 0) + s(1, 1) + s(2, 2), s(1, 2) - s(2, 1), s(2, 0) - s(0, 2), s(0, 1) - s(1, 0),
      s(1, 2) - s(2, 1), s(0, 0) - s(1, 1) - s(2, 2), s(0, 1) + s(1, 0), s(2, 0) + s(0, 2),
      s(2, 0) - s(0, 2), s(0, 1) + s(1, 0), -s(0, 0) + s(1, 1) - s(2, 2), s(1, 2) + s(2, 1),
      s(0, 1) - s(1, 0), s(2, 0) + s(0, 2), s(1, 2) + s(2, 1), -s(0, 0) - s(1, 1) + s(2, 2);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> es(n);
  const Eigen::Vector4d q = es.eigenvectors().col(3);
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).toRotationMatrix();
  t.translation() = cb - t.linear() * ca;
  return t;
}

/// numpy.percentile(v, 95) (linear interpolation).
double p95(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const double r = 0.95 * static_cast<double>(v.size() - 1);
  const std::size_t lo = static_cast<std::size_t>(r);
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (r - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

void expect_stats(const nlohmann::json& s, const std::vector<double>& e, double tol) {
  double sum = 0, ss = 0, mx = 0;
  for (double v : e) {
    sum += v;
    ss += v * v;
    mx = std::max(mx, v);
  }
  const double n = static_cast<double>(e.size());
  EXPECT_EQ(s["count"].get<std::size_t>(), e.size());
  EXPECT_NEAR(s["mean_mm"].get<double>(), sum / n, tol);
  EXPECT_NEAR(s["rms_mm"].get<double>(), std::sqrt(ss / n), tol);
  EXPECT_NEAR(s["max_mm"].get<double>(), mx, tol);
  EXPECT_NEAR(s["p95_mm"].get<double>(), p95(e), tol);
}

struct Rows {
  std::vector<std::string> point, kind;
  std::vector<JointVector> q;
  std::vector<Eigen::Vector3d> xyz, m;
  std::vector<double> dist;
};

Rows read_rows(const std::string& file) {
  const CsvTable t = CsvTable::read(file);
  Rows r;
  for (std::size_t i = 0; i < t.row_count(); ++i) {
    auto num = [&](const char* c) { return t.numeric_cell(i, t.column_index(c)); };
    r.point.push_back(t.row(i)[t.column_index("point")]);
    r.kind.push_back(t.row(i)[t.column_index("kind")]);
    JointVector q;
    for (int k = 0; k < 6; ++k) q[k] = num(("q" + std::to_string(k + 1)).c_str());
    r.q.push_back(q);
    r.xyz.emplace_back(num("x"), num("y"), num("z"));
    r.m.emplace_back(num("mx"), num("my"), num("mz"));
    r.dist.push_back(t.has_column("dist_b0") ? num("dist_b0") : NAN);
  }
  return r;
}

/// Ordinary kriging of 3-vectors with the covariance of "sph(sill=S,range=A)+nug(N)" at a location
/// that is no sample: [K 1; 1' 0] [w; mu] = [k; 1], K_ii = S + N.
Eigen::Vector3d ordinary_kriging(const std::vector<Eigen::Vector3d>& x, const std::vector<Eigen::Vector3d>& v,
                                 const Eigen::Vector3d& at, double sill, double range, double nugget) {
  auto cov = [&](double h) { return h >= range ? 0.0 : sill * (1.0 - 1.5 * h / range + 0.5 * std::pow(h / range, 3)); };
  const Eigen::Index n = static_cast<Eigen::Index>(x.size());
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n + 1, n + 1);
  Eigen::VectorXd rhs(n + 1);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index j = 0; j < n; ++j)
      a(i, j) = i == j ? sill + nugget : cov((x[static_cast<std::size_t>(i)] - x[static_cast<std::size_t>(j)]).norm());
    a(i, n) = a(n, i) = 1.0;
    rhs[i] = cov((x[static_cast<std::size_t>(i)] - at).norm());
  }
  rhs[n] = 1.0;
  const Eigen::VectorXd w = a.fullPivLu().solve(rhs);
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (Eigen::Index i = 0; i < n; ++i) p += w[i] * v[static_cast<std::size_t>(i)];
  return p;
}

TEST_F(ValidateCli, PredictionModeScoresHeldOutRowsWithTheStoredRegistration) {
  ASSERT_EQ(run("simulate --seed 1 --sample grid --step 125 --robot-out robot.json --out train.csv").exit_code, 0);
  ASSERT_EQ(run("simulate --seed 2 --sample cells --step 125 --out holdout.csv").exit_code, 0);
  const std::string model = "sph(sill=0.5,range=600)+nug(0.001)";
  const CliResult fit = run("fit --robot robot.json --data train.csv --method vector-kriging --space task --model \"" + model +
                            "\" --out model.json");
  ASSERT_EQ(fit.exit_code, 0) << fit.output();
  const CliResult v = run("validate --model model.json --data holdout.csv --out points.csv --summary-out summary.json "
                          "--report report.html");
  ASSERT_EQ(v.exit_code, 0) << v.output();

  const MdhModel robot = MdhModel::load(path("robot.json"));
  const Rows train = read_rows(path("train.csv")), held = read_rows(path("holdout.csv"));
  std::vector<Eigen::Vector3d> tm, tn, samples, errors;
  for (std::size_t i = 0; i < train.q.size(); ++i)
    if (train.kind[i] == "target") {
      tm.push_back(train.m[i]);
      tn.push_back(train.xyz[i]);
    }
  // The stored registration is the training rows' (tracker -> nominal), at full precision.
  const Eigen::Isometry3d reg = horn(tm, tn);
  const nlohmann::json mj = json("model.json");
  ASSERT_TRUE(mj.contains("registration")) << mj.dump().substr(0, 400);
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 4; ++k)
      EXPECT_NEAR(mj["registration"]["robot_from_tracker"][i][k].get<double>(), reg.matrix()(i, k), 1e-9);
  for (std::size_t i = 0; i < tm.size(); ++i) errors.push_back(reg * tm[i] - tn[i]);

  std::vector<double> before, after, dbefore, dafter;
  const Eigen::Vector3d base_nominal = held.xyz[0];
  ASSERT_EQ(held.kind[0], "base");
  const Eigen::Vector3d base_pred = held.xyz[0] + ordinary_kriging(tn, errors, held.xyz[0], 0.5, 600, 0.001);
  for (std::size_t i = 0; i < held.q.size(); ++i) {
    if (held.kind[i] != "target") continue;
    const Eigen::Vector3d p = forward_position(robot, held.q[i]);
    ASSERT_LT((p - held.xyz[i]).norm(), 1e-6);
    const Eigen::Vector3d predicted = p + ordinary_kriging(tn, errors, p, 0.5, 600, 0.001);
    const Eigen::Vector3d measured = reg * held.m[i];
    before.push_back((measured - p).norm());
    after.push_back((measured - predicted).norm());
    dbefore.push_back(std::abs(held.dist[i] - (p - base_nominal).norm()));
    dafter.push_back(std::abs(held.dist[i] - (predicted - base_pred).norm()));
  }
  ASSERT_EQ(before.size(), 64u);
  const nlohmann::json s = json("summary.json");
  EXPECT_EQ(s["points"].get<std::size_t>(), 64u);
  EXPECT_EQ(s["refused"].get<std::size_t>(), 0u);
  expect_stats(s["position"]["before"], before, 1e-9);
  expect_stats(s["position"]["after"], after, 1e-6);
  expect_stats(s["distance"]["before"], dbefore, 1e-9);
  expect_stats(s["distance"]["after"], dafter, 1e-6);
  // the model must actually help on held-out rows
  EXPECT_LT(s["position"]["after"]["rms_mm"].get<double>(), 0.5 * s["position"]["before"]["rms_mm"].get<double>());

  const CsvTable pts = CsvTable::read(path("points.csv"));
  ASSERT_EQ(pts.row_count(), 64u);
  for (const char* c : {"point", "status", "before_mm", "after_mm", "before_dx", "before_dy", "before_dz", "after_dx",
                        "after_dy", "after_dz"})
    EXPECT_TRUE(pts.has_column(c)) << c;
  for (std::size_t i = 0; i < 64; ++i) {
    EXPECT_EQ(pts.row(i)[pts.column_index("status")], "ok");
    EXPECT_NEAR(pts.numeric_cell(i, pts.column_index("after_mm")), after[i], 1e-6);
  }
  // the console prints the same figures
  EXPECT_NE(v.out.find("3-D position error"), std::string::npos) << v.out;
  const std::string html = read("report.html");
  EXPECT_NE(html.find("<svg"), std::string::npos);
  EXPECT_NE(html.find("SIMULATED"), std::string::npos);
}

TEST_F(ValidateCli, EveryMethodIsScoredAndNoneChangesNothing) {
  ASSERT_EQ(run("simulate --seed 1 --sample grid --step 125 --robot-out robot.json --out train.csv").exit_code, 0);
  ASSERT_EQ(run("simulate --seed 2 --sample cells --step 125 --out holdout.csv").exit_code, 0);
  for (const std::string method : {"none", "kinematic", "kinematic+kriging", "distance-idw", "position-idw"}) {
    SCOPED_TRACE(method);
    ASSERT_EQ(run("fit --robot robot.json --data train.csv --method " + method + " --out m.json").exit_code, 0);
    const CliResult v = run("validate --model m.json --data holdout.csv --summary-out s.json");
    ASSERT_EQ(v.exit_code, 0) << v.output();
    const nlohmann::json s = json("s.json");
    ASSERT_TRUE(s["position"].is_object()) << s.dump();
    const double b = s["position"]["before"]["rms_mm"].get<double>(), a = s["position"]["after"]["rms_mm"].get<double>();
    if (method == "none") {
      EXPECT_NEAR(a, b, 1e-12);
    } else if (method != "distance-idw") {  // radial-only distance-idw need not help the 3-D error much
      EXPECT_LT(a, 0.8 * b);
    }
    const double db = s["distance"]["before"]["rms_mm"].get<double>(), da = s["distance"]["after"]["rms_mm"].get<double>();
    if (method != "none") EXPECT_LT(da, 0.8 * db);
  }
}

// "before" is the nominal robot in its own registration (what `fit --method none` stores), the same
// for a calibrated model as for the uncorrected one, never the calibrated model's frame (issue 19).
TEST_F(ValidateCli, BeforeIsTheNominalRobotInItsOwnRegistration) {
  ASSERT_EQ(run("simulate --seed 1 --sample grid --step 125 --robot-out robot.json --out train.csv").exit_code, 0);
  ASSERT_EQ(run("simulate --seed 2 --sample cells --step 125 --out holdout.csv").exit_code, 0);
  ASSERT_EQ(run("fit --robot robot.json --data train.csv --method none --out none.json").exit_code, 0);
  ASSERT_EQ(run("fit --robot robot.json --data train.csv --method kinematic --out kin.json").exit_code, 0);
  ASSERT_EQ(run("validate --model none.json --data holdout.csv --summary-out none_s.json").exit_code, 0);
  const CliResult v = run("validate --model kin.json --data holdout.csv --summary-out kin_s.json");
  ASSERT_EQ(v.exit_code, 0) << v.output();
  const nlohmann::json none = json("none_s.json"), kin = json("kin_s.json");
  // the uncorrected robot's "after" is the nominal robot in its own registration
  for (const char* k : {"mean_mm", "rms_mm", "p95_mm", "max_mm"})
    EXPECT_NEAR(kin["position"]["before"][k].get<double>(), none["position"]["after"][k].get<double>(), 1e-9) << k;
  // and that registration is Horn's fit of the training readings onto the nominal FK
  const MdhModel robot = MdhModel::load(path("robot.json"));
  const Rows train = read_rows(path("train.csv"));
  std::vector<Eigen::Vector3d> tm, fk;
  for (std::size_t i = 0; i < train.q.size(); ++i)
    if (train.kind[i] == "target") {
      tm.push_back(train.m[i]);
      fk.push_back(forward_position(robot, train.q[i]));
    }
  const Eigen::Isometry3d reg = horn(tm, fk);
  const nlohmann::json mj = json("kin.json");
  ASSERT_TRUE(mj.contains("nominal_registration"));
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 4; ++k)
      EXPECT_NEAR(mj["nominal_registration"]["robot_from_tracker"][i][k].get<double>(), reg.matrix()(i, k), 1e-9);
  // the summary says which registration each figure uses
  EXPECT_NE(kin["position"]["before_registration"].get<std::string>().find("nominal robot's own"), std::string::npos);
  EXPECT_NE(kin["position"]["after_registration"].get<std::string>().find("model's stored"), std::string::npos);
  EXPECT_NE(v.out.find("nominal robot's own registration"), std::string::npos) << v.out;
  // a model file without it (written before it was stored): the nominal robot registered on the
  // held-out rows, said so
  nlohmann::json old = mj;
  old.erase("nominal_registration");
  write("old.json", old.dump());
  ASSERT_EQ(run("validate --model old.json --data holdout.csv --summary-out old_s.json").exit_code, 0);
  EXPECT_NE(json("old_s.json")["position"]["before_registration"].get<std::string>().find("held-out rows"),
            std::string::npos);
}

// The uncertainty columns and figures of validate and predict follow from each other as documented:
// per-axis variance var_mm2/3 (one model for the 3 components), r95 = sqrt(chi2_3(0.95) var/3),
// var_mm2 - var_field_mm2 = 3 x the nugget, coverage95 and mean_nees over the points.
TEST_F(ValidateCli, UncertaintyFiguresFollowFromThePointColumns) {
  ASSERT_EQ(run("simulate --seed 1 --sample grid --step 125 --robot-out robot.json --out train.csv").exit_code, 0);
  ASSERT_EQ(run("simulate --seed 2 --sample cells --step 125 --out holdout.csv").exit_code, 0);
  ASSERT_EQ(run("fit --robot robot.json --data train.csv --method vector-kriging --space task --model "
                "\"sph(sill=0.5,range=600)+nug(0.001)\" --out model.json").exit_code, 0);
  const CliResult v = run("validate --model model.json --data holdout.csv --out points.csv --summary-out s.json");
  ASSERT_EQ(v.exit_code, 0) << v.output();
  const CsvTable t = CsvTable::read(path("points.csv"));
  const double chi2_95 = 7.814727903251178;  // scipy.stats.chi2.ppf(0.95, 3)
  double within = 0, nees_sum = 0, n = 0;
  for (std::size_t i = 0; i < t.row_count(); ++i) {
    if (t.row(i)[t.column_index("status")] != "ok") continue;
    auto num = [&](const char* c) { return t.numeric_cell(i, t.column_index(c)); };
    const double var = num("var_mm2"), axis = var / 3.0;
    EXPECT_NEAR(var - num("var_field_mm2"), 3.0 * 0.001, 1e-12);
    EXPECT_NEAR(num("r95_mm"), std::sqrt(chi2_95 * axis), 1e-9);
    const double e2 = num("after_dx") * num("after_dx") + num("after_dy") * num("after_dy") + num("after_dz") * num("after_dz");
    EXPECT_NEAR(num("nees"), e2 / axis, 1e-9 * (1.0 + e2 / axis));
    within += num("after_mm") <= num("r95_mm");
    nees_sum += num("nees");
    n += 1;
  }
  ASSERT_EQ(n, 64.0);
  const nlohmann::json u = json("s.json")["uncertainty"];
  ASSERT_TRUE(u.is_object()) << json("s.json").dump();
  EXPECT_EQ(u["points"].get<double>(), n);
  EXPECT_NEAR(u["coverage95"].get<double>(), within / n, 1e-12);
  EXPECT_NEAR(u["mean_nees"].get<double>(), nees_sum / n, 1e-9);
  EXPECT_NE(v.out.find("within the 95 % radius"), std::string::npos) << v.out;

  // predict writes the same three figures for the same joints
  ASSERT_EQ(run("predict --model model.json --joints holdout.csv --out p.csv").exit_code, 0);
  const CsvTable p = CsvTable::read(path("p.csv"));
  for (std::size_t i = 0; i < p.row_count(); ++i) {
    if (p.row(i)[p.column_index("status")] != "ok") continue;
    const double var = p.numeric_cell(i, p.column_index("var_mm2"));
    EXPECT_NEAR(var - p.numeric_cell(i, p.column_index("var_field_mm2")), 0.003, 1e-12);
    EXPECT_NEAR(p.numeric_cell(i, p.column_index("r95_mm")), std::sqrt(chi2_95 * var / 3.0), 1e-9);
  }
  // compensate's p_inside: P(|e| <= tol) of the 3-D error, chi-square with 3 degrees of freedom in
  // tol² / (var/3) (its CDF by Simpson integration of the density written here)
  ASSERT_EQ(run("compensate --model model.json --targets holdout.csv --tolerance 0.05 --out c.csv").exit_code, 0);
  const CsvTable c = CsvTable::read(path("c.csv"));
  std::size_t checked = 0;
  for (std::size_t i = 0; i < c.row_count(); ++i) {
    if (c.row(i)[c.column_index("status")] != "ok") continue;
    const double axis = c.numeric_cell(i, c.column_index("var_mm2")) / 3.0;
    const double tmax = 0.05 / std::sqrt(axis);  // integrate over t = |e| / sigma
    const int steps = 2000;
    double cdf = 0.0;
    for (int k = 0; k <= steps; ++k) {
      const double t = tmax * k / steps;
      const double w = (k == 0 || k == steps) ? 1.0 : (k % 2 ? 4.0 : 2.0);
      cdf += w * std::sqrt(2.0 / M_PI) * t * t * std::exp(-0.5 * t * t);  // density of |Z| for Z ~ N(0, I3)
    }
    cdf *= tmax / steps / 3.0;
    EXPECT_NEAR(c.numeric_cell(i, c.column_index("p_inside")), cdf, 1e-10);
    ++checked;
  }
  EXPECT_GT(checked, 60u);
}

TEST_F(ValidateCli, PredictWritesRobotAndTrackerPositions) {
  ASSERT_EQ(run("simulate --seed 1 --sample grid --step 125 --robot-out robot.json --out train.csv").exit_code, 0);
  ASSERT_EQ(run("fit --robot robot.json --data train.csv --method vector-kriging --space task --model "
                "\"sph(sill=0.5,range=600)+nug(0.001)\" --out model.json").exit_code, 0);
  const MdhModel robot = MdhModel::load(path("robot.json"));
  const Rows train = read_rows(path("train.csv"));
  std::vector<Eigen::Vector3d> tm, tn, errors;
  for (std::size_t i = 0; i < train.q.size(); ++i)
    if (train.kind[i] == "target") {
      tm.push_back(train.m[i]);
      tn.push_back(train.xyz[i]);
    }
  const Eigen::Isometry3d reg = horn(tm, tn);
  for (std::size_t i = 0; i < tm.size(); ++i) errors.push_back(reg * tm[i] - tn[i]);
  // two rows inside the cube, one far outside it
  const JointVector inside1 = train.q[7], inside2 = (train.q[32] + train.q[33]) / 2;  // interior grid points
  JointVector outside = train.q[7];
  outside[0] += 40;
  std::string csv = "q1,q2,q3,q4,q5,q6,label\n";
  for (const JointVector& q : {inside1, inside2, outside}) {
    for (int k = 0; k < 6; ++k) csv += format_number(q[k]) + ",";
    csv += "r\n";
  }
  write("joints.csv", csv);
  const CliResult p = run("predict --model model.json --joints joints.csv --out p.csv");
  ASSERT_EQ(p.exit_code, 0) << p.output();
  const CsvTable t = CsvTable::read(path("p.csv"));
  for (const char* c : {"label", "px", "py", "pz", "tx", "ty", "tz", "var_mm2", "status"}) EXPECT_TRUE(t.has_column(c)) << c;
  std::size_t r = 0;
  for (const JointVector& q : {inside1, inside2}) {
    const Eigen::Vector3d nominal = forward_position(robot, q);
    const Eigen::Vector3d expected = nominal + ordinary_kriging(tn, errors, nominal, 0.5, 600, 0.001);
    const Eigen::Vector3d tracker = reg.inverse() * expected;
    EXPECT_EQ(t.row(r)[t.column_index("status")], "ok");
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(t.numeric_cell(r, t.column_index(std::string(1, "xyz"[k]).insert(0, "p"))), expected[k], 1e-6);
      EXPECT_NEAR(t.numeric_cell(r, t.column_index(std::string(1, "xyz"[k]).insert(0, "t"))), tracker[k], 1e-6);
    }
    EXPECT_GT(t.numeric_cell(r, t.column_index("var_mm2")), 0.0);
    ++r;
  }
  EXPECT_EQ(t.row(2)[t.column_index("status")], "outside-region");
  EXPECT_EQ(t.row(2)[t.column_index("px")], "");
}

TEST_F(ValidateCli, CalibratedRobotCarriesItsRegistrationIntoFk) {
  ASSERT_EQ(run("simulate --seed 1 --sample grid --step 125 --robot-out robot.json --out train.csv").exit_code, 0);
  const CliResult c = run("calibrate --robot robot.json --data train.csv --model position --out cal.json");
  ASSERT_EQ(c.exit_code, 0) << c.output();
  const nlohmann::json cal = json("cal.json");
  ASSERT_TRUE(cal.contains("registration")) << cal.dump().substr(0, 300);
  ASSERT_EQ(cal["registration"]["reflector_offset_mm"].size(), 3u);
  // the calibrated robot, mapped to the tracker frame with the stored registration, lands on the
  // tracker readings (to the calibration's residual, a few hundredths of a mm)
  std::string joints = "point,q1,q2,q3,q4,q5,q6,mx,my,mz\n";
  const Rows rows = read_rows(path("train.csv"));
  for (std::size_t i = 0; i < rows.q.size(); ++i) {
    joints += rows.point[i];
    for (int k = 0; k < 6; ++k) joints += "," + format_number(rows.q[i][k]);
    for (int k = 0; k < 3; ++k) joints += "," + format_number(rows.m[i][k]);
    joints += "\n";
  }
  write("joints.csv", joints);
  const CliResult fk = run("fk --robot cal.json --input joints.csv --out fk.csv");
  ASSERT_EQ(fk.exit_code, 0) << fk.output();
  const CsvTable t = CsvTable::read(path("fk.csv"));
  double worst = 0, ss = 0;
  for (std::size_t i = 0; i < t.row_count(); ++i) {
    Eigen::Vector3d d;
    for (int k = 0; k < 3; ++k) {
      const std::string a(1, "xyz"[k]);
      d[k] = t.numeric_cell(i, t.column_index("t" + a)) - t.numeric_cell(i, t.column_index("m" + a));
    }
    worst = std::max(worst, d.norm());
    ss += d.squaredNorm();
  }
  EXPECT_LT(worst, 1.0);
  // exactly the residual the calibration reported for its registration (same rows, same transform)
  EXPECT_NEAR(std::sqrt(ss / static_cast<double>(t.row_count())), cal["registration"]["residual_rms_mm"].get<double>(), 1e-9);
  // a compensation model works as fk --robot too (its command model, and its registration)
  ASSERT_EQ(run("fit --robot robot.json --data train.csv --method none --out none.json").exit_code, 0);
  const CliResult fk2 = run("fk --robot none.json --input joints.csv --out fk2.csv");
  ASSERT_EQ(fk2.exit_code, 0) << fk2.output();
  EXPECT_TRUE(CsvTable::read(path("fk2.csv")).has_column("tx"));
  // and validate reads the calibrated robot JSON as a model
  ASSERT_EQ(run("simulate --seed 2 --sample cells --step 125 --out holdout.csv").exit_code, 0);
  const CliResult v = run("validate --model cal.json --robot robot.json --data holdout.csv --summary-out s.json");
  ASSERT_EQ(v.exit_code, 0) << v.output();
  const nlohmann::json s = json("s.json");
  EXPECT_LT(s["position"]["after"]["rms_mm"].get<double>(), 0.5 * s["position"]["before"]["rms_mm"].get<double>());
}

TEST_F(ValidateCli, TargetsModeScoresTheValidationRunAfterCompensation) {
  ASSERT_EQ(run("simulate --seed 1 --sample grid --step 125 --robot-out robot.json --out train.csv").exit_code, 0);
  ASSERT_EQ(run("fit --robot robot.json --data train.csv --method vector-kriging --space task --model "
                "\"sph(sill=0.5,range=600)+nug(0.001)\" --out model.json").exit_code, 0);
  ASSERT_EQ(run("simulate --seed 3 --sample cells --step 125 --out targets.csv").exit_code, 0);
  ASSERT_EQ(run("compensate --model model.json --targets targets.csv --out joints.csv").exit_code, 0);
  // the validation run: the robot (simulated) is sent the compensated joints, and for the baseline
  // the nominal ones; the tracker measures both
  const CsvTable joints = CsvTable::read(path("joints.csv"));
  std::string cq = "q1,q2,q3,q4,q5,q6\n", nq = cq;
  std::vector<std::size_t> rows;
  for (std::size_t i = 0; i < joints.row_count(); ++i) {
    if (joints.row(i)[joints.column_index("kind")] != "target") continue;
    ASSERT_EQ(joints.row(i)[joints.column_index("status")], "ok");
    rows.push_back(i);
    for (int k = 1; k <= 6; ++k) {
      cq += joints.row(i)[joints.column_index("cq" + std::to_string(k))] + (k < 6 ? "," : "\n");
      nq += joints.row(i)[joints.column_index("nq" + std::to_string(k))] + (k < 6 ? "," : "\n");
    }
  }
  write("cq.csv", cq);
  write("nq.csv", nq);
  ASSERT_EQ(run("simulate --seed 4 --joints cq.csv --measure positions --out after.csv").exit_code, 0);
  ASSERT_EQ(run("simulate --seed 5 --joints nq.csv --measure positions --out before.csv").exit_code, 0);
  const Rows after = read_rows(path("after.csv")), before = read_rows(path("before.csv"));
  std::string csv = "point,run,nx,ny,nz,mx,my,mz\n";
  std::vector<Eigen::Vector3d> goal;
  for (std::size_t j = 0; j < rows.size(); ++j) {
    const std::size_t i = rows[j];
    std::string target;
    for (const char* c : {"nx", "ny", "nz"}) target += "," + joints.row(i)[joints.column_index(c)];
    goal.emplace_back(joints.numeric_cell(i, joints.column_index("nx")), joints.numeric_cell(i, joints.column_index("ny")),
                      joints.numeric_cell(i, joints.column_index("nz")));
    const std::string name = joints.row(i)[joints.column_index("point")];
    for (const auto* m : {&before, &after}) {
      const Eigen::Vector3d r = m->m[j + 1];  // row 0 is the base b0
      csv += name + (m == &before ? ",before" : ",after") + target + "," + format_number(r.x()) + "," +
             format_number(r.y()) + "," + format_number(r.z()) + "\n";
    }
  }
  write("run.csv", csv);
  const CliResult v = run("validate --targets --model model.json --data run.csv --summary-out s.json --out pts.csv");
  ASSERT_EQ(v.exit_code, 0) << v.output();
  // independent: error = registered measurement - target, with the training rows' registration
  const Rows train = read_rows(path("train.csv"));
  std::vector<Eigen::Vector3d> tm, tn;
  for (std::size_t i = 0; i < train.q.size(); ++i)
    if (train.kind[i] == "target") {
      tm.push_back(train.m[i]);
      tn.push_back(train.xyz[i]);
    }
  const Eigen::Isometry3d reg = horn(tm, tn);
  std::vector<double> eb, ea;
  for (std::size_t j = 0; j < rows.size(); ++j) {
    eb.push_back((reg * before.m[j + 1] - goal[j]).norm());
    ea.push_back((reg * after.m[j + 1] - goal[j]).norm());
  }
  const nlohmann::json s = json("s.json");
  EXPECT_EQ(s["mode"], "targets");
  EXPECT_EQ(s["points"].get<std::size_t>(), rows.size());
  expect_stats(s["position"]["before"], eb, 1e-9);
  expect_stats(s["position"]["after"], ea, 1e-9);
  EXPECT_LT(s["position"]["after"]["rms_mm"].get<double>(), 0.5 * s["position"]["before"]["rms_mm"].get<double>());
}

TEST_F(ValidateCli, CompensateSolvesPoseTargetsOnTheBranchOfTheData) {
  ASSERT_EQ(run("simulate --seed 1 --sample grid --step 125 --robot-out robot.json --out grid.csv").exit_code, 0);
  const MdhModel robot = MdhModel::load(path("robot.json"));
  const Rows grid = read_rows(path("grid.csv"));
  // a multistart solver reaches the targets below on one wrist branch (what compensate did before);
  // measure the grid on the other one (q4 + 180, -q5, q6 + 180 reach the same pose)
  const IkResult multistart = inverse_kinematics_multistart(robot, to_isometry({900, -100, 500, 180, 0, 0}));
  ASSERT_TRUE(multistart.ok());
  std::string csv = "q1,q2,q3,q4,q5,q6\n";
  double data_q5 = 0;
  for (std::size_t i = 0; i < grid.q.size(); ++i) {
    if (grid.kind[i] != "target") continue;
    JointVector q = grid.q[i];
    if (q[4] * multistart.q_deg[4] > 0) {
      q[3] += q[3] > 0 ? -180 : 180;
      q[4] = -q[4];
      q[5] += q[5] > 0 ? -180 : 180;
    }
    data_q5 = q[4];
    for (int k = 0; k < 6; ++k) csv += format_number(q[k]) + (k < 5 ? "," : "\n");
  }
  write("flipped.csv", csv);
  ASSERT_EQ(run("simulate --seed 1 --joints flipped.csv --measure positions --out train.csv").exit_code, 0);
  ASSERT_EQ(run("fit --robot robot.json --data train.csv --method vector-kriging --space joint --model "
                "\"sph(sill=0.5,range=200)+nug(0.001)\" --out model.json").exit_code, 0);
  // pose targets inside the cube at the data's orientation
  const std::vector<Eigen::Vector3d> points{{900, -100, 500}, {1010, 40, 600}, {1200, 200, 800}};
  std::string targets = "x,y,z,rx,ry,rz\n";
  for (const auto& p : points) targets += format_number(p.x()) + "," + format_number(p.y()) + "," + format_number(p.z()) + ",180,0,0\n";
  write("targets.csv", targets);
  ASSERT_LT(multistart.q_deg[4] * data_q5, 0.0) << "the data are on the other branch than multistart's";
  const CliResult c = run("compensate --model model.json --targets targets.csv --out joints.csv");
  ASSERT_EQ(c.exit_code, 0) << c.output();
  const CsvTable t = CsvTable::read(path("joints.csv"));
  for (std::size_t r = 0; r < points.size(); ++r) {
    EXPECT_EQ(t.row(r)[t.column_index("status")], "ok");
    EXPECT_GT(t.numeric_cell(r, t.column_index("nq5")) * data_q5, 0.0) << "row " << r << ": solved on the data's branch";
    EXPECT_GT(t.numeric_cell(r, t.column_index("cq5")) * data_q5, 0.0);
  }
}

// Where the misses at the other points lie within the variance the model states there, the
// orientation residual they measure is none beyond it: fit said "0 mrad per axis (1 sd)", read as a
// flange whose orientation is known exactly (issue 47 item 1; the real UR10 probe fit printed it).
TEST_F(ValidateCli, AnOrientationResidualWithinTheStatedVarianceIsNotCalledZeroMrad) {
  ASSERT_EQ(run("simulate --robot kr16 --seed 3 --sample scattered:200 --orientation-spread 30 --measure positions "
                "--systematic realistic --reflectors \"0,0,100;150,0,100;0,150,100\" --robot-out k.json --out n.csv")
                .exit_code,
            0);
  nlohmann::json robot = json("k.json");
  robot["tool"] = {{"x_mm", 0.0}, {"y_mm", 0.0}, {"z_mm", 100.0}, {"rx_deg", 0.0}, {"ry_deg", 0.0}, {"rz_deg", 0.0}};
  write("k1.json", robot.dump());
  const CliResult fit = run("fit --robot k1.json --data n.csv --out m.json");
  ASSERT_EQ(fit.exit_code, 0) << fit.err;
  EXPECT_NE(fit.out.find("readings: none beyond the variance the model states there"), std::string::npos) << fit.out;
  EXPECT_EQ(fit.out.find(" 0 mrad per axis"), std::string::npos) << fit.out;
}

// --tool moves the point predicted by the FK lever alone (the field is the same at every point of the
// flange; checked against FK here), widens the variance by the orientation term and is checked;
// locate-tool finds a second reflector from readings of it and refuses readings at one orientation.
// Readings of three nests on one plate (SIMULATED KR 16, realistic effects the kinematic model cannot
// express, tool orientations within 30 deg): a model fitted on r1 and r3 together (one calibration
// that locates r3 and so sees the flange's orientation), moved to r2 located from 40 readings,
// scores r2's held-out readings within 1.25x of a model fitted at r2 itself (issue 34; 1.02x here: the
// rigid motion of the flange its fields at r1 and r3 imply, plus the kriged residual of the 40
// readings), better than a model of r1 alone moved the same way, and both their 95 % radii hold: of
// 200 held-out readings, 95 % +- 2.5 binomial sd (1.5 % each) is 0.91-0.99.
TEST_F(ValidateCli, TwoReflectorsFitOneModelThatTransfersToALocatedThirdPoint) {
  ASSERT_EQ(run("simulate --robot kr16 --seed 3 --sample scattered:440 --orientation-spread 30 --measure positions "
                "--systematic realistic --reflectors \"0,0,100;150,0,100;0,150,100\" --robot-out kr16.json "
                "--out refl.csv").exit_code, 0);
  for (const auto& [name, p] : std::vector<std::pair<std::string, Eigen::Vector3d>>{
           {"r1", {0, 0, 100}}, {"r2", {150, 0, 100}}, {"r3", {0, 150, 100}}}) {
    nlohmann::json robot = json("kr16.json");
    robot["tool"] = {{"x_mm", p.x()}, {"y_mm", p.y()}, {"z_mm", p.z()}, {"rx_deg", 0.0}, {"ry_deg", 0.0}, {"rz_deg", 0.0}};
    write("kr16_" + name + ".json", robot.dump());
  }
  const CsvTable all = CsvTable::read(path("refl.csv"));
  const std::size_t point = all.column_index("point"), reflector = all.column_index("reflector"), kind = all.column_index("kind");
  std::vector<std::string> poses;  // in file order: the first 240 train, the rest are held out
  for (std::size_t i = 0; i < all.row_count(); ++i)
    if (all.cell(i, kind) == "target" && (poses.empty() || poses.back() != all.cell(i, point))) poses.emplace_back(all.cell(i, point));
  ASSERT_EQ(poses.size(), 440u);
  const std::set<std::string> train(poses.begin(), poses.begin() + 240);
  auto subset = [&](const std::string& out, std::set<std::string> labels, bool training, std::size_t limit = 0) {
    std::size_t taken = 0;
    rewrite("refl.csv", out, [](const CsvTable&, std::size_t, std::vector<std::string>&) {},
            [](const std::string&) { return true; },
            [&](std::size_t i) {
              const bool keep = all.cell(i, kind) == "target" && labels.count(std::string(all.cell(i, reflector))) &&
                                train.count(std::string(all.cell(i, point))) == (training ? 1u : 0u) &&
                                (limit == 0 || taken < limit);
              taken += keep ? 1 : 0;
              return keep;
            });
  };
  subset("train_r13.csv", {"r1", "r3"}, true);
  subset("train_r1.csv", {"r1"}, true);
  subset("train_r2.csv", {"r2"}, true);
  subset("locate_r2.csv", {"r2"}, true, 40);
  subset("test_r2.csv", {"r2"}, false);
  subset("train_r3.csv", {"r3"}, true);
  subset("test_r3.csv", {"r3"}, false);
  subset("test_all.csv", {"r1", "r2", "r3"}, false);
  const CliResult both = run("fit --robot kr16_r1.json --data train_r13.csv --out m13.json");
  ASSERT_EQ(both.exit_code, 0) << both.output();
  EXPECT_NE(both.out.find("points on the flange located with the robot"), std::string::npos) << both.out;
  EXPECT_NE(both.out.find("orientation residual of the flange measured"), std::string::npos) << both.out;
  ASSERT_EQ(run("fit --robot kr16_r1.json --data train_r1.csv --out m1.json").exit_code, 0);
  ASSERT_EQ(run("fit --robot kr16_r2.json --data train_r2.csv --out m2.json").exit_code, 0);
  auto score = [&](const std::string& model, const std::string& located) {
    const CliResult l = run("locate-tool --model " + model + " --data locate_r2.csv --out " + located);
    EXPECT_EQ(l.exit_code, 0) << l.output();
    const CliResult v = run("validate --model " + located + " --data test_r2.csv --summary-out s.json");
    EXPECT_EQ(v.exit_code, 0) << v.output();
    const nlohmann::json s = json("s.json");
    return std::make_pair(s["position"]["after"]["rms_mm"].get<double>(), s["uncertainty"]["coverage95"].get<double>());
  };
  const auto [rms13, coverage13] = score("m13.json", "m13_r2.json");
  const auto [rms1, coverage1] = score("m1.json", "m1_r2.json");
  ASSERT_EQ(run("validate --model m2.json --data test_r2.csv --summary-out s2.json").exit_code, 0);
  const double own = json("s2.json")["position"]["after"]["rms_mm"].get<double>();
  EXPECT_LT(rms13, 1.25 * own) << rms13 << " mm vs " << own << " mm fitted at r2";
  EXPECT_LT(rms13, rms1) << "r1 and r3 " << rms13 << " mm, r1 alone " << rms1 << " mm";
  EXPECT_GE(coverage13, 0.91);
  EXPECT_LE(coverage13, 0.99);
  // The one-point model's radius holds at the located point too: the kriged residual of the 40
  // readings (below) and, under it, the orientation residual they measured at that lever (0.83 mrad
  // here, against the 0.33 mrad one-point guess, under which 0.50 of the readings fell inside).
  EXPECT_GE(coverage1, 0.91) << rms1;
  EXPECT_LE(coverage1, 0.99) << rms1;
  EXPECT_TRUE(json("m1_r2.json").contains("orientation_residual"));
  // The located point's own readings, kriged over the joints (tool_point_correction), carry the turn
  // of the flange the model's points do not see. The same located models without it (the member
  // taken out: the orientation term then stands for it, as before session 23) scored 0.0511 mm (r1
  // and r3) and 0.166 mm (r1 alone) here; with it 0.0457 and 0.0507 mm, so even the one-point model
  // is within 1.25x of the model fitted at r2.
  for (const std::string name : {"m13_r2", "m1_r2"}) {
    nlohmann::json bare = json(name + ".json");
    ASSERT_TRUE(bare.contains("tool_point_correction")) << name;
    bare.erase("tool_point_correction");
    write(name + "_bare.json", bare.dump());
  }
  ASSERT_EQ(run("validate --model m13_r2_bare.json --data test_r2.csv --summary-out s13b.json").exit_code, 0);
  // The one-point model without its correction: the orientation residual its 40 readings measured
  // (taken at its one-sided 95 % upper bound since issue 47) supports no 150 mm lever, so its rows are
  // refused (orientation-unknown) where before this it scored them at 0.166 mm; with the correction
  // they are scored (rms1 above).
  const CliResult bare1 = run("validate --model m1_r2_bare.json --data test_r2.csv --summary-out s1b.json");
  EXPECT_EQ(bare1.exit_code, 1) << bare1.output();
  EXPECT_NE(bare1.err.find("orientation-unknown"), std::string::npos) << bare1.err;
  const double rms13_bare = json("s13b.json")["position"]["after"]["rms_mm"].get<double>();
  EXPECT_LT(rms13, 0.95 * rms13_bare) << rms13 << " mm with the correction, " << rms13_bare << " without";
  EXPECT_LT(rms1, 1.25 * own) << rms1 << " mm vs " << own << " mm fitted at r2";
  // The correction is of the located point's readings: moved by hand to another point, the model is
  // refused, naming the member (a correction never applies where it was not measured).
  nlohmann::json moved = json("m1_r2.json");
  moved["tool_point_correction"]["point_mm"][0] = moved["tool_point_correction"]["point_mm"][0].get<double>() + 20.0;
  write("m1_r2_moved.json", moved.dump());
  const CliResult moved_run = run("validate --model m1_r2_moved.json --data test_r2.csv");
  EXPECT_EQ(moved_run.exit_code, 2) << moved_run.output();
  EXPECT_NE(moved_run.output().find("tool_point_correction"), std::string::npos) << moved_run.output();
  // Not located, the one-point model does not know the flange's constant orientation error there
  // (0.5 mm at 150 mm on this robot): it refuses, naming the orientation and what would lift it.
  const CliResult unlocated = run("validate --model m1.json --data test_r2.csv --tool 150,0,100 --summary-out s1.json");
  EXPECT_EQ(unlocated.exit_code, 1) << unlocated.output();
  EXPECT_NE(unlocated.output().find("orientation-unknown"), std::string::npos) << unlocated.output();
  EXPECT_NE(unlocated.output().find("locate-tool"), std::string::npos) << unlocated.output();
  // validate takes the file of all three labels: the model's own by default, r3 at the point fit
  // located for it (scored as well as r1 there: both were fitted), r2 refused until located.
  const CliResult own_rows = run("validate --model m13.json --data test_all.csv --summary-out s_own.json");
  ASSERT_EQ(own_rows.exit_code, 0) << own_rows.output();
  const CliResult r3_rows = run("validate --model m13.json --data test_all.csv --reflector r3 --summary-out s_r3.json");
  ASSERT_EQ(r3_rows.exit_code, 0) << r3_rows.output();
  const double at_r1 = json("s_own.json")["position"]["after"]["rms_mm"].get<double>();
  const double at_r3 = json("s_r3.json")["position"]["after"]["rms_mm"].get<double>();
  EXPECT_EQ(json("s_own.json")["points"].get<int>(), 200);
  EXPECT_EQ(json("s_r3.json")["points"].get<int>(), 200);
  EXPECT_LT(at_r3, 1.25 * at_r1) << "r3 " << at_r3 << " mm, r1 " << at_r1 << " mm";
  // r3 is predicted by a field of its own readings (flange_points[1].field), so the two-point model
  // does as well there as a model fitted at r3 alone (0.0454 against 0.0438 mm here; 1.09x before
  // r3 had a field); 1.1x leaves the one calibration for two points its due.
  EXPECT_TRUE(json("m13.json")["flange_points"][1].contains("field"));
  ASSERT_EQ(run("fit --robot kr16_r3.json --data train_r3.csv --out m3.json").exit_code, 0);
  ASSERT_EQ(run("validate --model m3.json --data test_r3.csv --summary-out s3.json").exit_code, 0);
  const double own_r3 = json("s3.json")["position"]["after"]["rms_mm"].get<double>();
  EXPECT_LT(at_r3, 1.1 * own_r3) << "r3 " << at_r3 << " mm, fitted at r3 alone " << own_r3 << " mm";
  const CliResult r2_rows = run("validate --model m13.json --data test_all.csv --reflector r2 --summary-out s_r2.json");
  EXPECT_EQ(r2_rows.exit_code, 2) << r2_rows.output();
  EXPECT_NE(r2_rows.output().find("locate-tool"), std::string::npos) << r2_rows.output();
  EXPECT_FALSE(std::filesystem::exists(path("s_r2.json")));
  // The measured orientation residual is stored, and a hand-edited one beyond any robot is refused.
  nlohmann::json edited = json("m13.json");
  ASSERT_TRUE(edited.contains("orientation_residual")) << edited.dump().substr(0, 200);
  EXPECT_EQ(edited["orientation_residual"]["add_floor"], true) << "r1 and r3 are two points: one line";
  edited["orientation_residual"]["sigma_rad"] = 5.0;
  write("m13_edited.json", edited.dump());
  const CliResult hand = run("validate --model m13_edited.json --data test_r2.csv --tool 150,0,100");
  EXPECT_EQ(hand.exit_code, 2) << hand.output();
  EXPECT_NE(hand.output().find("orientation_residual"), std::string::npos) << hand.output();
  // A method that models one point refuses several, naming the column.
  const CliResult one_point = run("fit --robot kr16_r1.json --data train_r13.csv --method vector-kriging --out mv.json");
  EXPECT_EQ(one_point.exit_code, 2) << one_point.output();
  EXPECT_NE(one_point.output().find("reflector"), std::string::npos) << one_point.output();
  const CliResult unknown = run("fit --robot kr16_r1.json --data train_r13.csv --tool-reflector r9 --out mx.json");
  EXPECT_EQ(unknown.exit_code, 2) << unknown.output();
  EXPECT_NE(unknown.output().find("'r9'"), std::string::npos) << unknown.output();
  EXPECT_FALSE(std::filesystem::exists(path("mv.json")) || std::filesystem::exists(path("mx.json")));
  // calibrate locates every label with the robot: r3 within 2 mm of where it was mounted
  const CliResult cal = run("calibrate --robot kr16_r1.json --data train_r13.csv --model position --out cal.json");
  ASSERT_EQ(cal.exit_code, 0) << cal.output();
  EXPECT_NE(cal.out.find("'r3' is flange point 1"), std::string::npos) << cal.out;
}

TEST_F(ValidateCli, ToolOptionAndLocateToolWorkAtAnotherPointOfTheFlange) {
  ASSERT_EQ(run("simulate --seed 1 --sample grid --step 125 --robot-out robot.json --out train.csv").exit_code, 0);
  ASSERT_EQ(run("fit --robot robot.json --data train.csv --method vector-kriging --space task --model "
                "\"sph(sill=0.5,range=600)+nug(0.001)\" --out model.json").exit_code, 0);
  const MdhModel robot = MdhModel::load(path("robot.json"));
  const Rows train = read_rows(path("train.csv"));
  const JointVector q = (train.q[32] + train.q[33]) / 2;
  std::string csv = "q1,q2,q3,q4,q5,q6\n";
  for (int k = 0; k < 6; ++k) csv += format_number(q[k]) + (k < 5 ? "," : "\n");
  write("joints.csv", csv);
  // the tool moved by 100 mm along its own x axis
  const Eigen::Vector3d b = robot.tool() * Eigen::Vector3d(100, 0, 0);
  const std::string tool = format_number(b.x()) + "," + format_number(b.y()) + "," + format_number(b.z());
  ASSERT_EQ(run("predict --model model.json --joints joints.csv --out a.csv").exit_code, 0);
  const CliResult moved = run("predict --model model.json --joints joints.csv --tool " + tool + " --out b.csv");
  ASSERT_EQ(moved.exit_code, 0) << moved.output();
  EXPECT_NE(moved.out.find("100 mm from the reflector"), std::string::npos) << moved.out;
  const CsvTable ta = CsvTable::read(path("a.csv")), tb = CsvTable::read(path("b.csv"));
  Eigen::Isometry3d tool_b = robot.tool();
  tool_b.translation() = b;
  const Eigen::Vector3d fk_shift = forward_position(robot.with_tool(tool_b), q) - forward_position(robot, q);
  for (int k = 0; k < 3; ++k) {
    const std::string c = std::string("p") + "xyz"[k];
    EXPECT_NEAR(tb.numeric_cell(0, tb.column_index(c)) - ta.numeric_cell(0, ta.column_index(c)), fk_shift[k], 1e-6) << c;
  }
  EXPECT_EQ(tb.row(0)[tb.column_index("status")], "ok");
  EXPECT_GT(tb.numeric_cell(0, tb.column_index("var_mm2")), ta.numeric_cell(0, ta.column_index("var_mm2")));
  EXPECT_GT(tb.numeric_cell(0, tb.column_index("r95_mm")), ta.numeric_cell(0, ta.column_index("r95_mm")));
  // bad values: usage errors naming the option, nothing written
  for (const char* bad : {"3000,0,0", "1,2", "1,2,x", "nan,0,0"}) {
    const CliResult r = run(std::string("predict --model model.json --joints joints.csv --tool ") + bad + " --out c.csv");
    EXPECT_EQ(r.exit_code, 2) << bad << "\n" << r.output();
    EXPECT_NE(r.output().find("--tool"), std::string::npos) << r.output();
  }
  EXPECT_FALSE(std::filesystem::exists(path("c.csv")));
  // the second reflector measured at several orientations (the same robot: the same seed)
  ASSERT_EQ(run("simulate --seed 1 --sample grid --step 250 --orientation-spread 30 --tool-offset 100,0,0 --out b_all.csv")
                .exit_code, 0);
  const CliResult located = run("locate-tool --model model.json --data b_all.csv --out m_tool.json");
  ASSERT_EQ(located.exit_code, 0) << located.output();
  const nlohmann::json m = json("m_tool.json");
  ASSERT_TRUE(m.contains("working_tool")) << m.dump();
  const Eigen::Vector3d found(m["working_tool"].value("x_mm", 0.0), m["working_tool"].value("y_mm", 0.0),
                              m["working_tool"].value("z_mm", 0.0));
  // the simulated robot's tool differs from the nominal one by its geometric deviation (< 1 mm)
  EXPECT_LT((found - b).norm(), 1.0) << found.transpose() << " vs " << b.transpose() << "\n" << located.out;
  // validate scores the working tool: readings of it are its own point, whether located or given
  // with --tool, while the model at its reflector refuses them as another point (100 mm away). The
  // simulated x,y,z are the commanded reflector's nominal positions, so they go.
  rewrite("b_all.csv", "b_readings.csv", [](const CsvTable&, std::size_t, std::vector<std::string>&) {},
          [](const std::string& c) { return c != "x" && c != "y" && c != "z"; });
  const CliResult at_located = run("validate --model m_tool.json --data b_readings.csv --summary-out s_loc.json");
  EXPECT_EQ(at_located.exit_code, 0) << at_located.output();
  const CliResult at_tool = run("validate --model model.json --data b_readings.csv --tool " + tool + " --summary-out s_tool.json");
  EXPECT_EQ(at_tool.exit_code, 0) << at_tool.output();
  const CliResult at_reflector = run("validate --model model.json --data b_readings.csv --summary-out s_refl.json");
  EXPECT_EQ(at_reflector.exit_code, 2) << at_reflector.output();
  EXPECT_NE(at_reflector.output().find("another point"), std::string::npos) << at_reflector.output();
  EXPECT_FALSE(std::filesystem::exists(path("s_refl.json")));
  // readings at one orientation (the tool-down grid) cannot locate it
  const CliResult one = run("locate-tool --model model.json --data train.csv --out m2.json");
  EXPECT_EQ(one.exit_code, 2) << one.output();
  EXPECT_NE(one.output().find("distinct flange orientation"), std::string::npos) << one.output();
  EXPECT_FALSE(std::filesystem::exists(path("m2.json")));
}

}  // namespace
}  // namespace errfield::compensation
