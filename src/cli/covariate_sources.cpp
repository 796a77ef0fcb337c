#include "cli/covariate_sources.hpp"

#include <algorithm>

#include "errfield/error.hpp"

namespace errfield::cli {

CovariateSources covariate_sources(const std::vector<std::string>& entries, CoordinateSystem* coordinate_system) {
  CovariateSources s;
  for (const auto& e : entries) {
    const auto eq = e.find('=');
    if (eq == std::string::npos) {
      s.names.push_back(e);
      s.rasters.push_back(nullptr);
      continue;
    }
    const std::string name = e.substr(0, eq), file = e.substr(eq + 1);
    if (name.empty() || file.empty())
      throw ArgumentError("--covariates: '" + e + "'; expected COL (a column) or NAME=FILE (a raster)");
    if (std::find(s.names.begin(), s.names.end(), name) != s.names.end())
      throw ArgumentError("--covariates: '" + name + "' is given twice");
    s.names.push_back(name);
    s.rasters.push_back(std::make_shared<const CovariateRaster>(read_covariate_raster(file)));
    if (coordinate_system) coordinate_system->add(s.rasters.back()->crs, "covariate raster " + file, file);
  }
  return s;
}

Eigen::MatrixXd covariate_values(const CovariateSources& s, const CsvTable& table, const Eigen::MatrixXd& coords,
                                 const RowLabels& labels) {
  Eigen::MatrixXd out(coords.rows(), static_cast<Eigen::Index>(s.names.size()));
  for (std::size_t k = 0; k < s.names.size(); ++k) {
    const auto col = static_cast<Eigen::Index>(k);
    if (!s.rasters[k]) {
      out.col(col) = table.numeric_columns({s.names[k]}).col(0);
      continue;
    }
    if (coords.cols() != 2)
      throw ArgumentError("--covariates " + s.names[k] + "=" + s.rasters[k]->path +
                          ": a raster covariate needs 2-D --coords (x,y); got " + std::to_string(coords.cols()) + " columns");
    for (Eigen::Index i = 0; i < coords.rows(); ++i)
      out(i, col) = s.rasters[k]->at(coords(i, 0), coords(i, 1), labels(static_cast<std::size_t>(i)));
  }
  return out;
}

}  // namespace errfield::cli
