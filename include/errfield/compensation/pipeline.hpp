#pragma once
/// @file
/// The steps fit, predict, compensate and validate as `errfield fit/predict/compensate/validate`
/// run them on a table, without files or printing: the CLI and the Python module both call these,
/// so a model or an output column is the same whichever front end made it. Use them when your
/// measurements are a table (CsvTable) and you want the CLI's checks and output columns; use
/// model_fitting.hpp, prediction.hpp and compensation.hpp directly for finer control.

#include <cstddef>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "errfield/compensation/fitting/model_fitting.hpp"
#include "errfield/compensation/validation/validation.hpp"
#include "errfield/csv_table.hpp"
#include "errfield/robot/arm_configuration.hpp"
#include "errfield/robot/input_checks.hpp"
#include "errfield/robot/mdh_model.hpp"

namespace errfield::compensation {

/// One output column: numbers (NaN = an empty cell) or, when `text`, words (status).
struct OutputColumn {
  std::string name;
  std::vector<double> numbers;
  std::vector<std::string> words;
  /// Says the kind even when the column has no rows (a 0-row prediction still has float columns).
  bool text = false;
  bool is_words() const { return text; }
};

/// The columns a step adds to its input table, in the CLI's order, and the rows it refused (no
/// position or joints given for them: their numeric cells are NaN).
struct StepColumns {
  std::vector<OutputColumn> columns;
  std::size_t refused = 0;
  /// compensate: rows whose field gave no finite number (status no-prediction).
  std::size_t no_prediction = 0;
  /// compensate: the ceiling on move_mm that was applied (mm), and the rows refused for it
  /// (status correction-too-large).
  double max_correction_mm = 0.0;
  std::size_t too_large = 0;
  /// compensate: where each row's arm configuration came from (the config_source column's words,
  /// kConfigSource*), and how many rows each, in order of first appearance.
  std::vector<std::pair<std::string, std::size_t>> config_sources;
  /// compensate: rows refused because the compensated joints swing far more than the correction
  /// warrants (a singular configuration; status wrist-singular, elbow-singular, shoulder-singular or
  /// near-singular).
  std::size_t singular = 0;
  /// compensate: the largest move_mm among the rows compensated (status ok; 0 when none): what the
  /// ceiling above allowed and what the joints actually did are two numbers.
  double largest_move_mm = 0.0;
};

/// compensate's config_source words: the configuration a row is held to came from its seed joints
/// (sq1..sq6, or --seed), from the given nominal joints (joint targets), from the training sample
/// nearest the pose (the pose path's start), from `compensate --config`, or from nowhere (a model
/// without training joints and no seed: multistart, any configuration).
inline constexpr const char* kConfigSourceSeed = "seed";
inline constexpr const char* kConfigSourceGiven = "given";
inline constexpr const char* kConfigSourceNearestTraining = "nearest-training";
inline constexpr const char* kConfigSourcePinned = "config-option";
inline constexpr const char* kConfigSourceNone = "none";

/// A compensated row is refused as singular when some joint changes by more than
/// max(kSingularSwingFloorDeg, kSingularSwingDegPerMm x move_mm) from the nominal joints. Away from
/// singularities a correction of d mm with the orientation kept turns each joint by about d / reach
/// (0.1-0.5 deg for 4 mm on an industrial arm); 2.865 deg per mm is the turn of a 20 mm lever, shorter
/// than any link, so only a Jacobian near rank loss gets there (at q5 = 1e-7 a 4 mm correction
/// swung q4 and q6 by 49.5 deg, issue 35). The floor keeps tiny corrections from tripping it by
/// the solver's rounding.
inline constexpr double kSingularSwingDegPerMm = 2.865;
inline constexpr double kSingularSwingFloorDeg = 2.0;

/// `compensate --max-correction` by default: this many times the largest total correction the model
/// predicts at its own training poses (CompensationModel::largest_training_correction_mm) ...
inline constexpr double kMaxCorrectionFactor = 3.0;
/// ... and never below this (mm): a model fitted on a very accurate robot still corrects by up to 1 mm,
/// but not by the tens of mm of a wrong tool or robot.
inline constexpr double kMaxCorrectionFloorMm = 1.0;
/// The default ceiling for `model`: max(kMaxCorrectionFactor x largest training correction,
/// kMaxCorrectionFloorMm), on the robot the model was fitted with. Models without training joints
/// (files written before they were stored) get the floor.
double default_max_correction_mm(const CompensationModel& model);

/// The options of `errfield fit` as words (the CLI's spelling; Python passes the same words).
struct FitOptionText {
  /// auto (choose_method from the data) | distance-idw | position-idw | distance-kriging |
  /// vector-kriging | kinematic | kinematic+kriging
  std::string method = "auto";
  std::string space = "auto";           ///< auto (= joint) | task | joint
  double power = 1.0;                   ///< IDW power
  std::string model;                    ///< variogram model text or JSON file; "" or "auto": chosen
  std::string kind = "ordinary";        ///< ordinary | universal1 | universal2
  std::size_t base = 0;
  std::optional<double> region_margin;  ///< empty: FitOptions' default (5 deg joint, 0 mm task)
  std::string calibration;              ///< "" (automatic) | position | distance
  std::string robust;                   ///< "" or none | igg3
  double max_condition = 1e3;
  double outlier_limit = 5.0;           ///< FitOptions::outlier_limit (0 = off)
  std::string variance_calibration;     ///< "" or auto | loo | none (FitOptions::variance_calibration)
};

/// The FitOptions the words select, validated; ArgumentError naming the option (CLI spelling).
FitOptions fit_options_from_text(const FitOptionText& text);

/// What `errfield fit` checks besides FitOptions.
struct FitTableOptions {
  FitOptions fit;
  std::vector<Eigen::Vector3d> fixed_bases;  ///< --base-point: base points b0, b1, ... (robot frame, mm)
  bool robot_given = false;                  ///< for check_nominal_positions' message
  double max_registration_rms_mm = robot::kRegistrationRmsLimitMm;
  /// Called once the table has been read as measurements, before any fitting or registration
  /// check (the CLI warns here about values that look like metres); empty = nothing.
  std::function<void()> on_measurements_read;
};

/// Data must fit the robot: the checks every command that reads measurements with a robot or model
/// runs (fit, calibrate, validate, predict, compensate), one implementation - nominal x,y,z against
/// the FK of q1..q6 (robot::check_nominal_positions, 5 mm) and the registration of the tracker
/// readings mx,my,mz with a reflector offset (robot::check_tracker_registration, limit
/// `max_registration_rms_mm`). Reads only the columns `table` has (rows with an empty mx cell are
/// skipped); nothing happens without q1..q6. Throws InputError naming the file and the likely cause.
void check_table_fits_robot(const CsvTable& table, const robot::MdhModel& robot, const robot::RobotOrigin& origin,
                            double max_registration_rms_mm = robot::kRegistrationRmsLimitMm);

/// A fit and the number of measured points (targets, not base rows) it was made from.
struct TableFit {
  FitResult result;
  std::size_t points = 0;
};

/// `errfield fit` on a measurement table (the columns of `errfield simulate`): the input checks of
/// robot/input_checks.hpp, the registration residual before and after the fit, then
/// fit_compensation_model. Throws InputError naming table.source() as the CLI does.
TableFit fit_table(const robot::MdhModel& robot, const CsvTable& table, const FitTableOptions& options);

/// `errfield predict`: columns px,py,pz (robot frame), tx,ty,tz (tracker frame; only with a stored
/// registration), var_mm2 (variance of a new reading: field + nugget) and var_field_mm2 (field only)
/// when some row has a variance, r95_mm (radius around the predicted point holding a new reading
/// with 95 %, error_ball.hpp; vector fields) when some row has one, status; one row per joint vector.
/// `extrapolate`: rows outside the model's region are answered with status extrapolated
/// (predict_position's extrapolate) instead of refused.
StepColumns predict_columns(const CompensationModel& model, std::span<const robot::JointVector> q_deg, bool extrapolate = false);

/// Targets of `errfield compensate`: nominal joints q1..q6 (deg), or poses x,y,z,rx,ry,rz (mm, deg)
/// solved on the training joints' branch (or from `seed`).
struct CompensationTargets {
  std::vector<robot::JointVector> joints_deg;  ///< set: joint targets
  Eigen::MatrixXd poses;                       ///< else N x 6 poses
  std::optional<robot::JointVector> seed_deg;
  /// Pose targets: per-row seed joints (sq1..sq6, e.g. the taught positions), solved from and kept
  /// on their arm configuration; empty = none, a row with a NaN = none for that row (then seed_deg or
  /// the nearest training sample).
  std::vector<robot::JointVector> seed_rows_deg;
  /// `compensate --config`: every row is held to this arm configuration. Pose targets are solved
  /// from the nearest training sample on it (or their seed, which must be on it); a row whose
  /// nominal or compensated joints are on another is refused (config-change).
  std::optional<robot::ArmConfiguration> config;
};

/// The frame pose targets are given in (`compensate --frame`, Python `frame=`): the robot base frame
/// of the model's nominal robot (the frame its registration maps tracker readings into, and the one
/// compensate_columns takes), or the tracker frame (a part or fixture measured with the tracker).
enum class TargetFrame { robot, tracker };
/// "robot" or "tracker"; anything else is an ArgumentError naming `option` and the value.
TargetFrame parse_target_frame(const std::string& word, const std::string& option);
/// Brings `targets` into the robot base frame: nothing for TargetFrame::robot; for tracker, every
/// pose is mapped with the model's registration (poses_in_robot_frame, registration.hpp). Throws
/// ArgumentError naming `option` for joint targets (they have no frame; `targets_name` says whose) and
/// for a model without a registration (fitted without tracker positions; `model_name` says which).
void bring_targets_to_robot_frame(CompensationTargets& targets, const CompensationModel& model, TargetFrame frame,
                                  const std::string& option, const std::string& targets_name, const std::string& model_name);

/// Seeds must be joints the robot can take: --seed (`targets.seed_deg`) and every per-row seed
/// within `nominal`'s joint limits (a NaN row is "no seed"). Throws ArgumentError naming --seed, or
/// InputError naming `table`'s file, line (without a table: "seed row N", 1-based), column sq<k>
/// and the value (exit 2 in the CLI): a seed
/// outside the limits gave odd statuses (unreachable, branch-change) rather than saying the seed
/// was wrong. Also checks that seeds are on `targets.config` where one is pinned.
void check_seed_joints(const CompensationTargets& targets, const robot::MdhModel& nominal,
                       const CsvTable* table = nullptr);

/// Joint input in radians read as degrees lies within +-3.2 "deg", inside any training box, and
/// passes every other check. Throws InputError naming `source` when the joints look like radians
/// against the model's training joints (data_joints): every value of `q_deg` is within +-2 pi, at
/// least kRadiansSuspectJoints joints spread (standard deviation) over at least
/// kRadiansSuspectTrainingSpreadDeg in training, and on each of those the input spreads over less
/// than a tenth of the training's. Models without training joints (older files) are not checked.
void check_joints_not_radians(std::span<const robot::JointVector> q_deg, const CompensationModel& model,
                              const std::string& source, const std::string& override_option);
inline constexpr int kRadiansSuspectJoints = 3;
inline constexpr double kRadiansSuspectTrainingSpreadDeg = 10.0;

/// `validate` on a file of several points on the flange (a `reflector` column): the rows of one
/// label (`asked`, default the model's own point), with `model` moved to that label's located point
/// (a working tool) when it is a further point the model located; the file itself when it has one
/// label or none, except that a file whose every row carries the label of a further located point
/// is scored at that point without `asked` (unless `tool_given`). InputError naming the file for a label without rows, a label the model did not
/// locate, or several labels for a one-point model; ArgumentError when `tool_given` and the label is
/// a further point. `option_prefix` ("--" on the command line, "" in Python) names the options.
CsvTable rows_of_one_reflector(const CsvTable& file, const std::string& asked, bool tool_given, CompensationModel& model,
                               const std::string& option_prefix);

/// `validate` on readings of another point than the model's tool point (another reflector, another
/// tool): the free reflector offset the registration check fits hides it, and validate scored 150 mm
/// "after" errors with exit 0. Registers `measured_mm` at `q_deg` onto the model's command model with
/// a free reflector offset (robot::register_tracker) and throws InputError naming `source` and the
/// distance when that offset lies more than `limit_mm` from the command model's tool (the point the
/// model was fitted for) AND the model's stored registration leaves those readings more than
/// `limit_mm` RMS from the command model's FK (so a weakly determined offset on data of the same
/// point never trips it). Nothing without a stored registration or with fewer than 6 readings.
void check_readings_of_tool_point(const CompensationModel& model, std::span<const robot::JointVector> q_deg,
                                  std::span<const Eigen::Vector3d> measured_mm, const std::string& source,
                                  double limit_mm);
/// check_readings_of_tool_point's default limit (mm): a free offset fitted to readings of the same
/// point lands within ~1 mm of it on robots with mm-level errors.
inline constexpr double kToolPointShiftLimitMm = 5.0;

/// The per-row seed joints of pose targets, columns sq1..sq6 (deg), as CompensationTargets::seed_rows_deg
/// holds them: empty when `table` has no sq1 column; a row whose six cells are all empty is NaN (no seed
/// for that row); a row with some cells empty is an InputError naming the row and column.
std::vector<robot::JointVector> seed_rows_of(const CsvTable& table);

/// `errfield compensate`: columns nq1..nq6, nx,ny,nz, pred_dx..dz, pred_dl, var_mm2 (new reading:
/// field + nugget), p_inside (CompensatedTarget::p_within_tolerance), cmd_x..z, cq1..cq6,
/// var_field_mm2 (field only), r95_mm (vector fields), total_dx..dz and total_mm (the whole predicted
/// error of the tool point, calibration + field), move_mm (how far the compensated joints move the
/// tool point), nconfig and config (robot/arm_configuration.hpp: of the nominal and of the
/// compensated joints), config_source (where the configuration the row is held to came from,
/// kConfigSource*), status. `tolerance_mm` > 0 (ArgumentError otherwise). A refused target (unreachable,
/// branch-change, config-change: the nominal or compensated joints on another arm configuration than
/// the row's seed, --seed, --config, the training sample a pose target was solved from, or given
/// nominal joints, outside-region, not-credible, no-prediction, ik-*, correction-too-large: move_mm
/// above `max_correction_mm`; 0 = default_max_correction_mm; wrist-singular, elbow-singular,
/// shoulder-singular, near-singular: a joint swings more than kSingularSwingDegPerMm x move_mm) has
/// no joints. Throws ArgumentError when `targets.config` is set and no training sample is on it
/// for a pose target without a seed.
StepColumns compensate_columns(const CompensationModel& model, const robot::MdhModel& nominal,
                               const CompensationTargets& targets, double tolerance_mm, double max_correction_mm = 0.0);

/// The per-point columns of `errfield validate --out`: point, status, before_mm, after_mm,
/// before_dx..dz, after_dx..dz, before_dl_bK / after_dl_bK; then, for models with a variance,
/// var_mm2 and var_field_mm2, and where 3-D errors were scored against one, r95_mm and nees.
StepColumns validation_point_columns(const ValidationReport& report);

}  // namespace errfield::compensation
