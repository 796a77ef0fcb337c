// The exit statuses `errfield --help` documents (src/cli/run_cli.hpp): scripts branch on them, so
// every kind of failure must map to its status, whichever layer (CLI11 parsing, input reading,
// the job itself) detects it.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "support/cli_harness.hpp"

namespace errfield {
namespace exit_status_cli_test {

using ::testing::HasSubstr;

class ExitStatus : public testing::CliTest {
 protected:
  void SetUp() override { write("a.csv", "x,y,v\n0,0,1\n1,0,2\n0,1,3\n1,1,5\n"); }
};

TEST_F(ExitStatus, HelpAndVersionSucceedAndHelpDocumentsTheStatuses) {
  const auto help = run("--help");
  EXPECT_EQ(help.exit_code, 0) << help.output();
  EXPECT_THAT(help.out, HasSubstr("Exit status: 0 success; 1 the job failed"));
  EXPECT_THAT(help.out, HasSubstr("70 internal error"));
  EXPECT_EQ(run("variogram --help").exit_code, 0);
  const auto version = run("--version");
  EXPECT_EQ(version.exit_code, 0);
  EXPECT_THAT(version.out, HasSubstr("errfield"));
}

// CLI11 reports these with codes of its own (106 required, 105 conversion, 109 extras, ...);
// all are usage errors, status 2, with CLI11's message naming the option.
TEST_F(ExitStatus, EveryCommandLineMistakeIsAUsageError) {
  struct Case {
    const char* line;
    const char* says;
  };
  const Case cases[] = {
      {"", "A subcommand is required"},
      {"variogram --coords x,y --value v --bins 0:2:1", "--input is required"},
      {"variogram --input a.csv --coords x,y --value v --bins 0:2:1 --threads two", "--threads"},
      {"variogram --input a.csv --coords x,y --value v --bins 0:2:1 --no-such-option", "--no-such-option"},
      {"interpolate --samples a.csv", "--method is required"},
  };
  for (const auto& c : cases) {
    const auto r = run(c.line);
    EXPECT_EQ(r.exit_code, 2) << "errfield " << c.line << "\n" << r.output();
    EXPECT_THAT(r.output(), HasSubstr(c.says)) << "errfield " << c.line;
  }
}

TEST_F(ExitStatus, BadInputIsTwoAndAnUnwritableOutputIsOne) {
  const auto missing = run("variogram --input nosuch.csv --coords x,y --value v --bins 0:2:1");
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_THAT(missing.err, HasSubstr("nosuch.csv: cannot open file for reading"));
  const auto bad_column = run("variogram --input a.csv --coords x,w --value v --bins 0:2:1");
  EXPECT_EQ(bad_column.exit_code, 2);
  EXPECT_THAT(bad_column.err, HasSubstr("'w'"));
  for (const char* command : {"variogram --input a.csv --bins 0:2:1", "cv --samples a.csv --method idw",
                              "interpolate --samples a.csv --method idw --targets a.csv --out p.csv"}) {
    const auto twice = run(std::string(command) + " --coords x,y,x --value v");
    EXPECT_EQ(twice.exit_code, 2) << command << "\n" << twice.output();
    EXPECT_THAT(twice.err, HasSubstr("--coords: column 'x' is named twice")) << command;
  }
  const auto unwritable =
      run("variogram --input a.csv --coords x,y --value v --bins 0:2:1 --out no/such/dir/v.csv");
  EXPECT_EQ(unwritable.exit_code, 1) << unwritable.output();
  EXPECT_THAT(unwritable.err, HasSubstr("no/such/dir/v.csv"));
}

}  // namespace
}  // namespace errfield
