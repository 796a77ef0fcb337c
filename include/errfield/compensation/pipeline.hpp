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
#include <vector>

#include <Eigen/Core>

#include "errfield/compensation/model_fitting.hpp"
#include "errfield/compensation/validation.hpp"
#include "errfield/csv_table.hpp"
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
};

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
/// registration), var_mm2 (only when some row has a variance), status, one row per joint vector.
StepColumns predict_columns(const CompensationModel& model, std::span<const robot::JointVector> q_deg);

/// Targets of `errfield compensate`: nominal joints q1..q6 (deg), or poses x,y,z,rx,ry,rz (mm, deg)
/// solved on the training joints' branch (or from `seed`).
struct CompensationTargets {
  std::vector<robot::JointVector> joints_deg;  ///< set: joint targets
  Eigen::MatrixXd poses;                       ///< else N x 6 poses
  std::optional<robot::JointVector> seed_deg;
};

/// `errfield compensate`: columns nq1..nq6, nx,ny,nz, pred_dx..dz, pred_dl, var_mm2, p_inside,
/// cmd_x..z, cq1..cq6, status. `tolerance_mm` > 0 (ArgumentError otherwise). A refused target
/// (unreachable, branch-change, outside-region, not-credible, no-prediction, ik-*) has no joints.
StepColumns compensate_columns(const CompensationModel& model, const robot::MdhModel& nominal,
                               const CompensationTargets& targets, double tolerance_mm);

/// The per-point columns of `errfield validate --out`: point, status, before_mm, after_mm,
/// before_dx..dz, after_dx..dz, before_dl_bK / after_dl_bK.
StepColumns validation_point_columns(const ValidationReport& report);

}  // namespace errfield::compensation
