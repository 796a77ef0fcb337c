#pragma once
/// Readings of several points on one flange (reflector nests on a plate, labelled per row, e.g. a
/// `reflector` column): which point each reading is, and where each point starts for the joint
/// calibration (calibration.hpp, the multi-point register_tracker and calibrate_positions). Each
/// label is first registered on its own readings, which locates it on the flange to a few tenths
/// of a mm: a start the joint fit refines, whatever the labels' order in the file.

#include <string>
#include <vector>

#include <Eigen/Core>

#include "errfield/robot/calibration.hpp"

namespace errfield::robot {

struct LabelledFlangePoints {
  /// Label of point k: labels[0] is the model's tool point (PositionMeasurement::flange_point 0).
  std::vector<std::string> labels;
  /// Each label's position on the flange (flange frame, mm) from its own registration, in the order
  /// of `labels`: element 0 is the tool point's, elements 1.. the further points' starts.
  std::vector<Eigen::Vector3d> located_mm;
  /// Readings per label, in the order of `labels`.
  std::vector<std::size_t> readings;

  /// located_mm without the tool point: the starts the multi-point overloads take.
  std::vector<Eigen::Vector3d> further_points_mm() const {
    return {located_mm.begin() + (located_mm.empty() ? 0 : 1), located_mm.end()};
  }
};

/// Sets `data[i].flange_point` from `row_labels[i]` (one per reading). Point 0 is `tool_label` when
/// given (InputError naming `source` and the labels present if no reading has it), else the label
/// whose own registration puts it nearest `model`'s tool point. Each label needs at least 4 readings
/// (InputError naming it and its count).
LabelledFlangePoints assign_flange_points(const MdhModel& model, std::vector<PositionMeasurement>& data,
                                          const std::vector<std::string>& row_labels, const std::string& tool_label,
                                          const CalibrationOptions& options, const std::string& source);

}  // namespace errfield::robot
