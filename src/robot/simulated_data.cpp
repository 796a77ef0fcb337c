#include "errfield/robot/simulated_data.hpp"
#include "robot/degrees.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "errfield/error.hpp"

namespace errfield::robot {

namespace {
}

Eigen::Vector3d random_unit_vector(SimulationRng& rng) {
  // Uniform on the sphere: z uniform in [-1, 1], azimuth uniform (Archimedes' hat-box theorem).
  const double z = rng.uniform(-1.0, 1.0), phi = rng.uniform(0.0, 2.0 * std::numbers::pi);
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  return {r * std::cos(phi), r * std::sin(phi), z};
}

Eigen::Matrix3d random_orientation_in_cone(const Eigen::Matrix3d& center, double spread_deg, SimulationRng& rng) {
  if (!(spread_deg >= 0.0 && spread_deg <= 180.0))
    throw ArgumentError("orientation spread " + std::to_string(spread_deg) + " deg; expected a value in [0, 180]");
  if (spread_deg == 0.0) return center;
  // Uniform over the cap: cos(tilt) uniform in [cos(spread), 1] (equal areas), azimuth uniform.
  const double c = rng.uniform(std::cos(spread_deg * kDeg), 1.0);
  const double tilt = std::acos(std::min(1.0, c)), azimuth = rng.uniform(0.0, 2.0 * std::numbers::pi);
  const double spin = rng.uniform(-spread_deg, spread_deg) * kDeg;
  const Eigen::Vector3d tilt_axis(std::cos(azimuth), std::sin(azimuth), 0.0);  // in the tool frame
  return center * Eigen::AngleAxisd(tilt, tilt_axis).toRotationMatrix() *
         Eigen::AngleAxisd(spin, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

JointVector random_joints_in_box(const JointVector& lo_deg, const JointVector& hi_deg, SimulationRng& rng) {
  JointVector q;
  for (int j = 0; j < kJointCount; ++j) {
    if (!(lo_deg[j] <= hi_deg[j]))
      throw ArgumentError("joint box: q" + std::to_string(j + 1) + " low " + std::to_string(lo_deg[j]) +
                          " > high " + std::to_string(hi_deg[j]));
    q[j] = rng.uniform(lo_deg[j], hi_deg[j]);
  }
  return q;
}

JointVector round_joints(const JointVector& q_deg, int decimals) {
  if (decimals < 0 || decimals > 12)
    throw ArgumentError("joint decimals " + std::to_string(decimals) + "; expected 0..12");
  const double scale = std::pow(10.0, decimals);
  JointVector r;
  for (int j = 0; j < kJointCount; ++j) r[j] = std::round(q_deg[j] * scale) / scale;
  return r;
}

std::vector<std::size_t> choose_outliers(std::size_t n, double fraction, SimulationRng& rng) {
  if (!(fraction >= 0.0 && fraction <= 1.0))
    throw ArgumentError("outlier fraction " + std::to_string(fraction) + "; expected a value in [0, 1]");
  const auto count = static_cast<std::size_t>(std::llround(fraction * static_cast<double>(n)));
  // Partial Fisher-Yates: the first `count` of a random permutation.
  std::vector<std::size_t> idx(n);
  for (std::size_t i = 0; i < n; ++i) idx[i] = i;
  for (std::size_t i = 0; i < count; ++i) std::swap(idx[i], idx[i + rng.below(n - i)]);
  idx.resize(count);
  std::sort(idx.begin(), idx.end());
  return idx;
}

}  // namespace errfield::robot
