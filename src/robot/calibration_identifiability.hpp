#pragma once
// Internal: which candidate parameters a set of measurements identifies (calibration.hpp).
//
// Identifiability is judged on PHYSICALLY scaled Jacobian columns: a length parameter moves in
// mm, an angle in units of 1/reach rad (the angle that moves a point at the arm's reach by 1 mm).
// A column then says how many mm of the measured quantity one physical mm of the parameter
// changes, for every parameter alike. Normalizing each column to unit norm instead would make a
// column that only rounding noise moves (e.g. the tool offset at one constant orientation with
// joints recorded to a few decimals) look as identifiable as any other, and the solver would
// then move that parameter by metres to fit the noise.

#include <vector>

#include <Eigen/Core>

#include "robot/calibration_problems.hpp"

namespace errfield::robot::detail {

/// Σ(|a_i| + |d_i|) + |tool translation| (mm): an upper bound on the distance of the tool point
/// from joint 1's frame, the lever that turns a radian into a length.
double arm_reach_mm(const MdhModel& model);

/// Per candidate: the size of one physical unit in the Jacobian's units (1 for lengths and point
/// coordinates, 1/reach for angles, rad).
Eigen::VectorXd physical_units(const std::vector<int>& candidates, double reach_mm);

/// 2-norm condition number (largest / smallest singular value; infinity if singular).
double condition_number(const Eigen::MatrixXd& m);

struct ParameterSelection {
  std::vector<int> kept;
  std::vector<RemovedParameter> removed;
  double condition_number = 1.0;  ///< of the physically scaled columns of `kept`
  /// Tikhonov weight toward the initial values (mm² per physical mm²); 0: none.
  double regularization = 0.0;
  /// select_parameters_regularized: the candidates removed as weakly identifiable (also in
  /// `removed`), in removal order.
  std::vector<int> weak;
};

/// `jac` has one column per candidate, in the Jacobian's own units (mm/rad, mm/mm). In candidate
/// order: a column whose physical size is below `tolerance` times the largest one has no effect;
/// a column keeping less than `tolerance` of its norm after projection on the kept ones is
/// redundant (reported with its largest coefficients). Then, while the condition number of the
/// kept physical columns exceeds `max_condition`, the parameter dominating the weakest singular
/// direction is removed as weakly identifiable.
ParameterSelection select_parameters(const Eigen::MatrixXd& jac, const std::vector<int>& candidates, double reach_mm,
                                     double tolerance, double max_condition);

/// Structural selection as select_parameters (no effect, redundant), then every structurally
/// identifiable parameter is kept and solved with a Tikhonov penalty toward the initial values,
/// weight 0.1 · (largest singular value / max_condition)² in physical units (`regularization`):
/// directions much stronger than its square root are fitted as plain least squares, much weaker
/// ones stay at the initial values. A parameter of which less than `min_participation` is
/// determined (Σ_i f_i V_ji², the filter factors f_i = s_i² / (s_i² + weight) weighting its
/// share in each singular direction) is removed, the least determined first, until none is left.
ParameterSelection select_parameters_regularized(const Eigen::MatrixXd& jac, const std::vector<int>& candidates,
                                                double reach_mm, double tolerance, double max_condition,
                                                double min_participation);

/// How many of `candidates` measurements of this kind identify at all on this robot: the
/// redundancy selection on a generic, well-spread set of poses. Data with no more equations than
/// that cannot identify the model, however they are placed.
std::size_t generically_identifiable(const CalibrationProblem& problem, const CalibrationState& s,
                                     const std::vector<int>& candidates, double reach_mm, double tolerance);

}  // namespace errfield::robot::detail
