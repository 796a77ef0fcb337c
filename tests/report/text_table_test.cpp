#include "errfield/report/text_table.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "errfield/error.hpp"

namespace errfield::report {
namespace text_table_test {

TEST(TextTable, AlignsColumnsAndPrintsUnits) {
  TextTable t({{"method", "", Align::Left}, {"max", "mm"}, {"mean", "mm"}});
  t.add_row({"none", "1.346", "0.514"});
  t.add_row({"distance-idw", "0.104", "0.037"});
  t.add_separator();
  t.add_row({"paper", "12.5", "0.1"});
  const std::string text = t.to_text("");
  // Columns are padded to their widest cell and separated by two spaces; numbers right-aligned.
  std::vector<std::string> lines;
  std::size_t start = 0;
  for (std::size_t p; (p = text.find('\n', start)) != std::string::npos; start = p + 1)
    lines.push_back(text.substr(start, p - start));
  ASSERT_EQ(lines.size(), 7u);  // header, units, rule, 2 rows, rule, 1 row
  EXPECT_EQ(lines[0], "method          max   mean");
  EXPECT_EQ(lines[1], "               [mm]   [mm]");
  EXPECT_EQ(lines[3], "none          1.346  0.514");
  EXPECT_EQ(lines[4], "distance-idw  0.104  0.037");
  EXPECT_EQ(lines[5], std::string(lines[2]));  // the separator is the same rule
  EXPECT_EQ(lines[6], "paper          12.5    0.1");
  EXPECT_TRUE(t.separator_before(2));
  EXPECT_FALSE(t.separator_before(1));
}

TEST(TextTable, RejectsRowOfWrongLength) {
  TextTable t(std::vector<TextColumn>{TextColumn("a"), TextColumn("b")});
  EXPECT_THROW(t.add_row({"1"}), ArgumentError);
}

TEST(TextTable, WidthCountsCodePoints) {
  EXPECT_EQ(display_width("γ [mm²]"), 7u);
  TextTable t(std::vector<TextColumn>{TextColumn("γ", "mm²")});
  t.add_row({"0.1"});
  EXPECT_EQ(t.to_text(""), "    γ\n[mm²]\n-----\n  0.1\n");
}

TEST(Fixed, FormatsDecimalsAndMissing) {
  EXPECT_EQ(fixed(0.10449, 3), "0.104");
  EXPECT_EQ(fixed(-0.0001, 3), "0.000");
  EXPECT_EQ(fixed(2.0, 0), "2");
  EXPECT_EQ(fixed(std::nan(""), 3), "-");
}

}  // namespace
}  // namespace errfield::report
