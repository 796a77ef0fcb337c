#include "errfield/compensation/model/tool_point_correction.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <span>

#include <Eigen/Eigenvalues>
#include <nlohmann/json.hpp>

#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"
#include "errfield/kriging.hpp"
#include "errfield/metrics.hpp"

namespace errfield::compensation {

using robot::JointVector;

struct ToolPointCorrection::Kriged {
  std::array<std::optional<Kriging<JointVector, double, JointSpaceMetric>>, 3> axis;
  std::array<std::vector<double>, 3> values;
};

namespace {

/// The field model's structures (nugget dropped) at unit total sill, every range times `multiplier`:
/// the correlation ρ_m. None without a bounded structure.
std::optional<VariogramModel> correlation_of(const VariogramModel& field_model, double multiplier) {
  std::vector<ModelComponent> structures;
  double total = 0.0;
  for (const ModelComponent& c : field_model.components()) {
    if (c.kind == ModelKind::Nugget) continue;
    if (!c.bounded() || !(c.sill > 0.0) || !(c.range > 0.0)) return std::nullopt;
    structures.push_back(c);
    total += c.sill;
  }
  if (structures.empty() || !(total > 0.0)) return std::nullopt;
  for (ModelComponent& c : structures) {
    c.sill /= total;
    c.range *= multiplier;
  }
  return VariogramModel(std::move(structures), field_model.anisotropy());
}

/// ρ(q_i, q_j) over the readings.
Eigen::MatrixXd correlation_matrix(const VariogramModel& correlation, const std::vector<JointVector>& q) {
  const Eigen::Index n = static_cast<Eigen::Index>(q.size());
  const VariogramModel isotropic = correlation.isotropic_part();
  Eigen::MatrixXd r(n, n);
  JointVector mapped;
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j <= i; ++j) {
      const JointVector d = q[static_cast<std::size_t>(i)] - q[static_cast<std::size_t>(j)];
      correlation.anisotropy().apply(d.data(), mapped.data(), robot::kJointCount);
      r(i, j) = r(j, i) = isotropic.covariance(mapped.norm());
    }
  return r;
}

/// The negative log-likelihood (constant dropped) of values whose coordinates on ρ's eigenvectors
/// are `y` (eigenvalues `lambda`) under covariance s ρ + n I.
double profile_nll(const Eigen::VectorXd& y, const Eigen::VectorXd& lambda, double s, double n) {
  double v = 0.0;
  for (Eigen::Index j = 0; j < y.size(); ++j) {
    const double d = s * std::max(lambda[j], 0.0) + n;
    v += std::log(d) + y[j] * y[j] / d;
  }
  return 0.5 * v;
}

/// The sill s >= 0 that minimizes profile_nll at noise n, searched over [0, 100 v] with v the
/// values' mean square: a grid over log s (and s = 0), then golden sections between the best grid
/// point's neighbours. Returns (s, its negative log-likelihood).
std::pair<double, double> most_likely_sill(const Eigen::VectorXd& y, const Eigen::VectorXd& lambda, double n) {
  const double v = std::max(y.squaredNorm() / static_cast<double>(y.size()), std::numeric_limits<double>::min());
  const double lo = std::log(1e-6 * v), hi = std::log(1e2 * v);
  const int steps = 80;
  double best_s = 0.0, best = profile_nll(y, lambda, 0.0, n);
  int best_k = -1;
  for (int k = 0; k <= steps; ++k) {
    const double s = std::exp(lo + (hi - lo) * k / steps);
    const double value = profile_nll(y, lambda, s, n);
    if (value < best) best = value, best_s = s, best_k = k;
  }
  if (best_k < 0) return {0.0, best};
  double a = lo + (hi - lo) * std::max(best_k - 1, 0) / steps, b = lo + (hi - lo) * std::min(best_k + 1, steps) / steps;
  const double g = (std::sqrt(5.0) - 1.0) / 2.0;
  for (int it = 0; it < 60; ++it) {
    const double c = b - g * (b - a), d = a + g * (b - a);
    if (profile_nll(y, lambda, std::exp(c), n) < profile_nll(y, lambda, std::exp(d), n)) b = d;
    else a = c;
  }
  const double s = std::exp(0.5 * (a + b)), value = profile_nll(y, lambda, s, n);
  return value < best ? std::pair{s, value} : std::pair{best_s, best};
}

/// The most likely sills (one per axis) and the one noise variance of all three at correlation ρ
/// (its eigenvalues `lambda`, the values' coordinates on its eigenvectors `y`, one column per axis):
/// the noise over a log grid from 1e-4 to 1 times the values' mean square, the sills profiled.
struct AxisFit {
  Eigen::Vector3d sill = Eigen::Vector3d::Zero();
  double noise = 0.0;
  double nll = std::numeric_limits<double>::infinity();
};
AxisFit most_likely_sills_and_noise(const Eigen::MatrixXd& y, const Eigen::VectorXd& lambda) {
  const double v = y.squaredNorm() / static_cast<double>(y.size());
  AxisFit best;
  if (!(v > 0.0) || !std::isfinite(v)) return best;
  const int steps = 40;
  for (int k = 0; k <= steps; ++k) {
    const double n = v * std::pow(10.0, -4.0 + 4.0 * k / steps);
    AxisFit fit;
    fit.noise = n;
    fit.nll = 0.0;
    for (int axis = 0; axis < 3; ++axis) {
      const auto [s, nll] = most_likely_sill(y.col(axis), lambda, n);
      fit.sill[axis] = s;
      fit.nll += nll;
    }
    if (fit.nll < best.nll) best = fit;
  }
  return best;
}

/// The correlations the likelihood chooses among: the model field's structures with every range
/// times each of kRangeMultipliers, and an isotropic gau over the joints (deg) at each of
/// kIsotropicRangesDeg (a field's own anisotropy can be of no use for the flange's turn: REML gave
/// SIMULATED UR5e readings ranges of 0.3 deg along q1, white noise to any other quantity).
std::vector<VariogramModel> candidate_correlations(const VariogramModel& field_model) {
  std::vector<VariogramModel> out;
  for (double m : kRangeMultipliers)
    if (std::optional<VariogramModel> rho = correlation_of(field_model, m)) out.push_back(std::move(*rho));
  for (double range : kIsotropicRangesDeg)
    out.emplace_back(std::vector<ModelComponent>{ModelComponent{ModelKind::Gaussian, 1.0, range}});
  return out;
}

KrigingOptions simple_kriging_options() {
  KrigingOptions o;
  o.kind = KrigingKind::Simple;
  o.simple_mean = {0.0};
  o.nugget = NuggetTreatment::MeasurementError;
  o.threads = 1;
  // A pose read twice is one location: its readings averaged (their noise halved).
  o.duplicates = DuplicatePolicy::Average;
  return o;
}

/// s ρ plus the nugget n.
VariogramModel axis_model(const VariogramModel& correlation, double sill, double noise) {
  std::vector<ModelComponent> c = correlation.components();
  for (ModelComponent& m : c) m.sill *= sill;
  c.push_back(ModelComponent{ModelKind::Nugget, noise, 0.0});
  return VariogramModel(std::move(c), correlation.anisotropy());
}

}  // namespace

ToolPointCorrection::ToolPointCorrection(Eigen::Vector3d point_mm, std::vector<JointVector> q_deg,
                                         std::vector<Eigen::Vector3d> residual_flange_mm, VariogramModel correlation,
                                         Eigen::Vector3d sill_mm2, double noise_mm2)
    : point_mm_(std::move(point_mm)),
      q_deg_(std::move(q_deg)),
      residual_flange_mm_(std::move(residual_flange_mm)),
      correlation_(std::move(correlation)),
      sill_mm2_(std::move(sill_mm2)),
      noise_mm2_(noise_mm2) {
  auto kriged = std::make_shared<Kriged>();
  for (int k = 0; k < 3; ++k) {
    kriged->values[k].reserve(q_deg_.size());
    for (const Eigen::Vector3d& r : residual_flange_mm_) kriged->values[k].push_back(r[k]);
    // A sill of 0 (no residual field on this axis) predicts 0 with variance 0: no system to solve.
    if (sill_mm2_[k] > 0.0)
      kriged->axis[k].emplace(std::span<const JointVector>(q_deg_), std::span<const double>(kriged->values[k]),
                              axis_model(correlation_, sill_mm2_[k], noise_mm2_), simple_kriging_options());
  }
  kriged_ = std::move(kriged);
}

std::optional<ToolPointCorrection> ToolPointCorrection::fit_once(const Eigen::Vector3d& point_mm,
                                                                 const std::vector<JointVector>& q_deg,
                                                                 const std::vector<Eigen::Vector3d>& flange,
                                                                 const VariogramModel& field_model) {
  const std::size_t n = q_deg.size();
  Eigen::MatrixXd values(static_cast<Eigen::Index>(n), 3);
  for (std::size_t i = 0; i < n; ++i) values.row(static_cast<Eigen::Index>(i)) = flange[i].transpose();
  AxisFit best;
  std::optional<VariogramModel> best_rho;
  for (const VariogramModel& rho : candidate_correlations(field_model)) {
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(correlation_matrix(rho, q_deg));
    if (eig.info() != Eigen::Success) continue;
    const AxisFit fit = most_likely_sills_and_noise(eig.eigenvectors().transpose() * values, eig.eigenvalues());
    if (fit.nll < best.nll) best = fit, best_rho = rho;
  }
  if (!best_rho) return std::nullopt;
  ToolPointCorrection c(point_mm, q_deg, flange, *best_rho, best.sill, best.noise);
  c.variance_factor_ = c.leave_one_out_variance_factor();
  return c;
}

std::optional<ToolPointCorrection> ToolPointCorrection::fit(const Eigen::Vector3d& point_mm,
                                                            const std::vector<JointVector>& q_deg,
                                                            const std::vector<Eigen::Matrix3d>& flange_rotation,
                                                            const std::vector<Eigen::Vector3d>& residual_mm,
                                                            const VariogramModel& field_model) {
  const std::size_t n = q_deg.size();
  if (n < kMinToolPointCorrectionReadings || flange_rotation.size() != n || residual_mm.size() != n) return std::nullopt;
  if (!point_mm.allFinite()) return std::nullopt;
  std::vector<Eigen::Vector3d> flange(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (!q_deg[i].allFinite() || !residual_mm[i].allFinite() || !flange_rotation[i].allFinite()) return std::nullopt;
    flange[i] = flange_rotation[i].transpose() * residual_mm[i];
  }
  // A gross reading (a bumped nest, a beam break) would be kriged as a spike of the turn: the
  // likelihood then picks a short range and the correction spoils its neighbours (one reading
  // 0.6 mm off among 40 took a point from 0.046 to 0.066 mm held-out, worse than no correction).
  // So readings are judged as fit's outlier screen judges rows: each by its leave-one-out residual
  // (an excluded one by the prediction of the others) in units of its stated sd, against the
  // robust scale of the kept ones; up to kOutlierRounds rounds, each refitting without the flagged.
  std::vector<bool> excluded(n, false);
  std::optional<ToolPointCorrection> c = fit_once(point_mm, q_deg, flange, field_model);
  for (int round = 0; c && round < kOutlierRounds; ++round) {
    std::vector<double> u(n, 0.0);  // RMS over the axes of residual / sd
    const std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> held = c->held_out_residuals();
    std::vector<JointVector> out_q;
    std::vector<std::size_t> out_index;
    std::size_t kept = 0;
    for (std::size_t i = 0; i < n; ++i) {
      if (excluded[i]) {
        out_q.push_back(q_deg[i]);
        out_index.push_back(i);
      } else if (kept < held.size()) {
        const auto& [r, v] = held[kept++];
        u[i] = std::sqrt((r.array().square() / v.array().max(1e-300)).sum() / 3.0);
      }
    }
    if (kept != held.size() || held.size() + out_q.size() != n) break;  // readings were merged: no screen
    if (!out_q.empty()) {
      const std::vector<ToolPointCorrectionPrediction> p =
          c->predict(out_q, std::vector<Eigen::Matrix3d>(out_q.size(), Eigen::Matrix3d::Identity()));
      for (std::size_t j = 0; j < out_q.size(); ++j) {
        const Eigen::Vector3d r = flange[out_index[j]] - p[j].error_mm;
        const Eigen::Vector3d v = p[j].axis_variance_mm2.array() + c->noise_mm2();
        u[out_index[j]] = std::sqrt((r.array().square() / v.array()).sum() / 3.0);
      }
    }
    std::vector<double> judged;
    for (std::size_t i = 0; i < n; ++i)
      if (!excluded[i]) judged.push_back(u[i]);
    std::nth_element(judged.begin(), judged.begin() + static_cast<std::ptrdiff_t>(judged.size() / 2), judged.end());
    // The median of sqrt(chi²_3 / 3), 0.888, is what the median of u is where the stated sd holds.
    const double scale = judged[judged.size() / 2] / 0.888;
    std::vector<bool> flagged(n);
    std::size_t flagged_count = 0;
    for (std::size_t i = 0; i < n; ++i) {
      flagged[i] = u[i] > kOutlierLimit * scale;
      flagged_count += flagged[i] ? 1 : 0;
    }
    if (flagged == excluded || n - flagged_count < kMinToolPointCorrectionReadings) break;
    excluded = flagged;
    std::vector<JointVector> q_kept;
    std::vector<Eigen::Vector3d> flange_kept;
    for (std::size_t i = 0; i < n; ++i)
      if (!excluded[i]) q_kept.push_back(q_deg[i]), flange_kept.push_back(flange[i]);
    c = fit_once(point_mm, q_kept, flange_kept, field_model);
  }
  if (c) c->excluded_readings_ = static_cast<std::size_t>(std::count(excluded.begin(), excluded.end(), true));
  return c;
}

std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> ToolPointCorrection::leave_one_out_by_axis() const {
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> out(residual_flange_mm_.size());
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = {residual_flange_mm_[i], Eigen::Vector3d::Zero()};
  for (int k = 0; k < 3; ++k) {
    if (!kriged_->axis[k]) continue;  // an axis without a field: the value itself, no kriging variance
    const KrigingCrossValidation<double> cv = kriged_->axis[k]->leave_one_out();
    if (cv.residual.size() != out.size() || cv.variance.size() != out.size()) return {};
    for (std::size_t i = 0; i < out.size(); ++i) {
      out[i].first[k] = cv.residual[i];
      out[i].second[k] = std::max(0.0, cv.variance[i] - noise_mm2_);
    }
  }
  return out;
}

std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> ToolPointCorrection::held_out_residuals() const {
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> out = leave_one_out_by_axis();
  // The kriging part scaled as predict scales it; the reading's noise as is.
  for (auto& [residual, variance] : out) variance = (variance_factor_ * variance.array() + noise_mm2_).matrix();
  return out;
}

double ToolPointCorrection::leave_one_out_variance_factor() const {
  // Residual² and the part of its variance the factor scales (the kriging variance; the reading's
  // noise stays), per reading and fielded axis.
  std::vector<std::pair<double, double>> z;
  for (const auto& [residual, variance] : leave_one_out_by_axis())
    for (int k = 0; k < 3; ++k)
      if (kriged_->axis[k]) z.emplace_back(residual[k] * residual[k], variance[k]);
  if (z.empty()) return 1.0;
  // The factor that maximizes the readings' leave-one-out log score, sum of
  // -1/2 [log(f v + n) + r² / (f v + n)]: its derivative in f, sum of v (f v + n - r²) / (f v + n)²,
  // falls from positive to negative where the stated variance fits the residuals (a reading whose
  // kriging variance is ~0, on an axis without a field, weighs nothing, as it should).
  auto slope = [&](double f) {
    double d = 0.0;
    for (const auto& [r2, v] : z) {
      const double total = f * v + noise_mm2_;
      d += v * (total - r2) / (total * total);
    }
    return d;
  };
  double lo = std::log(kMinVarianceFactor), hi = std::log(kMaxVarianceFactor);
  if (slope(std::exp(lo)) >= 0.0) return kMinVarianceFactor;
  if (slope(std::exp(hi)) <= 0.0) return kMaxVarianceFactor;
  for (int it = 0; it < 60; ++it) {
    const double mid = 0.5 * (lo + hi);
    (slope(std::exp(mid)) < 0.0 ? lo : hi) = mid;
  }
  return std::exp(0.5 * (lo + hi));
}

std::vector<ToolPointCorrectionPrediction> ToolPointCorrection::predict(const std::vector<JointVector>& q_deg,
                                                                        const std::vector<Eigen::Matrix3d>& flange_rotation) const {
  std::vector<ToolPointCorrectionPrediction> out(q_deg.size());
  std::array<KrigingPrediction<double>, 3> axis;
  for (int k = 0; k < 3; ++k)
    if (kriged_->axis[k]) axis[k] = kriged_->axis[k]->predict(std::span<const JointVector>(q_deg));
  for (std::size_t t = 0; t < q_deg.size(); ++t) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero(), variance = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k)
      if (kriged_->axis[k] && axis[k].usable() && t < axis[k].mean.size()) {
        mean[k] = axis[k].mean[t];
        variance[k] = variance_factor_ * std::max(0.0, axis[k].variance[t]);
      } else if (kriged_->axis[k]) {
        mean[k] = 0.0;
        variance[k] = variance_factor_ * sill_mm2_[k];  // what nothing kriged leaves: the whole residual
      }
    const Eigen::Matrix3d& r = flange_rotation[t];
    out[t].error_mm = r * mean;
    // The flange axes' variances carried to the robot frame (they are independent): diag(R V Rᵀ).
    out[t].axis_variance_mm2 = r.cwiseAbs2() * variance;
  }
  return out;
}

ToolPointCorrectionPrediction ToolPointCorrection::predict(const JointVector& q_deg,
                                                           const Eigen::Matrix3d& flange_rotation) const {
  return predict(std::vector<JointVector>{q_deg}, std::vector<Eigen::Matrix3d>{flange_rotation}).front();
}

std::vector<Eigen::Vector3d> ToolPointCorrection::leave_one_out_residual_mm() const {
  const std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> held = leave_one_out_by_axis();
  if (held.empty()) return residual_flange_mm_;  // readings were merged: their values as they are
  std::vector<Eigen::Vector3d> out;
  for (const auto& [residual, variance] : held) out.push_back(residual);
  return out;
}

nlohmann::json ToolPointCorrection::to_json() const {
  nlohmann::json q = nlohmann::json::array(), r = nlohmann::json::array();
  for (const JointVector& v : q_deg_) q.push_back({v[0], v[1], v[2], v[3], v[4], v[5]});
  for (const Eigen::Vector3d& v : residual_flange_mm_) r.push_back({v.x(), v.y(), v.z()});
  return {{"point_mm", {point_mm_.x(), point_mm_.y(), point_mm_.z()}},
          {"correlation", correlation_.to_string()},
          {"sill_mm2", {sill_mm2_.x(), sill_mm2_.y(), sill_mm2_.z()}},
          {"noise_mm2", noise_mm2_},
          {"variance_factor", variance_factor_},
          {"joints_deg", std::move(q)},
          {"residual_flange_mm", std::move(r)}};
}

namespace {

/// A stored correction (from_json) whose axis has sill 0 holds residuals there of mean square at most
/// this many times its noise: a chi-square of kMinToolPointCorrectionReadings noise readings exceeds
/// that with negligible probability, so more is a field the file says is not there.
constexpr double kMaxZeroSillNoiseRatio = 25.0;
/// The longest correlation range (deg) a stored correction may hold: ten turns of a joint.
constexpr double kMaxCorrelationRangeDeg = 3600.0;

/// A stored correction's variogram against the residuals it holds, as fit chooses it
/// (most_likely_sills_and_noise): the noise at most the values' mean square, each sill at most 100
/// times its axis's, an axis of sill 0 only where its residuals are noise-sized, and ranges a
/// correlation over the joints can have. A hand-edited noise or range of 1e300, or residuals put on
/// an axis the file says holds none, would otherwise state a variance nothing measured.
template <class Fail>
void check_against_residuals(const VariogramModel& rho, const Eigen::Vector3d& sill, double noise,
                             const std::vector<Eigen::Vector3d>& residual, const Fail& fail) {
  Eigen::Vector3d mean_square = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& r : residual) mean_square += r.cwiseAbs2() / static_cast<double>(residual.size());
  const double all = mean_square.sum() / 3.0;
  constexpr double kSlack = 1.0 + 1e-9;
  if (noise > kSlack * all)
    throw fail("noise_mm2 " + format_number(noise) + " exceeds the mean square " + format_number(all) +
               " mm2 of its residual_flange_mm, the most a fit gives it (the file was edited?)");
  for (int k = 0; k < 3; ++k) {
    const std::string axis(1, "xyz"[k]);
    if (sill[k] > kSlack * 100.0 * mean_square[k] + 1e-300)
      throw fail("sill_mm2 of flange axis " + axis + " " + format_number(sill[k]) + " exceeds 100 x the mean square " +
                 format_number(mean_square[k]) + " mm2 of its residuals, the most a fit gives it (the file was edited?)");
    if (sill[k] == 0.0 && mean_square[k] > kMaxZeroSillNoiseRatio * noise)
      throw fail("flange axis " + axis + " has sill_mm2 0 (no residual field: predicted 0 there) but residuals of mean "
                 "square " + format_number(mean_square[k]) + " mm2, over " + format_number(kMaxZeroSillNoiseRatio) +
                 " x noise_mm2 " + format_number(noise) + " (the file was edited?)");
  }
  for (const ModelComponent& c : rho.components())
    if (!(c.range <= kMaxCorrelationRangeDeg))
      throw fail("correlation range " + format_number(c.range) + " deg exceeds " + format_number(kMaxCorrelationRangeDeg) +
                 " deg (ten turns of a joint: no correlation over the joints; the file was edited?)");
}

}  // namespace

ToolPointCorrection ToolPointCorrection::from_json(const nlohmann::json& j, const std::string& source) {
  const std::string where = source + ": tool_point_correction";
  auto fail = [&](const std::string& what) { return InputError(where + ": " + what, source); };
  if (!j.is_object()) throw fail("must be an object");
  auto numbers = [&](const nlohmann::json& a, std::size_t count, const std::string& member) {
    if (!a.is_array() || a.size() != count) throw fail(member + " must hold " + std::to_string(count) + " numbers");
    std::vector<double> v;
    for (const nlohmann::json& x : a) {
      if (!x.is_number() || !std::isfinite(x.get<double>())) throw fail(member + " must hold finite numbers");
      v.push_back(x.get<double>());
    }
    return v;
  };
  auto member = [&](const char* name) -> const nlohmann::json& {
    if (!j.contains(name)) throw fail("missing member " + std::string(name));
    return j[name];
  };
  const std::vector<double> p = numbers(member("point_mm"), 3, "point_mm");
  const std::vector<double> s = numbers(member("sill_mm2"), 3, "sill_mm2");
  if (std::any_of(s.begin(), s.end(), [](double v) { return v < 0.0; })) throw fail("sill_mm2 must be >= 0");
  const double noise = numbers(nlohmann::json::array({member("noise_mm2")}), 1, "noise_mm2")[0];
  if (!(noise > 0.0)) throw fail("noise_mm2 must be > 0");
  const double factor = numbers(nlohmann::json::array({member("variance_factor")}), 1, "variance_factor")[0];
  if (!(factor >= kMinVarianceFactor && factor <= kMaxVarianceFactor))
    throw fail("variance_factor must lie in [" + format_number(kMinVarianceFactor) + ", " +
               format_number(kMaxVarianceFactor) + "]");
  if (!member("correlation").is_string()) throw fail("correlation must be a model text");
  VariogramModel rho;
  try {
    rho = VariogramModel::parse(member("correlation").get<std::string>());
  } catch (const ArgumentError& e) {
    throw fail(std::string("correlation: ") + e.what());
  }
  if (rho.nugget() != 0.0 || !rho.bounded() || std::abs(rho.sill() - 1.0) > 1e-9)
    throw fail("correlation must be bounded structures of total sill 1 without nugget (the file was edited?)");
  const nlohmann::json& q = member("joints_deg");
  const nlohmann::json& r = member("residual_flange_mm");
  if (!q.is_array() || !r.is_array() || q.size() != r.size() || q.size() < kMinToolPointCorrectionReadings)
    throw fail("joints_deg and residual_flange_mm must hold one row per reading, at least " +
               std::to_string(kMinToolPointCorrectionReadings));
  std::vector<JointVector> joints;
  std::vector<Eigen::Vector3d> residual;
  for (std::size_t i = 0; i < q.size(); ++i) {
    const std::vector<double> qi = numbers(q[i], 6, "joints_deg[" + std::to_string(i) + "]");
    const std::vector<double> ri = numbers(r[i], 3, "residual_flange_mm[" + std::to_string(i) + "]");
    joints.push_back(Eigen::Map<const JointVector>(qi.data()));
    residual.emplace_back(ri[0], ri[1], ri[2]);
  }
  check_against_residuals(rho, Eigen::Vector3d(s[0], s[1], s[2]), noise, residual, fail);
  try {
    ToolPointCorrection c(Eigen::Vector3d(p[0], p[1], p[2]), std::move(joints), std::move(residual), std::move(rho),
                          Eigen::Vector3d(s[0], s[1], s[2]), noise);
    c.variance_factor_ = factor;
    return c;
  } catch (const Error& e) {
    throw fail(e.what());
  }
}

}  // namespace errfield::compensation
