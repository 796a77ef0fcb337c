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

// The components to fit: the structure without its nugget (options.nugget says what becomes of it).
std::vector<ModelComponent> fitted_structure(const std::vector<ModelComponent>& structure_in) {
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
  return structure;
}

// Lags and semivariances are fitted divided by their largest values, so that the bounds and
// starting points below hold for data in any unit.
struct Scales {
  double h = 1.0, g = 1.0;
  std::vector<double> h_used, g_used;  // the bins that take part, in the data's units (for the reported SSE)
};

// The bins that take part, into `pr` in scaled units.
Scales take_bins(std::span<const double> lag, std::span<const double> gamma, std::span<const std::uint64_t> pairs,
                 const VariogramFitOptions& options, Problem& pr) {
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
  Scales sc;
  sc.h_used = pr.h;
  sc.g_used = pr.g;
  sc.h = pr.h.empty() ? 1.0 : *std::max_element(pr.h.begin(), pr.h.end());
  sc.g = pr.g.empty() ? 1.0 : *std::max_element(pr.g.begin(), pr.g.end());
  if (!(sc.g > 0.0)) sc.g = 1.0;
  for (auto& v : pr.h) v /= sc.h;
  for (auto& v : pr.g) v /= sc.g;
  return sc;
}

struct Box {
  std::vector<double> lb, ub;
};

// Parameter layout and bounds (scaled).
Box parameter_box(const std::vector<ModelComponent>& structure, const VariogramFitOptions& options, const Scales& sc,
                  bool free_nugget) {
  const double sill_hi = options.sill_max > 0.0 ? options.sill_max / sc.g : 100.0;
  const double range_lo = options.range_min > 0.0 ? options.range_min / sc.h : 1e-6;
  const double range_hi = options.range_max > 0.0 ? options.range_max / sc.h : 100.0;
  Box b;
  for (const auto& c : structure) {
    b.lb.push_back(0.0);
    b.ub.push_back(c.kind == ModelKind::Power || c.kind == ModelKind::Linear
                       ? std::numeric_limits<double>::max() / 4  // slope-like: no natural scale cap
                       : sill_hi);
    if (c.kind == ModelKind::Power) {
      b.lb.push_back(1e-3);
      b.ub.push_back(1.999);
    } else if (has_range(c.kind)) {
      b.lb.push_back(range_lo);
      b.ub.push_back(range_hi);
    }
  }
  if (free_nugget) {
    b.lb.push_back(0.0);
    b.ub.push_back(sill_hi);
  }
  for (auto& u : b.ub)
    if (u > 1e6) u = 1e6;  // BOBYQA wants finite bounds; 10^6 x the scaled data is far outside
  return b;
}

// The caller's own parameters in scaled units (0 where not given): one of the starts, and the
// values of held parameters.
std::vector<double> given_parameters(const std::vector<ModelComponent>& structure, const VariogramFitOptions& options,
                                     const Scales& sc, bool free_nugget) {
  std::vector<double> given;
  for (const auto& c : structure) {
    if (c.kind == ModelKind::Power) {
      given.push_back(c.sill > 0.0 ? c.sill * std::pow(sc.h, c.range) / sc.g : 0.0);
      given.push_back(c.range);
    } else if (c.kind == ModelKind::Linear) {
      given.push_back(c.sill > 0.0 ? c.sill * sc.h / sc.g : 0.0);
    } else {
      given.push_back(c.sill > 0.0 ? c.sill / sc.g : 0.0);
      given.push_back(c.range > 0.0 ? c.range / sc.h : 0.0);
    }
  }
  const double nugget_given = options.nugget_start > 0.0 ? options.nugget_start / sc.g : 0.0;
  if (free_nugget) given.push_back(nugget_given);
  return given;
}

// Held parameters (gstat's fit.sills / fit.ranges = FALSE): pr.is_free over the full layout.
void mark_held(const std::vector<ModelComponent>& structure, const VariogramFitOptions& options, std::size_t n_full,
               Problem& pr) {
  pr.is_free.assign(n_full, true);
  for (const auto* hold : {&options.hold_sill, &options.hold_range}) {
    if (!hold->empty() && hold->size() != structure.size())
      throw ArgumentError("fit_variogram: " + std::to_string(hold->size()) + " hold flags for " +
                          std::to_string(structure.size()) +
                          " structure component(s); expected one per non-nugget component");
  }
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

// Starting points (free entries only): sill shared by the structure, ranges at fractions of the
// largest lag, and first the caller's own parameters when every free one is given.
std::vector<std::vector<double>> starting_points(const Problem& pr, const std::vector<double>& given, const Box& box,
                                                 int wanted_starts) {
  const std::vector<ModelComponent>& structure = pr.structure;
  const std::size_t n_full = box.lb.size();
  const double g_max = 1.0;
  const double g_first = pr.g.front();
  const double nug0 = pr.free_nugget ? std::min(0.5 * g_first, 0.5 * g_max) : 0.0;
  const double fractions[] = {1.0 / 3.0, 0.1, 0.6, 1.0, 0.03, 2.0, 0.2, 0.45, 1.5, 5.0};
  std::vector<std::vector<double>> starts;  // full vectors
  const int n_starts = std::min<int>(wanted_starts, static_cast<int>(std::size(fractions)));
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
      else x[p] = std::clamp(x[p], box.lb[p], box.ub[p]);
    }
  for (auto& x : starts) x = pr.compress(x);
  return starts;
}

struct BestRun {
  std::vector<double> x;
  detail::BobyqaOutcome outcome;
};

// A local BOBYQA run from each start, then a restart from the best: its trust region often shrinks
// early on flat valleys. The best converged run, or the first failure when none converged.
BestRun best_of_starts(detail::Bobyqa& bobyqa, Problem& pr, const std::vector<std::vector<double>>& starts,
                       std::size_t dim) {
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
    std::vector<double> x = best;
    const auto run = local(x);
    if (run.converged && run.objective <= best_run->objective) {
      best_run = run;
      best = x;
    }
  }
  return {std::move(best), best_run ? *best_run : *first_failure};
}

// The fitted full parameter vector back to the data's units; held values and a fixed nugget
// exactly as given (the scaling's round trip may change the last bit).
VariogramModel model_in_data_units(const Problem& pr, const std::vector<double>& best_full, const Scales& sc,
                                   const std::vector<ModelComponent>& structure, const VariogramFitOptions& options) {
  std::vector<ModelComponent> comps = pr.components_of_full(best_full.data());
  for (auto& c : comps) {
    switch (c.kind) {
      case ModelKind::Power: c.sill = c.sill * sc.g / std::pow(sc.h, c.range); break;
      case ModelKind::Linear: c.sill = c.sill * sc.g / sc.h; break;
      case ModelKind::Nugget: c.sill *= sc.g; break;
      default:
        c.sill *= sc.g;
        c.range *= sc.h;
    }
  }
  for (std::size_t i = 0; i < structure.size(); ++i) {
    if (!options.hold_sill.empty() && options.hold_sill[i]) comps[i].sill = structure[i].sill;
    if (!options.hold_range.empty() && options.hold_range[i]) comps[i].range = structure[i].range;
  }
  if (options.nugget == NuggetMode::Fixed) {
    for (auto& c : comps)
      if (c.kind == ModelKind::Nugget) c.sill = options.nugget_value;
  }
  return VariogramModel(std::move(comps));
}


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
  const std::vector<ModelComponent> structure = fitted_structure(structure_in);
  Problem pr;
  pr.weighting = options.weighting;
  pr.structure = structure;
  const Scales sc = take_bins(lag, gamma, pairs, options, pr);
  pr.free_nugget = options.nugget == NuggetMode::Free;
  pr.fixed_nugget = options.nugget == NuggetMode::Fixed ? options.nugget_value / sc.g : 0.0;
  const Box box = parameter_box(structure, options, sc, pr.free_nugget);
  const std::vector<double> given = given_parameters(structure, options, sc, pr.free_nugget);
  const std::size_t n_full = box.lb.size();
  mark_held(structure, options, n_full, pr);
  pr.full = given;
  const std::size_t dim = static_cast<std::size_t>(std::count(pr.is_free.begin(), pr.is_free.end(), true));
  if (dim == 0)
    throw ArgumentError("fit_variogram: every parameter is held; nothing to fit");
  if (pr.h.size() < dim)
    throw ArgumentError("fit_variogram: " + std::to_string(pr.h.size()) + " usable bin(s) for " +
                        std::to_string(dim) + " free parameter(s); need at least as many bins");

  const std::vector<std::vector<double>> starts = starting_points(pr, given, box, options.starts);
  detail::Bobyqa bobyqa(pr.compress(box.lb), pr.compress(box.ub), options.relative_tolerance, options.max_evaluations,
                        "fit_variogram");
  const BestRun best = best_of_starts(bobyqa, pr, starts, dim);

  VariogramFitResult result;
  result.evaluations = pr.evaluations;
  result.bins_used = pr.h.size();
  result.message = bobyqa.describe(best.outcome, "SSE");
  result.status = best.outcome.converged              ? FitStatus::Converged
                  : best.outcome.hit_evaluation_limit ? FitStatus::MaxEvaluations
                                                      : FitStatus::Failed;
  // A parameter stuck at an upper bound usually means the structure does not fit the data (e.g. a
  // bounded model on a variogram that keeps rising): say so.
  const std::vector<double> best_full = pr.expand(best.x.data());
  for (std::size_t p = 0; p < n_full; ++p)
    if (pr.is_free[p] && box.ub[p] > box.lb[p] && best_full[p] >= box.ub[p] * (1 - 1e-9))
      result.message += "; parameter " + std::to_string(p + 1) + " at its upper bound";
  result.model = model_in_data_units(pr, best_full, sc, structure, options);
  result.weighted_sse = weighted_sse(sc.h_used, sc.g_used, pr.n, result.model, options.weighting);
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
