#include "errfield/robot/paper_reference.hpp"

#include <gtest/gtest.h>

#include <filesystem>

#include "errfield/csv_table.hpp"

namespace errfield::robot::paper {
namespace paper_reference_test {

namespace fs = std::filesystem;

// The compiled-in values must equal the CSV transcription kept in data/paper, and the project's
// shared transcription when it sits beside the clone (CI has it; an installed copy does not).
std::vector<fs::path> sources(const std::string& file) {
  std::vector<fs::path> out{fs::path(ERRFIELD_SOURCE_DIR) / "data/paper" / file};
  for (const char* shared : {"/../shared/paper/tables/", "/../../shared/paper/tables/"}) {
    const fs::path p = fs::path(std::string(ERRFIELD_SOURCE_DIR) + shared + file);
    if (fs::exists(p)) out.push_back(p);
  }
  return out;
}

void expect_variogram_equal(std::span<const VariogramRow> rows, const std::string& file, const std::string& lo,
                            const std::string& hi) {
  for (const auto& path : sources(file)) {
    SCOPED_TRACE(path.string());
    const CsvTable t = CsvTable::read(path.string());
    const auto l = t.numeric_column(lo), h = t.numeric_column(hi), g = t.numeric_column("gamma_mm2");
    ASSERT_EQ(l.size(), rows.size());
    for (std::size_t i = 0; i < rows.size(); ++i) {
      EXPECT_EQ(l[i], rows[i].lag_lo);
      EXPECT_EQ(h[i], rows[i].lag_hi);
      EXPECT_EQ(g[i], rows[i].gamma_mm2);
    }
  }
}

void expect_summary_equal(std::span<const ErrorSummaryRow> rows, const std::string& file, const std::string& key) {
  for (const auto& path : sources(file)) {
    SCOPED_TRACE(path.string());
    const CsvTable t = CsvTable::read(path.string());
    const auto mx = t.numeric_column("max_mm"), mean = t.numeric_column("mean_mm"), sd = t.numeric_column("std_mm");
    const std::size_t k = t.column_index(key);
    ASSERT_EQ(t.row_count(), rows.size());
    for (std::size_t i = 0; i < rows.size(); ++i) {
      EXPECT_EQ(t.row(i)[k], rows[i].name);
      EXPECT_EQ(mx[i], rows[i].max_mm);
      EXPECT_EQ(mean[i], rows[i].mean_mm);
      EXPECT_EQ(sd[i], rows[i].std_mm);
    }
  }
}

TEST(PaperReference, CompiledValuesMatchTheTranscription) {
  expect_variogram_equal(table3_joint_variogram(), "table3_joint_variogram.csv", "lag_lo_deg", "lag_hi_deg");
  expect_variogram_equal(table4_task_variogram(), "table4_task_variogram.csv", "lag_lo_mm", "lag_hi_mm");
  expect_summary_equal(table6_compensation(), "table6_compensation.csv", "method");
  expect_summary_equal(table8_assembly(), "table8_assembly.csv", "stage");
}

TEST(PaperReference, PublishedVariogramsRiseWithLag) {
  for (auto rows : {table3_joint_variogram(), table4_task_variogram()})
    for (std::size_t i = 1; i < rows.size(); ++i) {
      EXPECT_GT(rows[i].gamma_mm2, rows[i - 1].gamma_mm2);
      EXPECT_EQ(rows[i].lag_lo, rows[i - 1].lag_hi);
    }
}

}  // namespace
}  // namespace errfield::robot::paper
