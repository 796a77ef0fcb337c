// The inverse-distance-weighting methods of `errfield interpolate` and `errfield cv`:
//   idw-grid  the paper's rule on a complete regular 3-D grid (GridIdw)
//   idw       k nearest / radius neighbours among scattered samples (ScatteredIdw)

#include <cmath>

#include "cli/interpolation_methods.hpp"
#include "errfield/error.hpp"
#include "errfield/value_rows.hpp"
#include "errfield/cross_validation.hpp"
#include "errfield/grid_idw.hpp"
#include "errfield/interpolation_options.hpp"
#include "errfield/scattered_idw.hpp"

namespace errfield::cli {
namespace {

InterpolationResult interpolate_grid(const InterpolationRequest& r) {
  if (r.coord_columns.size() != 3)
    throw ArgumentError("--method idw-grid needs exactly 3 coordinate columns (x,y,z); --coords has " +
                        std::to_string(r.coord_columns.size()));
  GridIdwOptions options;
  options.power = r.shared.power.value_or(1.0);
  options.clamp = r.shared.clamp;
  return with_value_type(r.value_columns.size(), [&]<class V>() {
    const auto values = rows_as_values<V>(r.sample_values);
    const auto idw = GridIdw<V>::from_samples(r.sample_coords, values, options, r.sample_labels);
    InterpolationResult result;
    if (!options.clamp) {
      // Throws OutsideGridError naming the first target outside and the grid bounds.
      result.pred = values_as_rows(idw.predict(r.target_coords, r.target_labels));
      return result;
    }
    std::vector<V> out(static_cast<std::size_t>(r.target_coords.rows()));
    std::vector<GridIdwStatus> status(out.size());
    idw.predict_with_status(r.target_coords, out, status);
    std::size_t clamped = 0, outside = 0, first_outside = 0;
    for (std::size_t i = 0; i < status.size(); ++i) {
      clamped += status[i] == GridIdwStatus::Clamped;
      if (status[i] == GridIdwStatus::Outside && outside++ == 0) first_outside = i;
    }
    if (outside)  // only non-finite coordinates are Outside when clamping; CsvTable rejects those
      throw InputError(r.target_labels(first_outside) + ": target has no prediction", r.target_labels.source,
                       r.target_labels.line(first_outside));
    // Clamping keeps the target's own distances to the nearest cell's vertices: far enough out
    // (1e300) their squares overflow and the weights are 0 / 0. Said, never an empty "interpolated".
    for (std::size_t i = 0; i < out.size(); ++i) {
      bool finite = true;
      for (int c = 0; c < ValueTraits<V>::kComponents; ++c) finite = finite && std::isfinite(ValueTraits<V>::component(out[i], c));
      if (!finite)
        throw InputError(r.target_labels(i) + ": target is too far outside the grid (" + idw.grid().describe() +
                             ") to be interpolated from the nearest cell with --clamp: its distances to the cell "
                             "overflow a double; check its coordinates and units",
                         r.target_labels.source, r.target_labels.line(i));
    }
    if (clamped)
      result.notes.push_back(std::to_string(clamped) + " of " + std::to_string(out.size()) +
                             " targets are outside the grid (" + idw.grid().describe() +
                             ") and were interpolated from the nearest cell (--clamp)");
    result.pred = values_as_rows(out);
    return result;
  });
}

ScatteredIdwOptions scattered_options(const SharedInterpolationOptions& shared) {
  return scattered_idw_options_from_text({shared.power, shared.neighbors, shared.radius}, cli_option_names());
}

InterpolationResult interpolate_scattered(const InterpolationRequest& r) {
  const ScatteredIdwOptions options = scattered_options(r.shared);
  const auto points = rows_as_points(r.sample_coords);
  const auto targets = rows_as_points(r.target_coords);
  return with_value_type(r.value_columns.size(), [&]<class V>() {
    const ScatteredIdw<Eigen::VectorXd, V> idw(points, rows_as_values<V>(r.sample_values), options);
    std::vector<V> out(targets.size());
    std::vector<ScatteredIdwStatus> status(targets.size());
    idw.predict_with_status(std::span<const Eigen::VectorXd>(targets), std::span<V>(out), std::span<ScatteredIdwStatus>(status));
    InterpolationResult result;
    std::size_t none = 0, first = 0;
    for (std::size_t i = 0; i < status.size(); ++i)
      if (status[i] == ScatteredIdwStatus::NoNeighbours && none++ == 0) first = i;
    if (none)
      result.notes.push_back(std::to_string(none) + " of " + std::to_string(status.size()) +
                             " targets have no sample within --radius " + format_number(options.radius) +
                             " (first: " + r.target_labels(first) + "); their prediction cells are empty");
    result.pred = values_as_rows(out);
    return result;
  });
}

CrossValidationOutput cross_validate_scattered(const CrossValidationRequest& r) {
  const auto points = rows_as_points(r.sample_coords);
  CrossValidationOptions cv;
  cv.folds = r.folds;
  cv.seed = r.seed;
  return with_value_type(r.value_columns.size(), [&]<class V>() {
    ScatteredIdwEstimator<Eigen::VectorXd, V> estimator;
    estimator.options = scattered_options(r.shared);
    const auto values = rows_as_values<V>(r.sample_values);
    const auto result = cross_validate(estimator, std::span<const Eigen::VectorXd>(points), std::span<const V>(values), cv);
    CrossValidationOutput out;
    out.fold = result.fold;
    out.pred = values_as_rows(result.predicted);
    out.variance = result.variance;
    return out;
  });
}

InterpolationMethodRegistration scattered_method{{
    "idw",
    "inverse-distance weighting over scattered samples in any number of coordinates: the --neighbors K "
    "nearest and/or those within --radius R (default all), weights 1/d^p (p = 2 unless --power, as gstat's "
    "idw); exact at the samples; a target with no sample within --radius gets empty cells",
    {"--power", "--neighbors", "--radius"},
    nullptr,
    &interpolate_scattered,
    &cross_validate_scattered,
}};

InterpolationMethodRegistration grid_method{{
    "idw-grid",
    "the paper's rule (SPEC eqs. 19-21): the samples must form a complete regular 3-D grid; each target is "
    "interpolated from the 8 vertices of its cell with weights 1/d^p (p = 1 unless --power); --clamp for "
    "targets outside the grid",
    {"--power", "--clamp"},
    nullptr,
    &interpolate_grid,
    nullptr,
}};

}  // namespace
}  // namespace errfield::cli
