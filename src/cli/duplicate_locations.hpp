#pragma once
// --duplicates of the commands that read samples (variogram, fit-variogram): what to do with rows
// at exactly the same coordinates. gstat keeps them in a variogram (lag 0, in the first bin) and
// refuses them in kriging (a singular matrix); its users average them first, which `average` does.

#include <string>

#include <Eigen/Core>

#include "errfield/csv_table.hpp"

namespace errfield::cli {

enum class DuplicateHandling {
  Keep,     ///< every row as given (variogram's default, as gstat's variogram)
  Average,  ///< one sample per location, the mean of each value column over the rows measuring it
  First,    ///< one sample per location, the first row's values
  Refuse,   ///< an InputError naming both rows' lines
};

/// "average" | "first" | "refuse" (and "keep" when `keep_allowed`); ArgumentError naming `option` otherwise.
DuplicateHandling duplicate_handling_from(const std::string& text, const std::string& option, bool keep_allowed);

/// The samples x (N x D), z (N x K, NaN = not measured) with the rows at equal coordinates merged
/// per `handling`, in the order of each location's first row. `merged` counts the rows folded
/// into an earlier one. Refuse throws InputError "<file>:<line>: this sample and <file>:<line> are at
/// the same location", advising `option` average|first.
struct MergedSamples {
  Eigen::MatrixXd x, z;
  std::size_t merged = 0;
};
MergedSamples merge_duplicate_locations(const Eigen::MatrixXd& x, const Eigen::MatrixXd& z, DuplicateHandling handling,
                                        const CsvTable& table, const std::string& option);

/// --duplicates TEXT of `command` ("variogram", "fit-variogram") on the samples x, z read from
/// `table`: merges in place and says on stderr how many rows were merged. Keep (or nothing to merge)
/// leaves them as they are. `covariates_given`: average and first are refused, since covariates
/// are read per row of the file.
void apply_duplicates_option(const std::string& text, const std::string& command, bool covariates_given, const CsvTable& table,
                             Eigen::MatrixXd& x, Eigen::MatrixXd& z);

}  // namespace errfield::cli
