// Bad-input catalogue, CSV level, for every command that reads a CSV file: each defect is put
// into one valid input of each command and the command must exit 2 with stderr naming the file,
// the line, the column and the offending value (or, for a missing column, the file and the
// column). BOM + CRLF + ';' must be accepted and give byte-identical output to the plain file.
// The robot commands' valid inputs are made by `errfield simulate` (SIMULATED data) at test time.

#include <functional>
#include <map>
#include <sstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "support/cli_test_common.hpp"

namespace errfield {
namespace command_csv_input_test {

using namespace testing::cli_common;

constexpr const char* kTargets = "x,y,z\n0.5,0.5,0.5\n0.25,0.5,0.75\n0.5,0.25,0.5\n0.75,0.75,0.25\n";

std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

std::vector<std::string> split_cells(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) cells.push_back(cell);
  if (!line.empty() && line.back() == ',') cells.emplace_back();
  return cells;
}

std::string join(const std::vector<std::string>& v, const std::string& sep) {
  std::string s;
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? sep : "") + v[i];
  return s;
}

// A CSV file as lines, with the header found past '#' comments; edits for the defects.
struct CsvText {
  std::vector<std::string> lines;
  std::size_t header = 0;  // index into lines

  explicit CsvText(const std::string& text) : lines(split_lines(text)) {
    while (header < lines.size() && (lines[header].empty() || lines[header][0] == '#')) ++header;
  }
  std::string text() const { return join(lines, "\n") + "\n"; }
  std::size_t column(const std::string& name) const {
    const auto h = split_cells(lines[header]);
    const auto it = std::find(h.begin(), h.end(), name);
    EXPECT_NE(it, h.end()) << name;
    return static_cast<std::size_t>(it - h.begin());
  }
  std::size_t header_cells() const { return split_cells(lines[header]).size(); }
  // 1-based file line of data row `r` (0-based).
  std::size_t line_of(std::size_t r) const { return header + 2 + r; }
  void set_cell(std::size_t r, const std::string& col, const std::string& value) {
    auto cells = split_cells(lines[header + 1 + r]);
    cells[column(col)] = value;
    lines[header + 1 + r] = join(cells, ",");
  }
};

// One command reading one CSV file (`file`, valid content `csv`), run as `args`, and a numeric
// column it needs (`column`). `missing_words`: what stderr says when that column is missing, if
// not "no column 'C'".
struct CommandCase {
  std::string name, file, column;
  std::vector<std::string> args;
  std::string missing_words;
  std::vector<std::string> outputs;  // files compared in the BOM/CRLF run
};

class CommandCsvBadInput : public ::testing::Test {
 protected:
  ScratchDir dir;
  std::map<std::string, std::string> valid;  // file -> valid content

  CliResult run(const std::vector<std::string>& args) {
    auto r = run_errfield(args, dir.path());
    EXPECT_EQ(r.signal, 0) << testing::command_line(args);
    EXPECT_THAT(r.err, Not(HasSubstr("internal error"))) << testing::command_line(args);
    return r;
  }
  void write(const std::string& file, const std::string& text) {
    valid[file] = text;
    dir.write(file, text);
  }
  void restore() {
    for (const auto& [f, t] : valid) dir.write(f, t);
  }

  // Valid inputs of every command; the robot ones from `errfield simulate` (SIMULATED).
  std::vector<CommandCase> prepare() {
    write("s.csv", kUnitCubeGrid);
    write("t.csv", kTargets);
    write("q.csv", "q1,q2,q3,q4,q5,q6\n0,0,0,0,0,0\n10,-20,30,-40,50,-60\n-5,-60,20,10,-30,90\n5,-45,10,0,40,0\n");
    write("v.csv", "lag_lo,lag_hi,lag_mean,gamma,pairs\n0,0.5,,,0\n0.5,1,0.8,1.2,10\n1,1.5,1.25,2.5,31\n"
                   "1.5,2,1.73,3.1,6\n2,2.5,2.23,3,8\n2.5,3,2.7,3.05,12\n");
    write("p.csv", "x,y,z\n1200,100,900\n1100,-200,800\n1000,0,1000\n900,300,950\n");
    // robot.json: the nominal robot with the ball; grid.csv's x,y,z are its FK.
    EXPECT_EQ(run({"simulate", "--sample", "grid", "--step", "125", "--out", "grid.csv", "--robot-out", "robot.json"}).exit_code,
              0);
    valid["grid.csv"] = dir.read("grid.csv");
    EXPECT_EQ(run({"fit", "--robot", "robot.json", "--data", "grid.csv", "--method", "position-idw", "--out", "model.json"})
                  .exit_code,
              0);
    // Compensation targets: nominal joints of a few grid targets.
    const CsvText grid(valid["grid.csv"]);
    std::string targets = "point,q1,q2,q3,q4,q5,q6\n";
    for (std::size_t r = 10; r < 16; ++r) {
      const auto cells = split_cells(grid.lines[grid.header + 1 + r]);
      targets += cells[0];
      for (const char* q : {"q1", "q2", "q3", "q4", "q5", "q6"}) {
        targets += ',';
        targets += cells[grid.column(q)];
      }
      targets += "\n";
    }
    write("targets.csv", targets);
    return {
        {"variogram", "s.csv", "v",
         {"variogram", "--input", "s.csv", "--coords", "x,y,z", "--value", "v", "--bins", "0:2:0.5", "--out", "o.csv"},
         "", {"o.csv"}},
        {"interpolate (samples)", "s.csv", "x",
         {"interpolate", "--method", "idw", "--samples", "s.csv", "--targets", "t.csv", "--coords", "x,y,z", "--value",
          "v", "--out", "o.csv"},
         "", {"o.csv"}},
        {"interpolate (targets)", "t.csv", "y",
         {"interpolate", "--method", "kriging", "--model", "sph(1,3)", "--samples", "s.csv", "--targets", "t.csv",
          "--coords", "x,y,z", "--value", "v", "--out", "o.csv"},
         "", {"o.csv"}},
        {"cv", "s.csv", "z",
         {"cv", "--method", "kriging", "--model", "sph(1,3)", "--samples", "s.csv", "--coords", "x,y,z", "--value", "v"},
         "", {}},
        {"fit-variogram", "v.csv", "gamma", {"fit-variogram", "--input", "v.csv", "--model", "sph", "--out", "o.json"},
         "", {"o.json"}},
        {"fk", "q.csv", "q2", {"fk", "--input", "q.csv", "--out", "o.csv"}, "", {"o.csv"}},
        {"ik", "p.csv", "y", {"ik", "--input", "p.csv", "--position-only", "--out", "o.csv"}, "", {"o.csv"}},
        {"simulate --joints", "q.csv", "q5", {"simulate", "--joints", "q.csv", "--out", "o.csv"}, "", {"o.csv"}},
        {"calibrate (position)", "grid.csv", "mx",
         {"calibrate", "--robot", "robot.json", "--data", "grid.csv", "--model", "position", "--out", "o.json"}, "", {"o.json"}},
        {"calibrate (distance)", "grid.csv", "dist_b0",
         {"calibrate", "--robot", "robot.json", "--data", "grid.csv", "--model", "distance", "--out", "o.json"}, "", {"o.json"}},
        {"fit", "grid.csv", "q2",
         {"fit", "--robot", "robot.json", "--data", "grid.csv", "--method", "position-idw", "--out", "o.json"}, "",
         {"o.json"}},
        {"compensate", "targets.csv", "q3",
         {"compensate", "--model", "model.json", "--targets", "targets.csv", "--out", "o.csv"},
         "targets need columns q1..q6", {"o.csv"}},
    };
  }
};

TEST_F(CommandCsvBadInput, EveryCommandNamesFileLineColumnAndValue) {
  for (const auto& c : prepare()) {
    SCOPED_TRACE(c.name);
    // The valid input works.
    restore();
    const CliResult ok = run(c.args);
    ASSERT_EQ(ok.exit_code, 0) << ok.err;

    // Bad cells in the third data row.
    const std::pair<std::string, std::string> cells[] = {{"abc", "'abc' is not a number"},
                                                         {"", "is empty; expected a number"},
                                                         {"nan", "'nan' is not a finite number"},
                                                         {"-inf", "'-inf' is not a finite number"},
                                                         {"1e999", "'1e999' is not a finite number"}};
    for (const auto& [cell, words] : cells) {
      CsvText t(valid[c.file]);
      t.set_cell(2, c.column, cell);
      restore();
      dir.write(c.file, t.text());
      const CliResult r = run(c.args);
      EXPECT_EQ(r.exit_code, 2) << "cell '" << cell << "'";
      EXPECT_THAT(r.err, AllOf(HasSubstr(c.file + ":" + std::to_string(t.line_of(2)) + ": column '" + c.column + "'"),
                               HasSubstr(words)))
          << "cell '" << cell << "'";
    }

    // Missing column (renamed in the header).
    {
      CsvText t(valid[c.file]);
      auto h = split_cells(t.lines[t.header]);
      h[t.column(c.column)] = "renamed_" + c.column;
      t.lines[t.header] = join(h, ",");
      restore();
      dir.write(c.file, t.text());
      const CliResult r = run(c.args);
      EXPECT_EQ(r.exit_code, 2);
      EXPECT_THAT(r.err, AllOf(HasSubstr(c.file), HasSubstr(c.missing_words.empty() ? "no column '" + c.column + "'"
                                                                                     : c.missing_words)));
    }

    // Duplicated column (appended to the header and to every row).
    {
      CsvText t(valid[c.file]);
      for (std::size_t i = t.header; i < t.lines.size(); ++i) t.lines[i] += i == t.header ? "," + c.column : ",0";
      restore();
      dir.write(c.file, t.text());
      const CliResult r = run(c.args);
      EXPECT_EQ(r.exit_code, 2);
      EXPECT_THAT(r.err, AllOf(HasSubstr(c.file + ":" + std::to_string(t.header + 1)),
                               HasSubstr("column '" + c.column + "' appears twice")));
    }

    // A row with an extra cell, and one with a cell missing.
    for (const int delta : {+1, -1}) {
      CsvText t(valid[c.file]);
      std::string& row = t.lines[t.header + 3];
      if (delta > 0) row += ",9";
      else row.erase(row.rfind(','));
      restore();
      dir.write(c.file, t.text());
      const CliResult r = run(c.args);
      EXPECT_EQ(r.exit_code, 2) << delta;
      EXPECT_THAT(r.err, AllOf(HasSubstr(c.file + ":" + std::to_string(t.line_of(2))),
                               HasSubstr("row has " + std::to_string(t.header_cells() + delta) + " cells"),
                               HasSubstr("the header has " + std::to_string(t.header_cells()))))
          << delta;
    }

    // BOM + CRLF + ';' as delimiter + a blank line: the same output, byte for byte.
    {
      std::vector<std::string> expected;
      for (const auto& o : c.outputs) expected.push_back(dir.read(o));
      CsvText t(valid[c.file]);
      for (std::size_t i = t.header; i < t.lines.size(); ++i) std::replace(t.lines[i].begin(), t.lines[i].end(), ',', ';');
      t.lines.insert(t.lines.begin() + static_cast<long>(t.header) + 2, "");
      std::string text = "\xEF\xBB\xBF" + join(t.lines, "\r\n") + "\r\n";
      restore();
      dir.write(c.file, text);
      const CliResult r = run(c.args);
      ASSERT_EQ(r.exit_code, 0) << r.err;
      EXPECT_EQ(r.out, ok.out);
      for (std::size_t k = 0; k < c.outputs.size(); ++k) EXPECT_EQ(dir.read(c.outputs[k]), expected[k]) << c.outputs[k];
    }
  }
}

}  // namespace
}  // namespace errfield
