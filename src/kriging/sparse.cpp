// Sparse back end: a compactly supported covariance (sph, wen, + nugget) is zero beyond the
// model's support, so K has only the pairs closer than that (found with the kd-tree). CHOLMOD
// factors it once. Means: c0'alpha over the few samples within the support, OpenMP over targets.
// Variances: |L^-1 P c0|^2 from batched forward solves (O(nnz(L)) per target, serialized).

#include <algorithm>
#include <cmath>

#include <omp.h>

#include "errfield/csv_table.hpp"
#include "kriging/cholmod_factor.hpp"
#include "kriging/kriging_engine.hpp"

namespace errfield::detail {

namespace {
std::string mib(double bytes) { return format_number(std::round(bytes / (1 << 20))); }
}  // namespace

ResourceError KrigingEngine::sparse_over_budget(const std::string& what) const {
  return ResourceError("kriging: the sparse back end with N = " + std::to_string(points_.cols()) +
                       " samples and a support of " + format_number(model_.support()) + ": " + what +
                       ", over the memory budget of " +
                       mib(static_cast<double>(options_.dense_memory_budget_bytes)) +
                       " MiB (dense_memory_budget_bytes); use a model with a shorter range (the sparse back end "
                       "pays off when each sample has few others within the range) or the local back end "
                       "(--backend local --neighbors 32)");
}

// The lower triangle of K holds one entry per pair closer than the support; a range covering
// everything makes it dense (N = 30,000: 4.5e8 entries, ~18 GB while being assembled). Counted on
// an evenly spaced subset of samples, before anything is allocated.
void KrigingEngine::check_sparse_budget_before_assembly(double r2) const {
  const Eigen::Index n = points_.cols();
  const Eigen::Index probes = std::min<Eigen::Index>(n, 256);
  std::vector<std::pair<std::size_t, double>> hits;
  double found = 0.0;
  for (Eigen::Index a = 0; a < probes; ++a) {
    tree_->within(points_.col(a * n / probes).data(), r2, hits);
    found += static_cast<double>(hits.size());
  }
  const double entries = (found / static_cast<double>(probes) * static_cast<double>(n) + static_cast<double>(n)) / 2;
  // pair<int,double> while gathering, then CSC (int + double) twice: ours and CHOLMOD's copy
  const double bytes = entries * (16.0 + 12.0 + 12.0);
  if (bytes > static_cast<double>(options_.dense_memory_budget_bytes))
    throw sparse_over_budget("about " + format_number(std::round(entries)) +
                             " pairs closer than the support make K nearly dense, ~" + mib(bytes) +
                             " MiB to assemble");
}

void KrigingEngine::setup_sparse() {
  const Eigen::Index n = points_.cols();
  if (n > std::numeric_limits<int>::max() / 2)
    throw ResourceError("kriging: the sparse back end supports up to 1e9 samples");
  const double support = model_.support();
  const double r2 = support * support;
  check_sparse_budget_before_assembly(r2);
  // Column j holds rows i >= j (lower triangle) with C(h_ij) != 0.
  std::vector<std::vector<std::pair<int, double>>> columns(static_cast<std::size_t>(n));
#pragma omp parallel num_threads(thread_count())
  {
    std::vector<std::pair<std::size_t, double>> hits;
#pragma omp for schedule(dynamic, 256)
    for (Eigen::Index j = 0; j < n; ++j) {
      tree_->within(points_.col(j).data(), r2, hits);
      auto& col = columns[static_cast<std::size_t>(j)];
      col.reserve(hits.size());
      for (const auto& [i, d2] : hits) {
        if (static_cast<Eigen::Index>(i) < j) continue;
        const double v = static_cast<Eigen::Index>(i) == j ? obs_var_[j]
                                                           : kernel_.at_positive_lag(std::sqrt(d2));
        if (v != 0.0 || static_cast<Eigen::Index>(i) == j) col.emplace_back(static_cast<int>(i), v);
      }
      std::sort(col.begin(), col.end());
    }
  }
  std::vector<int> col_ptr(static_cast<std::size_t>(n) + 1, 0), row_index;
  std::vector<double> vals;
  for (Eigen::Index j = 0; j < n; ++j)
    col_ptr[static_cast<std::size_t>(j) + 1] = col_ptr[static_cast<std::size_t>(j)] +
                                               static_cast<int>(columns[static_cast<std::size_t>(j)].size());
  row_index.reserve(static_cast<std::size_t>(col_ptr.back()));
  vals.reserve(static_cast<std::size_t>(col_ptr.back()));
  for (auto& col : columns) {
    for (const auto& [i, v] : col) {
      row_index.push_back(i);
      vals.push_back(v);
    }
    std::vector<std::pair<int, double>>().swap(col);
  }

  sparse_ = std::make_unique<CholmodFactor>();
  if (!sparse_->analyze(static_cast<int>(n), col_ptr, row_index, vals)) {
    report_.status = KrigingStatus::NotPositiveDefinite;
    report_.message = sparse_->message();
    return;
  }
  // The fill-reducing ordering predicts the factor exactly; refuse before the numeric factor
  // allocates it.
  const double factor_bytes = sparse_->predicted_factor_bytes();
  if (factor_bytes > static_cast<double>(options_.dense_memory_budget_bytes))
    throw sparse_over_budget("its Cholesky factor would hold ~" + mib(factor_bytes) + " MiB (" +
                             std::to_string(col_ptr.back()) + " non-zeros in K fill in)");
  double jitter = 0.0;
  for (int attempt = 0;; ++attempt) {
    if (sparse_->factorize(static_cast<int>(n), col_ptr, row_index, vals, jitter)) break;
    if (attempt >= options_.max_jitter_retries) {
      report_.status = KrigingStatus::NotPositiveDefinite;
      report_.message = sparse_->message() +
                        (jitter > 0 ? " (even with jitter " + format_number(jitter) + " on the diagonal)" : std::string());
      report_.jitter = jitter;
      return;
    }
    jitter = attempt == 0 ? options_.initial_jitter * kernel_.sill() : jitter * options_.jitter_growth;
  }
  report_.jitter = jitter;
  if (jitter > 0.0) report_.message = "added jitter " + format_number(jitter) + " to the diagonal to factor the covariance";
  // CHOLMOD's estimate is (min diag L / max diag L)^2 for L L': a rough, optimistic estimate.
  check_condition(sparse_->rcond());

  Eigen::MatrixXd x = values_;
  sparse_->solve(x);  // K^-1 z
  if (drift_terms_ > 0) {
    kinv_f_ = f_;
    sparse_->solve(kinv_f_);
    g_llt_.compute(f_.transpose() * kinv_f_);
    const double g_rcond = g_llt_.info() == Eigen::Success ? g_llt_.rcond() : 0.0;
    if (!(g_rcond > 1e-14)) {
      report_.status = KrigingStatus::SingularDrift;
      report_.message = singular_drift_message(g_rcond);
      return;
    }
    beta_ = g_llt_.solve(f_.transpose() * x);
    x -= kinv_f_ * beta_;
  } else {
    beta_.resize(0, components_);
  }
  alpha_ = std::move(x);
}

KrigingOutput KrigingEngine::predict_sparse(const Eigen::MatrixXd& embedded, const Eigen::MatrixXd& raw) const {
  const Eigen::Index n = points_.cols(), m = embedded.cols(), p = drift_terms_;
  const double c00 = target_variance();
  const double support = model_.support();
  const double r2 = support * support;
  const Eigen::MatrixXd f0_all = drift_matrix(raw);
  KrigingOutput out;
  out.status = report_.status;
  out.message = report_.message;
  out.mean.resize(m, components_);
  if (p > 0) out.mean.noalias() = f0_all.transpose() * beta_;
  else out.mean.setZero();

#pragma omp parallel num_threads(thread_count())
  {
    std::vector<std::pair<std::size_t, double>> hits;
#pragma omp for schedule(dynamic, 256)
    for (Eigen::Index t = 0; t < m; ++t) {
      tree_->within(embedded.col(t).data(), r2, hits);
      for (const auto& [i, d2] : hits)
        out.mean.row(t) += kernel_(std::sqrt(d2), c00) * alpha_.row(static_cast<Eigen::Index>(i));
    }
  }
  add_simple_mean(out.mean);
  if (!options_.compute_variance) return out;

  out.variance.resize(m);
  const Eigen::Index batch = static_cast<Eigen::Index>(std::min<std::size_t>(options_.target_batch, 64));
  Eigen::MatrixXd b;
  std::vector<std::pair<std::size_t, double>> hits;
  std::lock_guard<std::mutex> lock(sparse_->mutex());
  for (Eigen::Index start = 0; start < m; start += batch) {
    const Eigen::Index cnt = std::min(batch, m - start);
    b.setZero(n, cnt);
    for (Eigen::Index k = 0; k < cnt; ++k) {
      tree_->within(embedded.col(start + k).data(), r2, hits);
      for (const auto& [i, d2] : hits) b(static_cast<Eigen::Index>(i), k) = kernel_(std::sqrt(d2), c00);
    }
    Eigen::MatrixXd kinv_f_t_c0;
    if (p > 0) kinv_f_t_c0 = kinv_f_.transpose() * b;  // F'K^-1 c0, p x cnt
    sparse_->solve_forward(b);
    Eigen::VectorXd var = (c00 - b.colwise().squaredNorm().array()).transpose();
    if (p > 0) {
      Eigen::MatrixXd r = f0_all.middleCols(start, cnt) - kinv_f_t_c0;
      g_llt_.matrixL().solveInPlace(r);
      var += r.colwise().squaredNorm().transpose();
    }
    out.variance.segment(start, cnt) = var.cwiseMax(0.0);
  }
  return out;
}

}  // namespace errfield::detail
