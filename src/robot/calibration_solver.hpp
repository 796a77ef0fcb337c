#pragma once
// Internal: the Levenberg–Marquardt core of kinematic calibration with optional IGG3 robust
// reweighting (calibration.hpp). Takes a measurement model (calibration_problems.hpp), selects
// the identifiable candidates (calibration_identifiability.hpp), solves, and fills the result:
// identified model, kept and removed parameters, standard errors, residuals, weights, status.

#include <vector>

#include "robot/calibration_problems.hpp"

namespace errfield::robot::detail {

/// Throws InputError when the data have too few distinct poses for what measurements of their
/// kind can identify, ArgumentError for bad options or a non-finite start.
CalibrationResult solve_calibration(const CalibrationProblem& problem, const CalibrationState& start,
                                    const std::vector<int>& candidates, const CalibrationOptions& options);

/// IGG3 weights of per-measurement residual sizes (|v| for distances, 3-D norm for positions).
std::vector<double> igg3_weights(const std::vector<double>& sizes, int dim, const RobustOptions& options);

}  // namespace errfield::robot::detail
