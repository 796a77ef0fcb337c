#pragma once
/// Where each `--covariates` entry of a command comes from: a column of the input CSV (COL), or a
/// raster looked up at each point (NAME=FILE.tif / .asc, 2-D coordinates only). Shared by
/// `interpolate` (external drift), `variogram` (residual variogram) and `fit-variogram` (the
/// likelihood's drift), so one covariate means the same numbers in all three.

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "cli/coordinate_system.hpp"
#include "cli/raster_file.hpp"
#include "errfield/csv_table.hpp"
#include "errfield/row_labels.hpp"

namespace errfield::cli {

struct CovariateSources {
  std::vector<std::string> names;                               ///< the covariates' names, in order
  std::vector<std::shared_ptr<const CovariateRaster>> rasters;  ///< null: a CSV column
};

/// Parses the entries (COL or NAME=FILE) and reads every raster; each raster's CRS is added to
/// `coordinate_system` when given (a raster in another CRS than the samples is refused, naming both).
/// Throws ArgumentError for an empty name or file and a name given twice; the raster reader's
/// errors for a file GDAL cannot read.
CovariateSources covariate_sources(const std::vector<std::string>& entries, CoordinateSystem* coordinate_system = nullptr);

/// N x k covariates of the rows of `table` at `coords` (N x D): the CSV columns as numbers, the
/// rasters' pixel values at the points (2-D only; a point outside a raster or on nodata is an
/// InputError naming its row label).
Eigen::MatrixXd covariate_values(const CovariateSources& sources, const CsvTable& table, const Eigen::MatrixXd& coords,
                                 const RowLabels& labels);

}  // namespace errfield::cli
