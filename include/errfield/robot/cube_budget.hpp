#pragma once
/// The size budget of jobs whose output grows with a user option: a cube sampled in steps of
/// `step` (plan, simulate) has (size/step + 1)^3 grid points, so a typo such as `--step 0.01`
/// would ask for 10^14 points. Each point costs an inverse-kinematics solve and about 2.2 KB of
/// memory on its way to the output CSV (measured: docs/reliability.md, "Resource bounds"), so a
/// job is refused up front, with a ResourceError naming the option and the size, above
/// kMaxCubePoints.

#include <cstddef>
#include <string>

namespace errfield::robot {

/// Most cube points (grid nodes plus per-cell samples) one job may produce by default: ~2 GB of
/// memory and ~10 s of IK at the limit.
inline constexpr std::size_t kMaxCubePoints = 1'000'000;

/// The limit in force: kMaxCubePoints, or the environment variable ERRFIELD_MAX_CUBE_POINTS when it
/// holds a positive integer (raise it on a big machine; the CLI fuzzer lowers it to keep each run
/// short). Throws ArgumentError naming the variable when it is set to anything else.
std::size_t max_cube_points();

/// Throws ResourceError when a `size_mm` cube in steps of `step_mm` has more than max_cube_points()
/// grid nodes (plus, with `cell_samples`, one sample per cell). The message names `option` (e.g.
/// "--step"), the number of points and the smallest step that fits. Does nothing for a step that
/// is not finite and > 0 (the callers' own checks report those).
void check_cube_budget(double size_mm, double step_mm, bool cell_samples, const std::string& option);

/// Throws ResourceError when `count` points (named by `option`, e.g. "--sample random:N") exceed
/// max_cube_points().
void check_point_budget(double count, const std::string& option);

}  // namespace errfield::robot
