#include "bobyqa.hpp"

#include <nlopt.h>

#include "errfield/error.hpp"

namespace errfield::detail {
namespace {

struct Call {
  Bobyqa::Objective objective;
  void* data;
};

double trampoline(unsigned, const double* x, double*, void* call) {
  const auto* c = static_cast<const Call*>(call);
  return c->objective(x, c->data);
}

}  // namespace

struct Bobyqa::Impl {
  nlopt_opt opt = nullptr;
  ~Impl() {
    if (opt) nlopt_destroy(opt);
  }
};

Bobyqa::Bobyqa(std::span<const double> lower, std::span<const double> upper, double relative_tolerance,
               int max_evaluations, std::string_view caller)
    : impl_(std::make_unique<Impl>()), max_evaluations_(max_evaluations) {
  if (lower.size() != upper.size() || lower.empty())
    throw Error(std::string(caller) + ": optimizer box has " + std::to_string(lower.size()) + " lower and " +
                std::to_string(upper.size()) + " upper bounds");
  impl_->opt = nlopt_create(NLOPT_LN_BOBYQA, static_cast<unsigned>(lower.size()));
  if (!impl_->opt) throw Error(std::string(caller) + ": NLopt could not create a BOBYQA optimizer");
  nlopt_set_lower_bounds(impl_->opt, lower.data());
  nlopt_set_upper_bounds(impl_->opt, upper.data());
  nlopt_set_ftol_rel(impl_->opt, relative_tolerance);
  nlopt_set_xtol_rel(impl_->opt, relative_tolerance);
  nlopt_set_maxeval(impl_->opt, max_evaluations);
}

Bobyqa::~Bobyqa() = default;

BobyqaOutcome Bobyqa::minimize(Objective objective, void* data, std::vector<double>& x,
                               std::span<const double> initial_step) {
  Call call{objective, data};
  nlopt_set_min_objective(impl_->opt, &trampoline, &call);
  if (!initial_step.empty()) nlopt_set_initial_step(impl_->opt, initial_step.data());
  BobyqaOutcome out;
  const nlopt_result r = nlopt_optimize(impl_->opt, x.data(), &out.objective);
  out.nlopt_code = static_cast<int>(r);
  out.converged = r > 0 && r != NLOPT_MAXEVAL_REACHED && r != NLOPT_MAXTIME_REACHED;
  out.converged = out.converged || r == NLOPT_ROUNDOFF_LIMITED;
  out.hit_evaluation_limit = r == NLOPT_MAXEVAL_REACHED;
  return out;
}

std::string Bobyqa::describe(const BobyqaOutcome& o, std::string_view objective_name) const {
  switch (static_cast<nlopt_result>(o.nlopt_code)) {
    case NLOPT_SUCCESS: return "converged";
    case NLOPT_STOPVAL_REACHED: return "converged (stop value reached)";
    case NLOPT_FTOL_REACHED:
      return "converged (relative change of the " + std::string(objective_name) + " below tolerance)";
    case NLOPT_XTOL_REACHED: return "converged (relative change of the parameters below tolerance)";
    case NLOPT_MAXEVAL_REACHED:
      return "stopped at the evaluation limit (" + std::to_string(max_evaluations_) + ")";
    case NLOPT_MAXTIME_REACHED: return "stopped at the time limit";
    case NLOPT_ROUNDOFF_LIMITED: return "converged (limited by rounding)";
    case NLOPT_INVALID_ARGS: return "NLopt: invalid arguments";
    case NLOPT_OUT_OF_MEMORY: return "NLopt: out of memory";
    case NLOPT_FORCED_STOP: return "NLopt: forced stop";
    default: return "NLopt: failure (code " + std::to_string(o.nlopt_code) + ")";
  }
}

}  // namespace errfield::detail
