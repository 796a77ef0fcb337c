#pragma once
// The methods behind `errfield interpolate --method NAME` and `errfield cv --method NAME`.
//
// Each method registers itself from its own file, the way subcommands do, so adding one (e.g.
// kriging) needs no edit of cmd_interpolate.cpp / cmd_cv.cpp:
//
//   namespace {
//   struct KrigingOptions { std::string model; ... } opts;           // filled by CLI11
//   void add_options(CLI::App& cmd) { cmd.add_option("--model", opts.model, "...")->group("kriging"); }
//   InterpolationResult run(const InterpolationRequest& r) { ... }
//   errfield::cli::InterpolationMethodRegistration reg{{"kriging", "ordinary/simple/universal kriging",
//       {"--neighbors", "--radius"}, &add_options, &run}};
//   }
//
// The command reads the files, the coordinate and value columns and the shared options, and
// rejects options that belong to another method (options a method adds in add_options are
// recorded as its own; shared options are accepted only when listed in `accepts`).

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>
#include <Eigen/Core>

#include "cli/coordinate_system.hpp"
#include "errfield/csv_table.hpp"
#include "errfield/interpolation_options.hpp"
#include "errfield/row_labels.hpp"

namespace errfield::cli {

/// Options shared by several methods; empty when not given on the command line.
struct SharedInterpolationOptions {
  std::optional<double> power;           ///< --power P
  std::optional<std::size_t> neighbors;  ///< --neighbors K
  std::optional<double> radius;          ///< --radius R (coordinate unit)
  bool clamp = false;                    ///< --clamp
};

/// Input of an interpolation method, already parsed and checked (finite numbers, columns found).
struct InterpolationRequest {
  const CsvTable* samples = nullptr;
  const CsvTable* targets = nullptr;
  std::vector<std::string> coord_columns;  ///< --coords names, D >= 1
  std::vector<std::string> value_columns;  ///< --value names, C >= 1 (C > 1: a vector value)
  Eigen::MatrixXd sample_coords;           ///< N x D
  Eigen::MatrixXd sample_values;           ///< N x C
  Eigen::MatrixXd target_coords;           ///< M x D
  RowLabels sample_labels;                 ///< "S.csv:7"
  RowLabels target_labels;                 ///< "T.csv:9"
  SharedInterpolationOptions shared;
  /// The CRS the inputs agree on; a method that reads a further georeferenced file (a covariate
  /// raster) adds its CRS, which is refused when it differs. Null: not checked.
  CoordinateSystem* coordinate_system = nullptr;
};

/// Output of an interpolation method.
struct InterpolationResult {
  Eigen::MatrixXd pred;  ///< M x C; a NaN row means "no prediction" (written as empty cells)
  /// Names of pred's columns when the method chooses them (indicator kriging: p_lt_<T>, one per
  /// threshold, pred then M x thresholds); empty: pred, or pred_<col> per --value column.
  std::vector<std::string> prediction_names;
  /// Further columns after the predictions, e.g. {"var", ...}; NaN is written as an empty cell.
  std::vector<std::pair<std::string, std::vector<double>>> extra_columns;
  /// Lines printed to stderr after the run ("12 targets had no neighbour within --radius").
  std::vector<std::string> notes;
};

/// Input of a cross-validation run (`errfield cv`).
struct CrossValidationRequest {
  const CsvTable* samples = nullptr;
  std::vector<std::string> coord_columns;
  std::vector<std::string> value_columns;
  Eigen::MatrixXd sample_coords;  ///< N x D
  Eigen::MatrixXd sample_values;  ///< N x C
  RowLabels sample_labels;
  std::size_t folds = 0;          ///< 0 = leave-one-out, else k >= 2
  std::uint64_t seed = 1;         ///< fold assignment seed (k-fold)
  SharedInterpolationOptions shared;
  CoordinateSystem* coordinate_system = nullptr;  ///< as InterpolationRequest's
};

/// Output of a cross-validation run, per sample (rows in input order).
struct CrossValidationOutput {
  std::vector<std::size_t> fold;  ///< fold of each sample (0-based)
  Eigen::MatrixXd pred;           ///< N x C, NaN row = not predicted
  std::vector<double> variance;   ///< per sample prediction variance, empty if the method has none
  /// Further per-sample columns written after var (e.g. cokriging's var_<col>, cov_<A>_<B>).
  std::vector<std::pair<std::string, std::vector<double>>> extra_columns;
  std::vector<std::string> notes;
};

struct InterpolationMethod {
  std::string name;                 ///< value of --method
  std::string summary;              ///< one line for --help
  std::vector<std::string> accepts; ///< shared options it reads: "--power", "--neighbors", "--radius", "--clamp"
  void (*add_options)(CLI::App& command) = nullptr;  ///< its own options (may be null)
  InterpolationResult (*interpolate)(const InterpolationRequest&) = nullptr;  ///< null: not for interpolate
  CrossValidationOutput (*cross_validate)(const CrossValidationRequest&) = nullptr;  ///< null: not for cv
  /// True when the method, as its options are set, takes empty --value cells of the samples as
  /// "not measured" (NaN in sample_values; heterotopic cokriging). Null or false: an empty cell is
  /// an input error naming file, line and column, as before.
  bool (*takes_missing_values)() = nullptr;
};

std::vector<InterpolationMethod>& interpolation_methods();

struct InterpolationMethodRegistration {
  explicit InterpolationMethodRegistration(InterpolationMethod method) {
    interpolation_methods().push_back(std::move(method));
  }
};

/// Adds the method-specific options of every method to `command`, and returns a function that
/// checks, once parsed, that no option of another method than `chosen` was given.
struct MethodOptionOwnership {
  std::vector<std::pair<std::string, std::vector<CLI::Option*>>> owned;  // method name -> its options
  /// Throws ArgumentError naming the option and the method it belongs to.
  void check(const std::string& chosen, const std::vector<std::string>& accepted_shared,
             const std::vector<CLI::Option*>& shared_options) const;
};
MethodOptionOwnership add_method_options(CLI::App& command, bool for_cv);

/// Finds a method by name; throws ArgumentError listing the available ones.
const InterpolationMethod& find_method(const std::string& name, bool for_cv);
/// "idw-grid|idw|..." for help texts.
std::string method_names(bool for_cv);

/// Rows of a table as labels for messages ("S.csv:7").
RowLabels row_labels_of(const CsvTable& table, std::string noun);

/// The option names of interpolate/cv, for the messages of kriging_options_from_text and
/// scattered_idw_options_from_text.
OptionNames cli_option_names();

/// The unit written after a column name in a header ("dL [mm]" -> "mm"), or empty.
std::string unit_of_column(const CsvTable& table, const std::string& name);

[[noreturn]] void throw_unsupported_components(std::size_t components);

/// Calls f.template operator()<V>() with V = double for 1 component, Eigen::Matrix<double, C, 1>
/// for C = 2, 3; throws ArgumentError for other counts.
template <class F>
decltype(auto) with_value_type(std::size_t components, F&& f) {
  switch (components) {
    case 1: return f.template operator()<double>();
    case 2: return f.template operator()<Eigen::Vector2d>();
    case 3: return f.template operator()<Eigen::Vector3d>();
    default: break;
  }
  throw_unsupported_components(components);
}

}  // namespace errfield::cli
