#pragma once
/// The numbers the paper publishes (SPEC sections 2, 4, 5 and 7), compiled in so that a
/// reproduction can print them beside its own simulated results. Source and transcription notes:
/// data/paper/README.md. Use them for comparison only: they are the paper's values, not errfield's.

#include <array>
#include <span>
#include <string_view>

#include <Eigen/Core>

namespace errfield::robot::paper {

/// One bin of a published variogram: [lag_lo, lag_hi) and gamma (mm²). Lags in degrees (Table 3)
/// or mm (Table 4).
struct VariogramRow {
  double lag_lo;
  double lag_hi;
  double gamma_mm2;
};

/// Table 3: distance-error variogram over joint-space lags, 10° bins to 110°.
std::span<const VariogramRow> table3_joint_variogram();
/// Table 4: the same over task-space lags, 200 mm bins to 2,200 mm.
std::span<const VariogramRow> table4_task_variogram();

/// A max / mean / std summary of an error over a set of points (mm).
struct ErrorSummaryRow {
  std::string_view name;  ///< Table 6: method as named by `errfield fit` (or "none"); Table 8: "before"/"after"
  double max_mm;
  double mean_mm;
  double std_mm;
};

/// Table 6: distance error over the 64 samples (none, kinematic, position-idw, distance-idw).
std::span<const ErrorSummaryRow> table6_compensation();
/// Table 8: tool-tip deviation from the 15 holes, before and after compensation.
std::span<const ErrorSummaryRow> table8_assembly();

/// Table 2: joint ranges (deg) of the similarity study, {min, max} per joint. J3's printed
/// "[80, 40]" is read as [40, 80].
std::array<std::array<double, 2>, 6> table2_joint_ranges_deg();

/// Fig. 5: the grid step the paper chose (mm) and the side of its cube (mm).
inline constexpr double kChosenGridStepMm = 125.0;
inline constexpr double kCubeSideMm = 500.0;

/// Section 7: the plate frame of the assembly test, measured in the tracker frame:
/// x, y, z (mm), then three angles (deg) in the paper's order.
inline constexpr std::array<double, 6> kPlateFrameTracker = {1517.287, -282.698, -510.519, -65.461, -0.146, -179.440};

/// Table 7: tool and target-ball offsets in the flange frame, x, y, z (mm) and three angles (deg).
inline constexpr std::array<double, 6> kToolOffset = {0.018, -0.012, 77.025, 0.011, -0.015, 0.008};
inline constexpr std::array<double, 6> kBallOffset = {18.231, 10.452, 32.416, 0.124, -0.085, 14.500};

/// Section 1: the assembly tolerance (± mm) the paper aims at.
inline constexpr double kAssemblyToleranceMm = 0.25;

}  // namespace errfield::robot::paper
