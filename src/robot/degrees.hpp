#pragma once
// Radians per degree, for the robot module's sources (one definition: they may share a unity-build
// translation unit).

#include <numbers>

namespace errfield::robot {
inline constexpr double kDeg = std::numbers::pi / 180.0;
}  // namespace errfield::robot
