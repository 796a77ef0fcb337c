#pragma once
/// What makes simulated measurements look like real ones (issue 10, item 8): scattered poses with
/// varying tool orientation, joints recorded to a few decimals, a tool/reflector offset the
/// nominal robot does not know, and occasional gross outliers. `errfield simulate` combines them
/// (docs/robot.md "Simulating real-looking data"); everything built with them is SIMULATED data.

#include <cstddef>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "errfield/robot/mdh_model.hpp"
#include "errfield/robot/random.hpp"

namespace errfield::robot {

/// A unit vector uniformly distributed on the sphere.
Eigen::Vector3d random_unit_vector(SimulationRng& rng);

/// `center` turned so its z axis (the tool axis) is uniformly distributed over the spherical cap of
/// half-angle `spread_deg` around the original z axis, then spun about the new z axis by an angle
/// uniform in [-spread_deg, spread_deg]. spread_deg = 0 returns `center`; spread_deg must be in
/// [0, 180] (ArgumentError otherwise).
Eigen::Matrix3d random_orientation_in_cone(const Eigen::Matrix3d& center, double spread_deg, SimulationRng& rng);

/// Joints uniform in the box [lo, hi] (deg, per joint; lo <= hi).
JointVector random_joints_in_box(const JointVector& lo_deg, const JointVector& hi_deg, SimulationRng& rng);

/// Each joint rounded to `decimals` decimal places (half away from zero), as a controller that
/// records q1..q6 to that many decimals writes them. decimals in [0, 12] (ArgumentError otherwise).
JointVector round_joints(const JointVector& q_deg, int decimals);

/// round(fraction · n) distinct indices in [0, n), drawn uniformly, in increasing order: the rows a
/// gross outlier hits. fraction in [0, 1] (ArgumentError otherwise).
std::vector<std::size_t> choose_outliers(std::size_t n, double fraction, SimulationRng& rng);

}  // namespace errfield::robot
