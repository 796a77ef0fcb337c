#pragma once
/// The leave-one-out of joint error functions and a field together, per sample.
///
/// `fit` regresses the calibration's residuals on joint error functions (joint_error_functions.hpp)
/// and krigs what they leave. A field's own leave-one-out then understates a new pose's error: the
/// functions saw the left-out pose. Both are linear in the residuals, so the leave-one-out of the
/// two together is exact without refitting anything: at a sample of pose i,
///
///   e_i = r_i^field-LOO - L_i (beta_-i - beta),
///
/// L_i the field's leave-one-out operator applied to the functions' design at the field's point
/// (Kriging::leave_one_out_residuals_of: the weights do not depend on the values) and beta_-i - beta
/// the ridge's change when pose i is left out (JointErrorFunctionFit::held_out_coefficient_change_mrad).
/// The second term is the shift this header computes; the field's variance calibration adds it to
/// each sample's leave-one-out residual (KrigingFieldOptions::held_out_shift).
///
/// Why per sample and not one ratio (JointErrorFunctionFit::leave_one_out_inflation): the ratio
/// counts a pose at the edge of a joint's range, where the Legendre terms have leverage, in full,
/// though the field takes most of it back from the neighbouring poses. On SIMULATED UR5e probe
/// readings the ratio was x2.9 and the 95 % radius held 100 % of held-out readings (docs/robot.md,
/// "Predictive uncertainty").

#include <functional>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "errfield/compensation/model/compensation.hpp"
#include "errfield/compensation/model/joint_error_functions.hpp"
#include "errfield/robot/mdh_model.hpp"

namespace errfield::compensation {

/// Per sample of a field, in its samples' order: the shift (mm) of its leave-one-out residual.
/// Empty when the field cannot give its leave-one-out operator (not a vector kriging field, or
/// merged samples).
using HeldOutShift = std::function<std::vector<Eigen::Vector3d>(const ErrorField& field)>;

/// The shift for a field over readings at the tool point of `at`, the functions fitted (ordinary
/// ridge, `fit`) on readings at `reflector`'s tool point at `poses` (the fit's order). `at` equal to
/// `reflector`: the functions' own point; otherwise their design is carried to the point
/// (JointErrorFunctions::design_rows_at_point). A sample at a pose the functions did not see shifts
/// by nothing. Null when `fit` has no leave-one-out (no ridge fit, or another number of poses).
HeldOutShift joint_function_held_out_shift(std::shared_ptr<const JointErrorFunctionFit> fit,
                                           const std::vector<robot::JointVector>& poses,
                                           const robot::MdhModel& reflector, const robot::MdhModel& at);

}  // namespace errfield::compensation
