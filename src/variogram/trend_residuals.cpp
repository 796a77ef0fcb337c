#include "errfield/trend_residuals.hpp"

#include <cmath>

#include <Eigen/QR>

#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"

namespace errfield {

Eigen::MatrixXd ols_trend_residuals(const Eigen::MatrixXd& values, const Eigen::MatrixXd& covariates,
                                    const std::vector<std::string>& names, const RowLabels& labels) {
  const Eigen::Index n = values.rows(), k = covariates.cols();
  if (covariates.rows() != n && k > 0)
    throw ArgumentError("trend residuals: " + std::to_string(covariates.rows()) + " rows of covariates for " +
                        std::to_string(n) + " values; expected one row per value");
  if (!names.empty() && static_cast<Eigen::Index>(names.size()) != k)
    throw ArgumentError("trend residuals: " + std::to_string(names.size()) + " covariate names for " +
                        std::to_string(k) + " covariate columns");
  auto name = [&](Eigen::Index j) {
    return names.empty() ? "covariate " + std::to_string(j) : "covariate '" + names[static_cast<std::size_t>(j)] + "'";
  };
  if (n == 0) return values;
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < k; ++j)
      if (!std::isfinite(covariates(i, j))) {
        const auto row = static_cast<std::size_t>(i);
        const bool in_file = labels.in_file(row);
        throw InputError(labels(row) + ": " + name(j) + " is " + format_number(covariates(i, j)) +
                             "; expected a finite number",
                         in_file ? labels.source : std::string(), in_file ? labels.line(row) : 0,
                         names.empty() ? std::string() : names[static_cast<std::size_t>(j)]);
      }
  // Centred, scaled columns: the same span (so the same residuals), a better conditioned solve.
  Eigen::MatrixXd f(n, k + 1);
  f.col(0).setOnes();
  for (Eigen::Index j = 0; j < k; ++j) {
    const double mean = covariates.col(j).mean();
    const double scale = (covariates.col(j).array() - mean).abs().maxCoeff();
    if (!(scale > 0.0))
      throw InputError("trend residuals: " + name(j) + " is constant (" + format_number(covariates(0, j)) +
                       ") at all " + std::to_string(n) + " rows, like the mean term; drop it");
    f.col(j + 1) = (covariates.col(j).array() - mean) / scale;
  }
  // Name the first column that adds nothing to those before it (QR with columns in order).
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(f);
  const Eigen::MatrixXd r = qr.matrixQR().topRows(std::min(n, k + 1)).triangularView<Eigen::Upper>();
  for (Eigen::Index j = 1; j <= k; ++j)
    if (j >= n || std::abs(r(j, j)) <= 1e-9 * f.col(j).norm())
      throw InputError("trend residuals: " + name(j - 1) + " is (nearly) a linear combination of the terms before "
                       "it (the mean" + std::string(j > 1 ? " and the covariates listed before it" : "") + ") at the " +
                       std::to_string(n) + " rows, or there are too few rows; drop it");
  const Eigen::MatrixXd beta = qr.solve(values);
  return values - f * beta;
}

}  // namespace errfield
