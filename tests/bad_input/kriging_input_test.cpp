// Bad-input catalogue, kriging library level: sample geometries that make universal kriging's
// drift singular (collinear, coplanar, on a sphere for the quadratic drift) and too few samples
// for the drift. They are numerical outcomes, so a status (SingularDrift / TooFewSamples) whose
// message names the drift order and the geometry, and no prediction at all, never NaN means.
// The same at the command line: cli_input_test.cpp (CollinearAndCoplanarSamplesForUniversalKriging).

#include <cmath>
#include <numbers>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "errfield/kriging.hpp"
#include "support/cli_test_common.hpp"

namespace errfield {
namespace kriging_input_test {

using namespace testing::cli_common;
using P3 = Eigen::Vector3d;

const VariogramModel kModel = VariogramModel::parse("sph(sill=1,range=30)");

std::vector<double> values_of(const std::vector<P3>& p) {
  std::vector<double> v;
  for (const auto& x : p) v.push_back(std::sin(x.x()) + 0.5 * x.y() - 0.2 * x.z());
  return v;
}

KrigingOptions universal(int order, KrigingBackend backend = KrigingBackend::Dense) {
  KrigingOptions o;
  o.kind = KrigingKind::Universal;
  o.drift_order = order;
  o.backend = backend;
  if (backend == KrigingBackend::Local) o.neighbors = 8;
  return o;
}

// Runs universal kriging on `samples`; expects `status` with all `words` in the message, and a
// prediction that is refused (no means), not NaN.
void expect_refused(const std::vector<P3>& samples, const KrigingOptions& o, KrigingStatus status,
                    const std::vector<std::string>& words) {
  const auto values = values_of(samples);
  const Kriging<P3, double> k(samples, values, kModel, o);
  EXPECT_EQ(k.report().status, status) << k.report().message;
  for (const auto& w : words) EXPECT_THAT(k.report().message, HasSubstr(w));
  const std::vector<P3> targets{P3(0.5, 0.5, 0.5), P3(2, 1, 0)};
  const auto p = k.predict(targets);
  EXPECT_FALSE(p.usable());
  EXPECT_EQ(p.status, status);
  EXPECT_TRUE(p.mean.empty());
  EXPECT_EQ(p.message, k.report().message);
}

TEST(KrigingBadInput, CollinearSamplesWithALinearDrift) {
  std::vector<P3> line;
  for (int i = 0; i < 8; ++i) line.emplace_back(i, 2.0 * i, -i);
  for (auto backend : {KrigingBackend::Dense, KrigingBackend::Sparse})
    expect_refused(line, universal(1, backend), KrigingStatus::SingularDrift,
                   {"4 drift terms", "linear drift (order 1", "8 samples", "collinear", "lower drift order"});
}

TEST(KrigingBadInput, CoplanarSamplesWithALinearDrift) {
  std::vector<P3> plane;  // the tilted plane x + y + z = 3
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) plane.emplace_back(i, j, 3.0 - i - j);
  expect_refused(plane, universal(1), KrigingStatus::SingularDrift, {"linear drift (order 1", "coplanar"});
  // Ordinary kriging (constant mean) on the same plane is fine.
  const auto values = values_of(plane);
  EXPECT_TRUE((Kriging<P3, double>(plane, values, kModel).report().usable()));
}

TEST(KrigingBadInput, SamplesOnASphereWithAQuadraticDrift) {
  // x^2 + y^2 + z^2 = 25 at every sample: the quadratic terms are dependent with the constant.
  std::vector<P3> sphere;
  for (int i = 0; i < 6; ++i)
    for (int j = 1; j < 6; ++j) {
      const double th = std::numbers::pi * j / 6.0, ph = 2.0 * std::numbers::pi * i / 6.0;
      sphere.emplace_back(5 * std::sin(th) * std::cos(ph), 5 * std::sin(th) * std::sin(ph), 5 * std::cos(th));
    }
  expect_refused(sphere, universal(2), KrigingStatus::SingularDrift,
                 {"10 drift terms", "quadratic drift (order 2", "quadric surface"});
  // The linear drift on the same samples is fine: they span all three directions.
  const auto values = values_of(sphere);
  EXPECT_TRUE((Kriging<P3, double>(sphere, values, kModel, universal(1)).report().usable()));
}

TEST(KrigingBadInput, TooFewSamplesForTheDrift) {
  const std::vector<P3> few{P3(0, 0, 0), P3(1, 0, 0), P3(0, 1, 0), P3(0, 0, 1), P3(1, 1, 1)};
  expect_refused(few, universal(2), KrigingStatus::TooFewSamples,
                 {"5 samples", "10 drift terms", "quadratic drift (order 2"});
}

TEST(KrigingBadInput, LocalNeighbourhoodOnALineNamesTheDrift) {
  // Well spread overall, but the 8 neighbours of the target are all on the x axis.
  std::vector<P3> s;
  for (int i = 0; i < 8; ++i) s.emplace_back(i, 0, 0);
  for (int i = 0; i < 8; ++i) s.emplace_back(100 + i, 100 + 2 * i, 100 - i);
  const auto values = values_of(s);
  const Kriging<P3, double> k(s, values, kModel, universal(1, KrigingBackend::Local));
  ASSERT_TRUE(k.report().usable()) << k.report().message;
  const auto p = k.predict(std::vector<P3>{P3(3.5, 0.1, 0)});
  EXPECT_EQ(p.status, KrigingStatus::SingularDrift);
  EXPECT_EQ(p.failed_targets, 1u);
  EXPECT_THAT(p.message, AllOf(HasSubstr("target 0"), HasSubstr("linear drift (order 1"), HasSubstr("neighbours")));
}

}  // namespace
}  // namespace errfield
