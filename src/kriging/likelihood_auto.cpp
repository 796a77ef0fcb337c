// choose_likelihood_model (kriging_likelihood.hpp): families x {isotropic, ARD} by AIC/BIC, with
// ill-conditioned candidates refused.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <exception>
#include <optional>
#include <random>
#include <limits>

#include <Eigen/Cholesky>

#include "covariance_kernel.hpp"
#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"
#include "errfield/kriging_likelihood.hpp"
#include "errfield/range_plausibility.hpp"

namespace errfield {
namespace {

// Most samples whose covariance condition_number factorizes (as the exact likelihood: 72 MB, ~1 s);
// beyond, it estimates that of a fixed random subset of this size, a lower bound (the extreme
// eigenvalues of a principal submatrix lie inside those of the whole). The kriging engine reports
// the condition number of all samples when it factorizes them.
constexpr Eigen::Index kConditionSamples = kMaxLikelihoodSamples;

// A fixed random subset of `count` of the rows of x (with `values` beside them; may have no
// columns), in ascending row order, that depends on the rows' contents and not on their order in the
// file: the rows are put in lexicographic order of (coordinates, values) before the seeded shuffle.
// A subset drawn by row index changed the family fit chose for 687 SIMULATED KR 16 poses when the
// same rows came in another order (and the held-out RMS by 9 %).
std::vector<Eigen::Index> order_independent_subset(const Eigen::MatrixXd& x, const Eigen::MatrixXd& values,
                                                   std::size_t count, std::uint64_t seed) {
  std::vector<Eigen::Index> order(static_cast<std::size_t>(x.rows()));
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<Eigen::Index>(i);
  auto key_less = [&](Eigen::Index a, Eigen::Index b) {
    for (Eigen::Index k = 0; k < x.cols(); ++k)
      if (x(a, k) != x(b, k)) return x(a, k) < x(b, k);
    for (Eigen::Index k = 0; k < values.cols(); ++k)
      if (values(a, k) != values(b, k)) return values(a, k) < values(b, k);
    return false;
  };
  std::stable_sort(order.begin(), order.end(), key_less);
  std::mt19937_64 rng(seed);
  for (std::size_t i = order.size(); i > 1; --i) std::swap(order[i - 1], order[rng() % i]);
  order.resize(std::min(count, order.size()));
  std::sort(order.begin(), order.end());
  return order;
}

// 1-norm condition estimate of the model's covariance at the samples (as the dense kriging engine
// estimates it): infinity when not positive definite.
double condition_number(const Eigen::MatrixXd& all, const VariogramModel& model) {
  Eigen::MatrixXd subset;
  if (all.rows() > kConditionSamples)
    subset = all(order_independent_subset(all, Eigen::MatrixXd(all.rows(), 0), static_cast<std::size_t>(kConditionSamples),
                                          20261126),
                 Eigen::all);
  const Eigen::MatrixXd& x = all.rows() > kConditionSamples ? subset : all;
  const Eigen::Index n = x.rows(), d = x.cols();
  Eigen::MatrixXd pts(d, n);
  Eigen::VectorXd in(d), out(d);
  for (Eigen::Index i = 0; i < n; ++i) {
    in = x.row(i).transpose();
    model.anisotropy().apply(in.data(), out.data(), static_cast<int>(d));
    pts.col(i) = out;
  }
  const kernels::CovarianceKernel kernel(model);
  Eigen::MatrixXd k(n, n);
  // Nugget on the diagonal only, as in the likelihood (likelihood.cpp): repeated locations share
  // C(0) - nugget.
  for (Eigen::Index j = 0; j < n; ++j)
    kernels::covariance_block(kernel, pts.col(j).data(), static_cast<std::size_t>(n - j), pts.col(j).data(), 1,
                              static_cast<int>(d), kernel.sill() - kernel.nugget(), &k(j, j),
                              static_cast<std::size_t>(n));
  k.diagonal().setConstant(kernel.sill());
  Eigen::LLT<Eigen::MatrixXd> llt(k);
  if (llt.info() != Eigen::Success) return std::numeric_limits<double>::infinity();
  const double rc = llt.rcond();
  return rc > 0.0 ? 1.0 / rc : std::numeric_limits<double>::infinity();
}

// One candidate: a family (mat with its nu) and whether it has one range per coordinate.
struct CandidateSpec {
  ModelComponent structure;
  bool ard = false;
};

std::string spec_name(const CandidateSpec& c) {
  std::string s(model_kind_name(c.structure.kind));
  if (c.structure.kind == ModelKind::Matern) s += "(" + format_number(c.structure.nu) + ")";
  return s + (c.ard ? "@ard" : "@iso");
}

std::vector<CandidateSpec> candidate_specs(const ModelChoiceOptions& o, Eigen::Index dims) {
  std::vector<CandidateSpec> specs;
  for (const ModelKind kind : o.kinds) {
    std::vector<double> nus{0.5};
    if (kind == ModelKind::Matern) nus = o.matern_nu;
    for (const double nu : nus)
      for (int ard = 0; ard < 2; ++ard) {
        if ((ard == 0 && !o.try_isotropic) || (ard == 1 && (!o.try_ard || dims < 2))) continue;
        CandidateSpec c;
        c.structure.kind = kind;
        c.structure.nu = nu;
        c.ard = ard == 1;
        specs.push_back(c);
      }
  }
  return specs;
}

// A fit of one candidate, or why the data refused it.
struct CandidateFit {
  std::optional<LikelihoodFitResult> fit;
  std::string refusal;
};

// Fits the candidates `which` of `specs` on (x, values), candidate i from initial[i] as well when
// given. The fits run on the OpenMP threads, one candidate each (their own inner parallel regions
// then run on one thread; every fit is the same computation on any number of threads). Nothing is
// thrown inside the parallel region: an InputError is the candidate's refusal, anything else is
// rethrown after it.
std::vector<CandidateFit> fit_candidates(const Eigen::MatrixXd& x, const Eigen::MatrixXd& values,
                                         const std::vector<CandidateSpec>& specs, const std::vector<std::size_t>& which,
                                         const LikelihoodFitOptions& options,
                                         const std::vector<std::optional<VariogramModel>>& initial) {
  std::vector<CandidateFit> out(which.size());
  std::vector<std::exception_ptr> failures(which.size());
  const auto count = static_cast<long>(which.size());
#pragma omp parallel for schedule(dynamic, 1)
  for (long i = 0; i < count; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const CandidateSpec& c = specs[which[k]];
    LikelihoodFitOptions f = options;
    f.anisotropy = c.ard ? LikelihoodFitOptions::Anisotropy::Ard : LikelihoodFitOptions::Anisotropy::None;
    if (k < initial.size() && initial[k]) f.initial_model = initial[k];
    try {
      out[k].fit = fit_likelihood(x, values, {c.structure}, f);
    } catch (const InputError& e) {
      out[k].refusal = e.what();
    } catch (...) {
      failures[k] = std::current_exception();
    }
  }
  for (const auto& e : failures)
    if (e) std::rethrow_exception(e);
  return out;
}

// Where the covariance of one structure (kind, range, nu) falls to 5 % of its sill, in units of
// its range parameter: 1 for sph and the compactly supported kinds, 3 for exp, sqrt(3) for gau,
// by bisection for mat.
double practical_range_factor(const ModelComponent& c) {
  ModelComponent unit = c;
  unit.sill = 1.0;
  unit.range = 1.0;
  const VariogramModel m({unit});
  double lo = 0.0, hi = 1.0;
  while (m.covariance(hi) > 0.05 && hi < 1e6) hi *= 2.0;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    (m.covariance(mid) > 0.05 ? lo : hi) = mid;
  }
  return hi;
}

// Why `model` is implausible for samples spanning `extent` (max - min per coordinate) with this
// condition number, or empty: its ranges' shape (implausible_range_shape), a range below the
// smallest spacing, a near-singular kriging system.
std::string implausibility(const VariogramModel& model, const Eigen::RowVectorXd& extent, double spacing, double condition,
                           const ModelChoiceOptions& o) {
  std::vector<std::string> why =
      implausible_range_shape(model, extent, o.pathological_range_factor, o.pathological_anisotropy_ratio);
  // A range the samples cannot resolve (below their smallest spacing): what the fit calls a range is a nugget.
  for (const std::string& r : implausible_ranges(model, extent, spacing, std::numeric_limits<double>::infinity()))
    why.push_back(r);
  if (condition > o.near_singular_condition)
    why.push_back("near-singular kriging system (condition number " + format_number(condition) + " > " +
                  format_number(o.near_singular_condition) + ")");
  std::string s;
  for (const auto& w : why) s += (s.empty() ? "" : "; ") + w;
  return s;
}

// Fills candidate `cand` from a fit of it on samples x.
void record_fit(ModelChoiceCandidate& cand, const LikelihoodFitResult& r, const Eigen::MatrixXd& x,
                const Eigen::RowVectorXd& extent, double spacing, bool use_bic, const ModelChoiceOptions& o) {
  cand.model = r.model;
  cand.negative_log_likelihood = r.negative_log_likelihood;
  const double criterion = use_bic ? r.bic : r.aic;
  cand.condition_number = condition_number(x, r.model);
  cand.accepted = std::isfinite(criterion) && cand.condition_number <= o.max_condition_number;
  cand.implausible = cand.accepted ? implausibility(r.model, extent, spacing, cand.condition_number, o) : std::string();
  cand.note = cand.accepted ? r.message
                            : "refused: condition number " + format_number(cand.condition_number) + " > " +
                                  format_number(o.max_condition_number);
  cand.criterion = criterion;
}

}  // namespace

void ModelChoiceOptions::validate() const {
  fit.validate();
  if (kinds.empty()) throw ArgumentError("model choice: no model families to try");
  if (!try_isotropic && !try_ard) throw ArgumentError("model choice: neither isotropic nor ARD candidates");
  if (!(max_condition_number > 1.0)) throw ArgumentError("model choice: max_condition_number must be > 1");
  if (ranking_starts < 0 || ranking_local_runs < 0)
    throw ArgumentError("model choice: ranking_starts and ranking_local_runs must be >= 0 (0 = fit's)");
  if (confirmed < 1) throw ArgumentError("model choice: confirmed must be >= 1");
  if (confirm_subsample > 0 && choice_subsample > 0 && confirm_subsample < choice_subsample)
    throw ArgumentError("model choice: confirm_subsample must be 0 or >= choice_subsample");
  if (!(pathological_range_factor > 1.0) || !(pathological_anisotropy_ratio > 1.0) || !(near_singular_condition > 1.0))
    throw ArgumentError("model choice: pathological_range_factor, pathological_anisotropy_ratio and "
                        "near_singular_condition must be > 1");
}

ModelChoiceOptions ModelChoiceOptions::fast() {
  // Issue 49: 5-8 s per indicator threshold on fulmar's 595 samples and 14 s at 1,000 were nearly
  // all exact-likelihood evaluations (N^3 each, ~0.1 s at 1,000 samples) in the confirming fits,
  // which started from fit's 8 screened starts and ran 3 L-BFGS runs to 1e-9.
  ModelChoiceOptions o;
  o.choice_subsample = 250;
  o.ranking_starts = 4;
  o.ranking_local_runs = 1;
  o.confirm_with_plain_starts = false;
  o.confirm_plausible_first = true;
  o.confirmed = 2;
  o.fit.relative_tolerance = 1e-6;  // the AIC to ~1e-3 at these sizes
  o.fit.exact_max_samples = 500;
  return o;
}

namespace {

// The rows of an order-independent random subset of `size` samples (all when there are no more).
struct Rows {
  bool subset = false;
  Eigen::MatrixXd x, values;
};

Rows rows_of(const Eigen::MatrixXd& x, const Eigen::MatrixXd& values, std::size_t size, std::uint64_t seed) {
  const auto n = static_cast<std::size_t>(x.rows());
  Rows r;
  r.subset = size > 0 && n > size;
  if (r.subset) {
    const std::vector<Eigen::Index> order = order_independent_subset(x, values, size, seed);
    r.x = x(order, Eigen::all);
    r.values = values(order, Eigen::all);
  }
  return r;
}

// What every stage reads: the samples (all, the ranking's, the confirming fits'), their extents
// and spacing, the candidates and the options.
struct ChoiceInputs {
  const Eigen::MatrixXd& x;
  const Eigen::MatrixXd& values;
  const Eigen::MatrixXd& xr;
  const Eigen::MatrixXd& vr;
  const Eigen::MatrixXd& xconf;
  const Eigen::MatrixXd& vconf;
  const Eigen::RowVectorXd& extent;
  const Eigen::RowVectorXd& extent_r;
  double spacing;
  const std::vector<CandidateSpec>& specs;
  const ModelChoiceOptions& o;
  bool use_bic;
  bool confirm_needed;
};

// Stage 1: rank every candidate; while every one is ill-conditioned, raise the nugget floor
// (with nugget/sill >= N / limit the 2-norm condition number of the correlation matrix is below ~limit).
// Returns whether the floor was raised; `rank` and `fit` take the raised floor.
bool rank_candidates(const ChoiceInputs& in, LikelihoodFitOptions& rank, LikelihoodFitOptions& fit,
                     std::vector<CandidateFit>& ranked, ModelChoice& choice) {
  const ModelChoiceOptions& o = in.o;
  std::vector<std::size_t> every(in.specs.size());
  for (std::size_t i = 0; i < every.size(); ++i) every[i] = i;
  std::string last_notes;
  bool any_accepted = false;
  int attempt = 0;
  for (; attempt < 4 && !any_accepted; ++attempt) {
    if (attempt > 0) {
      rank.min_nugget_ratio = std::max(rank.min_nugget_ratio * 100.0, static_cast<double>(in.xr.rows()) / o.max_condition_number);
      fit.min_nugget_ratio = std::max(fit.min_nugget_ratio, rank.min_nugget_ratio);
    }
    ranked = fit_candidates(in.xr, in.vr, in.specs, every, rank, {});
    choice.candidates.assign(in.specs.size(), {});
    int fitted = 0;
    std::string first_refusal;
    for (std::size_t i = 0; i < in.specs.size(); ++i) {
      auto& cand = choice.candidates[i];
      if (!ranked[i].fit) {
        cand.note = ranked[i].refusal;
        if (first_refusal.empty()) first_refusal = ranked[i].refusal;
        continue;
      }
      ++fitted;
      record_fit(cand, *ranked[i].fit, in.xr, in.extent_r, in.spacing, in.use_bic, o);
      if (!in.confirm_needed) cand.all_samples_criterion = cand.criterion;
      any_accepted = any_accepted || cand.accepted;
    }
    // Every candidate refused the data itself (e.g. values that are all equal): a higher nugget
    // floor cannot help, and the data's own reason is the message.
    if (fitted == 0 && !first_refusal.empty())
      throw InputError("model choice: no candidate model could be fitted: " + first_refusal);
    last_notes.clear();
    for (std::size_t i = 0; i < choice.candidates.size() && i < 3; ++i)
      last_notes += (i ? "; " : "") + choice.candidates[i].note;
  }
  if (!any_accepted)
    throw InputError("model choice: no candidate model gave a kriging system with condition number <= " +
                     format_number(o.max_condition_number) + " (the first candidates of the last attempt: " + last_notes +
                     ")");
  return attempt > 1;
}

// The accepted candidates, best ranked first (plausible_first: those plausible on the ranking's
// samples first, each group best ranked first).
std::vector<std::size_t> accepted_by_rank(const ModelChoice& choice, bool plausible_first) {
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < choice.candidates.size(); ++i)
    if (choice.candidates[i].accepted) order.push_back(i);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const auto& ca = choice.candidates[a];
    const auto& cb = choice.candidates[b];
    if (plausible_first && ca.implausible.empty() != cb.implausible.empty()) return ca.implausible.empty();
    return ca.criterion < cb.criterion;
  });
  return order;
}

// Stage 2: confirm on all samples the best ranked (and the next, batch by batch, until one is
// plausible and well conditioned on all samples). Returns the confirmed candidates, in order.
std::vector<std::size_t> confirm_candidates(const ChoiceInputs& in, const LikelihoodFitOptions& fit,
                                            const std::vector<std::size_t>& order,
                                            std::vector<std::optional<LikelihoodFitResult>>& final_fit,
                                            ModelChoice& choice) {
  const ModelChoiceOptions& o = in.o;
  std::vector<std::size_t> confirmed;
  LikelihoodFitOptions confirm = fit;
  // By Vecchia's likelihood the plain fit's neighbour sets differ from the warm-started fit's, so
  // more runs would not make that guarantee; one run from the best screened start (nearly always
  // the subset estimate) keeps the cost of large N near the single refit it was.
  if (!o.confirm_with_plain_starts || likelihood_uses_vecchia(fit, static_cast<long>(in.xconf.rows()))) confirm.local_runs = 1;
  else confirm.local_runs = fit.local_runs + 1;
  // Without the plain starts' runs, the subset estimate is screened against one plain start only:
  // each screening is a factorization on every sample (0.2 s at 1,941, a tenth of a confirming fit).
  if (!o.confirm_with_plain_starts) confirm.starts = 1;
  // confirm_plausible_first: the order holds the candidates plausible on the ranking's samples
  // first; the confirmation stops where they end, and when there are none it confirms only the
  // first batch (the best kept with a warning) instead of every candidate one by one.
  std::size_t stop = order.size();
  if (o.confirm_plausible_first) {
    stop = 0;
    while (stop < order.size() && choice.candidates[order[stop]].implausible.empty()) ++stop;
    if (stop == 0) stop = std::min(order.size(), o.confirmed);
  }
  std::size_t next = 0;
  auto plausible_confirmed = [&] {
    for (std::size_t i : confirmed)
      if (choice.candidates[i].accepted && choice.candidates[i].implausible.empty()) return true;
    return false;
  };
  while (next < stop && !plausible_confirmed()) {
    std::vector<std::size_t> batch;
    std::vector<std::optional<VariogramModel>> initial;
    const std::size_t want = confirmed.empty() ? o.confirmed : 1;
    while (next < stop && batch.size() < want) {
      const std::size_t i = order[next++];
      batch.push_back(i);
      initial.emplace_back(choice.candidates[i].model);
    }
    const std::vector<CandidateFit> r = fit_candidates(in.xconf, in.vconf, in.specs, batch, confirm, initial);
    for (std::size_t k = 0; k < batch.size(); ++k) {
      const std::size_t i = batch[k];
      auto& cand = choice.candidates[i];
      confirmed.push_back(i);
      if (!r[k].fit) {
        cand.accepted = false;
        cand.note = "refused on all samples: " + r[k].refusal;
        continue;
      }
      const double ranking_criterion = cand.criterion;
      record_fit(cand, *r[k].fit, in.x, in.extent, in.spacing, in.use_bic, o);
      cand.all_samples_criterion = cand.criterion;
      cand.criterion = ranking_criterion;
      final_fit[i] = r[k].fit;
    }
  }
  return confirmed;
}

// The winner (-1: none): the smallest all-sample criterion among the confirmed, accepted, plausible
// fits; best_any the same among the accepted, plausible or not.
struct Winner {
  int best = -1, best_any = -1;
};

Winner smallest_criterion(const ModelChoice& choice, const std::vector<std::size_t>& confirmed,
                          const std::vector<std::optional<LikelihoodFitResult>>& final_fit) {
  Winner w;
  for (std::size_t i : confirmed) {
    const auto& c = choice.candidates[i];
    if (!c.accepted || !final_fit[i]) continue;
    if (w.best_any < 0 || c.all_samples_criterion < choice.candidates[static_cast<std::size_t>(w.best_any)].all_samples_criterion)
      w.best_any = static_cast<int>(i);
    if (c.implausible.empty() &&
        (w.best < 0 || c.all_samples_criterion < choice.candidates[static_cast<std::size_t>(w.best)].all_samples_criterion))
      w.best = static_cast<int>(i);
  }
  return w;
}

// Every confirmed candidate ill-conditioned on all samples: the best ranked, with the nugget
// floor raised until it is not (as the ranking does).
Winner refit_best_ranked(const ChoiceInputs& in, const LikelihoodFitOptions& fit, std::size_t i,
                         std::vector<std::optional<LikelihoodFitResult>>& final_fit, ModelChoice& choice) {
  const ModelChoiceOptions& o = in.o;
  const auto n = static_cast<std::size_t>(in.x.rows());
  Winner w;
  LikelihoodFitOptions f = fit;
  f.initial_model = choice.candidates[i].model;
  double cond = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 4; ++k) {
    f.min_nugget_ratio = std::max(f.min_nugget_ratio * 100.0, static_cast<double>(n) / o.max_condition_number);
    const std::vector<CandidateFit> r = fit_candidates(in.x, in.values, in.specs, {i}, f, {});
    if (!r[0].fit) break;
    cond = condition_number(in.x, r[0].fit->model);
    if (cond <= o.max_condition_number) {
      record_fit(choice.candidates[i], *r[0].fit, in.x, in.extent, in.spacing, in.use_bic, o);
      choice.candidates[i].all_samples_criterion = choice.candidates[i].criterion;
      final_fit[i] = r[0].fit;
      w.best_any = static_cast<int>(i);
      if (choice.candidates[i].implausible.empty()) w.best = w.best_any;
      break;
    }
  }
  if (w.best_any < 0)
    throw InputError("model choice: the refit of " + choice.candidates[i].model.to_string() + " on all " +
                     std::to_string(n) + " samples stays ill-conditioned (condition number " + format_number(cond) + ")");
  return w;
}

// One line on what won and how it was found, and the warnings about what was set aside.
void explain_choice(const ChoiceInputs& in, const LikelihoodFitOptions& fit, bool subset, bool confirm_subset,
                    bool floor_raised, const std::vector<std::size_t>& confirmed, std::size_t w, bool kept_implausible,
                    ModelChoice& choice) {
  const ModelChoiceOptions& o = in.o;
  const std::vector<CandidateSpec>& specs = in.specs;
  const auto n = static_cast<std::size_t>(in.x.rows());
  const std::string criterion_name = in.use_bic ? "BIC" : "AIC";
  const auto& winner = choice.candidates[w];
  choice.reason = "smallest " + criterion_name + " (" + format_number(winner.all_samples_criterion) + ") of ";
  if (subset)
    choice.reason += std::to_string(specs.size()) + " " + (fit.restricted ? "REML" : "ML") +
                     " fits (sph/exp/gau/mat with a nugget, isotropic and ARD) ranked on a random subset of " +
                     std::to_string(o.choice_subsample) + " of the " + std::to_string(n) + " samples, the best " +
                     std::to_string(confirmed.size()) + " refitted on " +
                     (confirm_subset ? "a subset of " + std::to_string(o.confirm_subsample) : std::string("all")) +
                     (likelihood_uses_vecchia(fit, static_cast<long>(in.xconf.rows())) ? " by Vecchia's likelihood" : "");
  else if (in.confirm_needed)
    choice.reason += std::to_string(specs.size()) + " " + (fit.restricted ? "REML" : "ML") +
                     " fits (sph/exp/gau/mat with a nugget, isotropic and ARD), the best " +
                     std::to_string(confirmed.size()) + " refitted with more starts";
  else
    choice.reason += std::to_string(specs.size()) + " " + (fit.restricted ? "REML" : "ML") +
                     " fits (sph/exp/gau/mat with a nugget, isotropic and ARD)";
  choice.reason += ", condition number " + format_number(winner.condition_number);
  if (floor_raised) choice.reason += ", nugget floor raised to " + format_number(fit.min_nugget_ratio) + " x sill";
  // What was set aside as implausible although its criterion was smaller.
  for (std::size_t i : confirmed) {
    const auto& c = choice.candidates[i];
    if (i == w || !c.accepted || c.implausible.empty() || !(c.all_samples_criterion < winner.all_samples_criterion)) continue;
    const std::string note = spec_name(specs[i]) + " (" + criterion_name + " " + format_number(c.all_samples_criterion) +
                             ") set aside as implausible: " + c.implausible;
    choice.reason += "; " + note;
    choice.warnings.push_back(note);
  }
  if (kept_implausible) {
    const std::string note = "every candidate fitted is implausible; kept " + spec_name(specs[w]) + ": " + winner.implausible;
    choice.reason += "; " + note;
    choice.warnings.push_back(note);
  } else {
    // A plausible winner may still have one ARD range far beyond its coordinate's extent: a trend there.
    for (const std::string& r : implausible_ranges(choice.model, in.extent, 0.0, o.pathological_range_factor))
      choice.warnings.push_back(spec_name(specs[w]) + ": " + r);
  }
}

}  // namespace

ModelChoice choose_likelihood_model(const Eigen::MatrixXd& x, const Eigen::MatrixXd& values,
                                    const ModelChoiceOptions& o) {
  o.validate();
  const Rows ranking_rows = rows_of(x, values, o.choice_subsample, 20261123);
  const bool subset = ranking_rows.subset;
  // The confirming fits' samples: all, or a larger subset (confirm_subsample).
  const Rows confirm_rows = rows_of(x, values, o.confirm_subsample, 20261207);
  const Eigen::MatrixXd& xr = subset ? ranking_rows.x : x;
  const Eigen::RowVectorXd extent = x.colwise().maxCoeff() - x.colwise().minCoeff();
  const Eigen::RowVectorXd extent_r = xr.colwise().maxCoeff() - xr.colwise().minCoeff();
  const std::vector<CandidateSpec> specs = candidate_specs(o, x.cols());

  LikelihoodFitOptions fit = o.fit;
  fit.fit_nugget = true;
  LikelihoodFitOptions rank = fit;
  if (o.ranking_starts > 0) rank.starts = o.ranking_starts;
  if (o.ranking_local_runs > 0) rank.local_runs = o.ranking_local_runs;
  // Ranking fits that are not the plain fits on all samples are confirmed (stage 2).
  const bool confirm_needed = subset || rank.starts != fit.starts || rank.local_runs != fit.local_runs;
  // The ranking only compares likelihoods; the standard errors, where wanted, come from the fit on all samples.
  if (confirm_needed) rank.standard_errors = false;
  const ChoiceInputs in{x, values, xr, subset ? ranking_rows.values : values,
                        confirm_rows.subset ? confirm_rows.x : x, confirm_rows.subset ? confirm_rows.values : values,
                        extent, extent_r,
                        smallest_sample_spacing(x),  // of all samples, for the subset's fits too
                        specs, o, o.criterion == ModelChoiceOptions::Criterion::Bic, confirm_needed};

  ModelChoice choice;
  std::vector<CandidateFit> ranked;
  const bool floor_raised = rank_candidates(in, rank, fit, ranked, choice);
  const std::vector<std::size_t> order = accepted_by_rank(choice, o.confirm_plausible_first);
  std::vector<std::optional<LikelihoodFitResult>> final_fit(specs.size());
  std::vector<std::size_t> confirmed;
  if (!confirm_needed) {
    for (std::size_t i : order) final_fit[i] = ranked[i].fit;
    confirmed = order;
  } else {
    confirmed = confirm_candidates(in, fit, order, final_fit, choice);
  }
  Winner winner = smallest_criterion(choice, confirmed, final_fit);
  if (winner.best_any < 0) winner = refit_best_ranked(in, fit, order.front(), final_fit, choice);
  const bool kept_implausible = winner.best < 0;
  const auto w = static_cast<std::size_t>(kept_implausible ? winner.best_any : winner.best);
  choice.model = final_fit[w]->model;
  choice.fit = *final_fit[w];
  explain_choice(in, fit, subset, confirm_rows.subset, floor_raised, confirmed, w, kept_implausible, choice);
  return choice;
}

double smallest_sample_spacing(const Eigen::MatrixXd& x) {
  const Eigen::Index n = x.rows();
  std::vector<Eigen::Index> order(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) order[static_cast<std::size_t>(i)] = i;
  std::sort(order.begin(), order.end(), [&](Eigen::Index a, Eigen::Index b) { return x(a, 0) < x(b, 0); });
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t a = 0; a < order.size(); ++a)
    for (std::size_t b = a + 1; b < order.size(); ++b) {
      const double dx = x(order[b], 0) - x(order[a], 0);
      if (dx >= best) break;  // sorted along the first coordinate: no closer pair further on
      const double d = (x.row(order[b]) - x.row(order[a])).norm();
      if (d > 0.0 && d < best) best = d;
    }
  return best;
}

std::vector<std::string> implausible_ranges(const VariogramModel& model, const Eigen::RowVectorXd& extent, double spacing,
                                            double factor) {
  static const char* const kAxis[] = {"x", "y", "z"};
  const Anisotropy& an = model.anisotropy();
  const bool ard = an.type() == Anisotropy::Type::Ard && an.dimension() == extent.size();
  std::vector<std::string> out;
  for (const ModelComponent& c : model.components()) {
    if (c.kind == ModelKind::Nugget || !c.bounded() || !(c.sill > 0.0)) continue;
    const double practical = c.range * practical_range_factor(c);
    for (Eigen::Index k = 0; k < (ard ? extent.size() : 1); ++k) {
      const double a = ard ? practical * an.parameters()[static_cast<std::size_t>(k)] : practical;
      const double e = ard ? extent[k] : extent.norm();
      const std::string along = ard ? " along coordinate " + std::to_string(k + 1) +
                                          (k < 3 ? " (" + std::string(kAxis[k]) + ")" : std::string())
                                    : std::string();
      if (a < spacing)
        out.push_back(std::string(model_kind_name(c.kind)) + " practical range " + format_number(a) + along +
                      " below the smallest sample spacing " + format_number(spacing) +
                      ": the samples cannot resolve it (it acts as a nugget)");
      else if (e > 0.0 && a > factor * e)
        out.push_back(std::string(model_kind_name(c.kind)) + " practical range " + format_number(a) + along + " is " +
                      format_number(a / e) + " x the samples' extent " + format_number(e) +
                      ": a trend over the data, not a range; model it (--kind universal1|universal2, or --covariates) or "
                      "hold the range (--fix range)");
    }
  }
  return out;
}

// Ranges are compared along each coordinate (ARD: range x multiplier; isotropic: against the
// diagonal). A range far beyond its coordinate's extent only says that the field is flat along it,
// so in the anisotropy ratio it counts as that limit (factor x extent), not as itself: a field flat
// along x is an answer, but one flat along x whose range along y is a thousandth of the data's
// extent is a stripe per sample line (issue 49: exp@ard with 2.5e8 along x and 92 m along y for
// fulmar's indicator at 5, taken because the ratio left out the long range).
std::vector<std::string> implausible_range_shape(const VariogramModel& model, const Eigen::RowVectorXd& extent,
                                                 double factor, double ratio) {
  double range = 0.0;
  for (const auto& c : model.components())
    if (c.kind != ModelKind::Nugget) range = std::max(range, c.range);
  std::vector<std::string> why;
  const Anisotropy& an = model.anisotropy();
  const bool ard = an.type() == Anisotropy::Type::Ard && an.dimension() == extent.size();
  const double diagonal = extent.norm();
  std::vector<double> within;  // ranges within the factor of their coordinate's extent
  std::vector<double> capped;  // the others, at the factor x their extent
  bool all_beyond = true;
  double longest = 0.0, longest_extent = 0.0;
  for (Eigen::Index k = 0; k < (ard ? extent.size() : 1); ++k) {
    const double a = ard ? range * an.parameters()[static_cast<std::size_t>(k)] : range;
    const double e = ard ? extent[k] : diagonal;
    if (!(e > 0.0)) continue;
    if (a <= factor * e) {
      all_beyond = false;
      within.push_back(a);
    } else {
      capped.push_back(factor * e);
      if (a / e > longest / std::max(longest_extent, 1e-300) || longest == 0.0) {
        longest = a;
        longest_extent = e;
      }
    }
  }
  if (all_beyond && longest > 0.0)
    why.push_back("range " + format_number(longest) + " beyond " + format_number(factor) + " x the samples' extent " +
                  format_number(longest_extent) + (ard ? " along every coordinate" : ""));
  if (!within.empty() && within.size() + capped.size() >= 2) {
    const double lo = *std::min_element(within.begin(), within.end());
    const double hi_within = *std::max_element(within.begin(), within.end());
    const double hi_capped = capped.empty() ? 0.0 : *std::max_element(capped.begin(), capped.end());
    const double hi = std::max(hi_within, hi_capped);
    if (hi > ratio * lo)
      why.push_back("anisotropy ratio " + format_number(hi / lo) + " > " + format_number(ratio) +
                    (hi_capped > hi_within
                         ? " (range " + format_number(lo) + " against one beyond " + format_number(factor) +
                               " x its coordinate's extent, counted as " + format_number(hi) + ": a stripe, not a field)"
                         : " (ranges " + format_number(hi) + " and " + format_number(lo) + ")"));
  }
  return why;
}

}  // namespace errfield
