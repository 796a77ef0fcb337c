// Local back end: per target, the k nearest samples (or those within a radius) from a kd-tree and a
// small dense kriging system solved in place. OpenMP over targets, one workspace per thread that
// only ever grows (no allocation per target once warm).

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>

#include <omp.h>

#include "errfield/csv_table.hpp"
#include "kriging/kriging_engine.hpp"
#include "kriging/neighbour_selection.hpp"

namespace errfield::detail {
namespace {

struct LocalWorkspace : NeighbourBuffers {
  Eigen::MatrixXd k, q, y, g, beta;
  Eigen::VectorXd c0, w, r, s, lambda;
  Eigen::RowVectorXd mean;

  void reserve(Eigen::Index n, Eigen::Index p, Eigen::Index comps, Eigen::Index ceiling) {
    if (k.rows() >= n && q.cols() >= p) return;
    // Doubling, but never past the largest system this job can have (the budget was checked
    // for that size, not for twice it).
    const Eigen::Index cap = std::max<Eigen::Index>(n, std::min(k.rows() * 2, ceiling));
    k.resize(cap, cap);
    q.resize(cap, p);
    y.resize(cap, comps);
    c0.resize(cap);
    w.resize(cap);
    lambda.resize(cap);
    g.resize(p, p);
    beta.resize(p, comps);
    r.resize(p);
    s.resize(p);
    mean.resize(comps);
  }
};

enum class TargetOutcome : std::uint8_t { Ok, TooFew, BelowMinimum, NotPositiveDefinite, SingularDrift, OverBudget };

// One thread's workspace for an n-neighbour system: the n x n matrix, the n-row blocks and the
// drift's small matrices.
double workspace_bytes(double n, double p, double comps) {
  return sizeof(double) * (n * n + n * (p + comps + 3.0) + p * (p + comps + 2.0));
}

// The largest neighbour count whose workspaces, one per thread, fit the budget.
std::size_t neighbours_that_fit(double budget, int threads, double p, double comps) {
  double lo = 0, hi = 1e9;
  while (hi - lo > 1) {
    const double mid = std::floor((lo + hi) / 2);
    (workspace_bytes(mid, p, comps) * threads <= budget ? lo : hi) = mid;
  }
  return static_cast<std::size_t>(lo);
}

}  // namespace

KrigingOutput KrigingEngine::predict_local(const Eigen::MatrixXd& embedded, const Eigen::MatrixXd& raw,
                                           bool leave_one_out, const Eigen::VectorXd& block_weights,
                                           bool with_weights) const {
  const Eigen::Index group = std::max<Eigen::Index>(1, block_weights.size());
  const Eigen::Index m = embedded.cols() / group, p = drift_terms_, comps = components_;
  const bool want_var = options_.compute_variance || leave_one_out;
  const bool want_w = (options_.keep_weights || with_weights) && !leave_one_out;
  // Several value columns (conditional simulation kriges the data and 100 draws with one system):
  // each target's weights once, then applied to every column - n products per column instead of
  // an n x n triangular solve per column (issue 36's job: the local kriging 13 % -> 6 % of the
  // run). One column keeps the solve, which costs the same, so its results keep their bits.
  const bool apply_weights = comps > 1;
  const bool want_lambda = want_w || apply_weights;
  // The values sample by sample (C x N): a neighbour's C values are contiguous.
  const Eigen::MatrixXd values_by_sample = apply_weights ? Eigen::MatrixXd(values_.transpose()) : Eigen::MatrixXd();
  const double c00 = block_variance(embedded, block_weights);  // the target's own variance (a block's average)
  const double zero_lag = target_variance();          // C(0) between a sample and a target point
  // Between a sample and a point of a block's discretization: the nugget (micro-scale variation or
  // noise) averages out over the block, so a discretization point on a sample contributes C(0+),
  // as gstat has it; with C(0) the result would jump as the block moves by a hair.
  const double block_zero_lag = kernel_.sill() - kernel_.nugget();
  // Blocks: the neighbours of the block's centre (the mean of its points), as gstat does.
  Eigen::MatrixXd centre_embedded, centre_raw;
  if (group > 1) {
    centre_embedded.resize(embedded.rows(), m);
    centre_raw.resize(raw.rows(), m);
    for (Eigen::Index b = 0; b < m; ++b) {
      centre_embedded.col(b) = embedded.middleCols(b * group, group).rowwise().mean();
      centre_raw.col(b) = raw.middleCols(b * group, group).rowwise().mean();
    }
  }
  const NeighbourRule rule =
      NeighbourRule::from(options_.neighbors, options_.radius, options_.min_neighbours, options_.octant_max);
  const std::size_t k_max = options_.neighbors;
  const std::size_t n_samples = static_cast<std::size_t>(points_.cols());
  const Eigen::MatrixXd f0_all = block_drift_matrix(raw, block_weights);  // validated before the parallel region
  const double nan = std::numeric_limits<double>::quiet_NaN();

  // Memory budget, checked before any workspace exists: each thread holds one k x k system
  // (k = 30,000 would be 7.2 GB per thread). With a radius and no k the size is known only per
  // target; such a target stops the job below.
  const int threads = thread_count();
  const double budget = static_cast<double>(options_.dense_memory_budget_bytes);
  const std::size_t fit = neighbours_that_fit(budget, threads, static_cast<double>(p), static_cast<double>(comps));
  const auto mib = [](double b) { return format_number(std::round(b / (1 << 20))); };
  const auto over_budget = [&](std::size_t k, const std::string& what) {
    return ResourceError("kriging: the local back end with " + what + " solves a " +
                         std::to_string(k) + " x " + std::to_string(k) + " system per target, ~" +
                         mib(workspace_bytes(static_cast<double>(k), static_cast<double>(p),
                                             static_cast<double>(comps)) * threads) +
                         " MiB for " + std::to_string(threads) + " thread(s), over the memory budget of " +
                         mib(budget) + " MiB (dense_memory_budget_bytes); use --neighbors " + std::to_string(fit) +
                         " or fewer (20 to 100 is usual)" +
                         (k_max > 0 ? std::string() : ", or a smaller --radius"));
  };
  const std::size_t k_ceiling = k_max > 0 ? std::min(k_max + (leave_one_out ? 1 : 0), n_samples) : n_samples;
  if (k_max > 0 && k_ceiling > fit) throw over_budget(k_ceiling, "neighbors = " + std::to_string(k_max));
  std::atomic<std::size_t> largest_over{0};

  KrigingOutput out;
  out.mean.resize(m, comps);
  if (want_var) out.variance.resize(m);
  if (leave_one_out) out.residual.resize(m, comps);
  std::vector<TargetOutcome> outcome(static_cast<std::size_t>(m), TargetOutcome::Ok);
  // weights: per target at most k (or all within the radius); gathered per target then packed
  std::vector<std::vector<std::pair<std::size_t, double>>> target_weights;
  if (want_w) target_weights.resize(static_cast<std::size_t>(m));

#pragma omp parallel num_threads(thread_count())
  {
    LocalWorkspace ws;
    const std::size_t k_query = k_max > 0 ? std::min(k_max + (leave_one_out ? 1 : 0), n_samples) : 0;
    ws.size_for(k_query);
    const auto ceiling = static_cast<Eigen::Index>(std::max<std::size_t>(k_ceiling, 1));
    ws.reserve(static_cast<Eigen::Index>(std::max<std::size_t>(k_query, 1)), p, comps, ceiling);
#pragma omp for schedule(dynamic, 64)
    for (Eigen::Index t = 0; t < m; ++t) {
      // Neighbours by the model's lag, or by the raw coordinates (NeighbourMetric::Euclidean).
      const PointTree& tree = search_tree_ ? *search_tree_ : *tree_;
      const double* target = group > 1 ? centre_embedded.col(t).data() : embedded.col(t).data();  // the model's lag
      const double* query = search_tree_ ? (group > 1 ? centre_raw.col(t).data() : raw.col(t).data()) : target;
      const std::size_t self = leave_one_out ? static_cast<std::size_t>(t) : n_samples;
      const bool enough = select_neighbours(tree, query, rule, self, ws);
      const auto nn = static_cast<Eigen::Index>(ws.chosen.size());
      auto fail = [&](TargetOutcome o) {
        outcome[static_cast<std::size_t>(t)] = o;
        out.mean.row(t).setConstant(nan);
        if (want_var) out.variance[t] = nan;
        if (leave_one_out) out.residual.row(t).setConstant(nan);
      };
      if (!enough) {
        fail(TargetOutcome::BelowMinimum);
        continue;
      }
      if (nn == 0 || nn < p) {
        fail(TargetOutcome::TooFew);
        continue;
      }
      if (static_cast<std::size_t>(nn) > fit) {
        std::size_t seen = largest_over.load();
        while (static_cast<std::size_t>(nn) > seen && !largest_over.compare_exchange_weak(seen, static_cast<std::size_t>(nn))) {
        }
        fail(TargetOutcome::OverBudget);
        continue;
      }
      ws.reserve(nn, p, comps, ceiling);
      auto kb = ws.k.topLeftCorner(nn, nn);
      auto build = [&](double jitter) {
        for (Eigen::Index j = 0; j < nn; ++j) {
          const double* pj = points_.col(static_cast<Eigen::Index>(ws.chosen[static_cast<std::size_t>(j)])).data();
          for (Eigen::Index i = j; i < nn; ++i) {
            const double* pi = points_.col(static_cast<Eigen::Index>(ws.chosen[static_cast<std::size_t>(i)])).data();
            kb(i, j) = i == j ? obs_var_[static_cast<Eigen::Index>(ws.chosen[static_cast<std::size_t>(i)])] + jitter
                              : kernel_.at_positive_lag(kernels::column_distance(pi, pj, dimension_));
          }
        }
      };
      double jitter = 0.0;
      bool factored = false;
      for (int attempt = 0; attempt <= options_.max_jitter_retries; ++attempt) {
        build(jitter);
        Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> llt(kb);
        if (llt.info() == Eigen::Success) {
          factored = true;
          break;
        }
        jitter = attempt == 0 ? options_.initial_jitter * kernel_.sill() : jitter * options_.jitter_growth;
      }
      if (!factored) {
        fail(TargetOutcome::NotPositiveDefinite);
        continue;
      }
      const auto lower = kb.triangularView<Eigen::Lower>();
      auto c0 = ws.c0.head(nn);
      auto y = ws.y.topRows(nn);
      for (Eigen::Index i = 0; i < nn; ++i) {
        const auto s = static_cast<Eigen::Index>(ws.chosen[static_cast<std::size_t>(i)]);
        if (group == 1) {
          c0[i] = kernel_(kernels::column_distance(points_.col(s).data(), target, dimension_), zero_lag);
        } else {
          double sum = 0.0;
          for (Eigen::Index j = 0; j < group; ++j)
            sum += block_weights[j] * kernel_(kernels::column_distance(points_.col(s).data(),
                                                                      embedded.col(t * group + j).data(), dimension_),
                                              block_zero_lag);
          c0[i] = sum;
        }
        if (!apply_weights) y.row(i) = values_.row(s);
      }
      lower.solveInPlace(c0);  // w
      if (!apply_weights) lower.solveInPlace(y);
      double var = c00 - c0.squaredNorm();
      if (p > 0) {
        auto q = ws.q.topRows(nn);
        for (Eigen::Index i = 0; i < nn; ++i) q.row(i) = f_.row(static_cast<Eigen::Index>(ws.chosen[static_cast<std::size_t>(i)]));
        lower.solveInPlace(q);
        ws.g.noalias() = q.transpose() * q;
        Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> g_llt(ws.g);
        if (g_llt.info() != Eigen::Success || !(g_llt.rcond() > 1e-14)) {
          fail(TargetOutcome::SingularDrift);
          continue;
        }
        const auto f0 = f0_all.col(t);
        if (!apply_weights) {
          ws.beta.noalias() = q.transpose() * y;
          g_llt.solveInPlace(ws.beta);
          y.noalias() -= q * ws.beta;  // L^-1 (z - F beta)
          ws.mean.noalias() = f0.transpose() * ws.beta;
          ws.mean.noalias() += c0.transpose() * y;
        }
        ws.r.noalias() = f0 - q.transpose() * c0;
        ws.s = ws.r;
        g_llt.matrixL().solveInPlace(ws.s);
        var += ws.s.squaredNorm();
        if (want_lambda) {
          g_llt.solveInPlace(ws.r);  // G^-1 r
          ws.lambda.head(nn).noalias() = q * ws.r;
          ws.lambda.head(nn) += c0;
        }
      } else {
        if (!apply_weights) ws.mean.noalias() = c0.transpose() * y;
        if (want_lambda) ws.lambda.head(nn) = c0;
      }
      if (want_lambda) {
        auto lam = ws.lambda.head(nn);
        kb.triangularView<Eigen::Lower>().transpose().solveInPlace(lam);
        if (apply_weights) {
          ws.mean.setZero();
          for (Eigen::Index i = 0; i < nn; ++i)
            ws.mean += lam[i] * values_by_sample.col(static_cast<Eigen::Index>(ws.chosen[static_cast<std::size_t>(i)])).transpose();
        }
      }
      if (want_w) {
        const auto lam = ws.lambda.head(nn);
        auto& tw = target_weights[static_cast<std::size_t>(t)];
        tw.resize(static_cast<std::size_t>(nn));
        for (Eigen::Index i = 0; i < nn; ++i)
          tw[static_cast<std::size_t>(i)] = {original_index_[ws.chosen[static_cast<std::size_t>(i)]], lam[i]};
      }
      if (options_.kind == KrigingKind::Simple) ws.mean += simple_mean_.transpose();
      out.mean.row(t) = ws.mean;
      var = std::max(var, 0.0);
      if (leave_one_out) {
        out.variance[t] = var + noise_[t];  // the observation's own noise
        out.residual.row(t) = observed_.row(t) - ws.mean;
      } else if (want_var) {
        out.variance[t] = var;
      }
    }
  }

  if (largest_over.load() > 0)
    throw over_budget(largest_over.load(), "radius = " + format_number(options_.radius) + " and no neighbour count");

  // Summarize failures (validated statuses, never a silent NaN).
  std::size_t failed = 0, first = 0;
  TargetOutcome first_outcome = TargetOutcome::Ok;
  for (std::size_t t = 0; t < outcome.size(); ++t)
    if (outcome[t] != TargetOutcome::Ok) {
      if (failed++ == 0) {
        first = t;
        first_outcome = outcome[t];
      }
    }
  out.failed_targets = failed;
  out.status = report_.status;
  out.message = report_.message;
  if (failed > 0) {
    std::string why;
    switch (first_outcome) {
      case TargetOutcome::TooFew:
        out.status = KrigingStatus::TooFewSamples;
        why = "fewer neighbours than drift terms (or none) within the search radius";
        break;
      case TargetOutcome::BelowMinimum:
        out.status = KrigingStatus::TooFewSamples;
        why = "fewer than min_neighbours = " + std::to_string(options_.min_neighbours) +
              " neighbours within the search radius";
        break;
      case TargetOutcome::NotPositiveDefinite:
        out.status = KrigingStatus::NotPositiveDefinite;
        why = "local covariance matrix not positive definite after the jitter retries";
        break;
      case TargetOutcome::SingularDrift:
        out.status = KrigingStatus::SingularDrift;
        why = "the " + std::to_string(drift_terms_) + " drift terms of the " + drift_description() +
              " are linearly dependent over its neighbours (e.g. neighbours on one line or plane); use a lower "
              "drift order or more neighbours";
        break;
      case TargetOutcome::Ok:
      case TargetOutcome::OverBudget: break;
    }
    out.message = std::to_string(failed) + " of " + std::to_string(m) + (leave_one_out ? " samples" : " targets") +
                  " could not be kriged (mean and variance NaN); first: " + (leave_one_out ? "sample " : "target ") +
                  std::to_string(first) + ": " + why;
  }
  if (!want_var || (!options_.compute_variance && !leave_one_out)) out.variance.resize(0);
  if (want_w) {
    auto& wt = out.weights;
    wt.offset.assign(1, 0);
    for (const auto& tw : target_weights) {
      for (const auto& [s, v] : tw) {
        wt.sample.push_back(s);
        wt.weight.push_back(v);
      }
      wt.offset.push_back(wt.sample.size());
    }
  }
  return out;
}

}  // namespace errfield::detail
