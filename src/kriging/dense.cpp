// Dense back end: one Cholesky factorization of the N x N covariance; predictions in batches of
// targets, means from the precomputed alpha/beta (O(N) per target), variances from one blocked
// triangular solve per batch. OpenMP over batches, one workspace per thread.

#include <algorithm>
#include <cmath>

#include <omp.h>

#include "errfield/csv_table.hpp"
#include "kriging/kriging_engine.hpp"
#include "dense_cholesky.hpp"
#include "lower_triangular_solve.hpp"

namespace errfield::detail {

void KrigingEngine::setup_dense() {
  const auto n = static_cast<std::size_t>(points_.cols());
  // K and its factor live side by side while factoring; then the factor and its packed copy for
  // the variance kernel (~N^2/2). Leave-one-out needs one more N x N, checked when asked.
  const double bytes = 2.0 * static_cast<double>(n) * static_cast<double>(n) * sizeof(double);
  if (bytes > static_cast<double>(options_.dense_memory_budget_bytes))
    throw ResourceError("kriging: the dense back end needs ~" + format_number(std::round(bytes / (1 << 20))) +
                        " MiB for N = " + std::to_string(n) + " samples, over dense_memory_budget_bytes = " +
                        format_number(std::round(static_cast<double>(options_.dense_memory_budget_bytes) / (1 << 20))) +
                        " MiB; use the local back end (k nearest neighbours) or, with a compactly supported "
                        "model (sph, wen), the sparse back end");
  const auto ni = static_cast<Eigen::Index>(n);
  Eigen::MatrixXd k(ni, ni);
  const double zero = kernel_.sill();
#pragma omp parallel for schedule(dynamic, 16) num_threads(thread_count())
  for (Eigen::Index j = 0; j < ni; ++j) {
    // lower triangle only (LLT reads nothing else): points j..N-1 against point j
    kernels::covariance_block(kernel_, points_.col(j).data(), static_cast<std::size_t>(ni - j), points_.col(j).data(), 1,
                              dimension_, zero, &k(j, j), static_cast<std::size_t>(ni));
  }
  k.diagonal() = obs_var_;

  double jitter = 0.0;
  for (int attempt = 0;; ++attempt) {
    llt_.compute(k);
    if (llt_.info() == Eigen::Success) break;
    if (attempt >= options_.max_jitter_retries) {
      report_.status = KrigingStatus::NotPositiveDefinite;
      report_.message = "covariance matrix of the " + std::to_string(n) +
                        " samples is not positive definite" +
                        (jitter > 0 ? " even with jitter " + format_number(jitter) + " on the diagonal" : std::string()) +
                        " (check for near-duplicate samples or an invalid model)";
      report_.jitter = jitter;
      return;
    }
    const double add = attempt == 0 ? options_.initial_jitter * kernel_.sill()
                                    : jitter * (options_.jitter_growth - 1.0);
    k.diagonal().array() += add;
    jitter += add;
  }
  report_.jitter = jitter;
  if (jitter > 0.0)
    report_.message = "added jitter " + format_number(jitter) + " to the diagonal to factor the covariance";
  k.resize(0, 0);
  check_condition(llt_.rcond());
  if (options_.compute_variance && kernels::lower_solve_fast_available())
    packed_l_ = kernels::pack_lower(llt_.matrixLLT().data(), n, n);

  const auto& l = llt_.matrixL();
  Eigen::MatrixXd y = values_;
  l.solveInPlace(y);
  if (drift_terms_ > 0) {
    q_ = f_;
    l.solveInPlace(q_);
    g_llt_.compute(q_.transpose() * q_);
    const double g_rcond = g_llt_.info() == Eigen::Success ? g_llt_.rcond() : 0.0;
    if (!(g_rcond > 1e-14)) {
      report_.status = KrigingStatus::SingularDrift;
      report_.message = singular_drift_message(g_rcond);
      return;
    }
    beta_ = g_llt_.solve(q_.transpose() * y);
    y -= q_ * beta_;
  } else {
    beta_.resize(0, components_);
  }
  alpha_ = y;
  llt_.matrixU().solveInPlace(alpha_);
}

KrigingOutput KrigingEngine::predict_dense(const Eigen::MatrixXd& embedded, const Eigen::MatrixXd& raw,
                                           const Eigen::VectorXd& block_weights, bool with_weights) const {
  const Eigen::Index group = std::max<Eigen::Index>(1, block_weights.size());
  const Eigen::Index n = points_.cols(), m = embedded.cols() / group, p = drift_terms_;
  // blocks: a batch's block points share the workspace of a batch of points
  const Eigen::Index batch = std::max<Eigen::Index>(1, static_cast<Eigen::Index>(options_.target_batch) / group);
  const bool want_var = options_.compute_variance, want_w = options_.keep_weights || with_weights;
  const double c00 = block_variance(embedded, block_weights);      // the target's own variance (a block's average)
  const double zero_lag = target_variance();              // C(0) between a sample and a target point
  // ... and between a sample and a block's point: C(0+), the nugget averages out over a block (as in
  // gstat; C(0) would make the result jump when a discretization point meets a sample).
  const double block_zero_lag = kernel_.sill() - kernel_.nugget();
  const Eigen::MatrixXd f0_all = block_drift_matrix(raw, block_weights);  // p x M (validated before the parallel region)
  KrigingOutput out;
  out.status = report_.status;
  out.message = report_.message;
  out.mean.resize(m, components_);
  if (want_var) out.variance.resize(m);
  Eigen::MatrixXd weights;
  if (want_w) weights.resize(n, m);
  const Eigen::Index batches = (m + batch - 1) / batch;

#pragma omp parallel num_threads(thread_count())
  {
    // one workspace per thread, allocated once
    Eigen::MatrixXd c0(n, batch), w, r, s, block_points;
    if (want_w) w.resize(n, batch);
    if (group > 1) block_points.resize(n, batch * group);
#pragma omp for schedule(dynamic, 1)
    for (Eigen::Index b = 0; b < batches; ++b) {
      const Eigen::Index start = b * batch, cnt = std::min(batch, m - start);
      if (group == 1) {
        kernels::covariance_block(kernel_, points_.data(), static_cast<std::size_t>(n), embedded.col(start).data(),
                                  static_cast<std::size_t>(cnt), dimension_, zero_lag, c0.data(), static_cast<std::size_t>(n));
      } else {
        kernels::covariance_block(kernel_, points_.data(), static_cast<std::size_t>(n), embedded.col(start * group).data(),
                                  static_cast<std::size_t>(cnt * group), dimension_, block_zero_lag, block_points.data(),
                                  static_cast<std::size_t>(n));
        for (Eigen::Index t = 0; t < cnt; ++t) c0.col(t).noalias() = block_points.middleCols(t * group, group) * block_weights;
      }
      auto c = c0.leftCols(cnt);
      auto f0 = f0_all.middleCols(start, cnt);
      out.mean.middleRows(start, cnt).noalias() = c.transpose() * alpha_;
      if (p > 0) out.mean.middleRows(start, cnt).noalias() += f0.transpose() * beta_;
      if (!want_var && !want_w) continue;
      // c := W = L^-1 c0, the O(N^2) per target part: the AVX2/FMA kernel where the CPU has it
      // (Eigen's solve is SSE2-only in the default x86-64 build), else Eigen.
      if (packed_l_.n == static_cast<std::size_t>(n))
        kernels::lower_solve(packed_l_, c.data(), static_cast<std::size_t>(n), static_cast<std::size_t>(cnt));
      else
        llt_.matrixL().solveInPlace(c);
      if (want_var) out.variance.segment(start, cnt) = (c00 - c.colwise().squaredNorm().array()).transpose();
      if (p > 0) {
        r.noalias() = f0 - q_.transpose() * c;  // p x cnt
        s = r;
        g_llt_.matrixL().solveInPlace(s);
        if (want_var) out.variance.segment(start, cnt) += s.colwise().squaredNorm().transpose();
      }
      if (want_w) {
        auto wb = w.leftCols(cnt);
        wb = c;
        if (p > 0) wb.noalias() += q_ * g_llt_.solve(r);
        // Eigen's solve with a matrix right-hand side packs the whole N x N factor first: for the
        // one or few targets of a row-by-row caller (compensate, validate's orientation per pose)
        // that copy was most of the time (45 % of a real 831-pose validation). A vector solve reads
        // the factor in place.
        if (cnt < 8)
          for (Eigen::Index t = 0; t < cnt; ++t) llt_.matrixU().solveInPlace(wb.col(t));
        else
          llt_.matrixU().solveInPlace(wb);
        weights.middleCols(start, cnt) = wb;
      }
    }
  }
  // Rounding can leave variances of order -1e-16 * sill at the data; clamp them to 0.
  if (want_var) out.variance = out.variance.cwiseMax(0.0);
  add_simple_mean(out.mean);
  if (want_w) {
    out.weights.offset.resize(static_cast<std::size_t>(m) + 1);
    out.weights.sample.resize(static_cast<std::size_t>(n * m));
    out.weights.weight.assign(weights.data(), weights.data() + n * m);
    for (Eigen::Index t = 0; t <= m; ++t) out.weights.offset[static_cast<std::size_t>(t)] = static_cast<std::size_t>(t * n);
    for (Eigen::Index t = 0; t < m; ++t)
      for (Eigen::Index i = 0; i < n; ++i)
        out.weights.sample[static_cast<std::size_t>(t * n + i)] = original_index_[static_cast<std::size_t>(i)];
  }
  return out;
}

const Eigen::VectorXd& KrigingEngine::loo_precision_diagonal() const {
  std::call_once(pdiag_once_, [this] { pdiag_ = compute_loo_precision_diagonal(); });
  return pdiag_;
}

Eigen::VectorXd KrigingEngine::compute_loo_precision_diagonal() const {
  const Eigen::Index n = points_.cols();
  // diag(K^-1)_j = |L^-1 e_j|^2, and L^-1 e_j is zero above row j: each block of columns [c, c+w)
  // needs only the trailing triangle L[c:, c:], so the whole diagonal costs n^3/3 flops (not the n^3
  // of L^-1 I) and w columns of workspace per thread (not n^2). Blocks are fixed by n alone, so the
  // result does not depend on the thread count.
  constexpr Eigen::Index kWidth = 64;
  const Eigen::Index blocks = (n + kWidth - 1) / kWidth;
  const auto& l = llt_.matrixLLT();
  Eigen::VectorXd pdiag(n);
#pragma omp parallel num_threads(thread_count())
  {
    Eigen::MatrixXd work(n, std::min(kWidth, n));  // one workspace per thread
#pragma omp for schedule(dynamic, 1)
    for (Eigen::Index b = 0; b < blocks; ++b) {  // largest triangles first: balances the dynamic schedule
      const Eigen::Index c = b * kWidth, w = std::min(kWidth, n - c), m = n - c;
      auto x = work.topLeftCorner(m, w);
      x.setZero();
      x.topRows(w).setIdentity();
      kernels::lower_solve_in_place(&l(c, c), static_cast<std::size_t>(l.outerStride()), static_cast<std::size_t>(m),
                                    x.data(), static_cast<std::size_t>(work.outerStride()), static_cast<std::size_t>(w));
      pdiag.segment(c, w) = x.colwise().squaredNorm().transpose();
    }
  }
  if (drift_terms_ > 0) {
    Eigen::MatrixXd kinv_f = q_;
    llt_.matrixU().solveInPlace(kinv_f);  // K^-1 F
    Eigen::MatrixXd t = kinv_f.transpose();
    g_llt_.matrixL().solveInPlace(t);  // Lg^-1 F'K^-1
    pdiag -= t.colwise().squaredNorm().transpose();
  }
  return pdiag;
}

KrigingOutput KrigingEngine::loo_dense() const {
  // Closed form (Dubrule 1983): with A the bordered system [K F; F' 0] and P its inverse's top-left
  // block, P = K^-1 - K^-1 F G^-1 F' K^-1, the leave-one-out residual is alpha_i / P_ii and its
  // variance 1 / P_ii.
  const Eigen::Index n = points_.cols();
  const Eigen::VectorXd& pdiag = loo_precision_diagonal();
  KrigingOutput out;
  out.status = report_.status;
  out.message = report_.message;
  out.residual.resize(n, components_);
  out.variance.resize(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    out.residual.row(i) = alpha_.row(i) / pdiag[i];
    out.variance[i] = 1.0 / pdiag[i];
  }
  out.mean = observed_ - out.residual;
  return out;
}

Eigen::MatrixXd KrigingEngine::leave_one_out_residuals_of(const Eigen::MatrixXd& values) const {
  const Eigen::Index n = points_.cols();
  if (options_.backend != KrigingBackend::Dense)
    throw ArgumentError("kriging: leave-one-out residuals of other values need the dense back end");
  if (!report_.usable()) throw ArgumentError("kriging: leave-one-out residuals of other values: " + report_.message);
  if (values.rows() != static_cast<Eigen::Index>(original_index_.size()) || original_index_.size() != static_cast<std::size_t>(n))
    throw ArgumentError("kriging: leave-one-out residuals of " + std::to_string(values.rows()) + " values for " +
                        std::to_string(n) + " samples (" + std::to_string(original_index_.size()) +
                        " given); expected one row per sample and no merged samples");
  // P v as alpha_ is P times the values: K^-1 (v - F beta_v), beta_v the drift's GLS coefficients.
  Eigen::MatrixXd y(n, values.cols());
  for (Eigen::Index i = 0; i < n; ++i) y.row(i) = values.row(static_cast<Eigen::Index>(original_index_[static_cast<std::size_t>(i)]));
  llt_.matrixL().solveInPlace(y);
  if (drift_terms_ > 0) y -= q_ * g_llt_.solve(q_.transpose() * y);
  llt_.matrixU().solveInPlace(y);
  const Eigen::VectorXd& pdiag = loo_precision_diagonal();
  Eigen::MatrixXd out(n, values.cols());
  for (Eigen::Index i = 0; i < n; ++i)
    out.row(static_cast<Eigen::Index>(original_index_[static_cast<std::size_t>(i)])) = y.row(i) / pdiag[i];
  return out;
}

}  // namespace errfield::detail
