#include "lbfgs.hpp"

#include <nlopt.h>

#include "errfield/error.hpp"

namespace errfield::detail {
namespace {

struct LbfgsCall {
  GradientObjective f;
  void* data;
  int evaluations = 0;
};

double lbfgs_trampoline(unsigned, const double* x, double* grad, void* call) {
  auto* c = static_cast<LbfgsCall*>(call);
  ++c->evaluations;
  return c->f(x, grad, c->data);
}

}  // namespace

LbfgsOutcome minimize_lbfgs(GradientObjective f, void* data, std::vector<double>& x, std::span<const double> lower,
                            std::span<const double> upper, double ftol_rel, int max_evaluations) {
  if (lower.size() != x.size() || upper.size() != x.size() || x.empty())
    throw Error("minimize_lbfgs: box and start of different sizes");
  nlopt_opt opt = nlopt_create(NLOPT_LD_LBFGS, static_cast<unsigned>(x.size()));
  if (!opt) throw Error("minimize_lbfgs: NLopt could not create an L-BFGS optimizer");
  LbfgsCall call{f, data};
  nlopt_set_lower_bounds(opt, lower.data());
  nlopt_set_upper_bounds(opt, upper.data());
  nlopt_set_ftol_rel(opt, ftol_rel);
  nlopt_set_maxeval(opt, max_evaluations);
  nlopt_set_min_objective(opt, &lbfgs_trampoline, &call);
  LbfgsOutcome out;
  const nlopt_result r = nlopt_optimize(opt, x.data(), &out.objective);
  nlopt_destroy(opt);
  out.nlopt_code = static_cast<int>(r);
  out.evaluations = call.evaluations;
  out.converged = (r > 0 && r != NLOPT_MAXEVAL_REACHED && r != NLOPT_MAXTIME_REACHED) || r == NLOPT_ROUNDOFF_LIMITED;
  switch (r) {
    case NLOPT_FTOL_REACHED: out.message = "converged (relative change of the likelihood below tolerance)"; break;
    case NLOPT_XTOL_REACHED: out.message = "converged (relative change of the parameters below tolerance)"; break;
    case NLOPT_SUCCESS: out.message = "converged"; break;
    case NLOPT_ROUNDOFF_LIMITED: out.message = "converged (limited by rounding)"; break;
    case NLOPT_MAXEVAL_REACHED: out.message = "stopped at the evaluation limit (" + std::to_string(max_evaluations) + ")"; break;
    default: out.message = "NLopt L-BFGS: code " + std::to_string(static_cast<int>(r));
  }
  return out;
}

}  // namespace errfield::detail
