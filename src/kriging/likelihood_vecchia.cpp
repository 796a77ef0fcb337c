// The Vecchia likelihood (likelihood_vecchia.hpp). Each sample s, at position i of the ordering,
// is conditioned on its set c of nearest predecessors: with the correlation block R_cc (nugget on
// its diagonal), r = R_cs, b = R_cc^-1 r and d = R_ss - r'b, the whitened value of a column v is
// y(v) = (v_s - b'v_c) / sqrt(d). These are U'v for the sparse U of K^-1 ~ U U', so the dense
// formulas of likelihood_profile.cpp hold with log det R = sum log d and L^-1 [z f] replaced by the
// whitened columns. The gradient follows from db = R_cc^-1 (dr - dR_cc b) and
// dd = dR_ss - 2 b'dr + b'dR_cc b, per sample, so nothing beyond the small blocks is formed.

#include "kriging/likelihood_vecchia.hpp"

#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include <Eigen/Cholesky>

#include "covariance_kernel.hpp"

namespace errfield::detail {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// In-place Cholesky factor (lower triangle) of the k x k column-major matrix a; false when not
// positive definite. Eigen's blocked kernels, single-threaded here (EIGEN_DONT_PARALLELIZE), so
// every thread does the same operations in the same order.
bool cholesky(double* a, std::size_t k) {
  Eigen::Map<Eigen::MatrixXd> m(a, static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(k));
  const Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> llt(m);
  return llt.info() == Eigen::Success;
}

using Columns = Eigen::Map<Eigen::MatrixXd, 0, Eigen::OuterStride<>>;

// x <- L^-1 x for `columns` right-hand sides of leading dimension ld.
void forward(const double* l, std::size_t k, double* x, std::size_t columns = 1, std::size_t ld = 0) {
  const Eigen::Map<const Eigen::MatrixXd> factor(l, static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(k));
  Columns rhs(x, static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(columns),
              Eigen::OuterStride<>(static_cast<Eigen::Index>(ld ? ld : k)));
  factor.triangularView<Eigen::Lower>().solveInPlace(rhs);
}

// x <- (L L')^-1 x
void solve(const double* l, std::size_t k, double* x, std::size_t columns = 1, std::size_t ld = 0) {
  if (k == 0) return;
  forward(l, k, x, columns, ld);
  const Eigen::Map<const Eigen::MatrixXd> factor(l, static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(k));
  Columns rhs(x, static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(columns),
              Eigen::OuterStride<>(static_cast<Eigen::Index>(ld ? ld : k)));
  factor.triangularView<Eigen::Lower>().transpose().solveInPlace(rhs);
}

double dot(const double* a, const double* b, std::size_t k) {
  double s = 0.0;
  for (std::size_t i = 0; i < k; ++i) s += a[i] * b[i];
  return s;
}

// The GLS part shared by both entry points: from the whitened values y (N x C) and drift q (N x p),
// G = q'q, beta = G^-1 q'y, the residuals e = y - q beta, S = |e|^2 and log det G, summed over the
// samples in their order (no threaded products).
struct GlsFit {
  Eigen::LLT<Eigen::MatrixXd> g;
  Eigen::MatrixXd beta, e;
  double s = 0.0, logdet_g = 0.0;
  bool ok = true;
};

GlsFit gls(const Eigen::MatrixXd& w, Eigen::Index c, Eigen::Index p) {
  const Eigen::Index n = w.rows();
  GlsFit r;
  r.e = w.leftCols(c);
  if (p > 0) {
    Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(p, p), rhs = Eigen::MatrixXd::Zero(p, c);
    for (Eigen::Index i = 0; i < n; ++i)
      for (Eigen::Index a = 0; a < p; ++a) {
        const double qa = w(i, c + a);
        for (Eigen::Index b = 0; b < p; ++b) gram(a, b) += qa * w(i, c + b);
        for (Eigen::Index v = 0; v < c; ++v) rhs(a, v) += qa * w(i, v);
      }
    r.g.compute(gram);
    if (r.g.info() != Eigen::Success) {
      r.ok = false;
      return r;
    }
    r.beta = r.g.solve(rhs);
    for (Eigen::Index i = 0; i < p; ++i) r.logdet_g += 2.0 * std::log(r.g.matrixLLT()(i, i));
    for (Eigen::Index i = 0; i < n; ++i)
      for (Eigen::Index v = 0; v < c; ++v) {
        double t = 0.0;
        for (Eigen::Index a = 0; a < p; ++a) t += w(i, c + a) * r.beta(a, v);
        r.e(i, v) -= t;
      }
  }
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index v = 0; v < c; ++v) r.s += r.e(i, v) * r.e(i, v);
  return r;
}

// One thread's buffers for one sample's conditional given its k <= mmax neighbours (column-major
// k x k blocks, columns of leading dimension mmax): allocated once per thread, never per sample.
struct ConditionalWorkspace {
  ConditionalWorkspace(std::size_t mmax, std::size_t nv, std::size_t np)
      : rcc(mmax * mmax), dcoef(mmax * mmax), r(mmax), dr_coef(mmax), r2(mmax), b(mmax), values(mmax * nv),
        h(mmax * np), bdr(np), y(nv) {}
  std::vector<double> rcc, dcoef, r, dr_coef, r2, b;
  std::vector<double> values, h, bdr, y;
};

// R_cc (lower triangle, 1 + g on the diagonal) among the neighbours and r between them and the
// sample, with the correlation's derivative coefficients and the squared lags to the sample.
inline void neighbour_correlations(const Eigen::MatrixXd& u, const Correlation& corr, double g, int dims,
                                   const double* us, const Eigen::Index* set, std::size_t k,
                                   ConditionalWorkspace& ws) {
  for (std::size_t a = 0; a < k; ++a) {
    const double* ua = u.col(set[a]).data();
    ws.rcc[a + a * k] = 1.0 + g;
    for (std::size_t q = 0; q < a; ++q) {
      const double* uq = u.col(set[q]).data();
      double d2 = 0.0;
      for (int e = 0; e < dims; ++e) d2 += (ua[e] - uq[e]) * (ua[e] - uq[e]);
      double rho, dc;
      corr(std::sqrt(d2), rho, dc);
      ws.rcc[a + q * k] = rho;
      ws.dcoef[a + q * k] = dc;
    }
    double d2 = 0.0;
    for (int e = 0; e < dims; ++e) d2 += (ua[e] - us[e]) * (ua[e] - us[e]);
    double rho, dc;
    corr(std::sqrt(d2), rho, dc);
    ws.r[a] = rho;
    ws.dr_coef[a] = dc;
    ws.r2[a] = d2;
  }
}

// h_k = dr_k - dR_k b and b'dr_k, for the ranges (dR_ss = 0); the nugget's are set by the caller.
inline void range_derivative_terms(const Eigen::MatrixXd& u, int dims, bool ard, const double* us,
                                   const Eigen::Index* set, std::size_t k, std::size_t mmax,
                                   ConditionalWorkspace& ws) {
  std::vector<double>& h = ws.h;
  std::vector<double>& bdr = ws.bdr;
  const std::vector<double>& b = ws.b;
  std::fill(h.begin(), h.end(), 0.0);
  std::fill(bdr.begin(), bdr.end(), 0.0);
  for (std::size_t a = 0; a < k; ++a) {
    const double* ua = u.col(set[a]).data();
    if (ard) {
      for (int e = 0; e < dims; ++e) {
        const double drk = -ws.dr_coef[a] * (ua[e] - us[e]) * (ua[e] - us[e]);
        h[static_cast<std::size_t>(e) * mmax + a] += drk;
        bdr[static_cast<std::size_t>(e)] += b[a] * drk;
      }
    } else {
      const double drk = -ws.dr_coef[a] * ws.r2[a];
      h[a] += drk;
      bdr[0] += b[a] * drk;
    }
    for (std::size_t q = 0; q < a; ++q) {
      const double dc = ws.dcoef[a + q * k];
      if (dc == 0.0) continue;
      const double* uq = u.col(set[q]).data();
      if (ard) {
        for (int e = 0; e < dims; ++e) {
          const double t = -dc * (ua[e] - uq[e]) * (ua[e] - uq[e]);
          h[static_cast<std::size_t>(e) * mmax + a] -= t * b[q];
          h[static_cast<std::size_t>(e) * mmax + q] -= t * b[a];
        }
      } else {
        double d2 = 0.0;
        for (int e = 0; e < dims; ++e) d2 += (ua[e] - uq[e]) * (ua[e] - uq[e]);
        h[a] += dc * d2 * b[q];
        h[q] += dc * d2 * b[a];
      }
    }
  }
}

// The whole likelihood's derivative from the per-sample pieces:
// d nll = 0.5 C sum dd/d + (C m / S) sum e'(dy - dq beta) [+ C sum (G^-1 q_i)'dq_i for REML]
void add_profile_gradient(const GlsFit& fit, const Eigen::MatrixXd& w, const Eigen::MatrixXd& dw,
                          const Eigen::MatrixXd& dd_over_d, Eigen::Index c, Eigen::Index p, int np, double m,
                          bool restricted, double* grad) {
  const Eigen::Index n = w.rows(), nv = c + p;
  const double cc = static_cast<double>(c);
  const double scale = cc * m / fit.s;
  Eigen::VectorXd weight(nv), gq(p);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index v = 0; v < c; ++v) weight[v] = scale * fit.e(i, v);
    if (p > 0) {
      if (restricted) gq = fit.g.solve(w.row(i).tail(p).transpose());
      for (Eigen::Index a = 0; a < p; ++a) {
        double t = restricted ? cc * gq[a] : 0.0;
        for (Eigen::Index v = 0; v < c; ++v) t -= scale * fit.e(i, v) * fit.beta(a, v);
        weight[c + a] = t;
      }
    }
    for (int t = 0; t < np; ++t) {
      double gt = 0.5 * cc * dd_over_d(i, t);
      for (Eigen::Index v = 0; v < nv; ++v) gt += weight[v] * dw(i, t * nv + v);
      grad[t] += gt;
    }
  }
}

}  // namespace

double vecchia_profiled_nll(const Eigen::MatrixXd& u, const Eigen::MatrixXd& z, const Eigen::MatrixXd& f,
                            const VecchiaNeighbours& nb, const Correlation& corr, double g, bool ard, bool fit_nugget,
                            bool restricted, double* grad, double* sigma2) {
  const Eigen::Index n = u.cols(), c = z.cols(), p = f.cols(), nv = c + p;
  const int dims = static_cast<int>(u.rows());
  const int nr = ard ? dims : 1;
  const int np = nr + (fit_nugget ? 1 : 0);
  const bool want = grad != nullptr;
  if (want) std::fill(grad, grad + np, 0.0);
  Eigen::MatrixXd w(n, nv);                           // whitened [z f], by position
  Eigen::MatrixXd dw(want ? n : 0, want ? np * nv : 0);  // d w / d theta_k in columns k nv .. k nv + nv
  Eigen::MatrixXd dd_over_d(want ? n : 0, want ? np : 0);
  Eigen::VectorXd logd(n);
  const std::size_t mmax = nb.largest_set();
  int failed = 0;
#pragma omp parallel reduction(+ : failed)
  {
    ConditionalWorkspace ws(mmax, static_cast<std::size_t>(nv), static_cast<std::size_t>(np));
    std::vector<double>& rcc = ws.rcc;
    std::vector<double>& r = ws.r;
    std::vector<double>& b = ws.b;
    std::vector<double>& values = ws.values;
    std::vector<double>& h = ws.h;
    std::vector<double>& bdr = ws.bdr;
    std::vector<double>& y = ws.y;
#pragma omp for schedule(dynamic, 64)
    for (Eigen::Index i = 0; i < n; ++i) {
      const Eigen::Index s = nb.order[static_cast<std::size_t>(i)];
      const std::size_t k = nb.offsets[static_cast<std::size_t>(i) + 1] - nb.offsets[static_cast<std::size_t>(i)];
      const Eigen::Index* set = nb.sets.data() + nb.offsets[static_cast<std::size_t>(i)];
      const double* us = u.col(s).data();
      neighbour_correlations(u, corr, g, dims, us, set, k, ws);
      if (k > 0 && !cholesky(rcc.data(), k)) {
        ++failed;
        continue;
      }
      for (std::size_t a = 0; a < k; ++a) b[a] = r[a];
      solve(rcc.data(), k, b.data());
      const double d = 1.0 + g - dot(r.data(), b.data(), k);
      if (!(d > 0.0)) {
        ++failed;
        continue;
      }
      logd[i] = std::log(d);
      const double sd = std::sqrt(d);
      for (Eigen::Index v = 0; v < nv; ++v) {
        const Eigen::MatrixXd& m = v < c ? z : f;
        const Eigen::Index col = v < c ? v : v - c;
        double* vc = values.data() + static_cast<std::size_t>(v) * mmax;
        for (std::size_t a = 0; a < k; ++a) vc[a] = m(set[a], col);
        y[static_cast<std::size_t>(v)] = (m(s, col) - dot(b.data(), vc, k)) / sd;
        w(i, v) = y[static_cast<std::size_t>(v)];
      }
      if (!want) continue;
      // R_cc^-1 v_c for each column (overwriting v_c: the gradient needs only these).
      solve(rcc.data(), k, values.data(), static_cast<std::size_t>(nv), mmax);
      range_derivative_terms(u, dims, ard, us, set, k, mmax, ws);
      for (int t = 0; t < np; ++t) {
        double* ht = h.data() + static_cast<std::size_t>(t) * mmax;
        double dd;
        if (t < nr) {
          dd = -bdr[static_cast<std::size_t>(t)] - dot(b.data(), ht, k);
        } else {  // the nugget: dR = g I, dr = 0
          for (std::size_t a = 0; a < k; ++a) ht[a] = -g * b[a];
          dd = g * (1.0 + dot(b.data(), b.data(), k));
        }
        dd_over_d(i, t) = dd / d;
        // dy(v) = -(db'v_c) / sqrt(d) - y dd / (2 d), db'v_c = h_t' R_cc^-1 v_c
        for (Eigen::Index v = 0; v < nv; ++v)
          dw(i, t * nv + v) = -dot(ht, values.data() + static_cast<std::size_t>(v) * mmax, k) / sd -
                              0.5 * y[static_cast<std::size_t>(v)] * dd / d;
      }
    }
  }
  if (failed > 0) return kInfinity;
  const GlsFit fit = gls(w, c, p);
  if (!fit.ok || !(fit.s > 0.0)) return kInfinity;
  double logdet = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) logdet += logd[i];
  const double cc = static_cast<double>(c);
  const double m = static_cast<double>(restricted ? n - p : n);
  const double s2 = fit.s / (cc * m);
  if (sigma2) *sigma2 = s2;
  const double nll = 0.5 * (cc * logdet + (restricted ? cc * fit.logdet_g : 0.0) + cc * m * std::log(s2) +
                            cc * m * (1.0 + std::log(2.0 * std::numbers::pi)));
  if (!want) return nll;
  add_profile_gradient(fit, w, dw, dd_over_d, c, p, np, m, restricted, grad);
  return nll;
}

double vecchia_model_nll(const Eigen::MatrixXd& points, const Eigen::MatrixXd& z, const Eigen::MatrixXd& f,
                         const VariogramModel& model, bool restricted, const VecchiaNeighbours& nb) {
  const kernels::CovarianceKernel kernel(model);
  const Eigen::Index n = points.cols(), c = z.cols(), p = f.cols(), nv = c + p;
  const int dims = static_cast<int>(points.rows());
  // As the exact likelihood: the nugget on the diagonal only, coincident samples share C(0) - nugget.
  const double shared_zero_lag = kernel.sill() - kernel.nugget();
  Eigen::MatrixXd w(n, nv);
  Eigen::VectorXd logd(n);
  const std::size_t mmax = nb.largest_set() + 1;
  int failed = 0;
#pragma omp parallel reduction(+ : failed)
  {
    Eigen::MatrixXd local(dims, static_cast<Eigen::Index>(mmax));
    std::vector<double> block(mmax * mmax), x(mmax);
#pragma omp for schedule(dynamic, 64)
    for (Eigen::Index i = 0; i < n; ++i) {
      const std::size_t k = nb.offsets[static_cast<std::size_t>(i) + 1] - nb.offsets[static_cast<std::size_t>(i)];
      const Eigen::Index* set = nb.sets.data() + nb.offsets[static_cast<std::size_t>(i)];
      const Eigen::Index s = nb.order[static_cast<std::size_t>(i)];
      const std::size_t kk = k + 1;  // the set, then the sample
      for (std::size_t a = 0; a < k; ++a) local.col(static_cast<Eigen::Index>(a)) = points.col(set[a]);
      local.col(static_cast<Eigen::Index>(k)) = points.col(s);
      kernels::covariance_block(kernel, local.data(), kk, local.data(), kk, dims, shared_zero_lag, block.data(), kk);
      for (std::size_t a = 0; a < kk; ++a) block[a + a * kk] = kernel.sill();
      if (!cholesky(block.data(), kk)) {
        ++failed;
        continue;
      }
      // The last entry of L^-1 [v_c; v_s] is (v_s - b'v_c) / sqrt(d), and L(k, k)^2 = d.
      logd[i] = 2.0 * std::log(block[k + k * kk]);
      for (Eigen::Index v = 0; v < nv; ++v) {
        const Eigen::MatrixXd& m = v < c ? z : f;
        const Eigen::Index col = v < c ? v : v - c;
        for (std::size_t a = 0; a < k; ++a) x[a] = m(set[a], col);
        x[k] = m(s, col);
        forward(block.data(), kk, x.data());
        w(i, v) = x[k];
      }
    }
  }
  if (failed > 0) return kInfinity;
  const GlsFit fit = gls(w, c, p);
  if (!fit.ok) return kInfinity;
  double logdet = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) logdet += logd[i];
  const double cc = static_cast<double>(c);
  const double m = static_cast<double>(restricted ? n - p : n);
  return 0.5 * (cc * (logdet + (restricted ? fit.logdet_g : 0.0)) + fit.s + cc * m * std::log(2.0 * std::numbers::pi));
}

}  // namespace errfield::detail
