// Bad-input catalogue, round two (issue 12, "Exit statuses and messages"; "compensate --strict"):
// JSON inputs that are bad input, not internal errors (a number beyond a double, a wrong type, a
// key given twice, a directory); option values that were accepted silently; messages that named
// the library's fields instead of the command-line option; an unknown command; row errors that
// did not name file:line. Every case: the exit status `errfield --help` documents and the words
// that point at what to fix. Robot data are SIMULATED (`errfield simulate`).

#include <algorithm>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "errfield/csv_table.hpp"
#include "errfield/csv_writing.hpp"
#include "errfield/error.hpp"
#include "errfield/json_file.hpp"
#include "errfield/robot/mdh_model.hpp"
#include "support/cli_test_common.hpp"

namespace errfield {
namespace json_and_option_input_test {

using namespace testing::cli_common;
namespace fs = std::filesystem;

// A simulated grid (27 points), its robot, a fitted vector-kriging model and the plan of the cube
// as targets, made once for the suite (ScratchDir names itself after the running test, and there
// is none yet in SetUpTestSuite: the directory is managed here).
class RobotFiles : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("errfield_RobotFiles_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    auto r = run({"simulate", "--seed", "5", "--step", "250", "--out", "g.csv", "--robot-out", "robot.json"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    r = run({"fit", "--robot", "robot.json", "--data", "g.csv", "--method", "vector-kriging", "--out", "m.json"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    r = run({"plan", "--robot", "robot.json", "--cube", "750,-250,350,500", "--step", "250", "--out", "t.csv"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  static void TearDownTestSuite() {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  static CliResult run(const std::vector<std::string>& args) { return run_errfield(args, dir_); }
  static std::string path(const std::string& name) { return (dir_ / name).string(); }
  static std::string read(const std::string& name) { return ScratchDir::slurp(dir_ / name); }
  static void write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name, std::ios::binary) << text;
  }
  static fs::path dir_;
};
fs::path RobotFiles::dir_;

// ---- JSON files --------------------------------------------------------------------------------

TEST(JsonFile, NumberBeyondADoubleNamesFileLineAndKey) {
  const std::string text = "{\n  \"links\": [\n    {\"a_mm\": 1e400}\n  ]\n}\n";
  try {
    parse_json_text(text, "r.json");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "r.json");
    EXPECT_EQ(e.row(), 3u);
    EXPECT_THAT(e.what(), AllOf(HasSubstr("r.json:3"), HasSubstr("1e400"), HasSubstr("links[0].a_mm"),
                                HasSubstr("beyond the range of a double")));
  }
}

TEST(JsonFile, DuplicateKeyNamesItsPathAndLine) {
  const std::string text = "{\"links\": [{}, {},\n {\"a_mm\": 1,\n  \"a_mm\": 2}]}";
  try {
    parse_json_text(text, "r.json");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.row(), 3u);
    EXPECT_THAT(e.what(), AllOf(HasSubstr("r.json:3"), HasSubstr("'links[2].a_mm' given twice")));
  }
  // The same key in two different objects is fine.
  EXPECT_NO_THROW(parse_json_text(R"({"a": {"x": 1}, "b": {"x": 2}, "c": [{"x": 1}, {"x": 2}]})", "ok.json"));
}

TEST(JsonFile, InvalidJsonAndEmptyFileAreBadInput) {
  EXPECT_THROW(parse_json_text("{\"a\": }", "x.json"), InputError);
  EXPECT_THROW(parse_json_text("", "x.json"), InputError);
  try {
    parse_json_text("{\n\"a\": tru}", "x.json");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("x.json:2"), HasSubstr("not valid JSON")));
  }
}

TEST_F(RobotFiles, RobotJsonWithAHugeNumberOrADuplicateKeyExitsTwo) {
  auto j = robot::MdhModel::er20_c10().to_json();
  std::string text = j.dump(1);
  const auto pos = text.find("\"a_mm\"");
  ASSERT_NE(pos, std::string::npos);
  const std::size_t number = pos + std::string("\"a_mm\": ").size();
  const std::size_t number_end = text.find_first_of(",\n}", number);
  write("huge.json", text.substr(0, number) + "1e400" + text.substr(number_end));
  auto r = run({"fk", "--robot", "huge.json", "--input", "t.csv", "--out", "o.csv"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("huge.json:"), HasSubstr("1e400"), HasSubstr("links[0].a_mm")));
  write("dup.json", text.substr(0, pos) + "\"a_mm\": 5, " + text.substr(pos));
  r = run({"fk", "--robot", "dup.json", "--input", "t.csv", "--out", "o.csv"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("dup.json:"), HasSubstr("links[0].a_mm' given twice")));
  EXPECT_FALSE(fs::exists(path("o.csv")));
}

TEST_F(RobotFiles, ADirectoryGivenAsJsonOrCsvIsNamedAsADirectory) {
  fs::create_directories(path("adir"));
  auto r = run({"fk", "--robot", "adir", "--input", "t.csv", "--out", "o.csv"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("adir"), HasSubstr("is a directory")));
  r = run({"compensate", "--model", "adir", "--targets", "t.csv", "--out", "o.csv"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("is a directory"));
  r = run({"simulate", "--config", "adir", "--out", "o.csv"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("is a directory"));
  r = run({"fk", "--input", "adir", "--out", "o.csv"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("adir: is a directory"), Not(HasSubstr("empty"))));
}

TEST_F(RobotFiles, ModelJsonWithWrongTypesExitsTwoNamingTheKey) {
  const auto model = nlohmann::json::parse(read("m.json"));
  ASSERT_EQ(model["field"]["kind"], "vector-kriging");
  struct Case {
    const char* key;
    nlohmann::json value;
  };
  for (const Case& c : {Case{"nugget_is_measurement_error", "yes"}, Case{"region_margin_mm", "wide"},
                        Case{"space", 3}, Case{"samples", nlohmann::json::array()}}) {
    auto bad = model;
    bad["field"][c.key] = c.value;
    write("bad.json", bad.dump(1));
    const auto r = run({"compensate", "--model", "bad.json", "--targets", "t.csv", "--out", "o.csv"});
    EXPECT_EQ(r.exit_code, 2) << c.key << ": " << r.err;
    EXPECT_THAT(r.err, AllOf(HasSubstr("bad.json"), HasSubstr(c.key))) << c.key;
  }
  // A simulation set-up whose link deviations are numbers instead of objects.
  write("sim.json", R"({"geometry": {"links": [1, 2, 3, 4, 5, 6]}})");
  const auto r = run({"simulate", "--config", "sim.json", "--step", "500", "--out", "o.csv"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("sim.json"), HasSubstr("geometry.links[0]"), HasSubstr("expected an object")));
  EXPECT_FALSE(fs::exists(path("o.csv")));
}

// Issue 20: predict/validate --model and fk --robot ended in "internal error: type_error.307" (exit
// 70) on a JSON file whose top level is not an object, where fit, calibrate, plan... said exit 2.
TEST_F(RobotFiles, JsonWhoseTopLevelIsNotAnObjectExitsTwoNamingTheFile) {
  struct Case {
    const char* text;
    const char* kind;
  };
  for (const Case& c : {Case{"[1,2,3]", "an array"}, Case{"[]", "an array"}, Case{"\"x\"", "a string"},
                        Case{"null", "null"}, Case{"5", "a number"}}) {
    write("top.json", c.text);
    for (const std::vector<std::string>& args :
         {std::vector<std::string>{"predict", "--model", "top.json", "--joints", "t.csv", "--out", "o.csv"},
          std::vector<std::string>{"validate", "--model", "top.json", "--data", "g.csv"},
          std::vector<std::string>{"fk", "--robot", "top.json", "--input", "t.csv", "--out", "o.csv"},
          std::vector<std::string>{"compensate", "--model", "top.json", "--targets", "t.csv", "--out", "o.csv"}}) {
      const auto r = run(args);
      EXPECT_EQ(r.exit_code, 2) << args[0] << " " << c.text << ": " << r.err;
      EXPECT_THAT(r.err, AllOf(HasSubstr("top.json"), HasSubstr(std::string("the top level is ") + c.kind),
                               HasSubstr("must be a JSON object")))
          << args[0] << " " << c.text;
    }
  }
  EXPECT_FALSE(fs::exists(path("o.csv")));
}

// Issue 20 (input limits): a robot JSON nesting 100,000 arrays. The parser is iterative, but dump()
// (messages quote values) and comparisons recurse once per level: refused while parsing.
TEST_F(RobotFiles, DeeplyNestedJsonIsRefusedNamingTheLimit) {
  write("deep.json", "{\"links\": " + std::string(100000, '[') + std::string(100000, ']') + "}");
  const auto r = run({"fk", "--robot", "deep.json", "--input", "t.csv", "--out", "o.csv"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("deep.json:1"), HasSubstr("nested more than 100 levels")));
  EXPECT_FALSE(fs::exists(path("o.csv")));
}

// Issue 20: "vector-kriging field: 0 samples; need at least 8" named no file.
TEST_F(RobotFiles, ModelFileErrorsNameTheFile) {
  auto model = nlohmann::json::parse(read("m.json"));
  model["field"]["samples"]["joints_deg"] = nlohmann::json::array();
  model["field"]["samples"]["position_mm"] = nlohmann::json::array();
  model["field"]["values"] = nlohmann::json::array();
  write("empty_field.json", model.dump(1));
  const auto r = run({"predict", "--model", "empty_field.json", "--joints", "t.csv", "--out", "o.csv"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("empty_field.json: "), HasSubstr("0 samples")));
  EXPECT_FALSE(fs::exists(path("o.csv")));
}

// Issue 20: `predict --out p.csv > /dev/full` replaced p.csv, then exited 1.
TEST_F(RobotFiles, PredictToAFullStandardOutputKeepsThePreviousFile) {
  write("p.csv", "previous\n");
  const std::vector<std::string> args{"predict", "--model", path("m.json"), "--joints", path("t.csv"), "--out",
                                      path("p.csv")};
  const CliResult r = testing::run_errfield_to_full_stdout(args, dir_);
  ASSERT_EQ(r.signal, 0);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("cannot write to standard output"));
  EXPECT_EQ(read("p.csv"), "previous\n") << "a run that failed replaced its output";
}

// ---- compensate --strict -----------------------------------------------------------------------

TEST_F(RobotFiles, CompensateStrictWritesNothingNamesTheRowAndExitsOne) {
  // The plan's targets plus one far outside the modelled cube (row 2 of the file, line 3).
  const std::string plan = read("t.csv");
  const std::size_t header_end = plan.find('\n') + 1;
  std::string far = plan.substr(header_end, plan.find('\n', header_end) - header_end);
  // q1..q6 are the last six cells: turn the base joint by 90 degrees, out of the cube.
  auto split = [](const std::string& line) {
    std::vector<std::string> out;
    for (std::size_t start = 0, comma; start <= line.size(); start = comma + 1) {
      comma = line.find(',', start);
      if (comma == std::string::npos) comma = line.size();
      out.push_back(line.substr(start, comma - start));
    }
    return out;
  };
  std::vector<std::string> cells = split(far);
  cells[cells.size() - 6] = std::to_string(std::stod(cells[cells.size() - 6]) + 90.0);
  // Its nominal x,y turn with it (90 deg about the base's z axis): the row stays the FK of its
  // joints, which compensate checks (issue 18).
  const std::vector<std::string> header = split(plan.substr(0, header_end - 1));
  const auto col = [&](const std::string& name) {
    return static_cast<std::size_t>(std::find(header.begin(), header.end(), name) - header.begin());
  };
  const std::string x = cells[col("x")], y = cells[col("y")];
  cells[col("x")] = std::to_string(-std::stod(y));
  cells[col("y")] = x;
  std::string row;
  for (const auto& c : cells) row += (row.empty() ? "" : ",") + c;
  write("strict.csv", plan.substr(0, header_end) + row + "\n" + plan.substr(header_end));
  write("j.csv", "previous\n");
  const auto r = run({"compensate", "--model", "m.json", "--targets", "strict.csv", "--out", "j.csv", "--strict"});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("--strict"), HasSubstr("strict.csv:2: outside-region"), HasSubstr("1 of ")));
  EXPECT_EQ(read("j.csv"), "previous\n") << "a failed --strict run replaced the output";
  // Without --strict the same run succeeds and marks the row.
  const auto ok = run({"compensate", "--model", "m.json", "--targets", "strict.csv", "--out", "j.csv"});
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
  EXPECT_THAT(read("j.csv"), HasSubstr("outside-region"));
}

// ---- option values accepted silently -----------------------------------------------------------

TEST_F(RobotFiles, CompensateToleranceMustBePositiveAndFinite) {
  for (const char* v : {"-1", "0", "nan", "inf"}) {
    const auto r = run({"compensate", "--model", "m.json", "--targets", "t.csv", "--out", "tol.csv", "--tolerance", v});
    EXPECT_EQ(r.exit_code, 2) << v << ": " << r.err;
    EXPECT_THAT(r.err, HasSubstr("--tolerance")) << v;
  }
  EXPECT_FALSE(fs::exists(path("tol.csv")));
}

TEST(OptionValues, NegativeCountsAreRefusedNotWrapped) {
  ScratchDir dir;
  dir.write("g.csv", kUnitCubeGrid);
  for (const std::string cmd : {"interpolate", "cv"}) {
    std::vector<std::string> args{cmd, "--method", "idw", "--samples", "g.csv", "--coords", "x,y,z", "--value", "v",
                                  "--neighbors", "-3"};
    if (cmd == "interpolate") args.insert(args.end(), {"--targets", "g.csv", "--out", "o.csv"});
    const auto r = run_errfield(args, dir.path());
    EXPECT_EQ(r.exit_code, 2) << cmd << ": " << r.err;
    EXPECT_THAT(r.err, AllOf(HasSubstr("--neighbors"), HasSubstr("negative"))) << cmd;
  }
  const auto r = run_errfield({"simulate", "--seed", "-1", "--step", "500", "--out", "o.csv"}, dir.path());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("--seed"));
  EXPECT_FALSE(fs::exists(dir.path() / "o.csv"));
}

// Issue 35: `plan --count -1` and `--seed -1` wrapped to 2^64 - 1 (CLI11 2.1 reads "-1" into an
// unsigned option). Every command's every unsigned option (its help's type UINT) refuses "-1"
// naming the option, so that one added later cannot miss the check.
TEST(OptionValues, EveryUnsignedOptionOfEveryCommandRefusesANegativeValue) {
  ScratchDir dir;
  const auto top = run_errfield({"--help"}, dir.path());
  ASSERT_EQ(top.exit_code, 0);
  std::vector<std::string> commands;
  {
    std::istringstream lines(top.out.substr(top.out.find("Subcommands:")));
    std::string line;
    std::getline(lines, line);
    while (std::getline(lines, line) && line.rfind("  ", 0) == 0) {
      std::istringstream words(line);
      std::string name;
      if (words >> name) commands.push_back(name);
    }
  }
  ASSERT_GT(commands.size(), 10u) << top.out;
  std::size_t checked = 0;
  std::set<std::string> seeds;
  for (const auto& command : commands) {
    const auto help = run_errfield({command, "--help"}, dir.path());
    std::istringstream lines(help.out);
    std::string line;
    while (std::getline(lines, line)) {
      std::istringstream words(line);
      std::string option, type;
      if (!(words >> option >> type) || option.rfind("--", 0) != 0 || (type.rfind("UINT", 0) != 0 && type.rfind("INT:UINT", 0) != 0)) continue;  // simulate --seed: INT:UINT
      option = option.substr(0, option.find(','));
      const auto r = run_errfield({command, option, "-1"}, dir.path());
      EXPECT_EQ(r.exit_code, 2) << command << " " << option << " -1\n" << r.err;
      // kUnsignedInteger's words, or those of a range check that comes first (--simulations).
      EXPECT_THAT(r.err, AllOf(HasSubstr(option), AnyOf(HasSubstr("negative"), HasSubstr("not in range"))))
          << command << " " << option;
      ++checked;
      if (option == "--seed") seeds.insert(command);
    }
  }
  // plan's --count and the seeds of simulate, plan, cv, variogram, fit and reproduce at least.
  EXPECT_GE(checked, 10u);
  for (const char* c : {"plan", "simulate", "cv", "variogram", "reproduce"}) EXPECT_TRUE(seeds.count(c)) << c;
}

TEST(OptionValues, FitVariogramRangeMaxAndNu) {
  ScratchDir dir;
  dir.write("v.csv", "lag_lo,lag_hi,lag_mean,gamma,pairs\n0,1,0.5,0.1,10\n1,2,1.5,0.3,20\n2,3,2.5,0.45,30\n"
                     "3,4,3.5,0.5,30\n4,5,4.5,0.5,30\n");
  for (const char* v : {"0", "-5", "nan"}) {
    const auto r = run_errfield({"fit-variogram", "--input", "v.csv", "--model", "sph", "--range-max", v}, dir.path());
    EXPECT_EQ(r.exit_code, 2) << v << ": " << r.output();
    EXPECT_THAT(r.err, HasSubstr("--range-max")) << v;
  }
  auto r = run_errfield({"fit-variogram", "--input", "v.csv", "--model", "sph", "--nu", "1.5"}, dir.path());
  EXPECT_EQ(r.exit_code, 2) << r.output();
  EXPECT_THAT(r.err, AllOf(HasSubstr("--nu"), HasSubstr("mat")));
  r = run_errfield({"fit-variogram", "--input", "v.csv", "--model", "sph", "--range-max", "10"}, dir.path());
  EXPECT_EQ(r.exit_code, 0) << r.output();
  // Issue 35: a Matérn nu of 1e8 hung the WLS fit, 1e10 exited 70 (the Bessel function threw):
  // nu beyond kMaxMaternNu (100) is refused naming --nu and the range, as for --lmc.
  for (const char* nu : {"1e10", "1e8", "101"}) {
    r = run_errfield({"fit-variogram", "--input", "v.csv", "--model", "mat", "--nu", nu}, dir.path());
    EXPECT_EQ(r.exit_code, 2) << nu << ": " << r.output();
    EXPECT_THAT(r.err, AllOf(HasSubstr("--nu"), HasSubstr("(0, 100]"))) << nu;
  }
  r = run_errfield({"fit-variogram", "--input", "v.csv", "--model", "mat", "--nu", "100"}, dir.path());
  EXPECT_EQ(r.exit_code, 0) << r.output();
}

// Issue 20: `simulate --tool-offset 1e300,0,0` exited 1 ("computed value is -inf").
TEST(OptionValues, SimulateToolOffsetBeyondAToolIsBadUsage) {
  ScratchDir dir;
  for (const char* v : {"1e300,0,0", "0,-2e4,0", "random:1e300"}) {
    const auto r = run_errfield({"simulate", "--step", "500", "--tool-offset", v, "--out", "o.csv"}, dir.path());
    EXPECT_EQ(r.exit_code, 2) << v << ": " << r.err;
    EXPECT_THAT(r.err, AllOf(HasSubstr("--tool-offset"), HasSubstr("at most 10000 mm"))) << v;
  }
  EXPECT_FALSE(fs::exists(dir.path() / "o.csv"));
  const auto ok = run_errfield({"simulate", "--step", "500", "--tool-offset", "1,2,3", "--out", "o.csv"}, dir.path());
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
}

// Issue 20: `pow(range=...)` with the exponent also given said "'exponent' given twice".
TEST(OptionMessages, PowerModelParameterGivenTwiceNamesBothSpellings) {
  ScratchDir dir;
  dir.write("g.csv", kUnitCubeGrid);
  const auto r = run_errfield({"cv", "--method", "kriging", "--samples", "g.csv", "--coords", "x,y,z", "--value", "v",
                               "--model", "pow(sill=1,range=1.5,exponent=1)"},
                              dir.path());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("the exponent of 'pow(sill=1,range=1.5,exponent=1)' is given twice"),
                           HasSubstr("'range' and as 'exponent'")));
}

// ---- messages that named internals -------------------------------------------------------------

TEST(OptionMessages, NameTheOptionNotTheLibraryField) {
  ScratchDir dir;
  dir.write("g.csv", kUnitCubeGrid);
  dir.write("p.csv", "x,y,z\n1000,0,1000\n");
  struct Case {
    std::vector<std::string> args;
    const char* option;
    const char* internal;
  };
  const std::vector<Case> cases{
      {{"variogram", "--input", "g.csv", "--coords", "x,y,z", "--value", "v", "--bins", "0:2:1", "--subsample", "2"},
       "--subsample", "pair_fraction"},
      {{"simulate", "--step", "7", "--out", "o.csv"}, "--step", "MeasurementCube"},
      {{"plan", "--cube", "750,-250,350,500", "--step", "7", "--out", "p.csv"}, "--step", "plan: step"},
      {{"ik", "--input", "p.csv", "--max-iterations", "0", "--out", "o.csv"}, "--max-iterations", "IkOptions"},
      {{"calibrate", "--data", "g.csv", "--max-condition", "0.5", "--out", "o.json"}, "--max-condition",
       "CalibrationOptions"},
      {{"calibrate", "--data", "g.csv", "--k0", "3", "--k1", "2", "--out", "o.json"}, "--k0", "CalibrationOptions"},
  };
  for (const auto& c : cases) {
    const auto r = run_errfield(c.args, dir.path());
    EXPECT_EQ(r.exit_code, 2) << testing::command_line(c.args) << "\n" << r.err;
    EXPECT_THAT(r.err, AllOf(HasSubstr(c.option), Not(HasSubstr(c.internal)))) << testing::command_line(c.args);
  }
}

TEST(OptionMessages, AnUnknownCommandIsNamed) {
  ScratchDir dir;
  const auto r = run_errfield({"interpolat", "--samples", "g.csv"}, dir.path());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, AllOf(HasSubstr("unknown command 'interpolat'"), HasSubstr("interpolate"),
                           Not(HasSubstr("A subcommand is required"))));
  // Still: no command at all is a usage error, and --help/--version succeed.
  EXPECT_EQ(run_errfield({}, dir.path()).exit_code, 2);
  EXPECT_EQ(run_errfield({"--version"}, dir.path()).exit_code, 0);
}

// ---- row errors with file:line ------------------------------------------------------------------

TEST(RowMessages, KFoldDuplicatesNameBothLines) {
  ScratchDir dir;
  // Row i (line i + 2) at (i, i^2 mod 7, i mod 5): distinct. Line 14 repeats line 6 (i = 4).
  std::string s = "x,y,z,v\n";
  for (int i = 0; i < 12; ++i)
    s += std::to_string(i) + "," + std::to_string(i * i % 7) + "," + std::to_string(i % 5) + "," + std::to_string(i % 3) + "\n";
  s += "4,2,4,9\n";
  dir.write("s.csv", s);
  for (const char* folds : {"3", "loo"}) {
    const auto r = run_errfield({"cv", "--method", "kriging", "--model", "sph(sill=1,range=20)", "--samples", "s.csv",
                                 "--coords", "x,y,z", "--value", "v", "--folds", folds},
                                dir.path());
    EXPECT_EQ(r.exit_code, 2) << folds << ": " << r.err;
    EXPECT_THAT(r.err, AllOf(HasSubstr("s.csv:14"), HasSubstr("s.csv:6"), HasSubstr("duplicates"))) << folds;
  }
}

TEST(RowMessages, UniversalDriftFailureNamesTheFile) {
  ScratchDir dir;
  std::string s = "x,y,z,v\n";
  for (int i = 0; i < 10; ++i) s += std::to_string(i) + "," + std::to_string(2 * i) + ",0," + std::to_string(i % 4) + "\n";
  dir.write("line.csv", s);
  dir.write("t.csv", "x,y,z\n1,1,1\n");
  const auto r = run_errfield({"interpolate", "--method", "kriging", "--kind", "universal1", "--model",
                               "sph(sill=1,range=20)", "--samples", "line.csv", "--targets", "t.csv", "--coords", "x,y,z",
                               "--value", "v", "--out", "o.csv"},
                              dir.path());
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("line.csv: kriging failed"), HasSubstr("collinear")));
  const auto cv = run_errfield({"cv", "--method", "kriging", "--kind", "universal1", "--model", "sph(sill=1,range=20)",
                                "--samples", "line.csv", "--coords", "x,y,z", "--value", "v"},
                               dir.path());
  EXPECT_EQ(cv.exit_code, 1) << cv.err;
  EXPECT_THAT(cv.err, HasSubstr("line.csv: kriging failed"));
}

// ---- issue 35: outputs and messages -------------------------------------------------------------

// Round three, still open then: `validate --out pts.csv > /dev/full` replaced pts.csv and exited 1.
// Every command that prints to standard output and writes files: all or nothing.
TEST_F(RobotFiles, AFullStandardOutputKeepsThePreviousFilesOfEveryCommand) {
  const std::vector<std::vector<std::string>> commands{
      {"validate", "--model", path("m.json"), "--data", path("g.csv"), "--out", path("prev.txt")},
      {"compensate", "--model", path("m.json"), "--targets", path("t.csv"), "--out", path("prev.txt")},
      {"fit", "--robot", path("robot.json"), "--data", path("g.csv"), "--method", "position-idw", "--out", path("prev.txt")},
      {"plan", "--robot", path("robot.json"), "--cube", "750,-250,350,500", "--step", "250", "--out", path("prev.txt")},
      {"calibrate", "--robot", path("robot.json"), "--data", path("g.csv"), "--model", "position", "--out",
       path("prev.txt")}};
  for (const auto& args : commands) {
    write("prev.txt", "previous\n");
    const CliResult r = testing::run_errfield_to_full_stdout(args, dir_);
    ASSERT_EQ(r.signal, 0) << args[0];
    EXPECT_EQ(r.exit_code, 1) << args[0] << ": " << r.err;
    EXPECT_THAT(r.err, HasSubstr("cannot write to standard output")) << args[0];
    EXPECT_EQ(read("prev.txt"), "previous\n") << args[0] << ": a run that failed replaced its output";
  }
}

// Point names are the user's text: "p,1" made validate and fk write files errfield itself refused.
TEST_F(RobotFiles, PointNamesWithDelimitersAndQuotesReadBackFromEveryOutput) {
  const CsvTable g = CsvTable::read(path("g.csv"));
  const std::size_t point = g.column_index("point");
  const std::vector<std::string> names{"p,1", "say \"x\"", " spaced ", "#4"};
  std::string text;
  append_csv_line(text, g.header());
  for (std::size_t i = 0; i < g.row_count(); ++i) {
    std::vector<std::string> cells = g.row(i);
    if (i >= 1 && i <= names.size()) cells[point] = names[i - 1];
    append_csv_line(text, cells);
  }
  write("named.csv", text);
  const auto v = run({"validate", "--model", path("m.json"), "--data", path("named.csv"), "--out", path("named_pts.csv")});
  ASSERT_EQ(v.exit_code, 0) << v.err;
  const auto fk = run({"fk", "--input", path("named.csv"), "--robot", path("robot.json"), "--out", path("named_fk.csv")});
  ASSERT_EQ(fk.exit_code, 0) << fk.err;
  // fk on its own output: errfield reads what it wrote.
  const auto again = run({"fk", "--input", path("named_fk.csv"), "--robot", path("robot.json"), "--out", path("named_fk2.csv")});
  ASSERT_EQ(again.exit_code, 0) << again.err;
  for (const char* file : {"named_pts.csv", "named_fk.csv", "named_fk2.csv"}) {
    const CsvTable out = CsvTable::read(path(file));
    const std::size_t c = out.column_index("point");
    std::vector<std::string> seen;
    for (std::size_t i = 0; i < out.row_count(); ++i) seen.emplace_back(out.cell(i, c));
    for (const auto& n : names) EXPECT_NE(std::find(seen.begin(), seen.end(), n), seen.end()) << file << ": '" << n << "'";
  }
}

// compensate exited 0 when it compensated nothing (predict, validate and cv exit 1).
TEST_F(RobotFiles, CompensateThatCompensatesNothingSaysWhy) {
  // Two targets out of reach, one reachable beyond the fitted grid (x 750..1250 mm).
  write("far.csv", "x,y,z,rx,ry,rz\n9000,0,500,180,0,180\n0,9000,500,180,0,180\n1500,0,600,180,0,180\n");
  // A failed job, as predict's: exit 1, the refusals counted by reason and the first rows named
  // (what the status column would have said), nothing written (an old output kept).
  write("far_out.csv", "previous\n");
  auto r = run({"compensate", "--model", path("m.json"), "--targets", path("far.csv"), "--out", path("far_out.csv")});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("none of the 3 targets"), HasSubstr("unreachable 2"), HasSubstr("outside-region 1"),
                           HasSubstr("far.csv:2: unreachable"), HasSubstr("far.csv:4: outside-region"),
                           HasSubstr("not written")));
  EXPECT_EQ(read("far_out.csv"), "previous\n");
  // --strict: the same, and so for one refusal among compensated targets.
  r = run({"compensate", "--strict", "--model", path("m.json"), "--targets", path("far.csv"), "--out", path("nothing_strict.csv")});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_FALSE(fs::exists(path("nothing_strict.csv")));
  write("some.csv", "x,y,z,rx,ry,rz\n1000,0,600,180,0,0\n1100,100,700,180,0,0\n9000,0,500,180,0,180\n");
  r = run({"compensate", "--model", path("m.json"), "--targets", path("some.csv"), "--out", path("some_out.csv")});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  r = run({"compensate", "--strict", "--model", path("m.json"), "--targets", path("some.csv"), "--out", path("some_strict.csv")});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("--strict: 1 of"), HasSubstr("unreachable")));
  EXPECT_FALSE(fs::exists(path("some_strict.csv")));
}

// "tool point moved by at most 10.463 mm" was the ceiling; the largest move was 3.61 mm. Both said.
TEST_F(RobotFiles, CompensateSaysTheLargestMoveAndTheCeilingApart) {
  const auto r = run({"compensate", "--model", path("m.json"), "--targets", path("t.csv"), "--out", path("moved.csv"),
                      "--max-correction", "7"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CsvTable out = CsvTable::read(path("moved.csv"));
  double largest = 0.0;
  for (std::size_t i = 0; i < out.row_count(); ++i)
    if (out.cell(i, out.column_index("status")) == "ok") largest = std::max(largest, out.numeric_cell(i, out.column_index("move_mm")));
  ASSERT_GT(largest, 0.0);
  EXPECT_THAT(r.out, HasSubstr("moved by " + format_number(std::round(largest * 1000.0) / 1000.0) + " mm at most"));
  EXPECT_THAT(r.out, HasSubstr("ceiling 7 mm (--max-correction)"));
}

// position-idw on scattered poses said "the x values are not evenly spaced ... would need 719866
// planes"; it says what the method needs, keeping what it found.
TEST_F(RobotFiles, PositionIdwOnScatteredPosesSaysItNeedsTheGrid) {
  const auto s = run({"simulate", "--seed", "3", "--sample", "scattered:40", "--out", "scattered.csv"});
  ASSERT_EQ(s.exit_code, 0) << s.err;
  const auto r = run({"fit", "--robot", path("robot.json"), "--data", path("scattered.csv"), "--method", "position-idw",
                      "--out", path("scattered.json")});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("position-idw needs the paper's regular grid of poses"),
                           HasSubstr("poses given are not one"), HasSubstr("--method auto")));
  EXPECT_FALSE(fs::exists(path("scattered.json")));
}

// Progress by elapsed time, whatever the row count: a 687-pose fit printed nothing for 12-24 s
// (only 1,000 rows counted as long). ERRFIELD_PROGRESS=1 stands in for a terminal and
// ERRFIELD_PROGRESS_AFTER=0 for a stage that has run 5 s.
TEST_F(RobotFiles, AStageThatRunsLongSaysSoWhateverTheRowCount) {
  const auto r = testing::run_errfield({"fit", "--robot", path("robot.json"), "--data", path("g.csv"), "--method",
                                        "vector-kriging", "--out", path("progress.json")},
                                       dir_, {"ERRFIELD_PROGRESS=1", "ERRFIELD_PROGRESS_AFTER=0"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("fit: "), HasSubstr("still running")));
  const auto quiet = run({"fit", "--robot", path("robot.json"), "--data", path("g.csv"), "--method", "vector-kriging",
                          "--out", path("progress.json")});
  EXPECT_THAT(quiet.err, Not(HasSubstr("still running")));  // not a terminal: nothing within 30 s
}

// Issue 47 item 14: a 5,000-pose fit ran past a minute with nothing on a pipe. A log (not a
// terminal) gets the "still running" lines of a long stage too (after 30 s, here 0), unless
// ERRFIELD_PROGRESS=0; and a fit with a field over --max-fit-readings is refused before any work
// (exit 3), naming the count, the option and the time it would take (per fit, and the gross-outlier
// screen's up to four fits: the per-fit figure alone had said 61 s of a real 295 s).
TEST_F(RobotFiles, ALongFitSaysSoOnAPipeAndAnOversizedOneIsRefusedUpFront) {
  const std::vector<std::string> fit{"fit", "--robot", path("robot.json"), "--data", path("g.csv"), "--method",
                                     "vector-kriging", "--out", path("progress.json")};
  const auto logged = testing::run_errfield(fit, dir_, {"ERRFIELD_PROGRESS_AFTER=0"});
  ASSERT_EQ(logged.exit_code, 0) << logged.err;
  EXPECT_THAT(logged.err, AllOf(HasSubstr("fit: "), HasSubstr("still running")));
  const auto off = testing::run_errfield(fit, dir_, {"ERRFIELD_PROGRESS=0", "ERRFIELD_PROGRESS_AFTER=0"});
  ASSERT_EQ(off.exit_code, 0) << off.err;
  EXPECT_THAT(off.err, Not(HasSubstr("still running")));

  const std::size_t rows = CsvTable::read(path("g.csv")).row_count();
  fs::remove(path("progress.json"));
  std::vector<std::string> small = fit;
  small.insert(small.end(), {"--max-fit-readings", std::to_string(rows - 1)});
  const auto r = run(small);
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr(std::to_string(rows) + " readings"), HasSubstr("--max-fit-readings " + std::to_string(rows - 1)),
                           HasSubstr("of CPU"), HasSubstr("up to 4 fits in all")));
  EXPECT_FALSE(fs::exists(path("progress.json")));
  // A method without a field has no such budget.
  small[6] = "kinematic";
  EXPECT_EQ(run(small).exit_code, 0);
}

// Round three: a bad option value exited 1 (the outliers overflowed later).
TEST_F(RobotFiles, SimulateOutliersBeyondTenMetresNameTheOption) {
  const auto r = run({"simulate", "--step", "250", "--outliers", "0.1:1e300", "--out", "outliers.csv"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("--outliers"), HasSubstr("1e300")));
  EXPECT_FALSE(fs::exists(path("outliers.csv")));
}

}  // namespace
}  // namespace errfield
