#pragma once
/// Locating a point rigidly attached to the flange (a second reflector nest, a tool tip) from a few
/// tracker readings of it, through a fitted model: `errfield locate-tool`. Use it when a model was
/// measured with one reflector and the robot works with another point: the model is kept, only its
/// working tool changes (CompensationModel::with_working_tool), so nothing is re-measured but the
/// few readings of the new point.
///
/// Least squares, linear in the point x (flange frame, mm): reading i at joints q_i, mapped into the
/// robot frame by the model's registration, p_i = R_reg m_i + t_reg, is modelled as
///   p_i = o_i + e_i + (I + [w_i]x) R_i x,
/// with (R_i, o_i) the flange pose by the model's calibrated command model, e_i the model's error
/// field at q_i (the field as fitted at the reflector, applied as a translation of the flange) plus
/// the joint error functions' displacement of the flange origin, and w_i the small rotation of the
/// flange those functions' angle errors cause. What the model does not say about the flange's
/// orientation (its unobservable residual) is what the residual of this fit shows. Readings where
/// the field refuses (outside its region, not credible) are left out and counted.
///
/// Frames and units: flange frame and robot frame, mm. Thread-safe (pure).

#include <cstddef>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "errfield/compensation/model/compensation.hpp"
#include "errfield/compensation/fitting/model_fitting.hpp"
#include "errfield/compensation/model/tool_point_correction.hpp"

namespace errfield::compensation {

/// Fewest readings the location screens for gross ones (a robust scale needs a few more than the 3
/// unknowns).
inline constexpr std::size_t kMinScreenedReadings = 8;

struct ToolLocationOptions {
  /// Flange orientations closer than this (deg, angle of the relative rotation) count as one.
  double distinct_orientation_deg = 10.0;
  /// At least this many distinct orientations: with fewer, the model's error at those poses goes into
  /// the point undiluted (it cannot be told from the point's offset).
  std::size_t min_orientations = 3;
  /// Readings whose residual RMS exceeds this many times what the model's own errors explain at the
  /// point are refused as not one rigid point.
  double not_rigid_factor = 3.0;
  /// Throws ArgumentError naming the member.
  void validate() const;
};

struct ToolLocation {
  Eigen::Vector3d tool_mm = Eigen::Vector3d::Zero();  ///< the located point, flange frame (mm)
  /// Standard deviation per flange axis (mm): the least-squares covariance scaled by the residual
  /// variance (readings taken as independent; the model's errors at nearby poses are not, so this is
  /// a lower bound).
  Eigen::Vector3d sd_mm = Eigen::Vector3d::Zero();
  double residual_rms_mm = 0.0;  ///< RMS of |residual| over the readings used
  /// What the model's own errors explain at the point (mm, RMS of a new reading): the model's
  /// predictive variance there (field, functions, nugget and the orientation term) where it has one,
  /// else its registration's residual RMS.
  double expected_rms_mm = 0.0;
  std::string expected_basis;    ///< "the model's predictive variance" or "the registration residual"
  std::size_t readings = 0;      ///< used
  std::size_t left_out = 0;      ///< where the field refused
  /// Gross readings left out of the location (and the correction): leave-one-out residual over
  /// ToolPointCorrection::kOutlierLimit robust sd, from kMinScreenedReadings readings on.
  std::size_t gross = 0;
  std::size_t orientations = 0;  ///< distinct flange orientations among the readings used
  double lever_mm = 0.0;         ///< distance of the point from the reflector the model was measured with
  bool field_used = false;       ///< the model's field (and functions) corrected the flange position
  std::vector<Eigen::Vector3d> residual_mm;  ///< per reading used (robot frame)
  /// The flange's orientation residual the readings show at the point's lever (MeasuredOrientation):
  /// their residual beyond the variance the model states there without its orientation term, read as
  /// w x L (3n numbers, 3 of them spent on the point). Empty for a point at the reflector (no lever)
  /// or a model without field.
  std::optional<MeasuredOrientation> orientation;
  /// The readings' residual against the located model's prediction at the point, kriged
  /// (tool_point_correction.hpp): null with fewer than kMinToolPointCorrectionReadings readings or a
  /// model whose field is not a joint-space vector kriging field.
  std::shared_ptr<const ToolPointCorrection> correction;
  /// RMS of |residual| at the readings against the located model without the correction, and the
  /// correction's leave-one-out RMS there (mm); NaN without a correction.
  double uncorrected_rms_mm = std::numeric_limits<double>::quiet_NaN();
  double correction_leave_one_out_rms_mm = std::numeric_limits<double>::quiet_NaN();
};

/// The model with the located point as its working tool (also its aimed tool point, for calibrated
/// models), its readings' kriged residual (ToolLocation::correction; any earlier one dropped) and,
/// where measured, the orientation residual the readings showed, so the variance at the point counts
/// what the one-point model could only guess.
CompensationModel with_located_tool(const CompensationModel& model, const ToolLocation& location);

/// Locates the point the readings measured. `readings` needs tracker positions (measured_mm) and the
/// model a registration. Throws InputError naming readings.source for: no tracker positions, a model
/// without registration, fewer than min_orientations distinct orientations, and readings that are not
/// one rigid point (residual beyond not_rigid_factor x expected).
ToolLocation locate_tool(const CompensationModel& model, const MeasurementSet& readings,
                         const ToolLocationOptions& options = {});

}  // namespace errfield::compensation
