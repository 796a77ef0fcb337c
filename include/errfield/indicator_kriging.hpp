#pragma once
/// Indicator kriging: the probability that the value at a target is below each of a few
/// thresholds, P(Z(x) < T_k), estimated without assuming a distribution. Use it when the question
/// is "how likely is the error here above the tolerance" and the values are skewed or have
/// outliers that a Gaussian model of Z would misjudge; 1 - P is the probability of reaching T_k.
///
/// For each threshold T_k (increasing) the samples become the indicators I(z < T_k) - 1 below
/// the threshold, 0 at or above it: the strict '<' that gstat users write, krige(I(z < T) ~ 1, ...)
/// - and the indicators are kriged with that threshold's own variogram model (any Kriging kind and
/// back end; ordinary kriging is the usual choice). Kriging each threshold on its own can give
/// values outside [0, 1] and a cdf that decreases from one threshold to the next ("order relation
/// violations"); correct_order_relations repairs them as GSLIB does (see there). The uncorrected
/// values are kept (raw) so that how much was repaired can be judged; many large corrections say
/// that the models of neighbouring thresholds disagree. docs/kriging.md, "Indicator kriging".

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"
#include "errfield/kriging.hpp"

namespace errfield {

/// What correct_order_relations changed.
struct OrderRelationCorrection {
  std::size_t rows_changed = 0;  ///< targets whose cdf was changed at all
  double max_change = 0.0;       ///< largest absolute change of one probability
};

/// Repairs each row of `cdf` (one target per row, one column per threshold in increasing order)
/// into a non-decreasing sequence in [0, 1], in place. GSLIB's correction (Deutsch & Journel,
/// GSLIB, 2nd ed. 1998, section V.1.6 "Order relation problems"; the same average in Rossi &
/// Deutsch, Mineral Resource Estimation, 2014, Fig. 9.6: "the corrected ccdf is obtained by
/// averaging the forward and downward corrections"):
///   p_k <- min(1, max(0, p_k))                          clip each probability to [0, 1]
///   u_1 = p_1,  u_k = max(u_{k-1}, p_k)                 upward pass (k increasing)
///   d_K = p_K,  d_k = min(d_{k+1}, p_k)                 downward pass (k decreasing)
///   p_k <- (u_k + d_k) / 2
/// Both passes give non-decreasing sequences, so does their average; a row that needs no
/// correction is left as it is. A row with a NaN (a target not kriged) is left untouched.
inline OrderRelationCorrection correct_order_relations(Eigen::Ref<Eigen::MatrixXd> cdf) {
  OrderRelationCorrection r;
  const Eigen::Index k = cdf.cols();
  std::vector<double> p(static_cast<std::size_t>(k)), up(p.size()), down(p.size());
  for (Eigen::Index t = 0; t < cdf.rows(); ++t) {
    if (cdf.row(t).array().isNaN().any() || k == 0) continue;
    for (Eigen::Index j = 0; j < k; ++j) p[static_cast<std::size_t>(j)] = std::clamp(cdf(t, j), 0.0, 1.0);
    up[0] = p[0];
    for (std::size_t j = 1; j < p.size(); ++j) up[j] = std::max(up[j - 1], p[j]);
    down.back() = p.back();
    for (std::size_t j = p.size() - 1; j-- > 0;) down[j] = std::min(down[j + 1], p[j]);
    bool changed = false;
    for (Eigen::Index j = 0; j < k; ++j) {
      const double corrected = 0.5 * (up[static_cast<std::size_t>(j)] + down[static_cast<std::size_t>(j)]);
      if (corrected != cdf(t, j)) {
        changed = true;
        r.max_change = std::max(r.max_change, std::fabs(corrected - cdf(t, j)));
        cdf(t, j) = corrected;
      }
    }
    r.rows_changed += changed ? 1 : 0;
  }
  return r;
}

/// The indicators I(z_i < threshold): 1.0 below, 0.0 at or above.
inline std::vector<double> indicators_below(std::span<const double> values, double threshold) {
  std::vector<double> out(values.size());
  for (std::size_t i = 0; i < values.size(); ++i) out[i] = values[i] < threshold ? 1.0 : 0.0;
  return out;
}

/// Throws ArgumentError unless the thresholds are finite and strictly increasing (at least one).
inline void check_indicator_thresholds(std::span<const double> thresholds) {
  if (thresholds.empty()) throw ArgumentError("indicator kriging: no thresholds; expected at least one");
  for (std::size_t k = 0; k < thresholds.size(); ++k) {
    if (!std::isfinite(thresholds[k]))
      throw ArgumentError("indicator kriging: threshold " + std::to_string(k + 1) + " is not finite");
    if (k > 0 && !(thresholds[k] > thresholds[k - 1]))
      throw ArgumentError("indicator kriging: thresholds must increase strictly; threshold " + std::to_string(k + 1) +
                          " (" + format_number(thresholds[k]) + ") is not above the one before (" +
                          format_number(thresholds[k - 1]) + ")");
  }
}

struct IndicatorKrigingOptions {
  bool correct_order = true;  ///< apply correct_order_relations to `probability`
};

/// Targets x thresholds.
struct IndicatorKrigingResult {
  Eigen::MatrixXd raw;          ///< kriged indicators, before any correction
  Eigen::MatrixXd probability;  ///< raw, order relations corrected (unless switched off)
  Eigen::MatrixXd variance;     ///< the indicator kriging variance of each threshold's model
  OrderRelationCorrection correction;
  std::vector<KrigingReport> reports;  ///< one per threshold
  /// Worst factorization status over thresholds; predictions exist when usable.
  KrigingStatus status = KrigingStatus::Ok;
  std::string message;          ///< the first non-empty message, naming its threshold
  std::size_t failed_targets = 0;  ///< targets without a prediction for some threshold (NaN rows)
  bool usable() const { return status == KrigingStatus::Ok || status == KrigingStatus::IllConditioned; }
};

/// Kriges I(values < thresholds[k]) with models[k] (one model per threshold, or one for all) and
/// `options`, at `targets`. Throws ArgumentError for mismatched sizes or bad thresholds; a
/// threshold whose system cannot be factored makes the result not usable (status, message).
template <Location L, class M = EuclideanMetric>
IndicatorKrigingResult indicator_kriging(std::span<const L> samples, std::span<const double> values,
                                         std::span<const L> targets, std::span<const double> thresholds,
                                         std::span<const VariogramModel> models, const KrigingOptions& options,
                                         const IndicatorKrigingOptions& indicator_options = {}, const M& metric = {}) {
  check_indicator_thresholds(thresholds);
  if (models.size() != 1 && models.size() != thresholds.size())
    throw ArgumentError("indicator kriging: " + std::to_string(models.size()) + " models for " +
                        std::to_string(thresholds.size()) + " thresholds; expected one model, or one per threshold");
  if (values.size() != samples.size())
    throw ArgumentError("indicator kriging: " + std::to_string(values.size()) + " values for " +
                        std::to_string(samples.size()) + " samples");
  const auto m = static_cast<Eigen::Index>(targets.size());
  const auto k = static_cast<Eigen::Index>(thresholds.size());
  IndicatorKrigingResult r;
  r.raw.setConstant(m, k, std::numeric_limits<double>::quiet_NaN());
  r.variance = r.raw;
  for (Eigen::Index j = 0; j < k; ++j) {
    const double t = thresholds[static_cast<std::size_t>(j)];
    const std::vector<double> indicator = indicators_below(values, t);
    const VariogramModel& model = models[models.size() == 1 ? 0 : static_cast<std::size_t>(j)];
    const Kriging<L, double, M> kriging(samples, std::span<const double>(indicator), model, options, metric);
    const std::string which = "threshold " + std::to_string(j + 1) + " (" + format_number(t) + "): ";
    r.reports.push_back(kriging.report());
    const auto note = [&](const std::string& message) {
      if (r.message.empty() && !message.empty()) r.message = which + message;
    };
    // The factorization decides whether there are predictions; targets a local search could not
    // krige are NaN rows (failed_targets), as in Kriging::predict.
    if (static_cast<int>(kriging.report().status) > static_cast<int>(r.status)) r.status = kriging.report().status;
    note(kriging.report().message);
    if (!kriging.report().usable()) continue;
    const KrigingPrediction<double> p = kriging.predict(targets);
    note(p.message);
    for (Eigen::Index i = 0; i < m; ++i) {
      r.raw(i, j) = p.mean[static_cast<std::size_t>(i)];
      if (!p.variance.empty()) r.variance(i, j) = p.variance[static_cast<std::size_t>(i)];
    }
  }
  for (Eigen::Index i = 0; i < m; ++i) r.failed_targets += r.raw.row(i).array().isNaN().any() ? 1 : 0;
  r.probability = r.raw;
  if (indicator_options.correct_order) r.correction = correct_order_relations(r.probability);
  return r;
}

}  // namespace errfield
