#include "errfield/csv_table.hpp"
#include "errfield/csv_writing.hpp"

#include <gtest/gtest.h>

#include "errfield/error.hpp"

namespace errfield {
namespace csv_table_test {

TEST(CsvTable, ReadsBomCrlfSemicolonsCommentsAndUnits) {
  const auto t = CsvTable::parse("\xEF\xBB\xBFx [mm];y (mm);v\r\n# comment\r\n\r\n1;2;3\r\n4; 5 ;6\r\n", "mem.csv");
  ASSERT_EQ(t.row_count(), 2u);
  EXPECT_EQ(t.numeric_column("x"), (std::vector<double>{1, 4}));
  EXPECT_EQ(t.numeric_column("y"), (std::vector<double>{2, 5}));
  EXPECT_EQ(t.line_of_row(1), 5u);
}

TEST(CsvTable, QuotedCellsKeepDelimiters) {
  const auto t = CsvTable::parse("name,v\n\"a,b\",1\n", "q.csv");
  EXPECT_EQ(t.cell(0, 0), "a,b");
}

TEST(CsvTable, BadCellNamesFileLineAndColumn) {
  const auto t = CsvTable::parse("x,v\n1,2\n3,abc\n", "bad.csv");
  try {
    t.numeric_column("v");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "bad.csv");
    EXPECT_EQ(e.row(), 3u);
    EXPECT_EQ(e.column(), "v");
    EXPECT_NE(std::string(e.what()).find("'abc'"), std::string::npos);
  }
}

TEST(CsvTable, RejectsNanInfEmptyAndMissingColumns) {
  const auto t = CsvTable::parse("x,v,w,e\n1,nan,inf,\n", "n.csv");
  EXPECT_THROW(t.numeric_column("v"), InputError);
  EXPECT_THROW(t.numeric_column("w"), InputError);
  EXPECT_THROW(t.numeric_column("e"), InputError);
  EXPECT_THROW(t.numeric_column("zz"), InputError);
}

TEST(CsvTable, RejectsRaggedRowsAndDuplicateColumns) {
  EXPECT_THROW(CsvTable::parse("x,v\n1,2,3\n", "r.csv"), InputError);
  EXPECT_THROW(CsvTable::parse("x,x\n1,2\n", "d.csv"), InputError);
  EXPECT_THROW(CsvTable::parse("", "e.csv"), InputError);
}

TEST(FormatNumber, RoundTripsExactly) {
  for (double v : {0.1, 1.0 / 3.0, -1234.5678e-12, 6.02e23}) {
    EXPECT_EQ(std::stod(format_number(v)), v);
  }
}

TEST(SplitList, TrimsAndRejectsEmptyItemsNamingTheOption) {
  EXPECT_EQ(split_list(" x, y ,z", "--coords"), (std::vector<std::string>{"x", "y", "z"}));
  try {
    split_list("x,,z", "--coords");
    FAIL() << "expected ArgumentError";
  } catch (const ArgumentError& e) {
    EXPECT_NE(std::string(e.what()).find("--coords: empty item in 'x,,z'"), std::string::npos) << e.what();
  }
}

TEST(SplitColumnList, ANameGivenTwiceIsAnErrorNamingTheOptionAndTheColumn) {
  EXPECT_EQ(split_column_list("q1,q2", "--coords"), (std::vector<std::string>{"q1", "q2"}));
  try {
    split_column_list("x, y, x", "--coords");
    FAIL() << "expected ArgumentError";
  } catch (const ArgumentError& e) {
    EXPECT_STREQ(e.what(), "--coords: column 'x' is named twice in 'x, y, x' (items 1 and 3)");
  }
}

// Issue 35: cells were written as they were, so a point named "p,1" made fk, plan and validate
// write files errfield itself refused ("row has 3 cells; the header has 2"). Every writer goes
// through csv_cell/append_csv_line; what they write must read back cell for cell.
TEST(CsvCell, EveryWrittenCellReadsBackExactly) {
  const std::vector<std::string> header{"point", "note", "v"};
  const std::vector<std::vector<std::string>> rows{{"p,1", "say \"hi\"", "1"},
                                                   {" lead", "trail ", "2"},
                                                   {"#3", "a;b", "3"},
                                                   {"two\nlines", "cr\rinside", "4"},
                                                   {"plain", "", "5"}};
  std::string text;
  append_csv_line(text, header);
  for (const auto& r : rows) append_csv_line(text, r);
  const auto t = CsvTable::parse(text, "w.csv");
  ASSERT_EQ(t.row_count(), rows.size()) << text;
  for (std::size_t r = 0; r < rows.size(); ++r)
    for (std::size_t c = 0; c < header.size(); ++c) EXPECT_EQ(t.cell(r, c), rows[r][c]) << "row " << r << " column " << c;
  // The row after a cell of two lines is on line 7 of the file (header 1, rows on 2, 3, 4, 5-6).
  EXPECT_EQ(t.line_of_row(4), 7u);
  EXPECT_EQ(csv_cell("plain"), "plain");  // nothing quoted that needs no quotes
  EXPECT_EQ(csv_cell("p,1"), "\"p,1\"");
  EXPECT_EQ(csv_cell("a\"b"), "\"a\"\"b\"");
}

TEST(CsvCell, OneEmptyCellIsNotABlankLine) {
  std::string text;
  append_csv_line(text, {"a"});
  append_csv_line(text, {""});
  append_csv_line(text, {"1"});
  const auto t = CsvTable::parse(text, "one.csv");
  ASSERT_EQ(t.row_count(), 2u);
  EXPECT_EQ(t.cell(0, 0), "");
}

TEST(CsvTable, AQuoteInACommentSwallowsNoRow) {
  const auto t = CsvTable::parse("# a 5\" reflector\nx,v\n1,2\n3,4\n", "c.csv");
  EXPECT_EQ(t.row_count(), 2u);
}

}  // namespace
}  // namespace errfield
