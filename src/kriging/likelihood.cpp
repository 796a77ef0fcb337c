#include "errfield/kriging_likelihood.hpp"

#include <cmath>
#include <limits>
#include <memory>
#include <numbers>

#include <Eigen/Cholesky>

#include "covariance_kernel.hpp"
#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"
#include "optim/bobyqa.hpp"

namespace errfield {
namespace {

// Drift matrix (N x p) in centred, scaled coordinates, as the kriging engine builds it.
Eigen::MatrixXd drift(const Eigen::MatrixXd& x, const LikelihoodFitOptions& o) {
  const Eigen::Index n = x.rows(), d = x.cols();
  if (o.kind == KrigingKind::Simple) return Eigen::MatrixXd(n, 0);
  const int order = o.kind == KrigingKind::Ordinary ? 0 : o.drift_order;
  const Eigen::RowVectorXd center = x.colwise().mean();
  Eigen::RowVectorXd scale = (x.rowwise() - center).cwiseAbs().colwise().maxCoeff();
  for (Eigen::Index k = 0; k < d; ++k)
    if (!(scale[k] > 0.0)) scale[k] = 1.0;
  const Eigen::MatrixXd u = (x.rowwise() - center).array().rowwise() / scale.array();
  std::vector<Eigen::VectorXd> cols{Eigen::VectorXd::Ones(n)};
  if (order >= 1)
    for (Eigen::Index k = 0; k < d; ++k) cols.push_back(u.col(k));
  if (order >= 2)
    for (Eigen::Index k = 0; k < d; ++k)
      for (Eigen::Index l = k; l < d; ++l) cols.push_back(u.col(k).cwiseProduct(u.col(l)));
  Eigen::MatrixXd f(n, static_cast<Eigen::Index>(cols.size()));
  for (std::size_t c = 0; c < cols.size(); ++c) f.col(static_cast<Eigen::Index>(c)) = cols[c];
  return f;
}

double nll(const Eigen::MatrixXd& x, const Eigen::VectorXd& z, const Eigen::MatrixXd& f, const VariogramModel& model,
           bool restricted) {
  const kernels::CovarianceKernel kernel(model);
  const Eigen::Index n = x.rows(), p = f.cols();
  const Eigen::MatrixXd xt = x.transpose();  // points as columns
  Eigen::MatrixXd k(n, n);
  for (Eigen::Index j = 0; j < n; ++j)
    kernels::covariance_block(kernel, xt.col(j).data(), static_cast<std::size_t>(n - j), xt.col(j).data(), 1,
                              static_cast<int>(xt.rows()), kernel.sill(), &k(j, j), static_cast<std::size_t>(n));
  Eigen::LLT<Eigen::MatrixXd> llt(k);
  if (llt.info() != Eigen::Success) return std::numeric_limits<double>::infinity();
  const auto& l = llt.matrixLLT();
  double logdet = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) logdet += 2.0 * std::log(l(i, i));
  Eigen::VectorXd y = z;
  llt.matrixL().solveInPlace(y);
  double extra = 0.0;
  if (p > 0) {
    Eigen::MatrixXd q = f;
    llt.matrixL().solveInPlace(q);
    Eigen::LLT<Eigen::MatrixXd> g(q.transpose() * q);
    if (g.info() != Eigen::Success) return std::numeric_limits<double>::infinity();
    const Eigen::VectorXd beta = g.solve(q.transpose() * y);
    y -= q * beta;
    if (restricted)
      for (Eigen::Index i = 0; i < p; ++i) extra += 2.0 * std::log(g.matrixLLT()(i, i));
  }
  const double m = restricted ? static_cast<double>(n - p) : static_cast<double>(n);
  return 0.5 * (logdet + extra + y.squaredNorm() + m * std::log(2.0 * std::numbers::pi));
}

void check_input(const Eigen::MatrixXd& x, const Eigen::VectorXd& z) {
  if (x.rows() != z.size())
    throw ArgumentError("likelihood: " + std::to_string(x.rows()) + " coordinate rows but " + std::to_string(z.size()) +
                        " values");
  if (x.rows() < 3) throw InputError("likelihood: " + std::to_string(x.rows()) + " samples; need at least 3");
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    if (!std::isfinite(z[i]))
      throw InputError("likelihood: value of sample " + std::to_string(i) + " is " + format_number(z[i]));
    for (Eigen::Index k = 0; k < x.cols(); ++k)
      if (!std::isfinite(x(i, k)))
        throw InputError("likelihood: coordinate " + std::to_string(k) + " of sample " + std::to_string(i) + " is " +
                         format_number(x(i, k)));
  }
}

struct Problem {
  const Eigen::MatrixXd* x;
  const Eigen::VectorXd* z;
  const Eigen::MatrixXd* f;
  std::vector<ModelComponent> structure;
  bool fit_nugget;
  bool restricted;
  int evaluations = 0;
  VariogramModel model_of(const double* theta) const {
    std::vector<ModelComponent> c = structure;
    std::size_t t = 0;
    for (auto& comp : c) {
      comp.sill = std::exp(theta[t++]);
      comp.range = std::exp(theta[t++]);
    }
    if (fit_nugget) {
      ModelComponent nug;
      nug.kind = ModelKind::Nugget;
      nug.sill = std::exp(theta[t++]);
      c.push_back(nug);
    }
    return VariogramModel(std::move(c));
  }
};

double objective(const double* theta, void* data) {
  auto& p = *static_cast<Problem*>(data);
  ++p.evaluations;
  const double v = nll(*p.x, *p.z, *p.f, p.model_of(theta), p.restricted);
  return std::isfinite(v) ? v : 1e300;
}

}  // namespace

void LikelihoodFitOptions::validate() const {
  if (kind == KrigingKind::Universal && (drift_order < 0 || drift_order > 2))
    throw ArgumentError("likelihood options: drift_order = " + std::to_string(drift_order) + "; expected 0, 1 or 2");
  if (!std::isfinite(simple_mean)) throw ArgumentError("likelihood options: simple_mean is not finite");
  if (max_evaluations < 1) throw ArgumentError("likelihood options: max_evaluations = " + std::to_string(max_evaluations) + "; expected >= 1");
  if (!(relative_tolerance > 0.0)) throw ArgumentError("likelihood options: relative_tolerance must be > 0");
}

double negative_log_likelihood(const Eigen::MatrixXd& coordinates, const Eigen::VectorXd& values,
                               const VariogramModel& model, const LikelihoodFitOptions& options) {
  options.validate();
  check_input(coordinates, values);
  Eigen::VectorXd z = values;
  if (options.kind == KrigingKind::Simple) z.array() -= options.simple_mean;
  return nll(coordinates, z, drift(coordinates, options), model, options.restricted);
}

LikelihoodFitResult fit_likelihood(const Eigen::MatrixXd& coordinates, const Eigen::VectorXd& values,
                                   const std::vector<ModelComponent>& structure, const LikelihoodFitOptions& options) {
  options.validate();
  check_input(coordinates, values);
  Problem pr;
  for (const auto& c : structure)
    if (c.kind != ModelKind::Nugget) {
      if (!c.bounded())
        throw ArgumentError("likelihood: component '" + std::string(model_kind_name(c.kind)) +
                            "' has no covariance (pow, lin); use nug, sph, exp, gau, mat or wen");
      pr.structure.push_back(c);
    }
  if (pr.structure.empty()) throw ArgumentError("likelihood: the structure has no non-nugget component");
  Eigen::VectorXd z = values;
  if (options.kind == KrigingKind::Simple) z.array() -= options.simple_mean;
  const Eigen::MatrixXd f = drift(coordinates, options);
  if (f.cols() >= coordinates.rows())
    throw InputError("likelihood: " + std::to_string(coordinates.rows()) + " samples for " + std::to_string(f.cols()) +
                     " drift terms");
  pr.x = &coordinates;
  pr.z = &z;
  pr.f = &f;
  pr.fit_nugget = options.fit_nugget;
  pr.restricted = options.restricted;

  const double var = std::max((values.array() - values.mean()).square().mean(), 1e-300);
  const double extent = (coordinates.colwise().maxCoeff() - coordinates.colwise().minCoeff()).norm();
  // All samples at one place: the ranges have no scale and every covariance matrix is singular
  // without a nugget; the fit "converged" with a likelihood of inf.
  if (!(extent > 0.0))
    throw InputError("likelihood: all " + std::to_string(coordinates.rows()) +
                     " samples are at one location; a variogram needs samples at different places");
  const double span = extent;
  std::vector<double> x0, lb, ub;
  const double ns = static_cast<double>(pr.structure.size());
  for (const auto& c : pr.structure) {
    x0.push_back(std::log(c.sill > 0.0 ? c.sill : var / ns));
    lb.push_back(std::log(var * 1e-6));
    ub.push_back(std::log(var * 100.0));
    x0.push_back(std::log(c.range > 0.0 ? c.range : span / 4.0));
    lb.push_back(std::log(span * 1e-4));
    ub.push_back(std::log(span * 10.0));
  }
  if (options.fit_nugget) {
    x0.push_back(std::log(var * 0.05));
    lb.push_back(std::log(var * 1e-10));
    ub.push_back(std::log(var * 10.0));
  }
  for (std::size_t i = 0; i < x0.size(); ++i) x0[i] = std::min(std::max(x0[i], lb[i]), ub[i]);
  detail::Bobyqa bobyqa(lb, ub, options.relative_tolerance, options.max_evaluations, "fit_likelihood");
  const detail::BobyqaOutcome outcome = bobyqa.minimize(&objective, &pr, x0);
  LikelihoodFitResult res;
  res.model = pr.model_of(x0.data());
  res.negative_log_likelihood = nll(coordinates, z, f, res.model, options.restricted);
  res.evaluations = pr.evaluations;
  res.converged = outcome.converged;
  res.message = bobyqa.describe(outcome, "likelihood");
  if (!std::isfinite(res.negative_log_likelihood))
    throw Error("likelihood: the negative log-likelihood is " + format_number(res.negative_log_likelihood) +
                " at the best parameters found (" + res.model.to_string() +
                "): the covariance matrix is singular there (duplicate locations without a nugget?); no model to "
                "report");
  return res;
}

}  // namespace errfield
