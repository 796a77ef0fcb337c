#pragma once
// The one place errfield talks to NLopt: a bounded, derivative-free local minimizer (BOBYQA) used
// by the variogram fit (weighted least squares) and the kriging likelihood fit (ML/REML). Kept out
// of the public headers so that <nlopt.h> never reaches users.

#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace errfield::detail {

/// How a BOBYQA run ended, in the caller's vocabulary.
struct BobyqaOutcome {
  bool converged = false;       ///< a tolerance was reached (or rounding limited further progress)
  bool hit_evaluation_limit = false;
  int nlopt_code = 0;           ///< nlopt_result, for messages
  double objective = 0.0;       ///< the value at the returned point
};

/// BOBYQA on a box [lower, upper] with relative tolerances on f and x and an evaluation limit.
/// One optimizer serves any number of local runs (multi-start); each run may set its initial step.
class Bobyqa {
 public:
  /// The objective: f(x) for x of the box's dimension. It must not throw (NLopt is C).
  using Objective = double (*)(const double* x, void* data);

  /// `caller` names the fit in the exception thrown when NLopt cannot create the optimizer.
  Bobyqa(std::span<const double> lower, std::span<const double> upper, double relative_tolerance,
         int max_evaluations, std::string_view caller);
  ~Bobyqa();
  Bobyqa(const Bobyqa&) = delete;
  Bobyqa& operator=(const Bobyqa&) = delete;

  /// Minimizes from x (in/out; clamped into the box by the caller). An empty initial_step keeps
  /// NLopt's default (a fraction of the box).
  BobyqaOutcome minimize(Objective objective, void* data, std::vector<double>& x,
                         std::span<const double> initial_step = {});

  /// "converged (relative change of the <objective_name> below tolerance)", "stopped at the
  /// evaluation limit (N)", ...: one wording for every fit.
  std::string describe(const BobyqaOutcome& outcome, std::string_view objective_name) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  int max_evaluations_;
};

}  // namespace errfield::detail
