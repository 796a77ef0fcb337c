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
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "errfield/csv_table.hpp"
#include "errfield/robot/compensation.hpp"
#include "errfield/robot/kriging_fields.hpp"

namespace errfield::robot {

/// What was measured, in memory.
struct MeasurementSet {
  std::string source;                     ///< file name, for messages
  std::vector<std::string> id;            ///< point names (targets)
  std::vector<JointVector> q_deg;         ///< commanded joints of the targets
  std::vector<Eigen::Vector3d> nominal_mm;  ///< nominal positions (robot frame)
  std::vector<Eigen::Vector3d> measured_mm; ///< tracker readings (tracker frame); empty if none
  std::vector<Eigen::Vector3d> base_nominal_mm;  ///< base points bK (robot frame)
  std::vector<JointVector> base_q_deg;  ///< joints of base rows (robot-position bases); empty for fixed bases
  /// distance[k][i]: measured distance from base point k to target i (mm); empty if none.
  std::vector<std::vector<double>> distance_mm;

  /// Reads the columns of `errfield simulate`: point, kind (base|target; absent = all targets),
  /// q1..q6 (deg), x,y,z (nominal, mm; absent = FK of `robot`), mx,my,mz (tracker, mm; optional),
  /// dist_b0, dist_b1, ... (mm; optional). A base row's nominal position is its base point; without
  /// base rows, `fixed_bases` give the base points of dist_b0.. (fixed points, robot frame).
  /// Throws InputError naming file, line and column.
  static MeasurementSet from_table(const CsvTable& table, const MdhModel& robot,
                                   const std::vector<Eigen::Vector3d>& fixed_bases = {});

  /// Distance errors to base k: dist_bk − |P − B_k| (mm). Throws InputError if absent.
  std::vector<double> distance_errors(std::size_t k) const;
};

/// Rigid registration robot ← tracker by least squares over point pairs (Horn's closed form via
/// SVD): the frame in which measured positions become position errors. 6 parameters; the residual
/// RMS (mm) says how well the rigid model fits (it absorbs the rigid part of the robot's error).
struct Registration {
  Eigen::Isometry3d robot_from_tracker = Eigen::Isometry3d::Identity();
  double residual_rms_mm = 0.0;
};
Registration fit_registration(const std::vector<Eigen::Vector3d>& tracker_mm,
                              const std::vector<Eigen::Vector3d>& robot_mm);

struct FitOptions {
  CompensationMethod method = CompensationMethod::distance_idw;
  FieldSpace space = FieldSpace::task;  ///< kriging methods only
  double idw_power = 1.0;               ///< IDW methods (the paper: 1)
  std::optional<VariogramModel> model;  ///< kriging; empty = chosen (choose_field_model)
  KrigingKind kind = KrigingKind::Ordinary;  ///< kriging methods: ordinary or universal
  int drift_order = 1;                       ///< universal kriging: polynomial drift order
  std::size_t base = 0;                 ///< which base point the distance methods use
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

/// Builds the model. Throws InputError when the data lack what the method needs (names the
/// columns). kinematic: calibrate_distances on the distances to base point `base` (a robot
/// position, i.e. a base row with joints); kinematic+kriging: that, then vector kriging of the 3-D
/// residuals (measured positions registered to the identified model).
FitResult fit_compensation_model(const MdhModel& robot, const MeasurementSet& data, const FitOptions& options);

}  // namespace errfield::robot
