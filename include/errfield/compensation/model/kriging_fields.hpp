#pragma once
/// Error fields by kriging (compensation.hpp): errfield's stronger options beside the paper's IDW.
/// Use them when you want a prediction variance (is the target inside a ±0.25 mm tolerance, with
/// what confidence?) or samples that are not a complete regular grid.
///  - distance kriging: the scalar distance error to a base point, kriged, then projected along
///    m = (P − P0)/|P − P0| like the paper's eq. 23 (radial correction only);
///  - vector kriging: the 3-D error vector dP (from registered positions, or recovered from
///    distances to >= 3 base points), the three components kriged with one shared factorization
///    (an intrinsic coregionalization with one structure; docs/reproduction.md says what that assumes).
/// Locations are the targets' nominal positions (task space, mm) or nominal joints (joint space,
/// deg): with a constant orientation both work; where the orientation varies, errors are similar in
/// joint space, not in task space (the paper's section 3.1).
///
/// The region a field answers for is, in task space, the box of its samples' nominal positions
/// widened by `region_margin_mm` and by kRegionToleranceMm (FK of rounded joints puts a target
/// on a face of the box micrometres outside it); in joint space, the box of the samples' joints
/// widened by `region_margin_deg` and kRegionToleranceDeg. Targets outside are refused, never
/// extrapolated.

#include <functional>
#include <memory>
#include <string>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "errfield/cross_validation.hpp"
#include "errfield/kriging.hpp"
#include "errfield/compensation/model/compensation.hpp"
#include "errfield/compensation/model/field_model_family.hpp"
#include "errfield/variogram_model.hpp"

namespace errfield::compensation {

enum class FieldSpace { task, joint };

/// What the region test always tolerates beyond the samples' box: 10 µm in task space, 1e-4 deg per
/// joint (≈ 3 µm at 1.5 m reach) in joint space. Far below any error a model predicts, far above
/// the rounding of joints recorded to 4+ decimals or of IK (1e-7 mm).
inline constexpr double kRegionToleranceMm = 0.01;
inline constexpr double kRegionToleranceDeg = 1e-4;
/// The default field's family choice (`fit --model auto`) ranks the candidates on this many samples
/// (all of them when fewer) and refits the best kFieldChoiceConfirmed on all: `fit --help`, its log
/// and docs/robot.md state these numbers.
inline constexpr std::size_t kFieldChoiceSubsample = 300;
inline constexpr std::size_t kFieldChoiceConfirmed = 2;
std::string_view field_space_name(FieldSpace s);
/// "task" | "joint"; throws ArgumentError.
FieldSpace field_space_from_name(std::string_view name);

/// How a field's predictive variance was calibrated on its own training data (fit does it for an
/// estimated variogram; `KrigingFieldOptions::calibrate_variance`). The leave-one-out residual of
/// each (merged) sample, observed − predicted from all the others, has a variance the model states
/// in closed form (kriging variance + nugget, per component), so z² = |residual|² / that variance
/// is χ²_K (K = 1 or 3 components) when the model is right. Multiplying every sill (nugget
/// included) by c multiplies each stated variance by c and leaves the kriging weights, so the
/// predicted errors, unchanged (ordinary and universal kriging are invariant to the covariance's
/// scale). c = max(mean z² / K, q95(z²) / χ²_K(0.95)): the smallest scale at which the model is
/// overconfident neither on average (mean z² / K <= 1, what the mean NEES checks) nor in the tail
/// (at least 95 % of the samples inside the 95 % region, what coverage95 and r95_mm check); errors
/// heavier-tailed than Gaussian (a field that ignores the tool's orientation) need the second.
/// Training data only, so a held-out check of the variance stays honest. Measured on SIMULATED
/// data with realistic systematic effects in docs/robot.md "Predictive uncertainty".
struct VarianceCalibration {
  double factor = 1.0;               ///< c: every sill and the nugget were multiplied by this
  /// mean leave-one-out z² per component of the model before, each z² capped at tail_factor ·
  /// χ²_K(0.999) (the calibration's `capped_samples` reached the cap)
  double mean_squared_z_before = 1;
  double tail_factor = 1;            ///< q95(z²) / χ²_K(0.95): the scale that puts 95 % in the 95 % region
  std::size_t samples = 0;           ///< (merged) samples the mean is over
  std::size_t capped_samples = 0;    ///< of them, those whose z² entered the mean at the cap
  std::string model_before;          ///< the variogram model before, VariogramModel::to_string
};

struct KrigingFieldOptions {
  FieldSpace space = FieldSpace::task;
  /// Variogram model of the values (mm², lag in mm or deg); empty = estimated from the samples
  /// (empirical variogram + best of sph/exp/gau with a free nugget, gstat's N_j/h² weights).
  std::optional<VariogramModel> model;
  /// With `model` empty: estimate within this family only (field_model_family.hpp); empty = the
  /// automatic choice.
  std::optional<FieldModelFamily> family;
  /// The nugget stands for measurement noise (smoothing, gstat's Err) rather than micro-scale
  /// variation: predictions are of the noise-free error. Default true (tracker + repeatability).
  bool nugget_is_measurement_error = true;
  /// Which kriging: ordinary (default) or universal with a polynomial drift of drift_order in the
  /// field's coordinates (simple kriging is not offered: the mean of an error field is unknown).
  KrigingKind kind = KrigingKind::Ordinary;
  int drift_order = 1;
  double region_margin_mm = 0.0;   ///< task space
  double region_margin_deg = 0.0;  ///< joint space, per joint
  /// Called before each long stage (factoring the N x N covariance, the leave-one-out) with what it
  /// is about to do, for progress output; empty = silent. Not called from parallel regions.
  std::function<void(const std::string& stage)> on_stage;
  /// Calibrate the predictive variance by leave-one-out (VarianceCalibration) before the field is
  /// returned: the field's model is then the calibrated one. fit_*_kriging_field only.
  bool calibrate_variance = false;
  /// With calibrate_variance: the values are what a preceding regression fitted on the same samples
  /// left (joint_error_functions.hpp), so their leave-one-out z² understate a new reading's by this
  /// factor (>= 1; the regression's own leave-one-out over in-sample residual ratio); the
  /// calibration multiplies them by it.
  double value_variance_inflation = 1.0;
  /// With calibrate_variance, vector fields: what re-estimating that regression without a sample
  /// changes at it (mm, one per sample in the order given), from the uncalibrated field (whose
  /// leave-one-out weights it needs, leave_one_out_residuals_of). Each sample's z² is then that of
  /// its leave-one-out residual plus this shift: the leave-one-out of regression and field together,
  /// per sample, in place of value_variance_inflation (which stays the fallback when the samples
  /// were merged). Empty = not used.
  std::function<std::vector<Eigen::Vector3d>(const ErrorField& uncalibrated)> held_out_shift;
  /// The calibration a field's model already carries (written to and read from the model JSON,
  /// member "variance_calibration"; the model string is the calibrated model).
  std::optional<VarianceCalibration> variance_calibration;
  /// Throws ArgumentError naming the field.
  void validate() const;
};

/// Samples of an error field: nominal positions (mm), nominal joints (deg), one per sample.
struct FieldSamples {
  std::vector<Eigen::Vector3d> position_mm;
  std::vector<robot::JointVector> joints_deg;
};

/// Kriging of distance errors `distance_error_mm` (one per sample) to `base_point_mm`.
/// Throws ArgumentError/InputError for mismatched sizes, fewer than 8 samples or non-finite data.
std::shared_ptr<const ErrorField> make_distance_kriging_field(const FieldSamples& samples,
                                                              std::vector<double> distance_error_mm,
                                                              const Eigen::Vector3d& base_point_mm,
                                                              const KrigingFieldOptions& options = {});

/// Kriging of 3-D position errors (robot frame, mm), one per sample.
std::shared_ptr<const ErrorField> make_vector_kriging_field(const FieldSamples& samples,
                                                            std::vector<Eigen::Vector3d> position_error_mm,
                                                            const KrigingFieldOptions& options = {});

/// A kriging field and its leave-one-out cross-validation, both from the one factorization (the
/// closed form of Dubrule 1983: O(N^3), not N refits). Samples at the same location (repeated
/// measurements of one pose) are averaged into one, so leave-one-out leaves out a location and
/// `leave_one_out.predicted` counts locations. Residual variances are those of a new observation
/// (kriging variance plus the measurement-error nugget), so mean_squared_z ~ 1 when calibrated.
struct KrigingFieldFit {
  std::shared_ptr<const ErrorField> field;
  VariogramModel model;  ///< the variogram model the field uses (the calibrated one, if calibrated)
  CrossValidationSummary leave_one_out;
  std::size_t merged_duplicates = 0;  ///< samples folded into another at the same location
  /// How the covariance was factored: condition number, jitter, IllConditioned status.
  KrigingReport factorization;
  /// The leave-one-out calibration of the variance, when it was asked for; `leave_one_out` is then
  /// that of the calibrated field (mean_squared_z 1 up to rounding).
  std::optional<VarianceCalibration> variance_calibration;
};

/// make_distance_kriging_field plus its leave-one-out summary (mm).
KrigingFieldFit fit_distance_kriging_field(const FieldSamples& samples, std::vector<double> distance_error_mm,
                                           const Eigen::Vector3d& base_point_mm,
                                           const KrigingFieldOptions& options = {});

/// make_vector_kriging_field plus its leave-one-out summary (norm of the 3-D residual, mm).
KrigingFieldFit fit_vector_kriging_field(const FieldSamples& samples, std::vector<Eigen::Vector3d> position_error_mm,
                                         const KrigingFieldOptions& options = {});

/// One sample's leave-one-out residual in a vector kriging field: observed − predicted from all the
/// other samples (mm, robot frame) and the variance of that residual per component (mm²: kriging
/// variance plus the nugget when it is measurement error), so |residual|² / variance ~ χ²₃.
struct SampleHoldOut {
  Eigen::Vector3d residual_mm = Eigen::Vector3d::Zero();
  double variance_mm2 = 0.0;
};

/// The leave-one-out residual of every sample of a vector kriging field, in the order the samples
/// were given, from the field's factorization (what fit's outlier screen judges rows by). Empty
/// when `field` is not a vector kriging field, when samples at the same location were merged
/// (leave-one-out then leaves out a location, not a row) or when the leave-one-out failed.
std::vector<SampleHoldOut> leave_one_out_by_sample(const ErrorField& field);

/// The residuals a vector kriging field's leave-one-out weights give for other values at its
/// samples: v_i - sum_j w_ij v_j, `values` one row per sample (any number of columns, each a
/// quantity over the samples), in the order the samples were given. Empty when `field` is not a
/// vector kriging field or its samples were merged.
Eigen::MatrixXd leave_one_out_residuals_of(const ErrorField& field, const Eigen::MatrixXd& values);

/// The variogram model of a vector kriging field over joint space (per component, the calibrated one
/// where the field's variance was calibrated); none for any other field.
std::optional<VariogramModel> joint_space_vector_field_model(const ErrorField& field);

/// The variogram model the fields estimate when none is given: empirical variogram of the values
/// over the samples' lags (10 bins up to 60% of the largest lag) and the best-fitting of sph/exp/gau
/// with a free nugget. `values` is N x K (K = 1 or 3). The model is that of one component (the
/// empirical gamma, a sum over the K components, is divided by K before the fit), as the fields and
/// the likelihood fit use it: a vector field's sill and nugget are per component.
VariogramModel estimate_field_variogram(const FieldSamples& samples, const Eigen::MatrixXd& values, FieldSpace space,
                                        const std::optional<FieldModelFamily>& family = std::nullopt);

/// The model a field uses when none is given, and why: choose_likelihood_model (REML with the
/// field's kriging kind; sph/exp/gau/mat(1.5, 2.5) with a nugget, isotropic or ARD over the six
/// joints in joint space or over x, y, z in task space, smallest AIC among well-conditioned fits)
/// at any N: the choice on a subset of 300, the refit on all samples by the Vecchia likelihood
/// beyond kExactLikelihoodMaxSamples (issue 23; before, beyond 3,000 samples,
/// estimate_field_variogram without a nugget or ARD). (Task space used
/// estimate_field_variogram until issue 19: it fitted no nugget on the paper's grid and claimed
/// too small a variance.)
VariogramModel choose_field_model(const FieldSamples& samples, const Eigen::MatrixXd& values,
                                  const KrigingFieldOptions& options, std::string& reason);

/// The field's variogram model for people: sill and nugget (mm², per component for vector fields) and, for each
/// bounded structure, the lag at which it reaches 95 % of its partial sill along each coordinate
/// (x, y, z in mm in task space; q1..q6 in deg in joint space; ARD multipliers applied), e.g.
/// "sill 0.0021 mm², nugget 4.1e-05 mm²; gau reaches 95 % of its sill at q1 4.33e+05,
/// q2 186, ... deg". A range far beyond the joint's travel means no decay along that joint.
std::string describe_field_model(const VariogramModel& model, FieldSpace space);

/// Reads a kriging field from JSON (called by error_field_from_json for kinds "distance-kriging" and
/// "vector-kriging"); nullptr for another kind.
std::shared_ptr<const ErrorField> kriging_field_from_json(const nlohmann::json& j, const std::string& source);

}  // namespace errfield::compensation
