// Bad-input catalogue, CSV reader level: every malformed file raises InputError naming the file,
// the row (1-based file line) and the column, and the message says so in words. The same cases
// at the command line are in cli_input_test.cpp.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"
#include "support/cli_test_common.hpp"

namespace errfield {
namespace csv_input_test {

using namespace testing::cli_common;

// Runs `f`, expects InputError with the given location, returns its message.
template <class F>
std::string expect_input_error(F f, const std::string& file, std::size_t row, const std::string& column) {
  try {
    f();
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), file);
    EXPECT_EQ(e.row(), row);
    EXPECT_EQ(e.column(), column);
    EXPECT_THAT(e.what(), HasSubstr(file));
    if (row > 1) {
      EXPECT_THAT(e.what(), HasSubstr(":" + std::to_string(row)));
    }
    if (!column.empty()) {
      EXPECT_THAT(e.what(), HasSubstr("'" + column));
    }
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected InputError, got another exception: " << e.what();
    return {};
  }
  ADD_FAILURE() << "expected InputError, nothing thrown";
  return {};
}

TEST(CsvBadInput, MissingColumnListsTheHeader) {
  const auto t = CsvTable::parse("x,y,z\n1,2,3\n", "m.csv");
  const auto msg = expect_input_error([&] { t.numeric_column("v"); }, "m.csv", 1, "v");
  EXPECT_THAT(msg, HasSubstr("x,y,z"));
}

TEST(CsvBadInput, ExtraAndMissingCellsNameTheRow) {
  auto msg = expect_input_error([] { CsvTable::parse("x,v\n1,2\n3,4,5\n", "e.csv"); }, "e.csv", 3, "");
  EXPECT_THAT(msg, HasSubstr("3 cells"));
  msg = expect_input_error([] { CsvTable::parse("x,v\n1,2\n\n# c\n3\n", "e.csv"); }, "e.csv", 5, "");
  EXPECT_THAT(msg, HasSubstr("1 cells"));
}

TEST(CsvBadInput, DuplicatedColumnsAlsoWhenOnlyTheUnitDiffers) {
  auto msg = expect_input_error([] { CsvTable::parse("x,v,x\n1,2,3\n", "d.csv"); }, "d.csv", 1, "x");
  EXPECT_THAT(msg, HasSubstr("twice"));
  expect_input_error([] { CsvTable::parse("x [mm],x (m)\n1,2\n", "d.csv"); }, "d.csv", 1, "x");
}

TEST(CsvBadInput, NonNumericEmptyNanAndInfCells) {
  const auto t = CsvTable::parse("x,v\n1,2\n2,abc\n3,\n4,nan\n5,-inf\n6,1e999\n", "c.csv");
  const auto only = [&](std::size_t line) {
    return [&t, line] {
      // One bad row at a time: a table of the header plus that line.
      const auto one = CsvTable::parse("x,v\n" + std::string(t.cell(line - 2, 0)) + "," + std::string(t.cell(line - 2, 1)) + "\n", "c.csv");
      one.numeric_column("v");
    };
  };
  EXPECT_THAT(expect_input_error([&] { t.numeric_column("v"); }, "c.csv", 3, "v"), HasSubstr("'abc' is not a number"));
  EXPECT_THAT(expect_input_error(only(4), "c.csv", 2, "v"), HasSubstr("empty"));
  EXPECT_THAT(expect_input_error(only(5), "c.csv", 2, "v"), HasSubstr("'nan' is not a finite number"));
  EXPECT_THAT(expect_input_error(only(6), "c.csv", 2, "v"), HasSubstr("'-inf' is not a finite number"));
  EXPECT_THAT(expect_input_error(only(7), "c.csv", 2, "v"),
              HasSubstr("'1e999' is not a finite number (beyond the range of a double)"));  // overflows
}

TEST(CsvBadInput, UnderflowReadsAsTheNearestDouble) {
  const auto t = CsvTable::parse("x,v\n1,1e-400\n2,-4e-320\n", "u.csv");
  const auto v = t.numeric_column("v");
  EXPECT_EQ(v[0], 0.0);
  EXPECT_EQ(v[1], -4e-320);  // subnormal, exactly as strtod reads it
}

TEST(CsvBadInput, BomAndCrlfAreReadAndLinesStayRight) {
  const auto t = CsvTable::parse("\xEF\xBB\xBFx;v\r\n1;2\r\n\r\n3;oops\r\n", "b.csv");
  EXPECT_EQ(t.header()[0], "x");  // the BOM is not part of the first name
  EXPECT_EQ(t.numeric_column("x"), (std::vector<double>{1, 3}));
  const auto msg = expect_input_error([&] { t.numeric_column("v"); }, "b.csv", 4, "v");
  EXPECT_THAT(msg, Not(HasSubstr("\r")));
  EXPECT_THAT(msg, HasSubstr("'oops'"));
}

TEST(CsvBadInput, EmptyFileAndHeaderOnly) {
  expect_input_error([] { CsvTable::parse("\xEF\xBB\xBF\r\n# only a comment\n", "h.csv"); }, "h.csv", 0, "");
  const auto t = CsvTable::parse("x,v\n", "h.csv");
  EXPECT_EQ(t.row_count(), 0u);
  EXPECT_TRUE(t.numeric_column("v").empty());
}

TEST(CsvBadInput, BinaryDataAndUnterminatedQuotes) {
  expect_input_error([] { CsvTable::parse(std::string("x,v\n1,\0\n", 7), "n.csv"); }, "n.csv", 0, "");
  expect_input_error([] { CsvTable::parse("x,v\n1,\"2\n", "q.csv"); }, "q.csv", 2, "");
}

TEST(CsvBadInput, MissingFileNamesIt) {
  try {
    CsvTable::read("/nonexistent/dir/none.csv");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "/nonexistent/dir/none.csv");
    EXPECT_THAT(e.what(), HasSubstr("cannot open"));
  }
}

}  // namespace
}  // namespace errfield
