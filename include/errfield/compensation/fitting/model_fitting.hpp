#pragma once
/// Step 3 of the pipeline (plan → measure → fit → compensate): build a CompensationModel from a
/// user's measurements. Use `MeasurementSet::from_table` on the CSV a measurement produced (the
/// columns of `errfield simulate`, docs/data-formats.md) and `fit_compensation_model` with the
/// method of your choice; the result carries a cross-validation summary to judge it by.
///
/// Frames: nominal positions in the robot base frame; measured positions in the tracker frame
/// (a rigid registration fitted here maps them to the robot frame); distances are frame-free.

#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "errfield/csv_table.hpp"
#include "errfield/compensation/model/compensation.hpp"
#include "errfield/compensation/model/joint_error_functions.hpp"
#include "errfield/compensation/model/kriging_fields.hpp"
#include "errfield/robot/calibration.hpp"

namespace errfield::compensation {

/// What was measured, in memory.
struct MeasurementSet {
  std::string source;                     ///< file name, for messages
  std::vector<std::string> id;            ///< point names (targets)
  std::vector<robot::JointVector> q_deg;         ///< commanded joints of the targets
  std::vector<Eigen::Vector3d> nominal_mm;  ///< nominal positions (robot frame)
  std::vector<Eigen::Vector3d> measured_mm; ///< tracker readings (tracker frame); empty if none
  std::vector<Eigen::Vector3d> base_nominal_mm;  ///< base points bK (robot frame)
  std::vector<robot::JointVector> base_q_deg;  ///< joints of base rows (robot-position bases); empty for fixed bases
  /// distance[k][i]: measured distance from base point k to target i (mm); empty if none.
  std::vector<std::vector<double>> distance_mm;
  /// Which point on the flange each target row reads (column `reflector`, any label; the pair
  /// (point, reflector) names a row); empty without the column.
  std::vector<std::string> reflector;

  /// The distinct `reflector` labels in the order they first appear (empty without the column).
  std::vector<std::string> reflector_labels() const;

  /// Reads the columns of `errfield simulate`: point, kind (base|target; absent = all targets),
  /// q1..q6 (deg), x,y,z (nominal, mm; absent = FK of `robot`), mx,my,mz (tracker, mm; optional),
  /// dist_b0, dist_b1, ... (mm; optional). A base row's nominal position is its base point; without
  /// base rows, `fixed_bases` give the base points of dist_b0.. (fixed points, robot frame).
  /// Throws InputError naming file, line and column.
  /// A `reflector` column with several labels (readings of several points on the flange) is refused
  /// unless `several_points` (fit's kinematic methods take them); rows of one pose (`point`) must
  /// then share their joints.
  static MeasurementSet from_table(const CsvTable& table, const robot::MdhModel& robot,
                                   const std::vector<Eigen::Vector3d>& fixed_bases = {}, bool several_points = false);

  /// Distance errors to base k: dist_bk − |P − B_k| (mm). Throws InputError if absent.
  std::vector<double> distance_errors(std::size_t k) const;
};

// Registration and fit_registration (robot ← tracker, the frame in which measured positions become
// position errors; fit stores it in the model it writes): compensation/model/registration.hpp.

// kReflectorAtToolMm (reflector and tool point as one point) is the model's: compensation.hpp.
/// Further apart than this (mm) the robot JSON's tool must be the wrong one (a second reflector nest,
/// a tool-less robot JSON): fit refuses unless FitOptions::reflector_far_ok.
inline constexpr double kReflectorFarMm = 50.0;

/// What the kinematic methods calibrate from.
enum class CalibrationData {
  automatic,  ///< positions when the data have them (mx,my,mz), else distances
  position,   ///< tracker positions: registration (with the reflector offset), then the model
  distance,   ///< distances to a base point (dist_bK): frame-free
};
/// "position" / "distance" (CLI `--calibration`); throws ArgumentError naming the option otherwise.
CalibrationData calibration_data_from_name(std::string_view name);

/// Whether the kriging methods calibrate the predictive variance by leave-one-out
/// (VarianceCalibration, kriging_fields.hpp: every sill × the mean leave-one-out z², predicted errors
/// unchanged).
enum class VarianceCalibrationChoice {
  automatic,      ///< when the variogram is estimated; a model the user gives is kept as given
  leave_one_out,  ///< always, also a given model
  none,           ///< never: the variance is the model's as estimated or given
};
/// "auto" / "loo" / "none" (CLI `--variance-calibration`); throws ArgumentError otherwise.
VarianceCalibrationChoice variance_calibration_from_name(std::string_view name);

/// FitOptions::joint_function_degree's default: the degree from the number of poses. Real robots'
/// joint errors vary faster with the angle than the simulator's: on every real laser-tracker set
/// here (UR5 700 and 1,000 poses, UR10 1,046 and 1,941) degree 12 beat 8 on held-out poses (mean
/// -4 to -12 %, RMS -5 to -12 %), while on SIMULATED sets of 40-240 poses it lost up to 40 % (80
/// poses) and gained only where the simulator injects cyclic errors; simulated pools of 687 poses
/// favoured 10-12 (docs/robot.md, "Joint error functions"; docs/realdata.md). Degrees 16-20 gained
/// more on some real sets and oscillated at the ends of a joint's range on another (0.11 -> 2.1 mm at
/// a UR10 B pose at the edge): not the default.
inline constexpr int kJointFunctionDegreeByPoses = -1;
inline constexpr int kJointFunctionDegreeFewPoses = 8;
inline constexpr int kJointFunctionDegreeManyPoses = 12;
inline constexpr std::size_t kJointFunctionManyPoses = 500;

struct FitOptions {
  CompensationMethod method = CompensationMethod::distance_idw;
  /// Use choose_method(data) instead of `method` (`fit --method auto`, the CLI's default).
  bool choose_method = false;
  FieldSpace space = FieldSpace::task;  ///< kriging methods only
  double idw_power = 1.0;               ///< IDW methods (the paper: 1)
  std::optional<VariogramModel> model;  ///< kriging; empty = chosen (choose_field_model)
  /// kriging, `model` empty: estimate within this family (`--model mat`); empty = the automatic choice.
  std::optional<FieldModelFamily> model_family;
  KrigingKind kind = KrigingKind::Ordinary;  ///< kriging methods: ordinary or universal
  int drift_order = 1;                       ///< universal kriging: polynomial drift order
  std::size_t base = 0;                 ///< which base point the distance methods use
  /// Kriging fields: how far beyond the samples' box a target is still predicted — mm in task
  /// space, degrees per joint in joint space (the box is then that of the samples' joints). Empty:
  /// 5 deg in joint space, 0 mm in task space. Why 5 deg: on SIMULATED held-out poses (KR 16, UR5e,
  /// paper set-up; docs/robot.md) it accepted the 1-4 of 100-150 held-out targets that fell just
  /// outside the training joints' box with no change in held-out RMS or maximum; the credibility
  /// check still refuses predictions beyond the fitted errors' range.
  std::optional<double> region_margin;
  /// kinematic methods: positions or distances, and the calibration's options (robust weights,
  /// condition number cap).
  CalibrationData calibration_data = CalibrationData::automatic;
  robot::CalibrationOptions calibration;
  /// Kinematic methods calibrated from positions: gross outliers — a tracker that lost the
  /// reflector, a wrong row — are excluded and the model fitted again without them (repeated until
  /// no new row is flagged, at most 3 times; noted and warned, every row listed). A row is flagged
  /// when u = s / (√3 σ0) is above this, σ0 = median s / 1.5382 (the robust scale of IGG3 for 3-D
  /// residuals), where s is the row's held-out residual against a kinematic+kriging field
  /// (leave-one-out; the field's prediction for a row already excluded) divided by its predictive σ
  /// per component (nugget included) — a reading its neighbours contradict. For kinematic+kriging
  /// that field is the model's own (a field without per-row leave-one-out screens nothing); for
  /// kinematic it is a joint-space one fitted with the same options to the same rows only to judge
  /// them, when `model` gives its variogram — without, kinematic screens nothing (estimating one
  /// multiplied the fit's time by 10-30). Judging by the calibration residual dropped real robot
  /// behaviour at the workspace extremes (issues 19 and 35: the same 11 real rows on three
  /// reflectors, held-out maximum doubled), so it is never used. 0 keeps
  /// every row. At most a fifth of the rows is excluded: more is not "a few gross outliers" and is
  /// only warned about. Why on at 5: on SIMULATED KR 16 sets with realistic systematic effects and
  /// 2 % × 3 mm outliers it dropped exactly the outliers and matched the oracle (docs/robot.md,
  /// "Gross outliers in fit").
  double outlier_limit = 5.0;
  /// kinematic+kriging: before the field, fit per-joint angle-error functions of this Legendre degree
  /// to the calibration's residuals (joint_error_functions.hpp) and krige what they leave; 0 = none;
  /// kJointFunctionDegreeByPoses (the default): joint_function_degree_for(poses).
  /// Why 8 below 500 poses: on SIMULATED held-out sets (KR 16 with realistic systematic effects, 40-240 poses from
  /// random, maximin and adaptive designs; KR 16 with compliance only, with outliers, with rigid
  /// joints; UR5e; ER20-C10) it lowered the held-out RMS by a third from 80 poses on, by 12 % at 40,
  /// never raised it by more than 7 % (one set of 40 poses) and kept the 95 % coverage; degrees 10-12
  /// gained more on some sets and lost on others (docs/robot.md, "Joint error functions").
  int joint_function_degree = kJointFunctionDegreeByPoses;
  /// The degree a fit on `poses` poses uses: joint_function_degree, or by the number of poses.
  int joint_function_degree_for(std::size_t poses) const;
  /// With the joint error functions: also the gravity-load terms (joint_error_functions.hpp), each
  /// joint's deflection under the weight of the arm beyond it, which depends on several joints.
  /// Why on: on SIMULATED KR 16 with realistic effects they took 7-18 % off the held-out RMS at
  /// 40-687 poses (9 % to 18 % with the link masses off the frame origins' lines, which they cannot
  /// express exactly); they cost up to 2 % on arms whose weight matters little (ER20-C10's stiff
  /// config, UR5e) (docs/robot.md, "Gravity-load terms").
  bool gravity_load = true;
  /// With the joint error functions: the physical prior on their coefficients and the gravity terms
  /// (JointFunctionPrior: why its sizes); an infinite sd leaves that group to the ridge alone.
  JointFunctionPrior joint_function_prior;
  /// With the joint error functions: after their ordinary fit they are refitted by generalized least
  /// squares under the field's covariance. A positive value drops that refit when it leaves the field
  /// more than this multiple of the ordinary fit's RMS; 0 (the default) always keeps it. Why 0: the
  /// guard (1.5, commit 7825b87) was chosen on SIMULATED KR 16 sets and an argument about one real log
  /// line; on the real laser-tracker data (docs/realdata.md) keeping the refit was better at every
  /// measured and every located point, by 11-20 % on a three-reflector IRB 120 (issue 45).
  double gls_guard_ratio = 0.0;
  /// Kriging methods: calibrate the predictive variance by leave-one-out (the variance the model
  /// states for a held-out reading, var_mm2 and r95_mm; docs/robot.md "Predictive uncertainty").
  VarianceCalibrationChoice variance_calibration = VarianceCalibrationChoice::automatic;
  /// Kinematic methods from positions: the reflector (the measured point, found from the data) and
  /// the robot's tool point (the robot JSON's tool, the point compensated) are two points. Further
  /// apart than kReflectorFarMm is refused as a wrong tool (InputError) unless this is set.
  bool reflector_far_ok = false;
  /// Data of several points on the flange (a `reflector` column): the label whose readings are the
  /// model's own point (the field's samples; the robot JSON's tool stays the point compensated).
  /// Empty: the label the data locate nearest the robot JSON's tool point.
  std::string tool_reflector;
  /// Called before each long stage (variogram, factorization, leave-one-out, calibration) with what
  /// it is about to do, for progress output; empty = silent.
  std::function<void(const std::string& stage)> on_stage;
  void validate() const;
};

/// Leave-one-out cross-validation of the fitted field on its own samples (mm).
struct CrossValidationReport {
  std::string method;  ///< how it was done (e.g. "leave-one-out, ordinary kriging")
  std::size_t samples = 0;
  double mean_abs_mm = 0, rms_mm = 0, max_abs_mm = 0;
  std::optional<double> mean_squared_z;  ///< kriging: ~1 when the variance is calibrated
  /// Kriging: the variogram model and how its system factored — what fit_compensation_model's
  /// credibility check judges (and refits with a nugget when it fails).
  std::optional<VariogramModel> variogram;
  std::optional<KrigingReport> factorization;
};

struct FitResult {
  CompensationModel model;
  std::optional<Registration> registration;  ///< when measured positions were used
  std::optional<CrossValidationReport> cross_validation;
  std::vector<std::string> notes;  ///< what was used and why
  /// What the user should act on: an ill-conditioned kriging system, a calibration whose robust
  /// weights did not settle. The model is still written; the CLI prints these to stderr.
  std::vector<std::string> warnings;
};

/// The method and field space a user gets without choosing (the CLI's `fit --method auto`, its
/// default), from what the data hold, and why (one sentence for the console and the model's notes).
/// Chosen by held-out 3-D / distance RMS on SIMULATED data (docs/robot.md, "Which method"):
///   - tracker positions (mx,my,mz): kinematic+kriging, the residuals kriged in joint space. Best on
///     every set measured: scattered poses of the KR 16 and the UR5e with varying orientation,
///     rounded joints and an unknown reflector offset, and the paper's 125 mm grid (where it beats
///     the paper's distance-idw 18x in 3-D and 7x on distances);
///   - distances only: kinematic, calibrated from the distances. Distance-kriging in joint space is
///     3x better on the paper's grid at constant orientation but 3x worse on scattered poses with
///     varying orientation; the calibration is good on both.
/// Throws InputError (naming the columns) when the data have neither.
struct MethodChoice {
  CompensationMethod method;
  FieldSpace space;
  std::string reason;
};
MethodChoice choose_method(const MeasurementSet& data);

/// Builds the model. Throws InputError when the data have not what the method needs (names the
/// columns). kinematic, from positions (the default when the data have mx,my,mz):
/// register_tracker (tracker ← robot base and the reflector offset) then calibrate_positions; the
/// identified model is expressed in the robot frame and `registration` holds robot ← tracker. From
/// distances: calibrate_distances on the distances to base point `base` (a base row's robot
/// position) or to every fixed point. kinematic+kriging: that, then vector kriging of the 3-D
/// residuals (measured positions mapped through the calibration's registration, or for distance
/// calibration a registration fitted to the identified model).
/// The model carries what later steps need: the registration of the training rows' tracker
/// readings (when the data have mx,my,mz) onto the model's own predictions, the nominal robot, the
/// training joints and the range of the fitted errors (compensation.hpp). No silent wrong model: a
/// kriging system beyond the condition limit (KrigingOptions, 1e12) or a leave-one-out error beyond
/// what any credible prediction could give (3 × the data's largest deviation from their mean) is
/// refitted with a nugget when the variogram was estimated (1e-4, 1e-3, 1e-2, 1e-1 of the sill, the
/// first that passes; noted), and refused with an Error naming the figures when the user gave the
/// model or no nugget helps.
FitResult fit_compensation_model(const robot::MdhModel& robot, const MeasurementSet& data, const FitOptions& options);

}  // namespace errfield::compensation
