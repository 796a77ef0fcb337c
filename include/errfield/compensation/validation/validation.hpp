#pragma once
/// Scoring a model on measurements it was not fitted on (`errfield validate`).
///
/// Prediction mode (validate_predictions): at each held-out row's commanded joints the model
/// predicts where the tool point is (prediction.hpp); the measurement is mapped into the robot frame
/// through the model's own stored registration — never re-registered on the held-out rows, which
/// would absorb part of the error being scored. "after" is the model's prediction; "before" the
/// nominal robot's FK (no compensation) with the nominal robot's own registration, as `fit --method
/// none` stores it (the model's "nominal_registration"): a calibrated model's registration would
/// put the nominal robot in a frame that is not its best (on real data 1.23 mm instead of 0.66).
/// Model files without it: non-kinematic models use their stored registration (fitted on the
/// nominal robot); kinematic ones and robot JSONs register the nominal robot on the held-out rows
/// themselves (noted). error = measured − predicted. Distances to base points (dist_bK) are scored
/// frame-free: measured − predicted distance.
///
/// Predictive uncertainty (models with a variance): per point the variance of a new reading
/// (field + nugget), its field part, for vector fields the 95 % radius r95 (error_ball.hpp) and
/// NEES = sum over the axes of e_i² / var_i (3 expected); the summary gives the share of points
/// within r95 (coverage95, 0.95 expected) and the mean NEES.
///
/// Targets mode (validate_targets): the validation run on the robot after compensation. Rows were
/// commanded with compensated joints (run = after) — and optionally the same targets with nominal
/// joints (run = before) — and carry the intended target position; error = measured − target.
///
/// Statistics are of the error magnitudes (3-D norm, |distance error|) over the points that were
/// not refused, before and after over the same points: count, mean, max, RMS and the 95th
/// percentile (linear interpolation between order statistics, numpy's default).

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json_fwd.hpp>

#include "errfield/csv_table.hpp"
#include "errfield/compensation/model/compensation.hpp"
#include "errfield/compensation/fitting/model_fitting.hpp"

namespace errfield::compensation {

struct ErrorStats {
  std::size_t count = 0;
  double mean_mm = std::numeric_limits<double>::quiet_NaN();
  double max_mm = std::numeric_limits<double>::quiet_NaN();
  double rms_mm = std::numeric_limits<double>::quiet_NaN();
  double p95_mm = std::numeric_limits<double>::quiet_NaN();
  /// Of |e| for every finite e (NaNs are skipped); NaN figures when there is none.
  static ErrorStats of(const std::vector<double>& errors_mm);
};

struct BeforeAfter {
  std::optional<ErrorStats> before;  ///< empty when nothing was measured without compensation
  ErrorStats after;
};

struct ValidatedPoint {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  std::string point;
  /// ok, outside-region, not-credible (prediction refused), refused (targets mode: the compensate
  /// status was not ok), no-measurement.
  std::string status = "ok";
  Eigen::Vector3d before_mm = Eigen::Vector3d::Constant(kNaN);  ///< position error vector, robot frame
  Eigen::Vector3d after_mm = Eigen::Vector3d::Constant(kNaN);
  std::vector<double> distance_before_mm, distance_after_mm;  ///< per base point K (signed)
  /// Prediction mode, models with a variance: of a new reading (field + nugget) and of the field
  /// alone (mm², ErrorPrediction); vector fields with scored positions: the 95 % radius (mm) and
  /// NEES = sum_i after_i² / var_i (3 expected).
  double var_mm2 = kNaN, var_field_mm2 = kNaN, r95_mm = kNaN, nees = kNaN;
  /// The point's joints (deg): the held-out row's (prediction mode), the run's q1..q6 or nominal
  /// nq1..nq6 (targets mode, when the file has them); NaN when unknown. For the report's view of
  /// where large errors and refusals are.
  Eigen::Matrix<double, 6, 1> q_deg = Eigen::Matrix<double, 6, 1>::Constant(kNaN);
  /// Scored: ok, or extrapolated (validate --extrapolate: answered beyond the model's region).
  bool ok() const { return status == "ok" || status == "extrapolated"; }
};

/// How well the predictive variance held on the scored points (prediction mode, vector fields).
struct UncertaintyCheck {
  std::size_t points = 0;  ///< points with a 3-D error and a variance
  double coverage95 = std::numeric_limits<double>::quiet_NaN();  ///< share with |e| <= r95 (0.95 expected)
  double mean_nees = std::numeric_limits<double>::quiet_NaN();   ///< mean of NEES (3 expected)
};

struct ValidationReport {
  std::string mode;  ///< "prediction" or "targets"
  std::vector<ValidatedPoint> points;
  std::size_t refused = 0;
  /// Points answered beyond the model's region (validate --extrapolate; scored, status extrapolated).
  std::size_t extrapolated = 0;
  std::optional<BeforeAfter> position;
  std::optional<BeforeAfter> distance;  ///< pooled over the base points
  std::size_t distance_columns = 0;
  /// Which registration maps the tracker readings of each position figure (one sentence each).
  std::string before_registration, after_registration;
  std::optional<UncertaintyCheck> uncertainty;
  std::vector<std::string> notes;

  /// {"mode","points","refused","position":{"before":{...}|null,"after":{...},"before_registration",
  /// "after_registration"},"distance":...,"uncertainty":{"points","coverage95","mean_nees"}|null,"notes"}
  /// with {"count","mean_mm","max_mm","rms_mm","p95_mm"} per block; "distance" only with distances.
  nlohmann::json summary_json() const;
  /// The console summary (the same figures).
  std::string summary_text() const;
};

/// Prediction mode on held-out rows. Positions are scored when the data have mx,my,mz and the model
/// has a registration (else a note says why not); distances when the data have dist_bK.
/// `extrapolate`: rows outside the model's region are scored too (predict_position's extrapolate).
ValidationReport validate_predictions(const CompensationModel& model, const MeasurementSet& data, bool extrapolate = false);

/// Targets mode. Columns: point; target nx,ny,nz (compensate output) or x,y,z (robot frame, mm);
/// mx,my,mz (tracker frame) and/or dist_bK; optional run (before|after; absent = after), kind
/// (base rows give the base points B_K at their target), status (rows not "ok" are refused).
/// `registration` maps the tracker readings (required for positions).
ValidationReport validate_targets(const CsvTable& table, const std::optional<Registration>& registration,
                                  const std::vector<Eigen::Vector3d>& fixed_bases = {});

/// A self-contained HTML page (report/html_report.hpp): the summary table, histograms of the error
/// magnitudes before/after and the errors per point before/after, for positions and distances.
std::string validation_report_html(const ValidationReport& report, const std::string& title, bool simulated);

}  // namespace errfield::compensation
