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

// One job's memory budget: each thread holds one k x k system (k = 30,000 would be 7.2 GB per
// thread), checked before any workspace exists.
struct LocalBudget {
  double bytes;
  int threads;
  double p, comps;
  std::size_t fit;    // the largest neighbour count that fits
  std::size_t k_max;  // the neighbour count asked for (0: by radius)

  ResourceError error(std::size_t k, const std::string& what) const {
    const auto mib = [](double b) { return format_number(std::round(b / (1 << 20))); };
    return ResourceError("kriging: the local back end with " + what + " solves a " + std::to_string(k) + " x " +
                         std::to_string(k) + " system per target, ~" +
                         mib(workspace_bytes(static_cast<double>(k), p, comps) * threads) + " MiB for " +
                         std::to_string(threads) + " thread(s), over the memory budget of " + mib(bytes) +
                         " MiB (dense_memory_budget_bytes); use --neighbors " + std::to_string(fit) +
                         " or fewer (20 to 100 is usual)" + (k_max > 0 ? std::string() : ", or a smaller --radius"));
  }
};

// What every target's solve reads: the engine's samples and model, the targets, and the job's
// switches. References only: built once per job, outside the parallel region.
struct LocalJob {
  const Eigen::MatrixXd& points;  // D x N embedded sample coordinates
  const Eigen::VectorXd& obs_var;
  const kernels::CovarianceKernel& kernel;
  int dimension;
  const Eigen::MatrixXd& values;            // N x C
  const Eigen::MatrixXd& values_by_sample;  // C x N when apply_weights
  const Eigen::MatrixXd& f;                 // N x p
  const Eigen::MatrixXd& f0_all;            // p x M, the targets' drift
  const KrigingOptions& options;
  const PointTree& tree;
  bool search_raw;  // neighbours by the raw coordinates (NeighbourMetric::Euclidean)
  const Eigen::MatrixXd& embedded;
  const Eigen::MatrixXd& raw;
  const Eigen::MatrixXd& centre_embedded;  // blocks: the centres' coordinates
  const Eigen::MatrixXd& centre_raw;
  const Eigen::VectorXd& block_weights;
  Eigen::Index group, p, comps;
  NeighbourRule rule;
  double c00, zero_lag, block_zero_lag;
  std::size_t n_samples, fit;
  bool leave_one_out, want_var, want_w, apply_weights, want_lambda;
  // for the results
  const Eigen::VectorXd& simple_mean;  // C, added with KrigingKind::Simple
  const std::vector<std::size_t>& original_index;
  const Eigen::VectorXd& noise;     // leave-one-out: the observation's own noise
  const Eigen::MatrixXd& observed;  // leave-one-out: the values as given
};

// Blocks: the neighbours of the block's centre (the mean of its points), as gstat does.
void block_centres(const Eigen::MatrixXd& embedded, const Eigen::MatrixXd& raw, Eigen::Index group, Eigen::Index m,
                   Eigen::MatrixXd& centre_embedded, Eigen::MatrixXd& centre_raw) {
  if (group <= 1) return;
  centre_embedded.resize(embedded.rows(), m);
  centre_raw.resize(raw.rows(), m);
  for (Eigen::Index b = 0; b < m; ++b) {
    centre_embedded.col(b) = embedded.middleCols(b * group, group).rowwise().mean();
    centre_raw.col(b) = raw.middleCols(b * group, group).rowwise().mean();
  }
}

// The neighbours' covariance matrix, factored in place; a growing jitter on the diagonal when it
// is not positive definite. False after the last retry.
inline bool factor_with_jitter(const LocalJob& job, LocalWorkspace& ws, Eigen::Index nn) {
  auto kb = ws.k.topLeftCorner(nn, nn);
  auto build = [&](double jitter) {
    for (Eigen::Index j = 0; j < nn; ++j) {
      const double* pj = job.points.col(static_cast<Eigen::Index>(ws.chosen[static_cast<std::size_t>(j)])).data();
      for (Eigen::Index i = j; i < nn; ++i) {
        const double* pi = job.points.col(static_cast<Eigen::Index>(ws.chosen[static_cast<std::size_t>(i)])).data();
        kb(i, j) = i == j ? job.obs_var[static_cast<Eigen::Index>(ws.chosen[static_cast<std::size_t>(i)])] + jitter
                          : job.kernel.at_positive_lag(kernels::column_distance(pi, pj, job.dimension));
      }
    }
  };
  double jitter = 0.0;
  for (int attempt = 0; attempt <= job.options.max_jitter_retries; ++attempt) {
    build(jitter);
    Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> llt(kb);
    if (llt.info() == Eigen::Success) return true;
    jitter = attempt == 0 ? job.options.initial_jitter * job.kernel.sill() : jitter * job.options.jitter_growth;
  }
  return false;
}

// c0: the covariances between the neighbours and target t (a block's: averaged over its points);
// y: the neighbours' values, when the system is solved for them.
inline void covariances_to_target(const LocalJob& job, Eigen::Index t, const double* target, LocalWorkspace& ws,
                                  Eigen::Index nn) {
  auto c0 = ws.c0.head(nn);
  auto y = ws.y.topRows(nn);
  for (Eigen::Index i = 0; i < nn; ++i) {
    const auto s = static_cast<Eigen::Index>(ws.chosen[static_cast<std::size_t>(i)]);
    if (job.group == 1) {
      c0[i] = job.kernel(kernels::column_distance(job.points.col(s).data(), target, job.dimension), job.zero_lag);
    } else {
      double sum = 0.0;
      for (Eigen::Index j = 0; j < job.group; ++j)
        sum += job.block_weights[j] * job.kernel(kernels::column_distance(job.points.col(s).data(),
                                                                         job.embedded.col(t * job.group + j).data(),
                                                                         job.dimension),
                                                 job.block_zero_lag);
      c0[i] = sum;
    }
    if (!job.apply_weights) y.row(i) = job.values.row(s);
  }
}

// Universal kriging's drift: q = L^-1 F, G = q'q, the GLS mean and the variance's drift term;
// lambda's drift part when the weights are wanted. False when the drift is singular over the
// neighbours.
inline bool solve_drift(const LocalJob& job, Eigen::Index t, LocalWorkspace& ws, Eigen::Index nn, double& var) {
  const auto lower = ws.k.topLeftCorner(nn, nn).triangularView<Eigen::Lower>();
  auto c0 = ws.c0.head(nn);
  auto y = ws.y.topRows(nn);
  auto q = ws.q.topRows(nn);
  for (Eigen::Index i = 0; i < nn; ++i) q.row(i) = job.f.row(static_cast<Eigen::Index>(ws.chosen[static_cast<std::size_t>(i)]));
  lower.solveInPlace(q);
  ws.g.noalias() = q.transpose() * q;
  Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> g_llt(ws.g);
  if (g_llt.info() != Eigen::Success || !(g_llt.rcond() > 1e-14)) return false;
  const auto f0 = job.f0_all.col(t);
  if (!job.apply_weights) {
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
  if (job.want_lambda) {
    g_llt.solveInPlace(ws.r);  // G^-1 r
    ws.lambda.head(nn).noalias() = q * ws.r;
    ws.lambda.head(nn) += c0;
  }
  return true;
}

// The weights themselves (K^-1 of lambda's right-hand side) and, with several value columns, the
// mean as their products with each neighbour's values.
inline void weights_and_mean(const LocalJob& job, LocalWorkspace& ws, Eigen::Index nn) {
  auto lam = ws.lambda.head(nn);
  ws.k.topLeftCorner(nn, nn).triangularView<Eigen::Lower>().transpose().solveInPlace(lam);
  if (job.apply_weights) {
    ws.mean.setZero();
    for (Eigen::Index i = 0; i < nn; ++i)
      ws.mean += lam[i] * job.values_by_sample.col(static_cast<Eigen::Index>(ws.chosen[static_cast<std::size_t>(i)])).transpose();
  }
}

// Target t's neighbours and kriging system, solved into ws: the mean in ws.mean, the weights in
// ws.lambda (when wanted); the variance (before the clamp at 0) in `var`.
inline TargetOutcome solve_target(const LocalJob& job, Eigen::Index t, LocalWorkspace& ws, Eigen::Index ceiling,
                                  std::atomic<std::size_t>& largest_over, double& var) {
  // Neighbours by the model's lag, or by the raw coordinates (NeighbourMetric::Euclidean).
  const double* target = job.group > 1 ? job.centre_embedded.col(t).data() : job.embedded.col(t).data();  // the model's lag
  const double* query = job.search_raw ? (job.group > 1 ? job.centre_raw.col(t).data() : job.raw.col(t).data()) : target;
  const std::size_t self = job.leave_one_out ? static_cast<std::size_t>(t) : job.n_samples;
  const bool enough = select_neighbours(job.tree, query, job.rule, self, ws);
  const auto nn = static_cast<Eigen::Index>(ws.chosen.size());
  if (!enough) return TargetOutcome::BelowMinimum;
  if (nn == 0 || nn < job.p) return TargetOutcome::TooFew;
  if (static_cast<std::size_t>(nn) > job.fit) {
    std::size_t seen = largest_over.load();
    while (static_cast<std::size_t>(nn) > seen && !largest_over.compare_exchange_weak(seen, static_cast<std::size_t>(nn))) {
    }
    return TargetOutcome::OverBudget;
  }
  ws.reserve(nn, job.p, job.comps, ceiling);
  if (!factor_with_jitter(job, ws, nn)) return TargetOutcome::NotPositiveDefinite;
  const auto lower = ws.k.topLeftCorner(nn, nn).triangularView<Eigen::Lower>();
  auto c0 = ws.c0.head(nn);
  auto y = ws.y.topRows(nn);
  covariances_to_target(job, t, target, ws, nn);
  lower.solveInPlace(c0);  // w
  if (!job.apply_weights) lower.solveInPlace(y);
  var = job.c00 - c0.squaredNorm();
  if (job.p > 0) {
    if (!solve_drift(job, t, ws, nn, var)) return TargetOutcome::SingularDrift;
  } else {
    if (!job.apply_weights) ws.mean.noalias() = c0.transpose() * y;
    if (job.want_lambda) ws.lambda.head(nn) = c0;
  }
  if (job.want_lambda) weights_and_mean(job, ws, nn);
  return TargetOutcome::Ok;
}

using TargetWeights = std::vector<std::vector<std::pair<std::size_t, double>>>;

// Target t's mean, variance (clamped at 0), leave-one-out residual and weights into the output.
inline void store_target(const LocalJob& job, Eigen::Index t, LocalWorkspace& ws, double var, KrigingOutput& out,
                         TargetWeights& target_weights) {
  const auto nn = static_cast<Eigen::Index>(ws.chosen.size());
  if (job.want_w) {
    const auto lam = ws.lambda.head(nn);
    auto& tw = target_weights[static_cast<std::size_t>(t)];
    tw.resize(static_cast<std::size_t>(nn));
    for (Eigen::Index i = 0; i < nn; ++i)
      tw[static_cast<std::size_t>(i)] = {job.original_index[ws.chosen[static_cast<std::size_t>(i)]], lam[i]};
  }
  if (job.options.kind == KrigingKind::Simple) ws.mean += job.simple_mean.transpose();
  out.mean.row(t) = ws.mean;
  var = std::max(var, 0.0);
  if (job.leave_one_out) {
    out.variance[t] = var + job.noise[t];  // the observation's own noise
    out.residual.row(t) = job.observed.row(t) - ws.mean;
  } else if (job.want_var) {
    out.variance[t] = var;
  }
}

// The first failed target and how many failed.
struct Failures {
  std::size_t count = 0, first = 0;
  TargetOutcome first_outcome = TargetOutcome::Ok;
};

Failures count_failures(const std::vector<TargetOutcome>& outcome) {
  Failures f;
  for (std::size_t t = 0; t < outcome.size(); ++t)
    if (outcome[t] != TargetOutcome::Ok) {
      if (f.count++ == 0) {
        f.first = t;
        f.first_outcome = outcome[t];
      }
    }
  return f;
}

// Validated statuses, never a silent NaN: the status and message of the first failure.
// `drift_text` describes the drift (needed for SingularDrift only).
void report_failures(const Failures& f, Eigen::Index m, bool leave_one_out, std::size_t min_neighbours,
                     int drift_terms, const std::string& drift_text, KrigingOutput& out) {
  std::string why;
  switch (f.first_outcome) {
    case TargetOutcome::TooFew:
      out.status = KrigingStatus::TooFewSamples;
      why = "fewer neighbours than drift terms (or none) within the search radius";
      break;
    case TargetOutcome::BelowMinimum:
      out.status = KrigingStatus::TooFewSamples;
      why = "fewer than min_neighbours = " + std::to_string(min_neighbours) + " neighbours within the search radius";
      break;
    case TargetOutcome::NotPositiveDefinite:
      out.status = KrigingStatus::NotPositiveDefinite;
      why = "local covariance matrix not positive definite after the jitter retries";
      break;
    case TargetOutcome::SingularDrift:
      out.status = KrigingStatus::SingularDrift;
      why = "the " + std::to_string(drift_terms) + " drift terms of the " + drift_text +
            " are linearly dependent over its neighbours (e.g. neighbours on one line or plane); use a lower "
            "drift order or more neighbours";
      break;
    case TargetOutcome::Ok:
    case TargetOutcome::OverBudget: break;
  }
  out.message = std::to_string(f.count) + " of " + std::to_string(m) + (leave_one_out ? " samples" : " targets") +
                " could not be kriged (mean and variance NaN); first: " + (leave_one_out ? "sample " : "target ") +
                std::to_string(f.first) + ": " + why;
}

void pack_weights(const TargetWeights& target_weights, KrigingWeights& wt) {
  wt.offset.assign(1, 0);
  for (const auto& tw : target_weights) {
    for (const auto& [s, v] : tw) {
      wt.sample.push_back(s);
      wt.weight.push_back(v);
    }
    wt.offset.push_back(wt.sample.size());
  }
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
  // The values sample by sample (C x N): a neighbour's C values are contiguous.
  const Eigen::MatrixXd values_by_sample = apply_weights ? Eigen::MatrixXd(values_.transpose()) : Eigen::MatrixXd();
  const double c00 = block_variance(embedded, block_weights);  // the target's own variance (a block's average)
  const double zero_lag = target_variance();          // C(0) between a sample and a target point
  // Between a sample and a point of a block's discretization: the nugget (micro-scale variation or
  // noise) averages out over the block, so a discretization point on a sample contributes C(0+),
  // as gstat has it; with C(0) the result would jump as the block moves by a hair.
  const double block_zero_lag = kernel_.sill() - kernel_.nugget();
  Eigen::MatrixXd centre_embedded, centre_raw;
  block_centres(embedded, raw, group, m, centre_embedded, centre_raw);
  const NeighbourRule rule =
      NeighbourRule::from(options_.neighbors, options_.radius, options_.min_neighbours, options_.octant_max);
  const std::size_t k_max = options_.neighbors;
  const std::size_t n_samples = static_cast<std::size_t>(points_.cols());
  const Eigen::MatrixXd f0_all = block_drift_matrix(raw, block_weights);  // validated before the parallel region
  const double nan = std::numeric_limits<double>::quiet_NaN();

  // Memory budget, checked before any workspace exists. With a radius and no k the size is known
  // only per target; such a target stops the job below.
  const int threads = thread_count();
  const double budget = static_cast<double>(options_.dense_memory_budget_bytes);
  const LocalBudget memory{budget, threads, static_cast<double>(p), static_cast<double>(comps),
                           neighbours_that_fit(budget, threads, static_cast<double>(p), static_cast<double>(comps)), k_max};
  const std::size_t k_ceiling = k_max > 0 ? std::min(k_max + (leave_one_out ? 1 : 0), n_samples) : n_samples;
  if (k_max > 0 && k_ceiling > memory.fit) throw memory.error(k_ceiling, "neighbors = " + std::to_string(k_max));
  std::atomic<std::size_t> largest_over{0};

  const LocalJob job{points_, obs_var_, kernel_, dimension_, values_, values_by_sample, f_, f0_all, options_,
                     search_tree_ ? *search_tree_ : *tree_, search_tree_ != nullptr, embedded, raw, centre_embedded,
                     centre_raw, block_weights, group, p, comps, rule, c00, zero_lag, block_zero_lag, n_samples,
                     memory.fit, leave_one_out, want_var, want_w, apply_weights, want_w || apply_weights,
                     simple_mean_, original_index_, noise_, observed_};

  KrigingOutput out;
  out.mean.resize(m, comps);
  if (want_var) out.variance.resize(m);
  if (leave_one_out) out.residual.resize(m, comps);
  std::vector<TargetOutcome> outcome(static_cast<std::size_t>(m), TargetOutcome::Ok);
  // weights: per target at most k (or all within the radius); gathered per target then packed
  TargetWeights target_weights;
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
      double var = 0.0;
      const TargetOutcome o = solve_target(job, t, ws, ceiling, largest_over, var);
      if (o != TargetOutcome::Ok) {
        outcome[static_cast<std::size_t>(t)] = o;
        out.mean.row(t).setConstant(nan);
        if (want_var) out.variance[t] = nan;
        if (leave_one_out) out.residual.row(t).setConstant(nan);
        continue;
      }
      store_target(job, t, ws, var, out, target_weights);
    }
  }

  if (largest_over.load() > 0)
    throw memory.error(largest_over.load(), "radius = " + format_number(options_.radius) + " and no neighbour count");
  const Failures failures = count_failures(outcome);
  out.failed_targets = failures.count;
  out.status = report_.status;
  out.message = report_.message;
  if (failures.count > 0)
    report_failures(failures, m, leave_one_out, options_.min_neighbours, drift_terms_,
                    failures.first_outcome == TargetOutcome::SingularDrift ? drift_description() : std::string(), out);
  if (!want_var || (!options_.compute_variance && !leave_one_out)) out.variance.resize(0);
  if (want_w) pack_weights(target_weights, out.weights);
  return out;
}

}  // namespace errfield::detail
