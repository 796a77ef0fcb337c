#pragma once
// A bounded quasi-Newton minimizer with gradients (NLopt's L-BFGS), for the likelihood fits whose
// gradients are analytic. Beside bobyqa.hpp so that <nlopt.h> stays out of the public headers.

#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace errfield::detail {

struct LbfgsOutcome {
  bool converged = false;  ///< a tolerance was reached (or rounding limited further progress)
  int nlopt_code = 0;
  int evaluations = 0;
  double objective = 0.0;
  std::string message;     ///< the outcome in words
};

/// f(x, grad): the value at x and, when grad is not null, its gradient. Must not throw.
using GradientObjective = double (*)(const double* x, double* grad, void* data);

/// Minimizes from x (in/out) inside [lower, upper]; ftol_rel relative tolerance on f.
LbfgsOutcome minimize_lbfgs(GradientObjective f, void* data, std::vector<double>& x, std::span<const double> lower,
                            std::span<const double> upper, double ftol_rel, int max_evaluations);

}  // namespace errfield::detail
