// validate's HTML report (issue 19): histogram bins readable, and a view of where - against which
// joints - the large errors and the refused points are.

#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "errfield/compensation/validation/validation.hpp"

namespace errfield::compensation {
namespace validation_report_test {

std::size_t occurrences(const std::string& s, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t p = s.find(what); p != std::string::npos; p = s.find(what, p + 1)) ++n;
  return n;
}

/// Five scored points and two refused ones, each with joints; hand-made, not simulated data.
ValidationReport sample_report() {
  ValidationReport r;
  r.mode = "prediction";
  std::vector<double> before, after;
  for (int i = 0; i < 7; ++i) {
    ValidatedPoint p;
    p.point = "p" + std::to_string(i);
    p.status = i < 5 ? "ok" : "outside-region";
    for (int j = 0; j < 6; ++j) p.q_deg[j] = -50.0 + 20.0 * i + j;
    if (p.ok()) {
      p.before_mm = Eigen::Vector3d(0.5 + 0.1 * i, 0.0, 0.0);
      p.after_mm = Eigen::Vector3d(0.01 * (i + 1), 0.02, 0.0);
      before.push_back(p.before_mm.norm());
      after.push_back(p.after_mm.norm());
    }
    r.points.push_back(p);
  }
  r.refused = 2;
  r.position = BeforeAfter{ErrorStats::of(before), ErrorStats::of(after)};
  return r;
}

TEST(ValidationReport, ShowsErrorsAndRefusalsAgainstEachJoint) {
  const std::string html = validation_report_html(sample_report(), "test", false);
  EXPECT_NE(html.find("Where: errors and refusals against each joint"), std::string::npos);
  for (int j = 1; j <= 6; ++j) EXPECT_NE(html.find("q" + std::to_string(j) + " [deg]"), std::string::npos) << j;
  // Per joint plot: 5 scored markers and 2 refused ones (red); the marker radius 3.2 is that of
  // data points (legend swatches are drawn at 3.5), so every data point of the six plots is counted.
  EXPECT_EQ(occurrences(html, "r=\"3.2\" fill=\"#b00020\""), 2u * 6u);
  EXPECT_EQ(occurrences(html, "r=\"3.2\""), 7u * 6u + 5u * 2u);  // + the per-point plot: before and after
}

TEST(ValidationReport, NoJointViewWithoutJoints) {
  ValidationReport r = sample_report();
  for (auto& p : r.points) p.q_deg.setConstant(ValidatedPoint::kNaN);
  const std::string html = validation_report_html(r, "test", false);
  EXPECT_EQ(html.find("against each joint"), std::string::npos);
}

TEST(ValidationReport, HistogramBinsAreLabelledByTheirLowerEdge) {
  const std::string html = validation_report_html(sample_report(), "test", false);
  // "0.1–0.2"-style labels overlapped at a dozen bins; the axis label gives the bin width instead.
  EXPECT_EQ(html.find("–"), std::string::npos);
  EXPECT_NE(html.find("bins of"), std::string::npos);
}

}  // namespace validation_report_test
}  // namespace errfield::compensation
