#pragma once
// Internal to fit_compensation_model: the credibility check of a fitted model (refit with a nugget
// or refuse) and the artifacts a written model carries (registration, nominal robot, training
// joints, credible range). See model_fitting.hpp for the rules.

#include <functional>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "errfield/compensation/fitting/model_fitting.hpp"

namespace errfield::compensation {

/// Why a kriging fit is not credible (condition beyond the limit, leave-one-out beyond 3 × the
/// data's largest deviation); empty when it is fine or the model has no kriging system.
std::string fit_problem(const FitResult& fit);

/// Returns `fit` if fit_problem() is empty; else refits with a nugget via `refit` when the variogram
/// was estimated (options.model empty), or throws Error naming the figures.
FitResult check_fitted_model(FitResult fit, const FitOptions& options,
                                    const std::function<FitResult(const VariogramModel&)>& refit);

/// A joint's transmission, compliance and load deflect it by tenths of a mrad to about 2 mrad (the
/// gravity prior's sd); 5 x that is no error of a joint but functions chasing the field or a wrong
/// robot description: on a real IRB 120 the GLS refit wrote 41-49 mrad, a Legendre part of -46.7
/// against a gravity part of +20.7 mrad (issue 47), which fit the measured point and nothing else.
inline constexpr double kPlausibleJointErrorMrad = 10.0;

/// The warning for joint error functions beyond kPlausibleJointErrorMrad over the training poses, or
/// whose polynomial and gravity-load parts cancel beyond it; none when they are plausible.
std::optional<std::string> implausible_joint_functions(const JointErrorFunctions::Size& size);

/// Stores the nominal robot (kinematic methods), the training joints, the credible range and the
/// registration (the training rows' tracker readings onto the model's own predictions, unless the
/// fit already registered them) in fit.model.
FitResult attach_artifacts(FitResult fit, const robot::MdhModel& nominal, const MeasurementSet& data);

/// The nominal robot `nominal` at the point a model's readings are of, for its "before" (the nominal
/// registration attach_artifacts stores, validate's held-out rows): the working tool where the model
/// has one (nominal_at_working_tool), else, for a calibrated model whose reflector lies further than
/// kReflectorAtToolMm from `nominal`'s tool (a robot JSON with tool 0, the reflector found by the
/// calibration), that reflector. At the flange centre a 0.8 mm robot read 118.9 mm "before" on real
/// data (issue 47).
robot::MdhModel nominal_at_measured_point(const CompensationModel& model, const robot::MdhModel& nominal);

/// Held-out readings as validate scores them: MeasurementSet::from_table with `nominal_robot` at the
/// point they are of (nominal_at_measured_point). A file's x,y,z columns are the controller's FK at the
/// robot JSON's (working) tool; where the model's point lies elsewhere they are not the readings'
/// nominal positions, so those are the nominal robot's FK at the point, as the nominal registration
/// was fitted (attach_artifacts). From x,y,z a KR 16 whose reflector the calibration found 19 mm from
/// the JSON's tool read 18.9 mm "before" for 1.1.
MeasurementSet readings_at_measured_point(const CsvTable& table, const CompensationModel& model,
                                          const robot::MdhModel& nominal_robot,
                                          const std::vector<Eigen::Vector3d>& fixed_bases);

/// Refuses (InputError naming the file, line, column 'reflector' and the value) a measurement table
/// whose rows carry more than one label in a column `reflector` (simulate --reflectors, nests on one
/// plate): a model is fitted to one point at a time. One label (the user kept one reflector's rows)
/// or no such column passes. Called before the check of x,y,z against the FK, which would blame the
/// robot for the other reflectors' rows.
void refuse_several_reflectors(const CsvTable& t);
// Whether the table has a `reflector` column with more than one label (readings of several points).
bool several_reflector_labels(const CsvTable& t);
// Refuses (InputError naming column 'reflector') readings of several points for a method that models one.
void refuse_several_points_for(const MeasurementSet& d, CompensationMethod method);

}  // namespace errfield::compensation
