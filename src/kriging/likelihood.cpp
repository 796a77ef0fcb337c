#include "errfield/kriging_likelihood.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>

#include <Eigen/Cholesky>
#include <Eigen/QR>

#include "covariance_kernel.hpp"
#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"
#include "kriging/likelihood_profile.hpp"
#include "kriging/likelihood_rotated.hpp"
#include "kriging/likelihood_vecchia.hpp"
#include "kriging/vecchia_neighbours.hpp"
#include "optim/bobyqa.hpp"

namespace errfield {
namespace {

// Drift matrix (N x p) in centred, scaled coordinates, as the kriging engine builds it. Centring
// and scaling change F by a unit-triangular map times the column scales, so log det F'K^-1F - and
// the REML likelihood - differ from the raw columns' (1, x, y, ..., x^2, ..., the covariates as
// given) by a constant: `log_scale_sum` gets the sum of the logs of those column scales.
Eigen::MatrixXd drift(const Eigen::MatrixXd& x, const LikelihoodFitOptions& o, double* log_scale_sum = nullptr) {
  if (log_scale_sum) *log_scale_sum = 0.0;
  const Eigen::Index n = x.rows(), d = x.cols();
  if (o.kind == KrigingKind::Simple) return Eigen::MatrixXd(n, 0);
  const int order = o.kind == KrigingKind::Ordinary ? 0 : o.drift_order;
  const Eigen::RowVectorXd center = x.colwise().mean();
  Eigen::RowVectorXd scale = (x.rowwise() - center).cwiseAbs().colwise().maxCoeff();
  for (Eigen::Index k = 0; k < d; ++k)
    if (!(scale[k] > 0.0)) scale[k] = 1.0;
  const Eigen::MatrixXd u = (x.rowwise() - center).array().rowwise() / scale.array();
  std::vector<Eigen::VectorXd> cols{Eigen::VectorXd::Ones(n)};
  double logs = 0.0;
  if (order >= 1)
    for (Eigen::Index k = 0; k < d; ++k) {
      cols.push_back(u.col(k));
      logs += std::log(scale[k]);
    }
  if (order >= 2)
    for (Eigen::Index k = 0; k < d; ++k)
      for (Eigen::Index l = k; l < d; ++l) {
        cols.push_back(u.col(k).cwiseProduct(u.col(l)));
        logs += std::log(scale[k]) + std::log(scale[l]);
      }
  // External drift: one more column per covariate, centred and scaled like the coordinates.
  const Eigen::MatrixXd& cov = o.covariates;
  if (cov.cols() > 0 && cov.rows() != n)
    throw ArgumentError("likelihood options: covariates has " + std::to_string(cov.rows()) + " rows for " +
                        std::to_string(n) + " samples; expected one row per sample");
  for (Eigen::Index j = 0; j < cov.cols(); ++j) {
    const double mean = cov.col(j).mean();
    const double spread = (cov.col(j).array() - mean).abs().maxCoeff();
    cols.push_back((cov.col(j).array() - mean) / (spread > 0.0 ? spread : 1.0));
    if (spread > 0.0) logs += std::log(spread);
  }
  if (log_scale_sum) *log_scale_sum = logs;
  Eigen::MatrixXd f(n, static_cast<Eigen::Index>(cols.size()));
  for (std::size_t c = 0; c < cols.size(); ++c) f.col(static_cast<Eigen::Index>(c)) = cols[c];
  return f;
}

// The same row twice (location and values): the covariance of the pair is singular without a
// nugget while their equal values say there is none, and the fit ended on "a pure nugget effect".
// Said as what it is, naming the rows (1-based sample numbers, the data rows in input order).
void refuse_repeated_rows(const Eigen::MatrixXd& x, const Eigen::MatrixXd& z) {
  const Eigen::Index n = x.rows();
  std::vector<Eigen::Index> order(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) order[static_cast<std::size_t>(i)] = i;
  const auto key_less = [&](Eigen::Index a, Eigen::Index b) {
    for (Eigen::Index c = 0; c < x.cols(); ++c)
      if (x(a, c) != x(b, c)) return x(a, c) < x(b, c);
    for (Eigen::Index c = 0; c < z.cols(); ++c)
      if (z(a, c) != z(b, c)) return z(a, c) < z(b, c);
    return a < b;
  };
  std::sort(order.begin(), order.end(), key_less);
  std::size_t repeats = 0;
  Eigen::Index first = -1, later = -1;
  for (std::size_t k = 1; k < order.size(); ++k) {
    const Eigen::Index a = order[k - 1], b = order[k];
    if (x.row(a) != x.row(b) || z.row(a) != z.row(b)) continue;
    ++repeats;
    if (later < 0 || std::max(a, b) < later) first = std::min(a, b), later = std::max(a, b);
  }
  if (repeats == 0) return;
  throw InputError("likelihood: samples " + std::to_string(first + 1) + " and " + std::to_string(later + 1) +
                   " (data rows, 1-based) are duplicates: the same location and the same value" +
                   (repeats > 1 ? " (" + std::to_string(repeats) + " such repeated rows in all)" : std::string()) +
                   "; a row given twice is not a second measurement (a file concatenated twice?) and would read as "
                   "a pure nugget effect: drop the repeats");
}

// Covariates that are a linear combination of the other drift columns (another covariate, the
// constant or the coordinate terms) leave F without full rank; the fit then failed blaming
// "duplicate locations". Named, with what each depends on.
void refuse_collinear_covariates(const Eigen::MatrixXd& x, const LikelihoodFitOptions& o) {
  const Eigen::Index k = o.covariates.cols();
  if (k == 0 || o.covariates.rows() != x.rows()) return;
  const Eigen::MatrixXd f = drift(x, o);
  const Eigen::Index p = f.cols(), first_cov = p - k;
  const auto name = [&](Eigen::Index c) {
    if (c < first_cov) return c == 0 ? std::string("the constant") : "the coordinate term " + std::to_string(c);
    const auto j = static_cast<std::size_t>(c - first_cov);
    return j < o.covariate_names.size() ? "covariate '" + o.covariate_names[j] + "'"
                                        : "covariate " + std::to_string(j + 1);
  };
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(f);
  qr.setThreshold(1e-10);
  if (qr.rank() == p) return;
  const auto& perm = qr.colsPermutation().indices();
  std::vector<Eigen::Index> independent;
  for (Eigen::Index r = 0; r < qr.rank(); ++r) independent.push_back(perm(r));
  std::sort(independent.begin(), independent.end());
  std::string what;
  for (Eigen::Index r = qr.rank(); r < p; ++r) {
    Eigen::Index c = perm(r);
    if (c < first_cov) continue;  // a coordinate term found dependent: a covariate is the culprit below
    std::string on;
    if (f.col(c).squaredNorm() == 0.0) {
      on = " is constant (the constant term already holds it)";
    } else {
      Eigen::MatrixXd basis(f.rows(), static_cast<Eigen::Index>(independent.size()));
      for (std::size_t i = 0; i < independent.size(); ++i) basis.col(static_cast<Eigen::Index>(i)) = f.col(independent[i]);
      const Eigen::VectorXd coef = basis.colPivHouseholderQr().solve(f.col(c));
      std::string terms;
      for (std::size_t i = 0; i < independent.size(); ++i)
        if (std::abs(coef(static_cast<Eigen::Index>(i))) > 1e-8) terms += (terms.empty() ? "" : ", ") + name(independent[i]);
      on = " is a linear combination of " + (terms.empty() ? std::string("the other drift columns") : terms);
    }
    what += (what.empty() ? "" : "; ") + name(c) + on;
  }
  if (what.empty()) what = "the covariates repeat the coordinate terms of the drift (--kind universal1/2)";
  throw InputError("likelihood: collinear covariates: " + what +
                   "; the drift matrix has rank " + std::to_string(qr.rank()) + " for " + std::to_string(p) +
                   " columns, so their coefficients are not determined: drop the redundant covariate(s)");
}

double nll(const Eigen::MatrixXd& x, const Eigen::MatrixXd& z, const Eigen::MatrixXd& f, const VariogramModel& model,
           bool restricted) {
  const kernels::CovarianceKernel kernel(model);
  const Eigen::Index n = x.rows(), p = f.cols();
  const Eigen::MatrixXd xt = x.transpose();  // points as columns
  Eigen::MatrixXd k(n, n);
  // The nugget is noise of each reading: it belongs on the diagonal only. Two readings at one
  // location (a re-measured pose) share the continuous part, C(0) - nugget; with the whole C(0)
  // off the diagonal too their rows were equal and every model "singular" despite its nugget.
  const double shared_zero_lag = kernel.sill() - kernel.nugget();
  for (Eigen::Index j = 0; j < n; ++j)
    kernels::covariance_block(kernel, xt.col(j).data(), static_cast<std::size_t>(n - j), xt.col(j).data(), 1,
                              static_cast<int>(xt.rows()), shared_zero_lag, &k(j, j), static_cast<std::size_t>(n));
  k.diagonal().setConstant(kernel.sill());
  Eigen::LLT<Eigen::MatrixXd> llt(k);
  if (llt.info() != Eigen::Success) return std::numeric_limits<double>::infinity();
  const auto& l = llt.matrixLLT();
  double logdet = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) logdet += 2.0 * std::log(l(i, i));
  Eigen::MatrixXd y = z;
  llt.matrixL().solveInPlace(y);
  double extra = 0.0;
  if (p > 0) {
    Eigen::MatrixXd q = f;
    llt.matrixL().solveInPlace(q);
    Eigen::LLT<Eigen::MatrixXd> g(q.transpose() * q);
    if (g.info() != Eigen::Success) return std::numeric_limits<double>::infinity();
    const Eigen::MatrixXd beta = g.solve(q.transpose() * y);
    y -= q * beta;
    if (restricted)
      for (Eigen::Index i = 0; i < p; ++i) extra += 2.0 * std::log(g.matrixLLT()(i, i));
  }
  // Vector values: the components are independent given the shared model, so the terms sum.
  const double c = static_cast<double>(z.cols());
  const double m = restricted ? static_cast<double>(n - p) : static_cast<double>(n);
  return 0.5 * (c * (logdet + extra) + y.squaredNorm() + c * m * std::log(2.0 * std::numbers::pi));
}

// REML of the raw drift columns (the textbook value, Harville 1974, without nlme's + 0.5 log det F'F):
// the optimizer works with the scaled F, and the printed value adds the constant back (per value
// column). ML does not depend on the basis of F.
double textbook_reml_offset(const LikelihoodFitOptions& o, double log_scale_sum, Eigen::Index value_columns) {
  return o.restricted ? static_cast<double>(value_columns) * log_scale_sum : 0.0;
}

void check_input(const Eigen::MatrixXd& x, const Eigen::MatrixXd& z) {
  if (x.rows() != z.rows())
    throw ArgumentError("likelihood: " + std::to_string(x.rows()) + " coordinate rows but " + std::to_string(z.rows()) +
                        " values");
  if (z.cols() < 1) throw ArgumentError("likelihood: values have no column");
  if (x.rows() < 3) throw InputError("likelihood: " + std::to_string(x.rows()) + " samples; need at least 3");
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    for (Eigen::Index c = 0; c < z.cols(); ++c)
      if (!std::isfinite(z(i, c)))
        throw InputError("likelihood: value of sample " + std::to_string(i) + " (component " + std::to_string(c) +
                         ") is " + format_number(z(i, c)));
    for (Eigen::Index k = 0; k < x.cols(); ++k)
      if (!std::isfinite(x(i, k)))
        throw InputError("likelihood: coordinate " + std::to_string(k) + " of sample " + std::to_string(i) + " is " +
                         format_number(x(i, k)));
  }
}

struct Problem {
  const Eigen::MatrixXd* x;
  const Eigen::MatrixXd* z;
  const Eigen::MatrixXd* f;
  std::vector<ModelComponent> structure;
  bool fit_nugget;
  const LikelihoodFitOptions* options = nullptr;
  const detail::VecchiaNeighbours* neighbours = nullptr;  // Vecchia: isotropic, so fixed
  int evaluations = 0;
  // Held parameters: the optimizer sees only the entries of the full vector (log sill, log range
  // per component, then log nugget) whose is_free is set; the others stay at full's values.
  std::vector<double> full;
  std::vector<bool> is_free;
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
  VariogramModel model_of(const double* x) const {
    const std::vector<double> f = expand(x);
    const double* theta = f.data();
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


// The likelihood of `model` as written, exact or Vecchia as `o` says; Vecchia's neighbours are found
// in the model's metric (its anisotropy applied), unless `neighbours` gives them.
double nll_of_model(const Eigen::MatrixXd& x, const Eigen::MatrixXd& z, const Eigen::MatrixXd& f,
                    const VariogramModel& model, const LikelihoodFitOptions& o,
                    const detail::VecchiaNeighbours* neighbours = nullptr) {
  const Anisotropy& a = model.anisotropy();
  const bool vecchia = likelihood_uses_vecchia(o, static_cast<long>(x.rows()));
  if (a.isotropic() && !vecchia) return nll(x, z, f, model, o.restricted);
  // The drift stays a polynomial of the given coordinates; only the lags are mapped.
  Eigen::MatrixXd mapped = x;
  if (!a.isotropic()) {
    Eigen::VectorXd in(x.cols()), out(x.cols());
    for (Eigen::Index i = 0; i < x.rows(); ++i) {
      in = x.row(i).transpose();
      a.apply(in.data(), out.data(), static_cast<int>(in.size()));
      mapped.row(i) = out.transpose();
    }
  }
  if (!vecchia) return nll(mapped, z, f, model, o.restricted);
  const Eigen::MatrixXd points = mapped.transpose();
  if (neighbours) return detail::vecchia_model_nll(points, z, f, model, o.restricted, *neighbours);
  const detail::VecchiaNeighbours found = detail::find_vecchia_neighbours(points, o.vecchia_neighbours, o.vecchia_ordering);
  return detail::vecchia_model_nll(points, z, f, model, o.restricted, found);
}

double objective(const double* theta, void* data) {
  auto& p = *static_cast<Problem*>(data);
  ++p.evaluations;
  const double v = nll_of_model(*p.x, *p.z, *p.f, p.model_of(theta), *p.options, p.neighbours);
  return std::isfinite(v) ? v : 1e300;
}

LikelihoodFitResult fit_likelihood_checked(const Eigen::MatrixXd& coordinates, const Eigen::MatrixXd& values,
                                           const std::vector<ModelComponent>& structure,
                                           const LikelihoodFitOptions& options);
LikelihoodFitResult fit_bobyqa(const Eigen::MatrixXd& coordinates, const Eigen::MatrixXd& values,
                               const std::vector<ModelComponent>& structure, const LikelihoodFitOptions& options);

}  // namespace

bool likelihood_uses_vecchia(const LikelihoodFitOptions& options, long samples) {
  return options.method == LikelihoodMethod::Vecchia ||
         (options.method == LikelihoodMethod::Auto && samples > options.exact_max_samples);
}

namespace {

// The rotated fit's work (kMaxRotatedLikelihoodWork's units) and, beyond the budget, the refusal
// naming what fits: the samples at these options, and for Vecchia the neighbours at these samples.
void check_rotated_budget(long n, int dimension, const LikelihoodFitOptions& options) {
  if (options.anisotropy != LikelihoodFitOptions::Anisotropy::Rotated || (dimension != 2 && dimension != 3)) return;
  const double fits = dimension == 2 ? kRotatedProfileFits2d : kRotatedProfileFits3d;
  const bool vecchia = likelihood_uses_vecchia(options, n);
  const double m = options.vecchia_neighbours;
  const double nd = static_cast<double>(n);
  const double work = vecchia ? fits * nd * m * m * m : fits * nd * nd * nd;
  if (work <= kMaxRotatedLikelihoodWork) return;
  const double n_fit = vecchia ? std::floor(kMaxRotatedLikelihoodWork / (fits * m * m * m))
                               : std::floor(std::cbrt(kMaxRotatedLikelihoodWork / fits));
  std::string advice = "a subsample of at most " + format_number(n_fit) + " samples";
  if (vecchia) {
    const double m_fit = std::floor(std::cbrt(kMaxRotatedLikelihoodWork / (fits * nd)));
    if (m_fit >= 1) advice += ", or at most " + format_number(m_fit) + " Vecchia neighbours (vecchia_neighbours)";
  } else if (fits * nd * m * m * m <= kMaxRotatedLikelihoodWork) {
    advice += ", or the Vecchia likelihood (likelihood vecchia, " + format_number(m) + " neighbours)";
  }
  throw ResourceError("likelihood: rotated anisotropy in " + std::to_string(dimension) + "-D searches the angles with ~" +
                      format_number(fits) + " ARD fits, each of hundreds of " +
                      (vecchia ? "Vecchia evaluations of O(N m^3) (m = " + format_number(m) + ")"
                               : std::string("exact evaluations of O(N^3)")) +
                      ": for N = " + std::to_string(n) + " samples that is ~" + format_number(std::round(work / 6e8) / 10) +
                      " minutes' work on 2 cores, over the budget of about one; fits: " + advice +
                      "; or ARD (anisotropy ard: the axes' ranges, no angles, one fit)");
}

}  // namespace

void check_likelihood_budget(Eigen::Index samples, Eigen::Index columns, const LikelihoodFitOptions& options,
                             int dimension) {
  const long n = static_cast<long>(samples);
  check_rotated_budget(n, dimension, options);
  if (!likelihood_uses_vecchia(options, n)) {
    if (n > kMaxLikelihoodSamples)
      throw ResourceError("likelihood: " + std::to_string(n) +
                          " samples; the exact likelihood costs O(N^3) per evaluation and is limited to " +
                          std::to_string(kMaxLikelihoodSamples) +
                          " samples: use the Vecchia approximation (method auto or vecchia; 'errfield fit-variogram "
                          "--likelihood vecchia'), fit the empirical variogram ('--method wls') or a subsample");
    return;
  }
  if (n > kMaxVecchiaLikelihoodSamples)
    throw ResourceError("likelihood: " + std::to_string(n) + " samples; the Vecchia likelihood is limited to " +
                        std::to_string(kMaxVecchiaLikelihoodSamples) + " samples: fit a subsample");
  // Per sample: the neighbour sets, the whitened columns (values and drift) and their derivatives.
  const std::size_t drift_columns = options.kind == KrigingKind::Simple      ? 0
                                    : options.kind == KrigingKind::Ordinary ? 1
                                                                            : 28;  // at most (order 2, D = 6)
  const double bytes = detail::vecchia_memory_bytes(static_cast<std::size_t>(n), options.vecchia_neighbours,
                                                    static_cast<std::size_t>(columns) + drift_columns, 8);
  if (bytes > static_cast<double>(options.vecchia_memory_budget_bytes))
    throw ResourceError("likelihood: the Vecchia likelihood needs ~" + format_number(std::round(bytes / (1 << 20))) +
                        " MiB for N = " + std::to_string(n) + " samples and " +
                        std::to_string(options.vecchia_neighbours) + " neighbours, over vecchia_memory_budget_bytes = " +
                        format_number(std::round(static_cast<double>(options.vecchia_memory_budget_bytes) / (1 << 20))) +
                        " MiB: fewer neighbours or a subsample");
}

void LikelihoodFitOptions::validate() const {
  if (exact_max_samples < 1 || exact_max_samples > kExactLikelihoodMaxSamples)
    throw ArgumentError("likelihood options: exact_max_samples = " + std::to_string(exact_max_samples) +
                        " is outside 1.." + std::to_string(kExactLikelihoodMaxSamples));
  if (vecchia_neighbours < 1 || vecchia_neighbours > kMaxVecchiaNeighbours)
    throw ArgumentError("likelihood options: vecchia_neighbours = " + std::to_string(vecchia_neighbours) +
                        "; expected 1 to " + std::to_string(kMaxVecchiaNeighbours));
  if (kind == KrigingKind::Universal && (drift_order < 0 || drift_order > 2))
    throw ArgumentError("likelihood options: drift_order = " + std::to_string(drift_order) + "; expected 0, 1 or 2");
  if (!std::isfinite(simple_mean)) throw ArgumentError("likelihood options: simple_mean is not finite");
  if (kind == KrigingKind::Simple && covariates.cols() > 0)
    throw ArgumentError("likelihood options: covariates with kind simple; expected ordinary (external drift) or universal");
  for (Eigen::Index i = 0; i < covariates.rows(); ++i)
    for (Eigen::Index j = 0; j < covariates.cols(); ++j)
      if (!std::isfinite(covariates(i, j)))
        throw InputError("likelihood options: covariates(" + std::to_string(i) + ", " + std::to_string(j) + ") is " +
                         format_number(covariates(i, j)) + "; expected a finite number");
  if (max_evaluations < 1) throw ArgumentError("likelihood options: max_evaluations = " + std::to_string(max_evaluations) + "; expected >= 1");
  if (!(relative_tolerance > 0.0)) throw ArgumentError("likelihood options: relative_tolerance must be > 0");
  if (starts < 1 || local_runs < 1) throw ArgumentError("likelihood options: starts and local_runs must be >= 1");
  if (!(min_nugget_ratio >= 0.0) || !std::isfinite(min_nugget_ratio))
    throw ArgumentError("likelihood options: min_nugget_ratio must be a finite value >= 0");
  for (double nu : matern_nu_choices)
    if (!(nu > 0.0 && nu <= 100.0)) throw ArgumentError("likelihood options: matern_nu_choices has " + format_number(nu) + "; expected 0 < nu <= 100");
}

double negative_log_likelihood(const Eigen::MatrixXd& coordinates, const Eigen::MatrixXd& values,
                               const VariogramModel& model, const LikelihoodFitOptions& options) {
  options.validate();
  check_input(coordinates, values);
  Eigen::MatrixXd z = values;
  if (options.kind == KrigingKind::Simple) z.array() -= options.simple_mean;
  const Anisotropy& a = model.anisotropy();
  if (!a.isotropic() && a.dimension() != coordinates.cols())
    throw ArgumentError("likelihood: the model's anisotropy " + a.to_string() + " is for " +
                        std::to_string(a.dimension()) + " coordinates but the samples have " +
                        std::to_string(coordinates.cols()));
  double log_scales = 0.0;
  const Eigen::MatrixXd f = drift(coordinates, options, &log_scales);
  return nll_of_model(coordinates, z, f, model, options) + textbook_reml_offset(options, log_scales, values.cols());
}

LikelihoodFitResult fit_likelihood(const Eigen::MatrixXd& coordinates, const Eigen::MatrixXd& values,
                                   const std::vector<ModelComponent>& structure, const LikelihoodFitOptions& options) {
  options.validate();
  check_input(coordinates, values);
  // Arguments before data: an unbounded structure is the caller's mistake whatever the values.
  for (const auto& c : structure)
    if (c.kind != ModelKind::Nugget && !c.bounded())
      throw ArgumentError("likelihood: component '" + std::string(model_kind_name(c.kind)) +
                          "' has no covariance (pow, lin); use nug, sph, exp, gau, mat or wen");
  std::vector<double> nus = options.matern_nu_choices;
  for (const auto& c : structure)
    if (c.kind == ModelKind::Matern) nus.push_back(c.nu);
  for (double nu : nus)
    if (!(nu > 0.0 && nu <= kMaxMaternNu))
      throw ArgumentError("likelihood: Matérn nu = " + format_number(nu) + "; expected 0 < nu <= " + format_number(kMaxMaternNu));
  check_likelihood_budget(coordinates.rows(), values.cols(), options, static_cast<int>(coordinates.cols()));
  if (coordinates.rows() < kMinLikelihoodSamples)
    throw InputError("likelihood: " + std::to_string(coordinates.rows()) + " samples; need at least " +
                     std::to_string(kMinLikelihoodSamples));
  // A constant field has sill 0: the fit would "converge" on a sill of ~1e-34 that means nothing.
  const double spread = (values.colwise().maxCoeff() - values.colwise().minCoeff()).maxCoeff();
  if (!(spread > 0.0))
    throw InputError("likelihood: all " + std::to_string(coordinates.rows()) + " values are equal (" +
                     format_number(values(0, 0)) + "); a constant field has no variogram to fit");
  if (spread < kMinLikelihoodValueSpread || spread > kMaxLikelihoodValueSpread)
    throw InputError("likelihood: the values spread over " + format_number(spread) +
                     " (max - min); the likelihood overflows or underflows a double beyond [" +
                     format_number(kMinLikelihoodValueSpread) + ", " + format_number(kMaxLikelihoodValueSpread) +
                     "]: rescale the values (e.g. to units where they are of order 1) and scale the sill back");
  refuse_repeated_rows(coordinates, values);
  refuse_collinear_covariates(coordinates, options);
  LikelihoodFitResult res = fit_likelihood_checked(coordinates, values, structure, options);
  double log_scales = 0.0;
  drift(coordinates, options, &log_scales);
  res.negative_log_likelihood += textbook_reml_offset(options, log_scales, values.cols());
  const double n = static_cast<double>(coordinates.rows() * values.cols());
  res.aic = 2.0 * res.negative_log_likelihood + 2.0 * res.parameters;
  res.bic = 2.0 * res.negative_log_likelihood + res.parameters * std::log(n);
  return res;
}

namespace {

LikelihoodFitResult fit_likelihood_checked(const Eigen::MatrixXd& coordinates, const Eigen::MatrixXd& values,
                                           const std::vector<ModelComponent>& structure,
                                           const LikelihoodFitOptions& options) {
  std::vector<ModelComponent> non_nugget;
  for (const auto& c : structure)
    if (c.kind != ModelKind::Nugget) non_nugget.push_back(c);
  const bool ard = options.anisotropy != LikelihoodFitOptions::Anisotropy::None;
  const auto any = [](const std::vector<bool>& v) { return std::find(v.begin(), v.end(), true) != v.end(); };
  const bool holds = any(options.hold_sill) || any(options.hold_range);
  if (holds && ard)
    throw ArgumentError("likelihood: held parameters (hold_sill / hold_range) are for isotropic fits; not with ARD or "
                        "rotated anisotropy");
  if (holds) return fit_bobyqa(coordinates, values, structure, options);
  if (non_nugget.size() == 1 && non_nugget[0].kind == ModelKind::Matern && !options.matern_nu_choices.empty()) {
    LikelihoodFitResult best;
    bool have = false;
    for (double nu : options.matern_nu_choices) {
      std::vector<ModelComponent> s{non_nugget[0]};
      s[0].nu = nu;
      LikelihoodFitOptions o = options;
      o.matern_nu_choices.clear();
      LikelihoodFitResult r = fit_likelihood_checked(coordinates, values, s, o);
      if (!have || r.negative_log_likelihood < best.negative_log_likelihood) best = std::move(r), have = true;
    }
    best.message += "; nu chosen among the " + std::to_string(options.matern_nu_choices.size()) + " given";
    return best;
  }
  if (non_nugget.size() == 1 && detail::profiled_fit_supported(non_nugget[0])) {
    // All samples at one place: no range has a scale and the fit would "converge" to inf.
    if (coordinates.rows() > 0 && !((coordinates.colwise().maxCoeff() - coordinates.colwise().minCoeff()).norm() > 0.0))
      throw InputError("likelihood: all " + std::to_string(coordinates.rows()) +
                       " samples are at one location; a variogram needs samples at different places");
    Eigen::MatrixXd z = values;
    if (options.kind == KrigingKind::Simple) z.array() -= options.simple_mean;
    const Eigen::MatrixXd f = drift(coordinates, options);
    if (f.cols() >= coordinates.rows())
      throw InputError("likelihood: " + std::to_string(coordinates.rows()) + " samples for " +
                       std::to_string(f.cols()) + " drift terms");
    LikelihoodFitResult r = options.anisotropy == LikelihoodFitOptions::Anisotropy::Rotated
                                ? detail::fit_rotated_likelihood(coordinates, z, f, non_nugget[0], options)
                                : detail::fit_profiled_likelihood(coordinates, z, f, non_nugget[0], options);
    // Report the likelihood of the model as written, by the plain formula (a check of the profile).
    r.negative_log_likelihood = nll_of_model(coordinates, z, f, r.model, options);
    if (!std::isfinite(r.negative_log_likelihood))
      throw Error("likelihood: the negative log-likelihood is " + format_number(r.negative_log_likelihood) +
                  " at the best parameters found (" + r.model.to_string() +
                  "): the covariance matrix is singular there (duplicate locations without a nugget?); no model to "
                  "report");
    return r;
  }
  if (ard)
    throw ArgumentError("likelihood: ARD and rotated anisotropy fit one structure of sph, exp, gau, wen or mat with nu 0.5, 1.5 or 2.5 "
                        "(plus a nugget); got " + std::to_string(non_nugget.size()) + " structure(s)" +
                        (non_nugget.size() == 1 ? " '" + std::string(model_kind_name(non_nugget[0].kind)) + "'" : ""));
  return fit_bobyqa(coordinates, values, structure, options);
}

// The structure's covariance components (the nugget is a parameter of its own).
std::vector<ModelComponent> covariance_components(const std::vector<ModelComponent>& structure) {
  std::vector<ModelComponent> out;
  for (const auto& c : structure)
    if (c.kind != ModelKind::Nugget) {
      if (!c.bounded())
        throw ArgumentError("likelihood: component '" + std::string(model_kind_name(c.kind)) +
                            "' has no covariance (pow, lin); use nug, sph, exp, gau, mat or wen");
      out.push_back(c);
    }
  if (out.empty()) throw ArgumentError("likelihood: the structure has no non-nugget component");
  return out;
}

// Log parameters (sill, range per component, then a free nugget), their start and box from the
// values' variance and the samples' span; pr.is_free marks the held ones.
struct LogParameters {
  std::vector<double> x0, lb, ub;
};

LogParameters log_parameters(Problem& pr, const LikelihoodFitOptions& options, double var, double span) {
  std::vector<double> x0, lb, ub;
  const double ns = static_cast<double>(pr.structure.size());
  for (const auto* hold : {&options.hold_sill, &options.hold_range})
    if (!hold->empty() && hold->size() != pr.structure.size())
      throw ArgumentError("likelihood: " + std::to_string(hold->size()) + " hold flags for " +
                          std::to_string(pr.structure.size()) + " structure component(s); expected one per non-nugget "
                          "component");
  for (std::size_t i = 0; i < pr.structure.size(); ++i) {
    const ModelComponent& c = pr.structure[i];
    const bool hold_sill = !options.hold_sill.empty() && options.hold_sill[i];
    const bool hold_range = !options.hold_range.empty() && options.hold_range[i];
    const std::string name = std::string(model_kind_name(c.kind)) + " (structure " + std::to_string(i + 1) + ")";
    if (hold_sill && !(c.sill > 0.0 && std::isfinite(c.sill)))
      throw ArgumentError("likelihood: the sill of " + name + " is held but given as " + format_number(c.sill) +
                          "; a held sill needs a value > 0");
    if (hold_range && !(c.range > 0.0 && std::isfinite(c.range)))
      throw ArgumentError("likelihood: the range of " + name + " is held but given as " + format_number(c.range) +
                          "; a held range needs a value > 0");
    x0.push_back(std::log(c.sill > 0.0 ? c.sill : var / ns));
    lb.push_back(std::log(var * 1e-6));
    ub.push_back(std::log(var * 100.0));
    pr.is_free.push_back(!hold_sill);
    x0.push_back(std::log(c.range > 0.0 ? c.range : span / 4.0));
    lb.push_back(std::log(span * 1e-4));
    ub.push_back(std::log(span * 10.0));
    pr.is_free.push_back(!hold_range);
  }
  if (options.fit_nugget) {
    x0.push_back(std::log(options.nugget_start > 0.0 ? options.nugget_start : var * 0.05));
    lb.push_back(std::log(var * 1e-10));
    ub.push_back(std::log(var * 10.0));
    pr.is_free.push_back(true);
  }
  for (std::size_t i = 0; i < x0.size(); ++i)
    if (pr.is_free[i]) x0[i] = std::min(std::max(x0[i], lb[i]), ub[i]);  // held: as given, even outside
  return {std::move(x0), std::move(lb), std::move(ub)};
}

LikelihoodFitResult fit_bobyqa(const Eigen::MatrixXd& coordinates, const Eigen::MatrixXd& values,
                               const std::vector<ModelComponent>& structure, const LikelihoodFitOptions& options) {
  Problem pr;
  pr.structure = covariance_components(structure);
  Eigen::MatrixXd z = values;
  if (options.kind == KrigingKind::Simple) z.array() -= options.simple_mean;
  const Eigen::MatrixXd f = drift(coordinates, options);
  if (f.cols() >= coordinates.rows())
    throw InputError("likelihood: " + std::to_string(coordinates.rows()) + " samples for " + std::to_string(f.cols()) +
                     " drift terms");
  pr.x = &coordinates;
  pr.z = &z;
  pr.f = &f;
  pr.fit_nugget = options.fit_nugget;
  pr.options = &options;
  detail::VecchiaNeighbours neighbours;
  if (likelihood_uses_vecchia(options, static_cast<long>(coordinates.rows()))) {
    neighbours = detail::find_vecchia_neighbours(coordinates.transpose(), options.vecchia_neighbours,
                                                 options.vecchia_ordering);
    pr.neighbours = &neighbours;
  }

  const double var = std::max((values.rowwise() - values.colwise().mean()).array().square().mean(), 1e-300);
  const double extent = (coordinates.colwise().maxCoeff() - coordinates.colwise().minCoeff()).norm();
  // All samples at one place: the ranges have no scale and every covariance matrix is singular
  // without a nugget; the fit "converged" with a likelihood of inf.
  if (!(extent > 0.0))
    throw InputError("likelihood: all " + std::to_string(coordinates.rows()) +
                     " samples are at one location; a variogram needs samples at different places");
  LogParameters params = log_parameters(pr, options, var, extent);
  std::vector<double>& x0 = params.x0;
  const std::vector<double>& lb = params.lb;
  const std::vector<double>& ub = params.ub;
  pr.full = x0;
  if (std::count(pr.is_free.begin(), pr.is_free.end(), true) == 0)
    throw ArgumentError("likelihood: every parameter is held; nothing to fit");
  const std::vector<double> lb_free = pr.compress(lb), ub_free = pr.compress(ub);
  x0 = pr.compress(x0);
  detail::Bobyqa bobyqa(lb_free, ub_free, options.relative_tolerance, options.max_evaluations, "fit_likelihood");
  const detail::BobyqaOutcome outcome = bobyqa.minimize(&objective, &pr, x0);
  LikelihoodFitResult res;
  res.model = [&] {  // held values exactly as given (exp(log(v)) may change the last bit)
    std::vector<ModelComponent> c = pr.model_of(x0.data()).components();
    for (std::size_t i = 0; i < pr.structure.size(); ++i) {
      if (!options.hold_sill.empty() && options.hold_sill[i]) c[i].sill = pr.structure[i].sill;
      if (!options.hold_range.empty() && options.hold_range[i]) c[i].range = pr.structure[i].range;
    }
    return VariogramModel(std::move(c));
  }();
  res.negative_log_likelihood = nll_of_model(coordinates, z, f, res.model, options, pr.neighbours);
  res.evaluations = pr.evaluations;
  res.converged = outcome.converged;
  res.message = bobyqa.describe(outcome, "likelihood");
  if (!std::isfinite(res.negative_log_likelihood))
    throw Error("likelihood: the negative log-likelihood is " + format_number(res.negative_log_likelihood) +
                " at the best parameters found (" + res.model.to_string() +
                "): the covariance matrix is singular there (duplicate locations without a nugget?); no model to "
                "report");
  res.parameters = static_cast<int>(x0.size());  // the free ones
  for (const auto& c : res.model.components())
    if (c.kind != ModelKind::Nugget) {
      res.ranges.push_back(c.range);
      res.range_standard_errors.push_back(std::numeric_limits<double>::quiet_NaN());
    }
  return res;
}

}  // namespace

}  // namespace errfield
