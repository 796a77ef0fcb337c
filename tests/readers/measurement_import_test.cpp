// import-measurements on small foreign files written here: each difference a real export has
// (separator, decimal comma, column names, radians, metres, Euler and quaternion conventions, a
// target and a difference) read into errfield's columns, checked against the values computed in the
// test; each kind of bad input refused naming file, line, column and value. The real data sets are
// in realdata_test.cpp.

#include "errfield/readers/measurement_import.hpp"

#include <algorithm>
#include <numbers>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"
#include "errfield/robot/pose.hpp"
#include "support/cli_harness.hpp"

namespace errfield::readers {
namespace measurement_import_test {

constexpr double kRad = std::numbers::pi / 180.0;

class ImportMeasurements : public errfield::testing::CliTest {
 protected:
  // Runs the command and reads its output back with errfield's reader.
  CsvTable imported(const std::string& options) {
    const auto r = run("import-measurements --out " + path("out.csv") + " " + options);
    EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
    return CsvTable::read(path("out.csv"));
  }
  void expect_refused(const std::string& options, const std::vector<std::string>& words) {
    const auto r = run("import-measurements --out " + path("refused.csv") + " " + options);
    EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
    for (const auto& w : words) EXPECT_NE(r.err.find(w), std::string::npos) << "missing '" << w << "' in:\n" << r.err;
    EXPECT_FALSE(std::filesystem::exists(path("refused.csv")));
  }
};

// Six rows of joints, enough for the unit checks to speak.
std::string joint_rows(char sep, char decimal, bool radians) {
  std::string text;
  for (int k = 0; k < 6; ++k) {
    std::string row = "p" + std::to_string(k);
    for (int j = 0; j < 6; ++j) {
      const double deg = 10.0 * (k + 1) + j - 30.0;
      std::string v = format_number(radians ? deg * kRad : deg);
      if (decimal == ',') std::replace(v.begin(), v.end(), '.', ',');
      row += sep + v;
    }
    for (const char* p : {"1500.25", "-200.5", "300.75"}) {
      std::string v = p;
      if (decimal == ',') std::replace(v.begin(), v.end(), '.', ',');
      row += sep + v;
    }
    text += row + "\n";
  }
  return text;
}

TEST_F(ImportMeasurements, SemicolonsDecimalCommasRadiansAndAMap) {
  write("in.csv", "Name;A1;A2;A3;A4;A5;A6;X [mm];Y [mm];Z [mm]\n" + joint_rows(';', ',', true));
  const CsvTable t = imported("--in " + path("in.csv") +
                              " --sep ';' --decimal , --joint-units rad --map point=Name,q1=A1,q2=A2,q3=A3,q4=A4,q5=A5,"
                              "q6=A6,mx=X,my=Y,mz=Z --series day1");
  ASSERT_EQ(t.row_count(), 6u);
  EXPECT_EQ(t.header(), (std::vector<std::string>{"point", "q1", "q2", "q3", "q4", "q5", "q6", "mx", "my", "mz", "series"}));
  for (std::size_t r = 0; r < 6; ++r) {
    EXPECT_EQ(t.row(r)[0], "p" + std::to_string(r));
    for (int j = 0; j < 6; ++j)
      EXPECT_NEAR(t.numeric_cell(r, static_cast<std::size_t>(j + 1)), 10.0 * static_cast<double>(r + 1) + j - 30.0, 1e-12);
    EXPECT_EQ(t.numeric_cell(r, 7), 1500.25);
    EXPECT_EQ(t.numeric_cell(r, 9), 300.75);
    EXPECT_EQ(t.row(r)[10], "day1");
  }
}

TEST_F(ImportMeasurements, TargetPlusOrMinusDifferenceInMetres) {
  write("in.csv", "q1,q2,q3,q4,q5,q6,xt,yt,zt,ex,ey,ez\n"
                  "10,20,30,40,50,60,1.5,-0.25,0.75,0.001,-0.002,0.0005\n"
                  "11,21,31,41,51,61,1.25,0.5,0.5,-0.001,0.003,0\n");
  for (const auto& [from, sign] : std::vector<std::pair<std::string, double>>{{"target+dif", 1.0}, {"target-dif", -1.0}}) {
    const CsvTable t = imported("--in " + path("in.csv") + " --length-units m --position-from " + from +
                                " --map tx=xt,ty=yt,tz=zt,dx=ex,dy=ey,dz=ez");
    EXPECT_NEAR(t.numeric_column("mx")[0], (1.5 + sign * 0.001) * 1000, 1e-9) << from;
    EXPECT_NEAR(t.numeric_column("my")[1], (0.5 + sign * 0.003) * 1000, 1e-9) << from;
    EXPECT_EQ(t.row(1)[0], "2");  // no point column: the data row's number
  }
}

TEST_F(ImportMeasurements, OrientationConventionsBecomeFixedAxisXyz) {
  // One orientation written three ways: intrinsic XYZ degrees, extrinsic zyx radians, quaternion
  // x,y,z,w. Each must come out as the same errfield mrx,mry,mrz.
  const Eigen::Vector3d a(20.0, -35.0, 110.0);  // intrinsic X-Y-Z, degrees
  const Eigen::Matrix3d r = (Eigen::AngleAxisd(a.x() * kRad, Eigen::Vector3d::UnitX()) *
                             Eigen::AngleAxisd(a.y() * kRad, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(a.z() * kRad, Eigen::Vector3d::UnitZ()))
                                .toRotationMatrix();
  const Eigen::Quaterniond q(r);
  const std::string joints = "1,2,3,4,5,6,100,200,300";
  write("intrinsic.csv", "q1,q2,q3,q4,q5,q6,mx,my,mz,rx,ry,rz\n" + joints + "," + format_number(a.x()) + "," +
                             format_number(a.y()) + "," + format_number(a.z()) + "\n");
  // Extrinsic z-y-x: the same rotation is Rx Ry Rz = turn about fixed z by c, then y by b, then x by a.
  write("extrinsic.csv", "q1,q2,q3,q4,q5,q6,mx,my,mz,e1,e2,e3\n" + joints + "," + format_number(a.z() * kRad) + "," +
                             format_number(a.y() * kRad) + "," + format_number(a.x() * kRad) + "\n");
  write("quaternion.csv", "q1,q2,q3,q4,q5,q6,mx,my,mz,a,b,c,d\n" + joints + "," + format_number(q.x()) + "," +
                              format_number(q.y()) + "," + format_number(q.z()) + "," + format_number(q.w()) + "\n");
  const std::vector<std::string> runs = {
      "--in " + path("intrinsic.csv") + " --euler XYZ-intrinsic --map mrx=rx,mry=ry,mrz=rz",
      "--in " + path("extrinsic.csv") + " --euler zyx-extrinsic --angle-units rad --map mr1=e1,mr2=e2,mr3=e3",
      "--in " + path("quaternion.csv") + " --quaternion xyzw --map mq=a+b+c+d"};
  for (const std::string& options : runs) {
    const CsvTable t = imported(options + " --no-unit-check");
    const Eigen::Matrix3d got =
        robot::rotation_from_rpy_deg(t.numeric_column("mrx")[0], t.numeric_column("mry")[0], t.numeric_column("mrz")[0]);
    EXPECT_LT((got - r).cwiseAbs().maxCoeff(), 1e-12) << options;
  }
}

TEST_F(ImportMeasurements, HandEyeRowsKeepTheFlangePose) {
  // A flange pose (m, quaternion w last) and the measurement, no joints: registration readings.
  const Eigen::Quaterniond q = Eigen::Quaterniond(0.9, 0.1, -0.3, 0.2).normalized();
  std::string text = "fx;fy;fz;qx;qy;qz;qw;mx;my;mz\n";
  for (int k = 0; k < 5; ++k)
    text += format_number(0.1 * k) + ";0,5;1,25;" + format_number(q.x()) + ";" + format_number(q.y()) + ";" +
            format_number(q.z()) + ";" + format_number(q.w()) + ";100;200;300\n";
  for (char& c : text)
    if (c == '.') c = ',';
  write("he.csv", text);
  const CsvTable t = imported("--in " + path("he.csv") + " --decimal , --flange-length-units m --quaternion xyzw "
                              "--map flange_x=fx,flange_y=fy,flange_z=fz,flange_q=qx+qy+qz+qw");
  ASSERT_EQ(t.row_count(), 5u);
  EXPECT_FALSE(t.has_column("q1"));
  EXPECT_NEAR(t.numeric_column("flange_x")[3], 300.0, 1e-9);
  EXPECT_NEAR(t.numeric_column("flange_z")[0], 1250.0, 1e-9);
  const Eigen::Matrix3d got = robot::rotation_from_rpy_deg(t.numeric_column("flange_rx")[0], t.numeric_column("flange_ry")[0],
                                                           t.numeric_column("flange_rz")[0]);
  EXPECT_LT((got - q.toRotationMatrix()).cwiseAbs().maxCoeff(), 1e-12);
}

TEST_F(ImportMeasurements, BadCellsAreNamedByFileLineColumnAndValue) {
  const std::string header = "q1,q2,q3,q4,q5,q6,mx,my,mz\n";
  write("comma.csv", "q1;q2;q3;q4;q5;q6;mx;my;mz\n1;2;3;4;5;6;7;8;9\n1;2;3;4;5;6;7,5;8;9\n");
  expect_refused("--in " + path("comma.csv") + " --no-unit-check", {"comma.csv:3", "'mx'", "'7,5'", "decimal comma", "--decimal ,"});
  write("point.csv", "q1;q2;q3;q4;q5;q6;mx;my;mz\n1;2;3;4;5;6;7;8.5;9\n");
  expect_refused("--in " + path("point.csv") + " --decimal , --no-unit-check", {"point.csv:2", "'my'", "'8.5'", "decimal point"});
  write("nan.csv", header + "1,2,3,4,5,6,7,8,9\n1,2,3,4,5,6,7,8,nan\n");
  expect_refused("--in " + path("nan.csv") + " --no-unit-check", {"nan.csv:3", "'mz'", "'nan'", "not a finite number"});
  write("text.csv", header + "1,2,3,4,5,x,7,8,9\n");
  expect_refused("--in " + path("text.csv") + " --no-unit-check", {"text.csv:2", "'q6'", "'x'", "not a number"});
  expect_refused("--in " + path("text.csv") + " --map q6=A6", {"text.csv", "q6=A6", "not found", "q1, q2"});
  write("nojoints.csv", "a,b,mx,my,mz\n1,2,3,4,5\n");
  expect_refused("--in " + path("nojoints.csv"), {"nojoints.csv", "no joints q1..q6", "a, b, mx"});
  write("twice.csv", header + "1,2,3,4,5,6,7,8,9\n");
  expect_refused("--in " + path("twice.csv") + " --map q7=x", {"q7", "6 axes"});
  write("dup.csv", "point," + header + "a,1,2,3,4,5,6,7,8,9\na,1,2,3,4,5,6,7,8,9\n");
  expect_refused("--in " + path("dup.csv") + " --no-unit-check", {"dup.csv:3", "point 'a' again", "line 2"});
  write("quat.csv", "q1,q2,q3,q4,q5,q6,mx,my,mz,mqw,mqx,mqy,mqz\n1,2,3,4,5,6,7,8,9,1,1,0,0\n");
  expect_refused("--in " + path("quat.csv") + " --no-unit-check", {"quat.csv:2", "norm", "--quaternion"});
}

TEST_F(ImportMeasurements, UnitsThatDoNotFitTheNumbersAreRefused) {
  write("rad.csv", "p,A1,A2,A3,A4,A5,A6,X,Y,Z\n" + joint_rows(',', '.', true));
  const std::string map = " --map point=p,q1=A1,q2=A2,q3=A3,q4=A4,q5=A5,q6=A6,mx=X,my=Y,mz=Z";
  expect_refused("--in " + path("rad.csv") + map, {"rad.csv", "radians?", "--joint-units rad"});
  expect_refused("--in " + path("rad.csv") + " --joint-units deg" + map, {"radians?"});
  imported("--in " + path("rad.csv") + " --joint-units rad" + map);
  write("deg.csv", "p,A1,A2,A3,A4,A5,A6,X,Y,Z\n" + joint_rows(',', '.', false));
  expect_refused("--in " + path("deg.csv") + " --joint-units rad" + map, {"degrees?", "--joint-units deg"});
  // Positions of 1.5 m read as mm: metres?; as metres: fine; mm read as metres: millimetres?
  write("m.csv", "p,A1,A2,A3,A4,A5,A6,X,Y,Z\n" + [] {
    std::string s = joint_rows(',', '.', false);
    for (const char* from : {"1500.25", "-200.5", "300.75"}) {
      const std::string to = format_number(std::stod(from) / 1000);
      for (std::size_t p; (p = s.find(from)) != std::string::npos;) s.replace(p, std::string(from).size(), to);
    }
    return s;
  }());
  expect_refused("--in " + path("m.csv") + map, {"m.csv", "metres?", "--length-units m"});
  EXPECT_NEAR(imported("--in " + path("m.csv") + " --length-units m" + map).numeric_column("mx")[0], 1500.25, 1e-9);
  expect_refused("--in " + path("deg.csv") + " --length-units m" + map, {"millimetres?", "--length-units mm"});
  EXPECT_EQ(imported("--in " + path("rad.csv") + " --no-unit-check" + map).numeric_column("q1")[0], -20.0 * kRad);
}

TEST_F(ImportMeasurements, SpreadsheetRoundedTimesAreDroppedOtherTimesKept) {
  write("t.csv", "q1;q2;q3;q4;q5;q6;mx;my;mz;T;temp\n"
                 "1;2;3;4;5;6;700;800;900;2,02011E+13;21,5\n"
                 "1;2;3;4;5;7;700;800;900;2,02011E+13;21,75\n");
  const auto r = run("import-measurements --in " + path("t.csv") + " --decimal , --map time=T,temperature_c=temp "
                     "--no-unit-check --out " + path("out.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("'T' dropped: 2 of 2 cells are a spreadsheet's rounding ('2,02011E+13'"), std::string::npos)
      << r.out;
  const CsvTable t = CsvTable::read(path("out.csv"));
  EXPECT_FALSE(t.has_column("time"));
  EXPECT_EQ(t.numeric_column("temperature_c")[1], 21.75);
  write("t2.csv", "q1,q2,q3,q4,q5,q6,mx,my,mz,time\n1,2,3,4,5,6,700,800,900,20200714163904\n"
                  "1,2,3,4,5,7,700,800,900,2020-07-14T16:39:24\n");
  const CsvTable kept = imported("--in " + path("t2.csv") + " --no-unit-check");
  EXPECT_EQ(kept.row(0)[kept.column_index("time")], "20200714163904");
  EXPECT_EQ(kept.row(1)[kept.column_index("time")], "2020-07-14T16:39:24");
}

TEST_F(ImportMeasurements, AFailedImportLeavesThePreviousOutput) {
  write("good.csv", "q1,q2,q3,q4,q5,q6,mx,my,mz\n1,2,3,4,5,6,7,8,9\n");
  write("bad.csv", "q1,q2,q3,q4,q5,q6,mx,my,mz\n1,2,3,4,5,6,7,8,\n");
  ASSERT_EQ(run("import-measurements --no-unit-check --in " + path("good.csv") + " --out " + path("o.csv")).exit_code, 0);
  const std::string before = read("o.csv");
  EXPECT_EQ(run("import-measurements --no-unit-check --in " + path("bad.csv") + " --out " + path("o.csv")).exit_code, 2);
  EXPECT_EQ(read("o.csv"), before);
  EXPECT_EQ(run("import-measurements --in " + path("good.csv") + " --out " + path("good.csv")).exit_code, 2);
}

TEST(ForeignCsv, AnySeparatorKeepsQuotesCommentsAndLineNumbers) {
  errfield::testing::ScratchDir dir;
  const std::string file = dir.write("tab.csv", "# exported\na\tb c\t\"d\te\"\n\n1,5\t 2 \t\"x\"\"y\"\n3\t4\t\"z\"\n");
  const CsvTable t = read_foreign_csv(file, '\t');
  EXPECT_EQ(t.header(), (std::vector<std::string>{"a", "b c", "d\te"}));
  ASSERT_EQ(t.row_count(), 2u);
  EXPECT_EQ(t.row(0)[0], "1,5");
  EXPECT_EQ(t.row(0)[1], "2");
  EXPECT_EQ(t.row(0)[2], "x\"y");
  EXPECT_EQ(t.line_of_row(1), 5u);
  EXPECT_EQ(decimal_cell(t, 0, 0, ','), 1.5);
  try {
    (void)decimal_cell(t, 0, 0, '.');
    ADD_FAILURE() << "1,5 read in a '.' file";
  } catch (const InputError& e) {
    EXPECT_EQ(e.row(), 4u);
    EXPECT_EQ(e.column(), "a");
  }
}

}  // namespace measurement_import_test
}  // namespace errfield::readers
