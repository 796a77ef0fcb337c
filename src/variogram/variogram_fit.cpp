#include "errfield/variogram_fit.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>

#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"
#include "optim/bobyqa.hpp"

namespace errfield {

std::string_view weighting_name(FitWeighting w) {
  switch (w) {
    case FitWeighting::Nj: return "nj";
    case FitWeighting::Cressie: return "cressie";
    case FitWeighting::NjOverH2: return "nj_h2";
  }
  return "?";
}

FitWeighting weighting_from_name(std::string_view name) {
  if (name == "nj" || name == "1") return FitWeighting::Nj;
  if (name == "cressie" || name == "2") return FitWeighting::Cressie;
  if (name == "nj_h2" || name == "7") return FitWeighting::NjOverH2;
  throw ArgumentError("weights: unknown name '" + std::string(name) +
                      "'; known: nj (gstat fit.method 1), cressie (2), nj_h2 (7)");
}

void VariogramFitOptions::validate() const {
  auto fail = [](const std::string& field, double v, const std::string& expected) {
    throw ArgumentError("variogram fit options: " + field + " = " + format_number(v) + "; expected " +
                        expected);
  };
  if (nugget == NuggetMode::Fixed && !(nugget_value >= 0.0 && std::isfinite(nugget_value)))
    fail("nugget_value", nugget_value, "a finite value >= 0");
  if (!std::isfinite(range_min)) fail("range_min", range_min, "a finite value (<= 0: automatic)");
  if (!std::isfinite(range_max)) fail("range_max", range_max, "a finite value (<= 0: automatic)");
  if (!std::isfinite(sill_max)) fail("sill_max", sill_max, "a finite value (<= 0: automatic)");
  if (range_min > 0.0 && range_max > 0.0 && !(range_max > range_min))
    fail("range_max", range_max, "> range_min = " + format_number(range_min));
  if (starts < 1) fail("starts", starts, "an integer >= 1");
  if (!std::isfinite(nugget_start)) fail("nugget_start", nugget_start, "a finite value (<= 0: none)");
  if (!(relative_tolerance > 0.0 && relative_tolerance < 1.0))
    fail("relative_tolerance", relative_tolerance, "0 < tolerance < 1");
  if (max_evaluations < 10) fail("max_evaluations", max_evaluations, "an integer >= 10");
}

namespace {

double weight(FitWeighting w, std::uint64_t n, double h, double model_gamma) {
  const double nd = static_cast<double>(n);
  switch (w) {
    case FitWeighting::Nj: return nd;
    case FitWeighting::NjOverH2: return nd / (h * h);
    case FitWeighting::Cressie: return nd / (model_gamma * model_gamma);
  }
  return nd;
}

bool has_range(ModelKind k) { return k != ModelKind::Nugget && k != ModelKind::Linear; }

// The fitting problem in scaled units: h' = h / h_scale, gamma' = gamma / g_scale.
struct Problem {
  std::vector<double> h, g;
  std::vector<std::uint64_t> n;
  std::vector<ModelComponent> structure;  // kinds and nu; parameters filled from x
  FitWeighting weighting;
  bool free_nugget;
  double fixed_nugget;  // scaled
  // The full parameter vector (sill[, range] per component, then a free nugget), scaled; the
  // optimizer sees only the entries whose `is_free` is set, the others stay at `full`'s values.
  std::vector<double> full;
  std::vector<bool> is_free;
  int evaluations = 0;

  // Optimizer's x (free entries only) -> the full parameter vector.
  std::vector<double> expand(const double* x) const {
    std::vector<double> f = full;
    std::size_t k = 0;
    for (std::size_t p = 0; p < f.size(); ++p)
      if (is_free[p]) f[p] = x[k++];
    return f;
  }
  std::vector<double> compress(const std::vector<double>& f) const {
    std::vector<double> x;
    for (std::size_t p = 0; p < f.size(); ++p)
      if (is_free[p]) x.push_back(f[p]);
    return x;
  }

  // Full parameter vector -> scaled components (structure, then a nugget if any).
  std::vector<ModelComponent> components_of_full(const double* f) const {
    std::vector<ModelComponent> out = structure;
    std::size_t p = 0;
    for (auto& c : out) {
      c.sill = f[p++];
      if (has_range(c.kind)) c.range = f[p++];
    }
    const double nug = free_nugget ? f[p] : fixed_nugget;
    if (free_nugget || fixed_nugget > 0.0) out.push_back({ModelKind::Nugget, nug, 0.0, 0.5});
    return out;
  }

  double sse(const double* x) {
    ++evaluations;
    const std::vector<double> f = expand(x);
    const auto comps = components_of_full(f.data());
    double s = 0.0;
    for (std::size_t j = 0; j < h.size(); ++j) {
      double m = 0.0;
      for (const auto& c : comps) m += c.gamma(h[j]);
      if (weighting == FitWeighting::Cressie && !(m > 1e-300)) return 1e100;
      const double r = g[j] - m;
      s += weight(weighting, n[j], h[j], m) * r * r;
    }
    return std::isfinite(s) ? s : 1e100;
  }
};

double objective(const double* x, void* data) { return static_cast<Problem*>(data)->sse(x); }

}  // namespace

double weighted_sse(std::span<const double> lag, std::span<const double> gamma,
                    std::span<const std::uint64_t> pairs, const VariogramModel& model,
                    FitWeighting weighting) {
  double s = 0.0;
  for (std::size_t j = 0; j < lag.size(); ++j) {
    if (pairs[j] == 0) continue;
    const double m = model.gamma(lag[j]);
    const double r = gamma[j] - m;
    s += weight(weighting, pairs[j], lag[j], m) * r * r;
  }
  return s;
}

VariogramFitResult fit_variogram(std::span<const double> lag, std::span<const double> gamma,
                                 std::span<const std::uint64_t> pairs,
                                 const std::vector<ModelComponent>& structure_in,
                                 const VariogramFitOptions& options) {
  options.validate();
  if (lag.size() != gamma.size() || lag.size() != pairs.size())
    throw ArgumentError("fit_variogram: " + std::to_string(lag.size()) + " lags, " +
                        std::to_string(gamma.size()) + " semivariances and " +
                        std::to_string(pairs.size()) + " pair counts; expected equal sizes");
  std::vector<ModelComponent> structure;
  for (const auto& c : structure_in)
    if (c.kind != ModelKind::Nugget) structure.push_back(c);
  if (structure.empty())
    throw ArgumentError("fit_variogram: the model structure has no non-nugget component; "
                        "expected e.g. sph, exp, gau, mat, pow or lin");
  for (const auto& c : structure)
    if (c.kind == ModelKind::Matern && !(c.nu > 0.0 && c.nu <= kMaxMaternNu))
      throw ArgumentError("fit_variogram: Matérn nu = " + format_number(c.nu) + "; expected 0 < nu <= " +
                          format_number(kMaxMaternNu) + " (kMaxMaternNu: beyond it the model is gau's)");

  Problem pr;
  pr.weighting = options.weighting;
  pr.structure = structure;
  for (std::size_t j = 0; j < lag.size(); ++j) {
    if (pairs[j] == 0) continue;
    if (!std::isfinite(lag[j]) || lag[j] < 0.0)
      throw InputError("fit_variogram: bin " + std::to_string(j) + " has lag " + format_number(lag[j]) +
                       "; expected a finite value >= 0");
    if (!std::isfinite(gamma[j]) || gamma[j] < 0.0)
      throw InputError("fit_variogram: bin " + std::to_string(j) + " has gamma " +
                       format_number(gamma[j]) + "; expected a finite value >= 0");
    // N_j / h_j^2 is undefined at h = 0 (a bin of coincident points): such a bin is left out.
    if (options.weighting == FitWeighting::NjOverH2 && lag[j] == 0.0) continue;
    pr.h.push_back(lag[j]);
    pr.g.push_back(gamma[j]);
    pr.n.push_back(pairs[j]);
  }
  const std::vector<double> h_used = pr.h, g_used = pr.g;  // data units, for the reported SSE
  const double h_scale = pr.h.empty() ? 1.0 : *std::max_element(pr.h.begin(), pr.h.end());
  double g_scale = pr.g.empty() ? 1.0 : *std::max_element(pr.g.begin(), pr.g.end());
  if (!(g_scale > 0.0)) g_scale = 1.0;
  for (auto& v : pr.h) v /= h_scale;
  for (auto& v : pr.g) v /= g_scale;
  pr.free_nugget = options.nugget == NuggetMode::Free;
  pr.fixed_nugget = options.nugget == NuggetMode::Fixed ? options.nugget_value / g_scale : 0.0;

  // Parameter layout and bounds (scaled).
  const double sill_hi = options.sill_max > 0.0 ? options.sill_max / g_scale : 100.0;
  const double range_lo = options.range_min > 0.0 ? options.range_min / h_scale : 1e-6;
  const double range_hi = options.range_max > 0.0 ? options.range_max / h_scale : 100.0;
  std::vector<double> lb, ub;
  for (const auto& c : structure) {
    lb.push_back(0.0);
    ub.push_back(c.kind == ModelKind::Power || c.kind == ModelKind::Linear
                     ? std::numeric_limits<double>::max() / 4  // slope-like: no natural scale cap
                     : sill_hi);
    if (c.kind == ModelKind::Power) {
      lb.push_back(1e-3);
      ub.push_back(1.999);
    } else if (has_range(c.kind)) {
      lb.push_back(range_lo);
      ub.push_back(range_hi);
    }
  }
  if (pr.free_nugget) {
    lb.push_back(0.0);
    ub.push_back(sill_hi);
  }
  for (auto& u : ub)
    if (u > 1e6) u = 1e6;  // BOBYQA wants finite bounds; 10^6 x the scaled data is far outside

  // The caller's own parameters in scaled units (0 where not given): one of the starts, and the
  // values of held parameters.
  std::vector<double> given;
  for (const auto& c : structure) {
    if (c.kind == ModelKind::Power) {
      given.push_back(c.sill > 0.0 ? c.sill * std::pow(h_scale, c.range) / g_scale : 0.0);
      given.push_back(c.range);
    } else if (c.kind == ModelKind::Linear) {
      given.push_back(c.sill > 0.0 ? c.sill * h_scale / g_scale : 0.0);
    } else {
      given.push_back(c.sill > 0.0 ? c.sill / g_scale : 0.0);
      given.push_back(c.range > 0.0 ? c.range / h_scale : 0.0);
    }
  }
  const double nugget_given = options.nugget_start > 0.0 ? options.nugget_start / g_scale : 0.0;
  if (pr.free_nugget) given.push_back(nugget_given);

  // Held parameters (gstat's fit.sills / fit.ranges = FALSE).
  const std::size_t n_full = lb.size();
  pr.is_free.assign(n_full, true);
  for (const auto* hold : {&options.hold_sill, &options.hold_range}) {
    if (!hold->empty() && hold->size() != structure.size())
      throw ArgumentError("fit_variogram: " + std::to_string(hold->size()) + " hold flags for " +
                          std::to_string(structure.size()) +
                          " structure component(s); expected one per non-nugget component");
  }
  {
    std::size_t p = 0;
    for (std::size_t i = 0; i < structure.size(); ++i) {
      const ModelComponent& c = structure[i];
      const std::string name = std::string(model_kind_name(c.kind)) + " (structure " + std::to_string(i + 1) + ")";
      if (!options.hold_sill.empty() && options.hold_sill[i]) {
        if (!(c.sill > 0.0 && std::isfinite(c.sill)))
          throw ArgumentError("fit_variogram: the sill of " + name + " is held but given as " +
                              format_number(c.sill) + "; a held sill needs a value > 0");
        pr.is_free[p] = false;
      }
      ++p;
      if (has_range(c.kind)) {
        if (!options.hold_range.empty() && options.hold_range[i]) {
          if (!(c.range > 0.0 && std::isfinite(c.range)))
            throw ArgumentError("fit_variogram: the range of " + name + " is held but given as " +
                                format_number(c.range) + "; a held range needs a value > 0");
          pr.is_free[p] = false;
        }
        ++p;
      } else if (!options.hold_range.empty() && options.hold_range[i]) {
        throw ArgumentError("fit_variogram: " + name + " has no range to hold");
      }
    }
  }
  pr.full = given;
  const std::size_t dim = static_cast<std::size_t>(std::count(pr.is_free.begin(), pr.is_free.end(), true));
  if (dim == 0)
    throw ArgumentError("fit_variogram: every parameter is held; nothing to fit");
  if (pr.h.size() < dim)
    throw ArgumentError("fit_variogram: " + std::to_string(pr.h.size()) + " usable bin(s) for " +
                        std::to_string(dim) + " free parameter(s); need at least as many bins");

  // Starting points: sill shared by the structure, ranges at fractions of the largest lag.
  const double g_max = 1.0;
  const double g_first = pr.g.front();
  const double nug0 = pr.free_nugget ? std::min(0.5 * g_first, 0.5 * g_max) : 0.0;
  const double fractions[] = {1.0 / 3.0, 0.1, 0.6, 1.0, 0.03, 2.0, 0.2, 0.45, 1.5, 5.0};
  std::vector<std::vector<double>> starts;  // full vectors
  const int n_starts = std::min<int>(options.starts, static_cast<int>(std::size(fractions)));
  const double k = static_cast<double>(structure.size());
  for (int s = 0; s < n_starts; ++s) {
    std::vector<double> x;
    std::size_t i = 0;
    for (const auto& c : structure) {
      const double share = std::max(g_max - nug0, 0.05) / k;
      if (c.kind == ModelKind::Power) {
        x.push_back(share);
        x.push_back(std::clamp(0.5 + 0.25 * s, 0.1, 1.9));
      } else if (c.kind == ModelKind::Linear) {
        x.push_back(share);
      } else {
        x.push_back(share);
        x.push_back(fractions[s] * (static_cast<double>(i) + 1.0) / k);
      }
      ++i;
    }
    if (pr.free_nugget) x.push_back(nug0);
    starts.push_back(std::move(x));
  }
  {  // the caller's own parameters, when every free one is given (a free nugget may be left out)
    bool usable = true;
    std::vector<double> x = given;
    for (std::size_t p = 0; p + (pr.free_nugget ? 1 : 0) < n_full; ++p)
      if (!(x[p] > 0.0)) usable = false;
    if (pr.free_nugget && !(x.back() > 0.0)) x.back() = nug0;
    if (usable) starts.insert(starts.begin(), std::move(x));
  }
  for (auto& x : starts)
    for (std::size_t p = 0; p < n_full; ++p) {
      if (!pr.is_free[p]) x[p] = given[p];  // held: exactly the given value, even outside the box
      else x[p] = std::clamp(x[p], lb[p], ub[p]);
    }
  std::vector<double> lb_free = pr.compress(lb), ub_free = pr.compress(ub);
  for (auto& x : starts) x = pr.compress(x);

  detail::Bobyqa bobyqa(lb_free, ub_free, options.relative_tolerance, options.max_evaluations, "fit_variogram");
  auto local = [&](std::vector<double>& x) {
    // Initial steps: a tenth of the parameter's size, at least a small absolute one.
    std::vector<double> step(dim);
    for (std::size_t p = 0; p < dim; ++p)
      step[p] = std::max(0.1 * std::max(std::fabs(x[p]), 0.1), 1e-4);
    return bobyqa.minimize(&objective, &pr, x, step);
  };

  std::vector<double> best = starts.front();
  std::optional<detail::BobyqaOutcome> best_run;   // the best converged run
  std::optional<detail::BobyqaOutcome> first_failure;
  for (auto x : starts) {
    const auto run = local(x);
    if (run.converged) {
      if (!best_run || run.objective < best_run->objective) {
        best_run = run;
        best = x;
      }
    } else if (!first_failure) {
      first_failure = run;
    }
  }
  if (best_run) {
    // A restart from the best point: BOBYQA's trust region often shrinks early on flat valleys.
    std::vector<double> x = best;
    const auto run = local(x);
    if (run.converged && run.objective <= best_run->objective) {
      best_run = run;
      best = x;
    }
  }
  const detail::BobyqaOutcome outcome = best_run ? *best_run : *first_failure;

  VariogramFitResult result;
  result.evaluations = pr.evaluations;
  result.bins_used = pr.h.size();
  result.message = bobyqa.describe(outcome, "SSE");
  result.status = outcome.converged              ? FitStatus::Converged
                  : outcome.hit_evaluation_limit ? FitStatus::MaxEvaluations
                                                 : FitStatus::Failed;
  // A parameter stuck at an upper bound usually means the structure does not fit the data (e.g. a
  // bounded model on a variogram that keeps rising): say so.
  const std::vector<double> best_full = pr.expand(best.data());
  for (std::size_t p = 0; p < n_full; ++p)
    if (pr.is_free[p] && ub[p] > lb[p] && best_full[p] >= ub[p] * (1 - 1e-9))
      result.message += "; parameter " + std::to_string(p + 1) + " at its upper bound";
  // Back to the data's units.
  std::vector<ModelComponent> comps = pr.components_of_full(best_full.data());
  for (auto& c : comps) {
    switch (c.kind) {
      case ModelKind::Power: c.sill = c.sill * g_scale / std::pow(h_scale, c.range); break;
      case ModelKind::Linear: c.sill = c.sill * g_scale / h_scale; break;
      case ModelKind::Nugget: c.sill *= g_scale; break;
      default:
        c.sill *= g_scale;
        c.range *= h_scale;
    }
  }
  for (std::size_t i = 0; i < structure.size(); ++i) {  // held values exactly as given
    if (!options.hold_sill.empty() && options.hold_sill[i]) comps[i].sill = structure[i].sill;
    if (!options.hold_range.empty() && options.hold_range[i]) comps[i].range = structure[i].range;
  }
  if (options.nugget == NuggetMode::Fixed) {
    // Keep the exact fixed value (scaling round trip may change the last bit).
    for (auto& c : comps)
      if (c.kind == ModelKind::Nugget) c.sill = options.nugget_value;
  }
  result.model = VariogramModel(std::move(comps));
  result.weighted_sse = weighted_sse(h_used, g_used, pr.n, result.model, options.weighting);
  return result;
}

VariogramFitResult fit_variogram(const EmpiricalVariogram& empirical,
                                 const std::vector<ModelComponent>& structure,
                                 const VariogramFitOptions& options) {
  std::vector<double> h, g;
  std::vector<std::uint64_t> n;
  for (const auto& b : empirical.bins) {
    if (b.pairs == 0) continue;
    h.push_back(b.lag_mean);
    g.push_back(b.gamma);
    n.push_back(b.pairs);
  }
  return fit_variogram(h, g, n, structure, options);
}

}  // namespace errfield
