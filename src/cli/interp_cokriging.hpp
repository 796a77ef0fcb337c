#pragma once
// `errfield interpolate|cv --method kriging --model lmc.json`: cokriging (errfield/cokriging.hpp)
// when the model file is a linear model of coregionalization. interp_kriging.cpp owns the options
// and hands over the parsed model and KrigingOptions; this file runs cokriging and names the
// output columns.

#include <string>

#include "cli/interpolation_methods.hpp"
#include "errfield/coregionalization_model.hpp"
#include "errfield/kriging.hpp"

namespace errfield::cli {

/// True when --model names a JSON file whose top level has "type": "lmc". Anything else (model
/// text, a variogram model JSON, a missing file) is for the shared-model path and its messages.
bool model_file_is_lmc(const std::string& model);

/// Reads the LMC of `path` and checks it against the --value columns: the same count, and, when
/// the model names its components, the same names in the same order (InputError naming both lists).
CoregionalizationModel load_lmc_for_values(const std::string& path, const std::vector<std::string>& value_columns);

/// Cokriging at the targets. Columns: pred (pred_<col>) from the command, then the prediction
/// variance per component (var for one column, var_<col> otherwise, Kriging's names) and the
/// prediction error covariances cov_<A>_<B> for every pair, A before B in --value order.
InterpolationResult interpolate_cokriging(const InterpolationRequest& r, const CoregionalizationModel& model,
                                          const KrigingOptions& options);

/// Leave-one-out cokriging (all components of a sample left out together). `variance` (the
/// command's var column) is the mean of the per-component residual variances; extra columns
/// var_<col> and cov_<A>_<B> hold the residual covariance.
CrossValidationOutput cross_validate_cokriging(const CrossValidationRequest& r, const CoregionalizationModel& model,
                                               const KrigingOptions& options);

}  // namespace errfield::cli
