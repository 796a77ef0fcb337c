// Cokriging under a linear model of coregionalization: the engine behind errfield::Cokriging, with
// the dense back end (one Cholesky of the NP x NP covariance) and the local back end (k nearest
// samples per target, a kP x kP solve each). Formulas: docs/kriging.md, "Cokriging".
//
// Notation (N samples, P components, p drift terms per component, unknowns ordered sample-major:
// row i*P + a is component a of sample i; drift column a*p + t is term t of component a):
//   K  (NP x NP) blocks C(h_ij), diagonal blocks C(0) = the model's sill
//   F  (NP x Pp) F(i*P + a, a*p + t) = f_t(x_i); F0 (Pp x P) F0(b*p + t, b) = f_t(x0)
//   C0 (NP x P) blocks C(h_i0); C00 (P x P) the target's own covariance
//   K = L L';  Q = L^-1 F;  G = Q'Q = Lg Lg';  y = L^-1 z;  beta = G^-1 Q'y
//   W = L^-1 C0;  R = F0 - Q'W
//   mean = F0' beta + W'(y - Q beta)          (P)
//   cov  = C00 - W'W + R' G^-1 R              (P x P prediction error covariance)
// Simple kriging is p = 0 on values with the known means subtracted. Kriging's engine is the case
// P = 1 (kriging_engine.hpp).
//
// Heterotopic data (a component not measured at some samples: NaN in values): the system has a row
// only for each (sample, component) that is measured, sample-major as above, so "i*P + a" reads as
// "the row of component a of sample i, if it exists" (row_start_, row_component_). The drift of a
// component with no row in the system has no column in F: its unbiasedness constraint cannot be
// met (no weights to sum to 1), so its prediction is NaN under ordinary and universal cokriging,
// while the others' constraints (their weights of it sum to 0) hold trivially.

#include "errfield/cokriging.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>

#include <Eigen/Cholesky>
#include <omp.h>

#include "errfield/csv_table.hpp"
#include "kriging/duplicate_samples.hpp"
#include "kriging/kd_tree.hpp"
#include "kriging/neighbour_selection.hpp"
#include "kriging/simple_mean.hpp"

namespace errfield::detail {

namespace {

enum class CokrigingOutcome : std::uint8_t { Ok, TooFew, BelowMinimum, NotPositiveDefinite, SingularDrift, OverBudget };

// One thread's matrices, grown but never shrunk, so that warm targets allocate nothing.
struct CokrigingWorkspace : NeighbourBuffers {
  Eigen::MatrixXd k, q, w, g, r, f0;
  Eigen::VectorXd y, beta;
  std::vector<Eigen::Index> row_sample;  // the local system's rows: sample and component
  std::vector<int> row_component;
  std::vector<int> slot;                 // drift slot of each component in this system, -1: none
  Eigen::MatrixXd cov;
  Eigen::VectorXd mean;
};

std::string cokriging_mib(double bytes) { return format_number(std::round(bytes / (1 << 20))); }

// Validated statuses, never a silent NaN: how many targets failed, and why the first did.
void report_local_failures(const std::vector<CokrigingOutcome>& outcome, bool leave_one_out,
                           std::size_t min_neighbours, CokrigingOutput& out) {
  std::size_t failed = 0, first = 0;
  for (std::size_t t = 0; t < outcome.size(); ++t)
    if (outcome[t] != CokrigingOutcome::Ok && failed++ == 0) first = t;
  out.failed_targets = failed;
  if (failed == 0) return;
  std::string why;
  switch (outcome[first]) {
    case CokrigingOutcome::TooFew:
      out.status = KrigingStatus::TooFewSamples;
      why = "fewer neighbours than drift terms (or none) within the search radius";
      break;
    case CokrigingOutcome::BelowMinimum:
      out.status = KrigingStatus::TooFewSamples;
      why = "fewer than min_neighbours = " + std::to_string(min_neighbours) + " neighbours within the search radius";
      break;
    case CokrigingOutcome::NotPositiveDefinite:
      out.status = KrigingStatus::NotPositiveDefinite;
      why = "local cokriging matrix not positive definite after the jitter retries";
      break;
    case CokrigingOutcome::SingularDrift:
      out.status = KrigingStatus::SingularDrift;
      why = "the drift terms are linearly dependent over its neighbours; use a lower drift order or more neighbours";
      break;
    case CokrigingOutcome::Ok:
    case CokrigingOutcome::OverBudget: break;
  }
  out.message = std::to_string(failed) + " of " + std::to_string(outcome.size()) + (leave_one_out ? " samples" : " targets") +
                " could not be cokriged (mean and covariance NaN); first: " + (leave_one_out ? "sample " : "target ") +
                std::to_string(first) + ": " + why;
}

}  // namespace

Eigen::MatrixXd cokriging_embedding(const Eigen::MatrixXd& raw, const std::vector<double>& scales,
                                    const Anisotropy& anisotropy) {
  if (scales.empty() && anisotropy.isotropic()) return raw;
  Eigen::MatrixXd e = raw;
  if (!scales.empty())
    for (Eigen::Index k = 0; k < e.rows(); ++k) e.row(k) *= scales[static_cast<std::size_t>(k)];
  if (anisotropy.isotropic()) return e;
  Eigen::MatrixXd mapped(e.rows(), e.cols());
  for (Eigen::Index j = 0; j < e.cols(); ++j)
    anisotropy.apply(e.col(j).data(), mapped.col(j).data(), static_cast<int>(e.rows()));
  return mapped;
}

class CokrigingEngine {
 public:
  CokrigingEngine(Eigen::MatrixXd embedded, Eigen::MatrixXd raw, Eigen::MatrixXd values,
                  const CoregionalizationModel& model, const KrigingOptions& options);

  const KrigingReport& report() const { return report_; }
  CokrigingOutput predict(const Eigen::MatrixXd& embedded, const Eigen::MatrixXd& raw) const;
  CokrigingOutput leave_one_out() const;

 private:
  void validate_options() const;
  void refuse_duplicates() const;
  void setup_dense();
  // P x P covariance at lag h > 0 into out (column-major, P*P doubles).
  void covariance_at(double h, double* out) const;
  // Target-side covariance block with sample s (zero lag: target_zero_).
  void target_block(const double* target, Eigen::Index s, double* out) const;
  void drift_row(const double* raw_point, double* out) const;
  void index_rows();
  Eigen::Index rows_of(Eigen::Index s) const { return row_start_[static_cast<std::size_t>(s) + 1] - row_start_[static_cast<std::size_t>(s)]; }
  int thread_count() const { return options_.threads > 0 ? options_.threads : omp_get_max_threads(); }
  // Local back end: the kP x kP system of the samples in ws.chosen for one target.
  CokrigingOutcome solve_local(const double* target, const double* target_raw, CokrigingWorkspace& ws) const;
  // Its steps: the system's rows and each component's drift slot (TooFew when a component has
  // fewer rows than drift terms); K built and factored in place with growing jitter (false: not
  // positive definite); the right-hand sides L^-1 k0 and L^-1 y; universal kriging's drift
  // (false: singular). `bp` is a P x P scratch block.
  CokrigingOutcome local_rows(CokrigingWorkspace& ws, Eigen::Index& present) const;
  bool factor_local(CokrigingWorkspace& ws, Eigen::Index np, double* bp) const;
  void local_right_hand_sides(const double* target, CokrigingWorkspace& ws, Eigen::Index np, double* bp) const;
  bool local_drift(const double* target_raw, CokrigingWorkspace& ws, Eigen::Index np, Eigen::Index pp) const;
  CokrigingOutput predict_dense(const Eigen::MatrixXd& embedded, const Eigen::MatrixXd& raw) const;
  CokrigingOutput predict_local(const Eigen::MatrixXd& embedded, const Eigen::MatrixXd& raw, bool leave_one_out) const;
  CokrigingOutput loo_dense() const;
  CokrigingOutput unusable() const;

  KrigingOptions options_;
  std::vector<CoregionalizationStructure> structures_;
  Eigen::MatrixXd sill_, nugget_;
  Eigen::MatrixXd target_zero_;  // C(0) between a sample and a target point, and the target's C00
  Eigen::MatrixXd points_, raw_;  // D x N
  Eigen::MatrixXd values_;        // N x P, simple kriging: means subtracted
  Eigen::MatrixXd observed_;      // N x P as given
  Eigen::VectorXd simple_mean_;   // P
  int dimension_ = 0, components_ = 0, drift_terms_ = 0;
  // Rows of the (global) system: sample s owns rows row_start_[s] .. row_start_[s + 1] - 1, one
  // per measured component, component row_component_[r]; drift_slot_[a] is the index of component
  // a's block of drift columns (-1: the component is measured nowhere, no drift columns).
  std::vector<Eigen::Index> row_start_;
  std::vector<int> row_component_;
  std::vector<int> drift_slot_;
  int drift_components_ = 0;
  Eigen::VectorXd drift_center_, drift_scale_;
  std::unique_ptr<PointTree> tree_, search_tree_;
  KrigingReport report_;
  // dense
  Eigen::LLT<Eigen::MatrixXd> llt_;
  Eigen::MatrixXd f_;     // NP x Pp
  Eigen::MatrixXd q_;     // L^-1 F
  Eigen::LLT<Eigen::MatrixXd> g_llt_;
  Eigen::VectorXd beta_;  // Pp
  Eigen::VectorXd ry_;    // L^-1 (z - F beta)
  Eigen::VectorXd alpha_; // K^-1 (z - F beta) = L^-T ry_: means without variances, O(NP^2) per target
  Eigen::VectorXd z_;     // NP
};

CokrigingEngine::CokrigingEngine(Eigen::MatrixXd embedded, Eigen::MatrixXd raw, Eigen::MatrixXd values,
                                 const CoregionalizationModel& model, const KrigingOptions& options)
    : options_(options),
      structures_(model.structures()),
      points_(std::move(embedded)),
      raw_(std::move(raw)),
      values_(std::move(values)) {
  options_.validate();
  validate_options();
  if (structures_.empty())
    throw ArgumentError("cokriging: the coregionalization model has no structures; expected at least one (e.g. nug + sph)");
  components_ = static_cast<int>(values_.cols());
  if (model.components() != components_)
    throw ArgumentError("cokriging: the model has " + std::to_string(model.components()) + " component(s) but the values have " +
                        std::to_string(components_));
  dimension_ = static_cast<int>(points_.rows());
  sill_ = model.sill();
  nugget_ = model.nugget();
  target_zero_ = options_.nugget == NuggetTreatment::MicroScale ? sill_ : Eigen::MatrixXd(sill_ - nugget_);
  observed_ = values_;
  index_rows();
  simple_mean_ = Eigen::VectorXd::Zero(components_);
  if (options_.kind == KrigingKind::Simple) {
    simple_mean_ = simple_mean_per_component(options_.simple_mean, components_, "cokriging");
    values_.rowwise() -= simple_mean_.transpose();
  }
  switch (options_.kind) {
    case KrigingKind::Simple: drift_terms_ = 0; break;
    case KrigingKind::Ordinary: drift_terms_ = 1; break;
    case KrigingKind::Universal:
      drift_terms_ = 1 + (options_.drift_order >= 1 ? dimension_ : 0) +
                     (options_.drift_order >= 2 ? dimension_ * (dimension_ + 1) / 2 : 0);
      break;
  }
  // Centred, scaled polynomial terms: the same span as the raw monomials, better conditioned.
  drift_center_ = raw_.rowwise().mean();
  drift_scale_ = Eigen::VectorXd::Ones(dimension_);
  for (int k = 0; k < dimension_; ++k) {
    const double s = (raw_.row(k).array() - drift_center_[k]).abs().maxCoeff();
    if (s > 0.0) drift_scale_[k] = s;
  }
  tree_ = std::make_unique<PointTree>(points_);
  refuse_duplicates();
  if (options_.backend == KrigingBackend::Local && options_.neighbour_metric == NeighbourMetric::Euclidean)
    search_tree_ = std::make_unique<PointTree>(raw_);
  if (options_.octant_max > 0 && (search_tree_ ? *search_tree_ : *tree_).dimension() > 3)
    throw ArgumentError("cokriging options: octant_max = " + std::to_string(options_.octant_max) + " with " +
                        std::to_string((search_tree_ ? *search_tree_ : *tree_).dimension()) +
                        " coordinates; octant search is defined for 1 to 3 coordinates");
  if (options_.backend == KrigingBackend::Local && options_.neighbors > 0 &&
      options_.neighbors < static_cast<std::size_t>(std::max(drift_terms_, 1)))
    throw ArgumentError("cokriging options: neighbors = " + std::to_string(options_.neighbors) + " but " +
                        std::string(kriging_kind_name(options_.kind)) + " cokriging here has " +
                        std::to_string(drift_terms_) + " drift terms per component; expected neighbors >= " +
                        std::to_string(std::max(drift_terms_, 1)));
  report_.samples_used = static_cast<std::size_t>(points_.cols());
  report_.drift_terms = static_cast<std::size_t>(drift_terms_ * drift_components_);
  if (points_.cols() < std::max(drift_terms_, 1)) {
    report_.status = KrigingStatus::TooFewSamples;
    report_.message = std::to_string(points_.cols()) + " samples for the " + std::to_string(drift_terms_) +
                      " drift terms per component; need at least as many samples as drift terms";
    return;
  }
  if (options_.backend == KrigingBackend::Dense) setup_dense();
}

void CokrigingEngine::index_rows() {
  const Eigen::Index n = values_.rows();
  row_start_.assign(static_cast<std::size_t>(n) + 1, 0);
  row_component_.clear();
  row_component_.reserve(static_cast<std::size_t>(n * components_));
  std::vector<std::size_t> measured(static_cast<std::size_t>(components_), 0);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (int a = 0; a < components_; ++a)
      if (!std::isnan(values_(i, a))) {
        row_component_.push_back(a);
        ++measured[static_cast<std::size_t>(a)];
      }
    row_start_[static_cast<std::size_t>(i) + 1] = static_cast<Eigen::Index>(row_component_.size());
    if (rows_of(i) == 0) {
      const auto row = static_cast<std::size_t>(i);
      const bool labelled = options_.sample_labels.lines.size() == static_cast<std::size_t>(n);
      throw InputError((labelled ? options_.sample_labels(row) + ": cokriging: this sample"
                                 : "cokriging: sample " + std::to_string(i)) +
                           " has no measured component (every value missing); expected at least one, or leave the sample out",
                       labelled ? options_.sample_labels.source : std::string(), labelled ? options_.sample_labels.line(row) : 0);
    }
  }
  drift_slot_.assign(static_cast<std::size_t>(components_), -1);
  drift_components_ = 0;
  for (int a = 0; a < components_; ++a)
    if (measured[static_cast<std::size_t>(a)] > 0) drift_slot_[static_cast<std::size_t>(a)] = drift_components_++;
}

void CokrigingEngine::validate_options() const {
  const auto refuse = [](const std::string& what, const std::string& instead) {
    throw ArgumentError("cokriging: " + what + " is not supported; " + instead);
  };
  if (options_.backend == KrigingBackend::Sparse) refuse("the sparse back end", "use the dense or local back end");
  if (!options_.covariates.empty()) refuse("external drift (covariates)", "use ordinary or universal cokriging without covariates");
  if (!options_.drift_functions.empty()) refuse("drift_functions", "use the polynomial drift (drift_order)");
  if (options_.keep_weights) refuse("keep_weights", "set it to false");
  if (options_.duplicates == DuplicatePolicy::Average)
    refuse("DuplicatePolicy::Average (merging duplicate samples)", "remove duplicates or average them before cokriging");
}

void CokrigingEngine::refuse_duplicates() const {
  if (const auto pair = first_duplicate(*tree_, points_, options_.duplicate_distance))
    throw_duplicate(*pair, options_.sample_labels, static_cast<std::size_t>(points_.cols()), "cokriging",
                    "); the cokriging matrix would be singular: remove one or average them");
}

void CokrigingEngine::covariance_at(double h, double* out) const {
  const int p = components_;
  std::fill(out, out + p * p, 0.0);
  for (const CoregionalizationStructure& s : structures_) {
    const double c = 1.0 - s.unit_gamma(h);
    if (c == 0.0) continue;
    const double* b = s.sills.data();
    for (int k = 0; k < p * p; ++k) out[k] += c * b[k];
  }
}

void CokrigingEngine::target_block(const double* target, Eigen::Index s, double* out) const {
  const double* x = points_.col(s).data();
  double h2 = 0.0;
  for (int k = 0; k < dimension_; ++k) h2 += (x[k] - target[k]) * (x[k] - target[k]);
  if (h2 == 0.0) std::copy(target_zero_.data(), target_zero_.data() + components_ * components_, out);
  else covariance_at(std::sqrt(h2), out);
}

void CokrigingEngine::drift_row(const double* raw_point, double* out) const {
  if (drift_terms_ == 0) return;
  int t = 0;
  out[t++] = 1.0;
  if (options_.kind != KrigingKind::Universal) return;
  const int d = dimension_;
  if (options_.drift_order >= 1)
    for (int k = 0; k < d; ++k) out[t++] = (raw_point[k] - drift_center_[k]) / drift_scale_[k];
  if (options_.drift_order >= 2)
    for (int k = 0; k < d; ++k)
      for (int l = k; l < d; ++l)
        out[t++] = (raw_point[k] - drift_center_[k]) / drift_scale_[k] * (raw_point[l] - drift_center_[l]) / drift_scale_[l];
}

void CokrigingEngine::setup_dense() {
  const Eigen::Index n = points_.cols(), P = components_, np = static_cast<Eigen::Index>(row_component_.size()),
                     pp = drift_terms_ * drift_components_;
  // K and its factor side by side while factoring; leave-one-out needs one more NP x NP.
  const double bytes = 2.0 * static_cast<double>(np) * static_cast<double>(np) * sizeof(double);
  const double budget = static_cast<double>(options_.dense_memory_budget_bytes);
  if (bytes > budget)
    throw ResourceError("cokriging: the dense back end needs ~" + cokriging_mib(bytes) + " MiB for N = " +
                        std::to_string(n) + " samples of " + std::to_string(P) + " components (an " + std::to_string(np) +
                        " x " + std::to_string(np) + " system), over dense_memory_budget_bytes = " + cokriging_mib(budget) +
                        " MiB; use the local back end (k nearest neighbours)");
  Eigen::MatrixXd k(np, np);
  // The P x P block of samples i, j restricted to the rows the two samples have.
  const auto put = [&](const Eigen::MatrixXd& block, Eigen::Index i, Eigen::Index j) {
    const Eigen::Index ri = row_start_[static_cast<std::size_t>(i)], rj = row_start_[static_cast<std::size_t>(j)];
    for (Eigen::Index v = 0; v < rows_of(j); ++v)
      for (Eigen::Index u = 0; u < rows_of(i); ++u)
        k(ri + u, rj + v) = block(row_component_[static_cast<std::size_t>(ri + u)], row_component_[static_cast<std::size_t>(rj + v)]);
  };
#pragma omp parallel for schedule(dynamic, 16) num_threads(thread_count())
  for (Eigen::Index j = 0; j < n; ++j) {
    Eigen::MatrixXd block(P, P);
    for (Eigen::Index i = j + 1; i < n; ++i) {
      covariance_at((points_.col(i) - points_.col(j)).norm(), block.data());
      put(block, i, j);
    }
    put(sill_, j, j);
  }
  const double scale = sill_.diagonal().maxCoeff();
  double jitter = 0.0;
  for (int attempt = 0;; ++attempt) {
    llt_.compute(k);
    if (llt_.info() == Eigen::Success) break;
    if (attempt >= options_.max_jitter_retries) {
      report_.status = KrigingStatus::NotPositiveDefinite;
      report_.message = "cokriging covariance matrix of the " + std::to_string(n) + " samples (" + std::to_string(np) +
                        " x " + std::to_string(np) + ") is not positive definite" +
                        (jitter > 0 ? " even with jitter " + format_number(jitter) + " on the diagonal" : std::string()) +
                        " (a component that is an exact combination of others without a nugget, or near-duplicate samples)";
      report_.jitter = jitter;
      return;
    }
    const double add = attempt == 0 ? options_.initial_jitter * scale : jitter * (options_.jitter_growth - 1.0);
    k.diagonal().array() += add;
    jitter += add;
  }
  report_.jitter = jitter;
  if (jitter > 0.0) report_.message = "added jitter " + format_number(jitter) + " to the diagonal to factor the covariance";
  k.resize(0, 0);
  const double rcond = llt_.rcond();
  report_.condition_number = rcond > 0.0 ? 1.0 / rcond : std::numeric_limits<double>::infinity();
  if (report_.condition_number > options_.max_condition_number) {
    report_.status = KrigingStatus::IllConditioned;
    report_.message = "cokriging covariance matrix condition number ~" + format_number(report_.condition_number) +
                      " exceeds max_condition_number " + format_number(options_.max_condition_number) +
                      "; predictions are returned but may be inaccurate";
  }
  z_.resize(np);
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index r = row_start_[static_cast<std::size_t>(i)]; r < row_start_[static_cast<std::size_t>(i) + 1]; ++r)
      z_[r] = values_(i, row_component_[static_cast<std::size_t>(r)]);
  Eigen::VectorXd y = llt_.matrixL().solve(z_);
  f_ = Eigen::MatrixXd::Zero(np, pp);
  if (pp > 0) {
    std::vector<double> row(static_cast<std::size_t>(drift_terms_));
    for (Eigen::Index i = 0; i < n; ++i) {
      drift_row(raw_.col(i).data(), row.data());
      for (Eigen::Index r = row_start_[static_cast<std::size_t>(i)]; r < row_start_[static_cast<std::size_t>(i) + 1]; ++r) {
        const int slot = drift_slot_[static_cast<std::size_t>(row_component_[static_cast<std::size_t>(r)])];
        for (Eigen::Index t = 0; t < drift_terms_; ++t) f_(r, slot * drift_terms_ + t) = row[static_cast<std::size_t>(t)];
      }
    }
    q_ = llt_.matrixL().solve(f_);
    g_llt_.compute(q_.transpose() * q_);
    const double g_rcond = g_llt_.info() == Eigen::Success ? g_llt_.rcond() : 0.0;
    if (!(g_rcond > 1e-14)) {
      report_.status = KrigingStatus::SingularDrift;
      report_.message = "the " + std::to_string(drift_terms_) + " drift terms per component are (nearly) linearly "
                        "dependent at the samples (reciprocal condition " + format_number(g_rcond) +
                        "); use a lower drift order or samples that span the coordinates";
      return;
    }
    beta_ = g_llt_.solve(q_.transpose() * y);
    ry_ = y - q_ * beta_;
  } else {
    beta_.resize(0);
    ry_ = y;
  }
  alpha_ = llt_.matrixU().solve(ry_);
}

CokrigingOutput CokrigingEngine::unusable() const {
  CokrigingOutput out;
  out.status = report_.status;
  out.message = report_.message;
  return out;
}

CokrigingOutput CokrigingEngine::predict(const Eigen::MatrixXd& embedded, const Eigen::MatrixXd& raw) const {
  if (!report_.usable()) return unusable();
  return options_.backend == KrigingBackend::Local ? predict_local(embedded, raw, false) : predict_dense(embedded, raw);
}

CokrigingOutput CokrigingEngine::leave_one_out() const {
  if (!report_.usable()) return unusable();
  return options_.backend == KrigingBackend::Local ? predict_local(points_, raw_, true) : loo_dense();
}

CokrigingOutput CokrigingEngine::predict_dense(const Eigen::MatrixXd& embedded, const Eigen::MatrixXd& raw) const {
  const Eigen::Index m = embedded.cols(), n = points_.cols(), P = components_,
                     np = static_cast<Eigen::Index>(row_component_.size()), p = drift_terms_;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  CokrigingOutput out;
  out.status = report_.status;
  out.message = report_.message;
  out.mean.resize(m, P);
  if (options_.compute_variance) out.covariance.resize(m, P * P);
  const auto lower = llt_.matrixL();
  // Targets in fixed batches: one triangular solve with batch * P right-hand sides reads the
  // NP x NP factor once per batch instead of once per target (a target at a time was memory bound:
  // 19 s for N = 1000, P = 3 and 2000 targets). The batches do not depend on the thread count, so
  // neither do the results.
  const auto batch = static_cast<Eigen::Index>(options_.target_batch);
  const Eigen::Index batches = (m + batch - 1) / batch;
#pragma omp parallel num_threads(thread_count())
  {
    Eigen::MatrixXd w, r(p * drift_components_, P), cov(P, P), block(P, P);
    Eigen::VectorXd mean(P), frow(p);
#pragma omp for schedule(dynamic, 1)
    for (Eigen::Index bt = 0; bt < batches; ++bt) {
      const Eigen::Index t0 = bt * batch, nb = std::min(batch, m - t0);
      w.resize(np, nb * P);
      for (Eigen::Index k = 0; k < nb; ++k) {
        const double* target = embedded.col(t0 + k).data();
        for (Eigen::Index i = 0; i < n; ++i) {
          target_block(target, i, block.data());
          for (Eigen::Index row = row_start_[static_cast<std::size_t>(i)]; row < row_start_[static_cast<std::size_t>(i) + 1]; ++row)
            w.block(row, k * P, 1, P) = block.row(row_component_[static_cast<std::size_t>(row)]);
        }
      }
      // Without variances the means are C0' alpha: no solve.
      if (options_.compute_variance) lower.solveInPlace(w);
      for (Eigen::Index k = 0; k < nb; ++k) {
        const Eigen::Index t = t0 + k;
        const auto wt = w.middleCols(k * P, P);
        mean.noalias() = wt.transpose() * (options_.compute_variance ? ry_ : alpha_);
        if (p > 0) {
          drift_row(raw.col(t).data(), frow.data());
          for (Eigen::Index b = 0; b < P; ++b) {
            const int slot = drift_slot_[static_cast<std::size_t>(b)];
            mean[b] = slot < 0 ? nan : mean[b] + frow.dot(beta_.segment(slot * p, p));
          }
        }
        out.mean.row(t) = mean.transpose();
        if (!options_.compute_variance) continue;
        cov = target_zero_;
        cov.noalias() -= wt.transpose() * wt;
        if (p > 0) {
          r.setZero();
          for (Eigen::Index b = 0; b < P; ++b)
            if (const int slot = drift_slot_[static_cast<std::size_t>(b)]; slot >= 0) r.block(slot * p, b, p, 1) = frow;
          r.noalias() -= q_.transpose() * wt;
          g_llt_.matrixL().solveInPlace(r);
          cov.noalias() += r.transpose() * r;
          for (Eigen::Index b = 0; b < P; ++b)
            if (drift_slot_[static_cast<std::size_t>(b)] < 0) {
              cov.row(b).setConstant(nan);
              cov.col(b).setConstant(nan);
            }
        }
        for (Eigen::Index b = 0; b < P; ++b)
          for (Eigen::Index a = 0; a < P; ++a) out.covariance(t, a + P * b) = cov(a, b);
      }
    }
  }
  if (options_.kind == KrigingKind::Simple) out.mean.rowwise() += simple_mean_.transpose();
  return out;
}

CokrigingOutput CokrigingEngine::loo_dense() const {
  // Block form of Dubrule (1983): with A the bordered system [[K, F], [F', 0]] and B = A^-1, the
  // residual of sample i's P observations when they are left out is B_ii^-1 (B [z; 0])_i and its
  // covariance is B_ii^-1, B_ii the P x P diagonal block of sample i in B's top-left NP x NP part,
  // K^-1 - K^-1 F G^-1 F'K^-1.
  const Eigen::Index n = points_.cols(), P = components_, np = static_cast<Eigen::Index>(row_component_.size());
  const double bytes = 2.0 * static_cast<double>(np) * static_cast<double>(np) * sizeof(double);
  if (bytes > static_cast<double>(options_.dense_memory_budget_bytes))
    throw ResourceError("cokriging: leave-one-out with the dense back end needs ~" + cokriging_mib(bytes) +
                        " MiB more for N = " + std::to_string(n) + " samples of " + std::to_string(P) +
                        " components, over dense_memory_budget_bytes; use the local back end");
  Eigen::MatrixXd b = llt_.solve(Eigen::MatrixXd::Identity(np, np));
  if (drift_terms_ > 0) {
    const Eigen::MatrixXd kinv_f = llt_.solve(f_);
    const Eigen::MatrixXd lg_inv_t = g_llt_.matrixL().solve(kinv_f.transpose());  // Lg^-1 F'K^-1
    b.noalias() -= lg_inv_t.transpose() * lg_inv_t;
  }
  const Eigen::VectorXd alpha = b * z_;
  CokrigingOutput out;
  out.status = report_.status;
  out.message = report_.message;
  out.mean.resize(n, P);
  out.residual.resize(n, P);
  out.covariance.resize(n, P * P);
  // A component not measured at sample i has no residual there: NaN in every output.
  out.mean.setConstant(std::numeric_limits<double>::quiet_NaN());
  out.residual.setConstant(std::numeric_limits<double>::quiet_NaN());
  out.covariance.setConstant(std::numeric_limits<double>::quiet_NaN());
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Index r0 = row_start_[static_cast<std::size_t>(i)], mi = rows_of(i);
    const Eigen::MatrixXd bii = b.block(r0, r0, mi, mi);
    const Eigen::MatrixXd cov = bii.llt().solve(Eigen::MatrixXd::Identity(mi, mi));
    const Eigen::VectorXd e = cov * alpha.segment(r0, mi);
    for (Eigen::Index u = 0; u < mi; ++u) {
      const int a = row_component_[static_cast<std::size_t>(r0 + u)];
      out.residual(i, a) = e[u];
      out.mean(i, a) = observed_(i, a) - e[u];
      for (Eigen::Index v = 0; v < mi; ++v)
        out.covariance(i, a + P * row_component_[static_cast<std::size_t>(r0 + v)]) = cov(u, v);
    }
  }
  return out;
}

CokrigingOutcome CokrigingEngine::local_rows(CokrigingWorkspace& ws, Eigen::Index& present) const {
  const auto nn = static_cast<Eigen::Index>(ws.chosen.size());
  const Eigen::Index P = components_, p = drift_terms_;
  // The rows of the chosen samples (one per measured component) and the components they cover.
  ws.row_sample.clear();
  ws.row_component.clear();
  ws.slot.assign(static_cast<std::size_t>(P), 0);
  for (Eigen::Index j = 0; j < nn; ++j) {
    const auto sj = static_cast<Eigen::Index>(ws.chosen[static_cast<std::size_t>(j)]);
    for (Eigen::Index r = row_start_[static_cast<std::size_t>(sj)]; r < row_start_[static_cast<std::size_t>(sj) + 1]; ++r) {
      ws.row_sample.push_back(sj);
      ws.row_component.push_back(row_component_[static_cast<std::size_t>(r)]);
      ++ws.slot[static_cast<std::size_t>(row_component_[static_cast<std::size_t>(r)])];
    }
  }
  const auto np = static_cast<Eigen::Index>(ws.row_sample.size());
  if (np == 0) return CokrigingOutcome::TooFew;
  present = 0;
  for (Eigen::Index a = 0; a < P; ++a) {
    const int count = ws.slot[static_cast<std::size_t>(a)];
    if (count > 0 && count < p) return CokrigingOutcome::TooFew;
    ws.slot[static_cast<std::size_t>(a)] = count > 0 ? static_cast<int>(present++) : -1;
  }
  return CokrigingOutcome::Ok;
}

bool CokrigingEngine::factor_local(CokrigingWorkspace& ws, Eigen::Index np, double* bp) const {
  const Eigen::Index P = components_;
  auto kb = ws.k.topLeftCorner(np, np);
  const auto entry = [&](Eigen::Index r, Eigen::Index c) {
    return bp[ws.row_component[static_cast<std::size_t>(r)] + P * ws.row_component[static_cast<std::size_t>(c)]];
  };
  const auto build = [&](double jitter) {
    // Rows of one sample are adjacent; a sample's block with another is computed once.
    for (Eigen::Index c0 = 0; c0 < np;) {
      const Eigen::Index sc = ws.row_sample[static_cast<std::size_t>(c0)];
      Eigen::Index c1 = c0;
      while (c1 < np && ws.row_sample[static_cast<std::size_t>(c1)] == sc) ++c1;
      std::copy(sill_.data(), sill_.data() + P * P, bp);
      for (Eigen::Index c = c0; c < c1; ++c) {
        for (Eigen::Index r = c0; r < c1; ++r) kb(r, c) = entry(r, c);
        kb(c, c) += jitter;
      }
      for (Eigen::Index r0 = c1; r0 < np;) {
        const Eigen::Index sr = ws.row_sample[static_cast<std::size_t>(r0)];
        Eigen::Index r1 = r0;
        while (r1 < np && ws.row_sample[static_cast<std::size_t>(r1)] == sr) ++r1;
        covariance_at((points_.col(sr) - points_.col(sc)).norm(), bp);
        for (Eigen::Index c = c0; c < c1; ++c)
          for (Eigen::Index r = r0; r < r1; ++r) kb(r, c) = entry(r, c);
        r0 = r1;
      }
      c0 = c1;
    }
  };
  const double scale = sill_.diagonal().maxCoeff();
  double jitter = 0.0;
  for (int attempt = 0; attempt <= options_.max_jitter_retries; ++attempt) {
    build(jitter);
    Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> llt(kb);
    if (llt.info() == Eigen::Success) return true;
    jitter = attempt == 0 ? options_.initial_jitter * scale : jitter * options_.jitter_growth;
  }
  return false;
}

void CokrigingEngine::local_right_hand_sides(const double* target, CokrigingWorkspace& ws, Eigen::Index np,
                                             double* bp) const {
  const Eigen::Index P = components_;
  const auto lower = ws.k.topLeftCorner(np, np).triangularView<Eigen::Lower>();
  auto w = ws.w.topRows(np);
  auto y = ws.y.head(np);
  for (Eigen::Index r0 = 0; r0 < np;) {
    const Eigen::Index s = ws.row_sample[static_cast<std::size_t>(r0)];
    target_block(target, s, bp);
    const Eigen::Map<const Eigen::MatrixXd> tb(bp, P, P);
    for (; r0 < np && ws.row_sample[static_cast<std::size_t>(r0)] == s; ++r0) {
      const int a = ws.row_component[static_cast<std::size_t>(r0)];
      w.row(r0) = tb.row(a);
      y[r0] = values_(s, a);
    }
  }
  lower.solveInPlace(w);
  lower.solveInPlace(y);
}

bool CokrigingEngine::local_drift(const double* target_raw, CokrigingWorkspace& ws, Eigen::Index np,
                                  Eigen::Index pp) const {
  const Eigen::Index P = components_, p = drift_terms_;
  const auto lower = ws.k.topLeftCorner(np, np).triangularView<Eigen::Lower>();
  auto w = ws.w.topRows(np);
  auto y = ws.y.head(np);
  auto q = ws.q.topLeftCorner(np, pp);
  auto f0 = ws.f0.topRows(pp);
  auto beta = ws.beta.head(pp);
  auto r = ws.r.topRows(pp);
  q.setZero();
  f0.setZero();
  double frow[16];
  std::vector<double> frow_big;
  double* fp = frow;
  if (p > 16) {
    frow_big.resize(static_cast<std::size_t>(p));
    fp = frow_big.data();
  }
  for (Eigen::Index i = 0; i < np; ++i) {
    drift_row(raw_.col(ws.row_sample[static_cast<std::size_t>(i)]).data(), fp);
    const int slot = ws.slot[static_cast<std::size_t>(ws.row_component[static_cast<std::size_t>(i)])];
    for (Eigen::Index t = 0; t < p; ++t) q(i, slot * p + t) = fp[t];
  }
  drift_row(target_raw, fp);
  for (Eigen::Index b = 0; b < P; ++b)
    if (const int slot = ws.slot[static_cast<std::size_t>(b)]; slot >= 0)
      for (Eigen::Index t = 0; t < p; ++t) f0(slot * p + t, b) = fp[t];
  lower.solveInPlace(q);
  auto g = ws.g.topLeftCorner(pp, pp);
  g.noalias() = q.transpose() * q;
  Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> g_llt(g);
  if (g_llt.info() != Eigen::Success || !(g_llt.rcond() > 1e-14)) return false;
  beta.noalias() = q.transpose() * y;
  g_llt.solveInPlace(beta);
  y.noalias() -= q * beta;
  ws.mean.noalias() = f0.transpose() * beta;
  ws.mean.noalias() += w.transpose() * y;
  r = f0;
  r.noalias() -= q.transpose() * w;
  g_llt.matrixL().solveInPlace(r);
  ws.cov.noalias() += r.transpose() * r;
  // A component with no row here has no unbiased predictor (see the top of the file).
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (Eigen::Index b = 0; b < P; ++b)
    if (ws.slot[static_cast<std::size_t>(b)] < 0) {
      ws.mean[b] = nan;
      ws.cov.row(b).setConstant(nan);
      ws.cov.col(b).setConstant(nan);
    }
  return true;
}

CokrigingOutcome CokrigingEngine::solve_local(const double* target, const double* target_raw, CokrigingWorkspace& ws) const {
  const Eigen::Index P = components_, p = drift_terms_;
  Eigen::Index present = 0;
  if (const CokrigingOutcome rows = local_rows(ws, present); rows != CokrigingOutcome::Ok) return rows;
  const auto np = static_cast<Eigen::Index>(ws.row_sample.size());
  const Eigen::Index pp = p * present;
  if (ws.k.rows() < np) {
    ws.k.resize(np, np);
    ws.w.resize(np, P);
    ws.q.resize(np, p * P);
    ws.y.resize(np);
  }
  if (ws.cov.rows() != P) {
    ws.cov.resize(P, P);
    ws.mean.resize(P);
    ws.f0.resize(p * P, P);
    ws.g.resize(p * P, p * P);
    ws.r.resize(p * P, P);
    ws.beta.resize(p * P);
  }
  double block[64];  // P * P doubles for P <= 8, else big_block
  Eigen::MatrixXd big_block;
  double* bp = block;
  if (P * P > 64) {
    big_block.resize(P, P);
    bp = big_block.data();
  }
  if (!factor_local(ws, np, bp)) return CokrigingOutcome::NotPositiveDefinite;
  local_right_hand_sides(target, ws, np, bp);
  auto w = ws.w.topRows(np);
  ws.cov = target_zero_;
  ws.cov.noalias() -= w.transpose() * w;
  if (p > 0) {
    if (!local_drift(target_raw, ws, np, pp)) return CokrigingOutcome::SingularDrift;
  } else {
    ws.mean.noalias() = w.transpose() * ws.y.head(np);
  }
  return CokrigingOutcome::Ok;
}

CokrigingOutput CokrigingEngine::predict_local(const Eigen::MatrixXd& embedded, const Eigen::MatrixXd& raw,
                                               bool leave_one_out) const {
  const Eigen::Index m = embedded.cols(), P = components_;
  const bool want_cov = options_.compute_variance || leave_one_out;
  const std::size_t n_samples = static_cast<std::size_t>(points_.cols());
  const std::size_t k_max = options_.neighbors;
  const NeighbourRule rule =
      NeighbourRule::from(options_.neighbors, options_.radius, options_.min_neighbours, options_.octant_max);
  const int threads = thread_count();
  const double budget = static_cast<double>(options_.dense_memory_budget_bytes);
  // One kP x kP system per thread (plus its kP-row blocks).
  const auto system_bytes = [&](std::size_t k) {
    const double np = static_cast<double>(k) * static_cast<double>(P);
    return sizeof(double) * (np * np + np * (P + P * drift_terms_ + 1.0)) * threads;
  };
  const auto over_budget = [&](std::size_t k, const std::string& what) {
    return ResourceError("cokriging: the local back end with " + what + " solves a " + std::to_string(k * P) + " x " +
                         std::to_string(k * P) + " system per target, ~" + cokriging_mib(system_bytes(k)) + " MiB for " +
                         std::to_string(threads) + " thread(s), over the memory budget of " + cokriging_mib(budget) +
                         " MiB (dense_memory_budget_bytes); use fewer neighbours (20 to 100 is usual)");
  };
  const std::size_t k_query = k_max > 0 ? std::min(k_max + (leave_one_out ? 1 : 0), n_samples) : 0;
  if (k_max > 0 && system_bytes(std::min(k_max, n_samples)) > budget)
    throw over_budget(std::min(k_max, n_samples), "neighbors = " + std::to_string(k_max));
  std::atomic<std::size_t> largest_over{0};

  CokrigingOutput out;
  out.mean.resize(m, P);
  if (want_cov) out.covariance.resize(m, P * P);
  if (leave_one_out) out.residual.resize(m, P);
  std::vector<CokrigingOutcome> outcome(static_cast<std::size_t>(m), CokrigingOutcome::Ok);
  const double nan = std::numeric_limits<double>::quiet_NaN();

#pragma omp parallel num_threads(threads)
  {
    CokrigingWorkspace ws;
    ws.size_for(k_query);
#pragma omp for schedule(dynamic, 64)
    for (Eigen::Index t = 0; t < m; ++t) {
      // Neighbours by the model's lag, or by the raw coordinates (NeighbourMetric::Euclidean).
      const PointTree& tree = search_tree_ ? *search_tree_ : *tree_;
      const double* target = embedded.col(t).data();
      const double* query = search_tree_ ? raw.col(t).data() : target;
      const std::size_t self = leave_one_out ? static_cast<std::size_t>(t) : n_samples;
      CokrigingOutcome o = CokrigingOutcome::Ok;
      if (!select_neighbours(tree, query, rule, self, ws)) {
        o = CokrigingOutcome::BelowMinimum;
      } else if (k_max == 0 && system_bytes(ws.chosen.size()) > budget) {
        std::size_t seen = largest_over.load();
        while (ws.chosen.size() > seen && !largest_over.compare_exchange_weak(seen, ws.chosen.size())) {
        }
        o = CokrigingOutcome::OverBudget;
      } else {
        o = solve_local(target, raw.col(t).data(), ws);
      }
      outcome[static_cast<std::size_t>(t)] = o;
      if (o != CokrigingOutcome::Ok) {
        out.mean.row(t).setConstant(nan);
        if (want_cov) out.covariance.row(t).setConstant(nan);
        if (leave_one_out) out.residual.row(t).setConstant(nan);
        continue;
      }
      if (options_.kind == KrigingKind::Simple) ws.mean += simple_mean_;
      out.mean.row(t) = ws.mean.transpose();
      if (leave_one_out) out.residual.row(t) = observed_.row(t) - ws.mean.transpose();
      if (!want_cov) continue;
      // Leave-one-out: the residual of the observation carries its own noise (the nugget matrix
      // when the nugget is measurement error).
      if (leave_one_out && options_.nugget == NuggetTreatment::MeasurementError) ws.cov += nugget_;
      for (Eigen::Index b = 0; b < P; ++b)
        for (Eigen::Index a = 0; a < P; ++a) out.covariance(t, a + P * b) = ws.cov(a, b);
    }
  }
  if (largest_over.load() > 0)
    throw over_budget(largest_over.load(), "radius = " + format_number(options_.radius) + " and no neighbour count");

  out.status = report_.status;
  out.message = report_.message;
  report_local_failures(outcome, leave_one_out, options_.min_neighbours, out);
  return out;
}

std::shared_ptr<const CokrigingEngine> make_cokriging_engine(Eigen::MatrixXd embedded, Eigen::MatrixXd raw,
                                                             Eigen::MatrixXd values,
                                                             const CoregionalizationModel& model,
                                                             const KrigingOptions& options) {
  return std::make_shared<const CokrigingEngine>(std::move(embedded), std::move(raw), std::move(values), model, options);
}

const KrigingReport& cokriging_report(const CokrigingEngine& engine) { return engine.report(); }

CokrigingOutput cokriging_predict(const CokrigingEngine& engine, const Eigen::MatrixXd& embedded,
                                  const Eigen::MatrixXd& raw) {
  return engine.predict(embedded, raw);
}

CokrigingOutput cokriging_leave_one_out(const CokrigingEngine& engine) { return engine.leave_one_out(); }

}  // namespace errfield::detail
