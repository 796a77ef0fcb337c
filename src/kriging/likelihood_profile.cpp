#include "kriging/likelihood_profile.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include <Eigen/Cholesky>

#include "dense_cholesky.hpp"
#include "errfield/csv_table.hpp"
#include "kriging/correlation_derivative.hpp"
#include "kriging/likelihood_vecchia.hpp"
#include "optim/lbfgs.hpp"

namespace errfield::detail {
namespace {

constexpr double kFailed = 1e300;

// W = (L L^T)^-1 from the Cholesky factor L (lower triangle of `factor`): its lower triangle and
// diagonal (each 64-column block is written from its diagonal row down, so the upper part is zero
// except inside the diagonal blocks; callers read the lower triangle only). The gradient needs W at every evaluation, and forming it was
// ~3n^3 flops on one core (a full triangular solve against the identity, then a general product):
// most of a REML fit's time. Here, in fixed blocks of 64 columns, L^-1's zeros above the diagonal are
// skipped (n^3/3 flops for L^-1, n^3/6 for the triangular product) and the blocks run on the OpenMP threads. Every block is the same
// single-threaded Eigen computation whatever the number of threads, so W does not depend on it.
void inverse_lower_triangle(const Eigen::MatrixXd& factor, Eigen::MatrixXd& linv, Eigen::MatrixXd& w) {
  constexpr Eigen::Index kBlock = 64;
  const Eigen::Index n = factor.rows();
  const Eigen::Index blocks = (n + kBlock - 1) / kBlock;
  linv.setZero(n, n);
  w.setZero(n, n);
  const auto size = [](Eigen::Index v) { return static_cast<std::size_t>(v); };
#pragma omp parallel for schedule(dynamic, 1)
  for (Eigen::Index b = 0; b < blocks; ++b) {
    // Columns c0..c0+nc of L^-1 are zero above row c0: solve L[c0:, c0:] X = I[c0:, c0:c0+nc].
    const Eigen::Index c0 = b * kBlock, nc = std::min(kBlock, n - c0), m = n - c0;
    linv.block(c0, c0, nc, nc).setIdentity();
    kernels::lower_solve_in_place(&factor(c0, c0), size(n), size(m), &linv(c0, c0), size(n), size(nc));
  }
#pragma omp parallel for schedule(dynamic, 1)
  for (Eigen::Index b = 0; b < blocks; ++b) {
    // W[i, j] = sum_k L^-1[k, i] L^-1[k, j]; for i, j >= c0 only rows k >= c0 contribute.
    const Eigen::Index c0 = b * kBlock, nc = std::min(kBlock, n - c0), m = n - c0;
    kernels::lower_transposed_product(&linv(c0, c0), size(n), size(m), &linv(c0, c0), size(n), size(nc), &w(c0, c0),
                                      size(n));
  }
}

// The profiled negative log-likelihood: with K = sigma^2 (R + g I) and sigma^2 at its optimum
// S / (C m), S = sum_c z_c' P z_c,
//   nll = 0.5 [C log|R+gI| + C log|F'(R+gI)^-1 F| (REML) + C m log(S / (C m)) + C m (1 + log 2 pi)],
// m = N - p (REML) or N (ML); its gradient is 0.5 sum_ij W_ij dR_ij/dtheta with
//   W = C P~ - (C m / S) A A',  A = P z,  P~ = P (REML) or (R+gI)^-1 (ML).
struct Profile {
  const Eigen::MatrixXd* x = nullptr;  // N x D
  const Eigen::MatrixXd* z = nullptr;  // N x C
  const Eigen::MatrixXd* f = nullptr;  // N x p
  Correlation corr{ModelKind::Exponential, 1};
  bool ard = false, fit_nugget = true, restricted = true;
  int dims = 0;
  Eigen::MatrixXd u, r, w, linv;  // r: the correlation matrix, then its Cholesky factor (lower triangle)
  double sigma2 = 0.0;
  const VecchiaNeighbours* vecchia = nullptr;  // set: the Vecchia approximation with these sets

  int range_count() const { return ard ? dims : 1; }

  double evaluate(const double* theta, double* grad) {
    const Eigen::Index n = x->rows(), c = z->cols(), p = f->cols();
    const int nr = range_count();
    u.resize(dims, n);
    for (int k = 0; k < dims; ++k) u.row(k) = x->col(k).transpose() * std::exp(-theta[ard ? k : 0]);
    const double g = fit_nugget ? std::exp(theta[nr]) : 0.0;
    if (vecchia) {
      const double v = vecchia_profiled_nll(u, *z, *f, *vecchia, corr, g, ard, fit_nugget, restricted, grad, &sigma2);
      return std::isfinite(v) ? v : kFailed;
    }
    r.resize(n, n);
    for (Eigen::Index j = 0; j < n; ++j) {
      r(j, j) = 1.0 + g;
      const double* uj = u.col(j).data();
      for (Eigen::Index i = j + 1; i < n; ++i) {
        const double* ui = u.col(i).data();
        double s = 0.0;
        for (int k = 0; k < dims; ++k) s += (ui[k] - uj[k]) * (ui[k] - uj[k]);
        double rho, d;
        corr(std::sqrt(s), rho, d);
        r(i, j) = rho;
      }
    }
    const bool factored = kernels::cholesky_lower_in_place(r.data(), static_cast<std::size_t>(n), static_cast<std::size_t>(n));
    if (grad) std::fill(grad, grad + nr + (fit_nugget ? 1 : 0), 0.0);
    if (!factored) return kFailed;
    const Eigen::MatrixXd& factor = r;
    const auto l = factor.triangularView<Eigen::Lower>();
    double logdet = 0.0;
    for (Eigen::Index i = 0; i < n; ++i) logdet += 2.0 * std::log(r(i, i));
    Eigen::MatrixXd y = l.solve(*z);
    // No drift (simple kriging): Eigen's triangular solve must not see a 0-column right-hand side.
    Eigen::MatrixXd q = p > 0 ? Eigen::MatrixXd(l.solve(*f)) : Eigen::MatrixXd(n, 0);
    Eigen::LLT<Eigen::MatrixXd> gl;
    double logdet_g = 0.0;
    if (p > 0) {
      gl.compute(q.transpose() * q);
      if (gl.info() != Eigen::Success) return kFailed;
      y -= q * gl.solve(q.transpose() * y);
      for (Eigen::Index i = 0; i < p; ++i) logdet_g += 2.0 * std::log(gl.matrixLLT()(i, i));
    }
    const double s = y.squaredNorm();
    const double cc = static_cast<double>(c);
    const double m = static_cast<double>(restricted ? n - p : n);
    if (!(s > 0.0)) return kFailed;
    sigma2 = s / (cc * m);
    const double nll = 0.5 * (cc * logdet + (restricted ? cc * logdet_g : 0.0) + cc * m * std::log(sigma2) +
                              cc * m * (1.0 + std::log(2.0 * std::numbers::pi)));
    if (!grad) return nll;

    const Eigen::MatrixXd a = l.transpose().solve(y);  // P z
    inverse_lower_triangle(r, linv, w);  // (R + gI)^-1, the lower triangle the loop below reads
    if (restricted && p > 0) {
      const Eigen::MatrixXd h = l.transpose().solve(q);  // (R + gI)^-1 F
      w.noalias() -= h * gl.solve(h.transpose());
    }
    w *= cc;
    w.noalias() -= (cc * m / s) * (a * a.transpose());
    for (Eigen::Index j = 0; j < n; ++j) {
      const double* uj = u.col(j).data();
      for (Eigen::Index i = j + 1; i < n; ++i) {
        const double* ui = u.col(i).data();
        double s2 = 0.0;
        for (int k = 0; k < dims; ++k) s2 += (ui[k] - uj[k]) * (ui[k] - uj[k]);
        double rho, d;
        corr(std::sqrt(s2), rho, d);
        // 0.5 (W_ij + W_ji) dR_ij, dR_ij/dlog a_k = -rho'(r)/r (u_ik - u_jk)^2
        const double wd = -w(i, j) * d;
        if (wd == 0.0) continue;
        if (ard) {
          for (int k = 0; k < dims; ++k) grad[k] += wd * (ui[k] - uj[k]) * (ui[k] - uj[k]);
        } else {
          grad[0] += wd * s2;
        }
      }
    }
    if (fit_nugget) grad[nr] = 0.5 * g * w.trace();
    return nll;
  }
};

double objective(const double* theta, double* grad, void* data) {
  const double v = static_cast<Profile*>(data)->evaluate(theta, grad);
  return std::isfinite(v) ? v : kFailed;
}

// Observed information of the profiled likelihood by forward differences of the analytic gradient
// (np + 1 evaluations; the step's O(h) error, ~1e-4 relative, is far below what a standard error
// needs); standard errors of the log ranges from its inverse (NaN when not positive definite).
std::vector<double> log_range_errors(Profile& pr, const std::vector<double>& theta) {
  const int np = static_cast<int>(theta.size());
  const int nr = pr.range_count();
  Eigen::MatrixXd h(np, np);
  std::vector<double> t = theta, g0(np), gp(np);
  pr.evaluate(theta.data(), g0.data());
  for (int i = 0; i < np; ++i) {
    const double step = 1e-4;
    t[i] = theta[i] + step;
    pr.evaluate(t.data(), gp.data());
    t[i] = theta[i];
    for (int j = 0; j < np; ++j) h(i, j) = (gp[j] - g0[j]) / step;
  }
  pr.evaluate(theta.data(), nullptr);  // restore sigma2 at the optimum
  const Eigen::MatrixXd hs = 0.5 * (h + h.transpose());
  Eigen::LLT<Eigen::MatrixXd> llt(hs);
  std::vector<double> se(nr, std::numeric_limits<double>::quiet_NaN());
  if (llt.info() != Eigen::Success) return se;
  const Eigen::MatrixXd cov = llt.solve(Eigen::MatrixXd::Identity(np, np));
  for (int k = 0; k < nr; ++k) se[k] = std::sqrt(std::max(cov(k, k), 0.0));
  return se;
}

}  // namespace

bool profiled_fit_supported(const ModelComponent& s) {
  switch (s.kind) {
    case ModelKind::Spherical:
    case ModelKind::Exponential:
    case ModelKind::Gaussian:
    case ModelKind::Wendland:
      return true;
    case ModelKind::Matern:
      return s.nu == 0.5 || s.nu == 1.5 || s.nu == 2.5;
    default:
      return false;
  }
}

double profiled_negative_log_likelihood(const Eigen::MatrixXd& x, const Eigen::MatrixXd& z, const Eigen::MatrixXd& f,
                                        const ModelComponent& structure, bool ard, bool fit_nugget, bool restricted,
                                        const std::vector<double>& theta, std::vector<double>* gradient,
                                        double* sigma2) {
  Profile pr;
  pr.x = &x;
  pr.z = &z;
  pr.f = &f;
  pr.corr = correlation_of(structure);
  pr.ard = ard;
  pr.fit_nugget = fit_nugget;
  pr.restricted = restricted;
  pr.dims = static_cast<int>(x.cols());
  if (gradient) gradient->assign(theta.size(), 0.0);
  const double v = pr.evaluate(theta.data(), gradient ? gradient->data() : nullptr);
  if (sigma2) *sigma2 = pr.sigma2;
  return v;
}

namespace {

// The search box in log range (and log nugget / partial sill), from the extent of the samples
// along each coordinate (or overall): `scale` is each range's natural size.
struct SearchBox {
  std::vector<double> scale, lb, ub;
};

SearchBox search_box(const Eigen::MatrixXd& x, const Profile& pr, const LikelihoodFitOptions& o, int nr, int np) {
  const Eigen::RowVectorXd extent = x.colwise().maxCoeff() - x.colwise().minCoeff();
  const double diagonal = extent.norm() > 0.0 ? extent.norm() : 1.0;
  SearchBox b;
  b.scale.resize(static_cast<std::size_t>(nr));
  b.lb.resize(static_cast<std::size_t>(np));
  b.ub.resize(static_cast<std::size_t>(np));
  for (int k = 0; k < nr; ++k) {
    b.scale[k] = pr.ard ? (extent[k] > 0.0 ? extent[k] : diagonal) : diagonal;
    b.lb[k] = std::log(b.scale[k] * 1e-4);
    b.ub[k] = std::log(b.scale[k] * 1e3);
  }
  if (o.fit_nugget) {
    b.lb[nr] = std::log(std::max(o.min_nugget_ratio, 1e-15));
    b.ub[nr] = std::log(10.0);
  }
  return b;
}

// Fixed fractions of each range's scale and nugget ratios, jittered by a fixed seed beyond the
// third start with ARD.
std::vector<std::vector<double>> plain_starts(const SearchBox& b, const Profile& pr, const LikelihoodFitOptions& o,
                                              int nr, int np) {
  std::vector<std::vector<double>> starts;
  const double factors[] = {0.5, 0.15, 1.5};
  const double nuggets[] = {0.05, 0.005, 0.3};
  std::mt19937_64 rng(20261123);
  std::uniform_real_distribution<double> jitter(std::log(0.5), std::log(2.0));
  for (int s = 0; s < std::max(o.starts, 1); ++s) {
    std::vector<double> t(np);
    for (int k = 0; k < nr; ++k) {
      t[k] = std::log(b.scale[k] * factors[s % 3]);
      if (s >= 3 && pr.ard) t[k] += jitter(rng);
    }
    if (o.fit_nugget) t[nr] = std::log(nuggets[(s / 3 + s) % 3]);
    for (int k = 0; k < np; ++k) t[k] = std::clamp(t[k], b.lb[k], b.ub[k]);
    starts.push_back(std::move(t));
  }
  return starts;
}

// The given model: its ranges along each coordinate (the isotropic range everywhere, or the
// largest ARD range for an isotropic fit) and its nugget / partial sill, first of the starts.
// Returns its ranges (empty: no usable model given).
std::vector<double> add_initial_model_start(const LikelihoodFitOptions& o, const Profile& pr, const SearchBox& b,
                                            int nr, int np, std::vector<std::vector<double>>& starts) {
  std::vector<double> initial_ranges;
  if (!o.initial_model) return initial_ranges;
  const VariogramModel& m = *o.initial_model;
  double range = 0.0, partial = 0.0;
  for (const auto& comp : m.components())
    if (comp.kind != ModelKind::Nugget) range = std::max(range, comp.range), partial += comp.sill;
  const Anisotropy& an = m.anisotropy();
  if (range > 0.0 && partial > 0.0) {
    std::vector<double> t(np);
    for (int k = 0; k < nr; ++k) {
      double rk = range;
      if (pr.ard && an.type() == Anisotropy::Type::Ard && an.dimension() == pr.dims) rk = range * an.parameters()[k];
      initial_ranges.push_back(rk);
      t[k] = std::clamp(std::log(rk), b.lb[k], b.ub[k]);
    }
    if (o.fit_nugget) t[nr] = std::clamp(std::log(std::max(m.nugget() / partial, 1e-300)), b.lb[nr], b.ub[nr]);
    starts.insert(starts.begin(), std::move(t));
  }
  return initial_ranges;
}

struct Search {
  double best = std::numeric_limits<double>::infinity();
  std::vector<double> theta;
  LbfgsOutcome outcome;
  int evaluations = 0, runs = 0;
};

// Every start screened by its likelihood, L-BFGS from the best local_runs of them.
Search search_from_screened(Profile& pr, const std::vector<std::vector<double>>& starts, const SearchBox& b,
                            const LikelihoodFitOptions& o) {
  std::vector<std::pair<double, std::size_t>> screened;
  for (std::size_t s = 0; s < starts.size(); ++s) screened.emplace_back(pr.evaluate(starts[s].data(), nullptr), s);
  std::sort(screened.begin(), screened.end());
  Search r;
  r.evaluations = static_cast<int>(starts.size());
  r.runs = std::min<int>(std::max(o.local_runs, 1), static_cast<int>(screened.size()));
  for (int run = 0; run < r.runs; ++run) {
    std::vector<double> t = starts[screened[static_cast<std::size_t>(run)].second];
    const LbfgsOutcome out = minimize_lbfgs(&objective, &pr, t, b.lb, b.ub, o.relative_tolerance, o.max_evaluations);
    r.evaluations += out.evaluations;
    if (out.objective < r.best) {
      r.best = out.objective;
      r.theta = t;
      r.outcome = out;
    }
  }
  return r;
}

// The structure at the fitted log ranges and nugget ratio, with sigma² (pr.sigma2, at best_theta).
VariogramModel fitted_model(const ModelComponent& structure, const Profile& pr, const std::vector<double>& best_theta,
                            const std::vector<double>& ranges, bool fit_nugget) {
  const int nr = static_cast<int>(ranges.size());
  ModelComponent c = structure;
  c.sill = pr.sigma2;
  c.range = *std::max_element(ranges.begin(), ranges.end());
  std::vector<ModelComponent> comps{c};
  if (fit_nugget) {
    ModelComponent nug;
    nug.kind = ModelKind::Nugget;
    nug.sill = pr.sigma2 * std::exp(best_theta[nr]);
    comps.push_back(nug);
  }
  Anisotropy aniso;
  if (pr.ard) {
    std::vector<double> mult(nr);
    for (int k = 0; k < nr; ++k) mult[k] = ranges[k] / c.range;
    aniso = Anisotropy::ard(std::move(mult));
  }
  return VariogramModel(std::move(comps), std::move(aniso));
}

// A range on its box bound is no estimate: the likelihood still improved towards the bound. With
// one range (or all ARD ranges there) the fit has not found a model; one ARD range on its upper
// bound alone says the field hardly varies along that coordinate, which is an answer: noted only.
void judge_bounds(const std::vector<double>& best_theta, const SearchBox& b, int nr, LikelihoodFitResult& res) {
  const std::vector<double>& lb = b.lb;
  const std::vector<double>& ub = b.ub;
  int at_upper = 0, at_lower = 0;
  std::string notes;
  for (int k = 0; k < nr; ++k) {
    const bool upper = best_theta[k] >= ub[k] - 1e-6, lower = best_theta[k] <= lb[k] + 1e-6;
    at_upper += upper;
    at_lower += lower;
    if (nr > 1 && (upper || lower))
      notes += "; range " + std::to_string(k + 1) + " is on its " + (upper ? "upper" : "lower") + " bound (" +
               format_number(std::exp(upper ? ub[k] : lb[k])) + ")";
  }
  const std::string which = nr > 1 ? "ranges all" : "range";
  if (at_upper == nr) {
    res.converged = false;
    res.message = "the " + which + " ended on the upper bound (1000 x the samples' extent = " +
                  format_number(std::exp(ub[0])) +
                  "): the likelihood still rises as the range grows, so the data show no finite range (a trend, or "
                  "a field that keeps growing over the sampled area); try a drift (--kind universal1) or an "
                  "unbounded family (pow or lin via --method wls) [optimizer: " + res.message + "]";
  } else if (at_lower == nr) {
    res.converged = false;
    res.message = "the " + which + " ended on the lower bound (1e-4 x the samples' extent = " +
                  format_number(std::exp(lb[0])) +
                  "): the samples show no spatial correlation at their spacing (a pure nugget effect) [optimizer: " +
                  res.message + "]";
  } else {
    res.message += notes;
  }
}

}  // namespace

LikelihoodFitResult fit_profiled_likelihood(const Eigen::MatrixXd& x, const Eigen::MatrixXd& z,
                                            const Eigen::MatrixXd& f, const ModelComponent& structure,
                                            const LikelihoodFitOptions& o) {
  Profile pr;
  pr.x = &x;
  pr.z = &z;
  pr.f = &f;
  pr.corr = correlation_of(structure);
  pr.ard = o.anisotropy == LikelihoodFitOptions::Anisotropy::Ard;
  pr.fit_nugget = o.fit_nugget;
  pr.restricted = o.restricted;
  pr.dims = static_cast<int>(x.cols());
  const int nr = pr.range_count();
  const int np = nr + (o.fit_nugget ? 1 : 0);
  const SearchBox box = search_box(x, pr, o, nr, np);
  std::vector<std::vector<double>> starts = plain_starts(box, pr, o, nr, np);
  // Vecchia: neighbour sets in the coordinates scaled by the initial model's ranges, else by the
  // starting ranges' common shape (the extent along each coordinate with ARD; any common scale
  // leaves isotropic sets unchanged), fixed
  // during the search so that the objective is smooth, then found again at the fitted ranges and
  // the search resumed from there (below).
  const bool vecchia = likelihood_uses_vecchia(o, static_cast<long>(x.rows()));
  VecchiaNeighbours neighbours;
  auto find_neighbours = [&](const std::vector<double>& ranges) {
    Eigen::MatrixXd scaled = x.transpose();
    for (int k = 0; k < pr.dims; ++k) scaled.row(k) /= ranges[static_cast<std::size_t>(pr.ard ? k : 0)];
    neighbours = find_vecchia_neighbours(scaled, o.vecchia_neighbours, o.vecchia_ordering);
    pr.vecchia = &neighbours;
  };
  const std::vector<double> initial_ranges = add_initial_model_start(o, pr, box, nr, np, starts);
  if (vecchia) find_neighbours(initial_ranges.empty() ? box.scale : initial_ranges);
  Search search = search_from_screened(pr, starts, box, o);
  if (!(search.best < kFailed))
    throw InputError("likelihood: the covariance is not positive definite at any starting point (values or "
                     "coordinates of extreme magnitude? rescale them to units of order 1)");
  if (vecchia && pr.ard) {
    std::vector<double> fitted(static_cast<std::size_t>(nr));
    for (int k = 0; k < nr; ++k) fitted[static_cast<std::size_t>(k)] = std::exp(search.theta[static_cast<std::size_t>(k)]);
    find_neighbours(fitted);
    std::vector<double> t = search.theta;
    const LbfgsOutcome out = minimize_lbfgs(&objective, &pr, t, box.lb, box.ub, o.relative_tolerance, o.max_evaluations);
    search.evaluations += out.evaluations;
    search.best = out.objective;
    search.theta = t;
    search.outcome = out;
  }
  const std::vector<double>& best_theta = search.theta;
  std::vector<double> se_log(static_cast<std::size_t>(nr), std::numeric_limits<double>::quiet_NaN());
  if (o.standard_errors) {
    se_log = log_range_errors(pr, best_theta);
    search.evaluations += np + 2;
  }
  pr.evaluate(best_theta.data(), nullptr);

  std::vector<double> ranges(nr);
  for (int k = 0; k < nr; ++k) ranges[k] = std::exp(best_theta[k]);
  LikelihoodFitResult res;
  res.model = fitted_model(structure, pr, best_theta, ranges, o.fit_nugget);
  res.negative_log_likelihood = search.best;
  res.evaluations = search.evaluations;
  res.converged = search.outcome.converged;
  res.message = search.outcome.message + " (best of " + std::to_string(search.runs) + " L-BFGS runs from " +
                std::to_string(starts.size()) + " screened starts" +
                (vecchia ? std::string("; Vecchia likelihood, ") + std::to_string(o.vecchia_neighbours) +
                               " neighbours" + (pr.ard ? ", sets found again at the fitted ranges" : "")
                         : std::string()) +
                ")";
  judge_bounds(best_theta, box, nr, res);
  res.parameters = np + 1;
  res.ranges = ranges;
  for (int k = 0; k < nr; ++k) res.range_standard_errors.push_back(ranges[k] * se_log[k]);
  return res;
}

}  // namespace errfield::detail
