// errfield.variogram, errfield.VariogramModel, errfield.fit_variogram and the likelihood fits.

#include <cmath>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <nlohmann/json.hpp>

#include "errfield/coregionalization_fit.hpp"
#include "errfield/csv_table.hpp"
#include "errfield/empirical_variogram.hpp"
#include "errfield/error.hpp"
#include "errfield/interpolation_options.hpp"
#include "errfield/kriging_likelihood.hpp"
#include "errfield/trend_residuals.hpp"
#include "errfield/variogram_fit.hpp"
#include "errfield/variogram_cloud.hpp"
#include "errfield/variogram_model.hpp"
#include "python/arrays.hpp"
#include "python/bindings.hpp"
#include "python/options.hpp"

namespace errfield::python {

namespace {

/// The result of errfield.variogram: the CLI's CSV columns as NumPy arrays.
struct PyVariogram {
  py::object lag_lo, lag_hi, lag_mean, gamma, pairs, component_gamma;
  std::string estimator, convention;
  double pair_fraction = 1.0;
};

// Covariate values (external drift): (rows,) for one covariate or (rows, k); None = none.
Eigen::MatrixXd covariates_rows(const py::object& covariates, Eigen::Index rows) {
  if (covariates.is_none()) return {};
  const MatrixArg c = matrix_arg(covariates, "covariates", ArraySpec{1, 2, -1, 1});
  if (c.data.rows() != rows)
    throw ArgumentError("covariates: " + std::to_string(c.data.rows()) + " rows but coords has " +
                        std::to_string(rows) + "; expected one row of covariate values per location");
  return c.data;
}

// The sampling options errfield.variogram and errfield.cross_variogram share, then the variogram
// computed without the GIL; `options` carries what differs (estimator, cross_variograms). The
// callers read the bin edges first, so a bad `bins` is reported before a bad option word.
EmpiricalVariogram variogram_without_gil(const Eigen::MatrixXd& x, const Eigen::MatrixXd& z, const LagBins& lag_bins,
                                         EmpiricalVariogramOptions options, const std::string& convention,
                                         double pair_fraction, std::uint64_t seed, int threads) {
  options.convention = convention_from_name(convention);
  options.pair_fraction = pair_fraction;
  options.seed = seed;
  options.threads = threads;
  options.validate();
  py::gil_scoped_release release;
  return empirical_variogram(x, z, lag_bins, options);
}

// Each bin's lag range, mean lag and pair count as NumPy arrays (the CSV's lag columns).
struct BinLagArrays {
  py::object lag_lo, lag_hi, lag_mean, pairs;
};
BinLagArrays bin_lag_arrays(const EmpiricalVariogram& v) {
  const std::size_t n = v.bins.size();
  std::vector<double> lo(n), hi(n), mean(n);
  std::vector<std::uint64_t> pairs(n);
  for (std::size_t k = 0; k < n; ++k) {
    lo[k] = v.bins[k].lag_lo;
    hi[k] = v.bins[k].lag_hi;
    mean[k] = v.bins[k].lag_mean;
    pairs[k] = v.bins[k].pairs;
  }
  return {to_numpy(lo), to_numpy(hi), to_numpy(mean), to_numpy(pairs)};
}

PyVariogram run_variogram(const py::object& coords, const py::object& values, const py::object& bins,
                          const std::string& estimator, const std::string& convention, double pair_fraction,
                          std::uint64_t seed, int threads, const py::object& covariates) {
  const MatrixArg x = matrix_arg(coords, "coords", ArraySpec{1, 2, -1, 2});
  MatrixArg z = matrix_arg(values, "values", ArraySpec{1, 2, -1, 1});
  if (z.data.rows() != x.data.rows())
    throw ArgumentError("values: " + std::to_string(z.data.rows()) + " rows but coords has " +
                        std::to_string(x.data.rows()) + "; expected one value (row) per location");
  if (!covariates.is_none()) z.data = ols_trend_residuals(z.data, covariates_rows(covariates, x.data.rows()));
  const LagBins lag_bins = LagBins::from_edges(vector_arg(bins, "bins", 2));
  EmpiricalVariogramOptions options;
  options.estimator = estimator_from_name(estimator);
  const EmpiricalVariogram v =
      variogram_without_gil(x.data, z.data, lag_bins, options, convention, pair_fraction, seed, threads);
  std::vector<double> gamma(v.bins.size());
  for (std::size_t k = 0; k < gamma.size(); ++k) gamma[k] = v.bins[k].gamma;
  const BinLagArrays lags = bin_lag_arrays(v);
  PyVariogram out;
  out.lag_lo = lags.lag_lo;
  out.lag_hi = lags.lag_hi;
  out.lag_mean = lags.lag_mean;
  out.gamma = to_numpy(gamma);
  out.pairs = lags.pairs;
  out.component_gamma = to_numpy(v.component_gamma);
  out.estimator = std::string(estimator_name(v.estimator));
  out.convention = std::string(convention_name(v.convention));
  out.pair_fraction = v.pair_fraction;
  return out;
}

/// errfield.variogram_cloud: every pair within the cutoff, as `errfield variogram --cloud`.
py::dict run_variogram_cloud(const py::object& coords, const py::object& values, double cutoff, std::uint64_t max_pairs) {
  const MatrixArg x = matrix_arg(coords, "coords", ArraySpec{1, 2, -1, 2});
  const MatrixArg z = matrix_arg(values, "values", ArraySpec{1, 2, -1, 1});
  VariogramCloudOptions o;
  o.cutoff = cutoff;
  o.max_pairs = max_pairs;
  VariogramCloud c;
  {
    py::gil_scoped_release release;
    c = variogram_cloud(x.data, z.data, o);
  }
  std::vector<std::uint64_t> left(c.left.begin(), c.left.end()), right(c.right.begin(), c.right.end());
  py::dict d;
  d["left"] = to_numpy(left);
  d["right"] = to_numpy(right);
  d["dist"] = to_numpy(c.dist);
  d["gamma"] = to_numpy(c.gamma);
  return d;
}

/// errfield.variogram_map: gstat's variogram map, as `errfield variogram --map`.
py::dict run_variogram_map(const py::object& coords, const py::object& values, double cutoff,
                           const std::pair<double, double>& width) {
  const MatrixArg x = matrix_arg(coords, "coords", ArraySpec{2, 2, 2, 2});
  const MatrixArg z = matrix_arg(values, "values", ArraySpec{1, 2, -1, 1});
  VariogramMapOptions o;
  o.cutoff = cutoff;
  o.width_x = width.first;
  o.width_y = width.second;
  VariogramMap m;
  {
    py::gil_scoped_release release;
    m = variogram_map(x.data, z.data, o);
  }
  Eigen::MatrixXd gamma(m.rows, m.columns), pairs(m.rows, m.columns);
  for (int r = 0; r < m.rows; ++r)
    for (int c = 0; c < m.columns; ++c) {
      const auto k = static_cast<std::size_t>(r) * static_cast<std::size_t>(m.columns) + static_cast<std::size_t>(c);
      gamma(r, c) = m.gamma[k];
      pairs(r, c) = static_cast<double>(m.pairs[k]);
    }
  py::dict d;
  d["dx"] = to_numpy(m.lag_x);
  d["dy"] = to_numpy(m.lag_y);
  d["gamma"] = to_numpy(gamma);
  d["pairs"] = to_numpy(pairs);
  return d;
}

/// errfield.cross_variogram: direct and cross variograms as a dict of NumPy arrays, gamma (bins, P, P).
py::dict run_cross_variogram(const py::object& coords, const py::object& values, const py::object& bins,
                             const std::string& convention, double pair_fraction, std::uint64_t seed, int threads) {
  const MatrixArg x = matrix_arg(coords, "coords", ArraySpec{1, 2, -1, 2});
  const MatrixArg z = matrix_arg(values, "values", ArraySpec{2, 2, -1, 2});
  if (z.data.rows() != x.data.rows())
    throw ArgumentError("values: " + std::to_string(z.data.rows()) + " rows but coords has " +
                        std::to_string(x.data.rows()) + "; expected one row of values per location");
  if (z.data.cols() < 2)
    throw ArgumentError("values: " + std::to_string(z.data.cols()) +
                        " column(s); cross-variograms need at least 2 components (N, P >= 2)");
  const LagBins lag_bins = LagBins::from_edges(vector_arg(bins, "bins", 2));
  EmpiricalVariogramOptions options;
  options.cross_variograms = true;
  const EmpiricalVariogram v =
      variogram_without_gil(x.data, z.data, lag_bins, options, convention, pair_fraction, seed, threads);
  const std::size_t n = v.bins.size();
  const int P = v.components();
  py::array_t<double> gamma({static_cast<py::ssize_t>(n), static_cast<py::ssize_t>(P), static_cast<py::ssize_t>(P)});
  auto g = gamma.mutable_unchecked<3>();
  for (std::size_t k = 0; k < n; ++k)
    for (int a = 0; a < P; ++a)
      for (int b = 0; b < P; ++b) g(static_cast<py::ssize_t>(k), a, b) = v.gamma_of(k, a, b);
  const BinLagArrays lags = bin_lag_arrays(v);
  py::dict d;
  d["lag_lo"] = lags.lag_lo;
  d["lag_hi"] = lags.lag_hi;
  d["lag_mean"] = lags.lag_mean;
  d["pairs"] = lags.pairs;
  d["gamma"] = gamma;
  d["convention"] = std::string(convention_name(v.convention));
  return d;
}

/// errfield.fit_lmc: the LMC fit of a cross_variogram result (or any mapping with lag_mean, pairs
/// and gamma (bins, P, P)).
py::dict run_fit_lmc(const py::object& variogram, const std::string& model, const std::string& method,
                     const std::string& weights, std::optional<double> nu, const py::object& names) {
  auto item = [&](const char* key) {
    if (py::isinstance<py::dict>(variogram)) {
      const py::dict d = variogram.cast<py::dict>();
      if (!d.contains(key)) throw ArgumentError(std::string("variogram: no '") + key + "'; expected the result of errfield.cross_variogram");
      return py::object(d[key]);
    }
    return py::object(variogram.attr(key));
  };
  const std::vector<double> lag = vector_arg(item("lag_mean"), "variogram lag_mean", 1, /*finite=*/false);  // NaN: empty bin
  const py::array_t<double, py::array::c_style | py::array::forcecast> pairs_in =
      py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(item("pairs"));
  const auto gamma_in = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(item("gamma"));
  if (!pairs_in || !gamma_in || gamma_in.ndim() != 3 || gamma_in.shape(1) != gamma_in.shape(2) ||
      static_cast<std::size_t>(gamma_in.shape(0)) != lag.size() || static_cast<std::size_t>(pairs_in.size()) != lag.size())
    throw ArgumentError("variogram: expected lag_mean (bins,), pairs (bins,) and gamma (bins, P, P), as errfield.cross_variogram returns");
  CrossVariogramTable table;
  const auto g = gamma_in.unchecked<3>();
  const py::ssize_t P = gamma_in.shape(1);
  for (std::size_t k = 0; k < lag.size(); ++k) {
    const double np = pairs_in.data()[k];
    if (!(np >= 0.0) || np != std::floor(np))
      throw ArgumentError("variogram: pairs[" + std::to_string(k) + "] = " + std::to_string(np) + "; expected an integer >= 0");
    table.lag.push_back(lag[k]);
    table.pairs.push_back(static_cast<std::uint64_t>(np));
    Eigen::MatrixXd m(P, P);
    for (py::ssize_t a = 0; a < P; ++a)
      for (py::ssize_t b = 0; b < P; ++b) m(a, b) = np == 0.0 ? 0.0 : g(static_cast<py::ssize_t>(k), a, b);
    table.gamma.push_back(std::move(m));
  }
  std::vector<std::string> component_names;
  if (!names.is_none()) component_names = names.cast<std::vector<std::string>>();
  CoregionalizationFitOptions o;
  o.method = lmc_fit_method_from_name(method);
  o.weighting = lmc_weighting_from_name(weights);
  const CoregionalizationTemplate t = parse_coregionalization_template(model, nu.value_or(0.0));
  if (!t.anisotropy.isotropic())
    throw ArgumentError("fit_lmc: the template's anisotropy @" + t.anisotropy.to_string() +
                        " cannot be applied to a computed variogram; compute cross_variogram on the mapped "
                        "coordinates (or use the CLI's fit-variogram --lmc --coords, which maps them)");
  CoregionalizationFitResult r;
  {
    py::gil_scoped_release release;
    const std::vector<ModelComponent> structures =
        t.ranges_given ? t.structures : fit_coregionalization_ranges(table, t.structures, o.weighting, component_names);
    r = fit_coregionalization(table, structures, o, component_names);
  }
  py::list structures;
  for (const CoregionalizationStructure& s : r.model.structures()) {
    py::dict d;
    d["kind"] = std::string(model_kind_name(s.kind));
    if (s.kind != ModelKind::Nugget) d["range"] = s.range;
    if (s.kind == ModelKind::Matern) d["nu"] = s.nu;
    d["sills"] = to_numpy(s.sills);
    structures.append(d);
  }
  py::dict d;
  d["structures"] = structures;
  d["json"] = nlohmann::json(r.model).dump(2) + "\n";
  d["weighted_residual"] = r.weighted_residual;
  d["iterations"] = r.iterations;
  d["converged"] = r.converged;
  d["smallest_eigenvalue_before_projection"] = to_numpy(r.smallest_eigenvalue_before_projection);
  d["bins_used"] = r.bins_used;
  d["message"] = r.message;
  return d;
}

/// Lags h as a scalar or an array of any shape; negative or NaN lags are an ArgumentError.
py::object evaluate(const py::object& h, const std::string& name, const std::function<double(double)>& f) {
  auto check = [&](double x) {
    if (!(x >= 0.0))
      throw ArgumentError(name + ": lag " + (std::isnan(x) ? std::string("nan") : std::to_string(x)) +
                          "; expected lags >= 0");
    return f(x);
  };
  if (py::isinstance<py::float_>(h) || py::isinstance<py::int_>(h)) return py::float_(check(h.cast<double>()));
  py::array any = py::array::ensure(h);
  if (!any || (any.dtype().kind() != 'f' && any.dtype().kind() != 'i' && any.dtype().kind() != 'u'))
    throw py::type_error(name + ": expected a number or an array of numbers (lags)");
  auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(any);
  py::array_t<double> out(std::vector<py::ssize_t>(a.shape(), a.shape() + a.ndim()));
  const double* in = a.data();
  double* w = out.mutable_data();
  for (py::ssize_t i = 0; i < a.size(); ++i) w[i] = check(in[i]);
  return out;
}

py::list components_list(const VariogramModel& model) {
  py::list out;
  for (const auto& c : model.components()) {
    py::dict d;
    d["kind"] = std::string(model_kind_name(c.kind));
    d["sill"] = c.sill;
    if (c.kind == ModelKind::Power) d["exponent"] = c.range;
    else if (c.kind != ModelKind::Nugget && c.kind != ModelKind::Linear) d["range"] = c.range;
    if (c.kind == ModelKind::Matern) d["nu"] = c.nu;
    out.append(d);
  }
  return out;
}

/// The structure to fit: a kind name ("sph"; "mat" needs nu) or a model text whose non-nugget
/// components (with their parameters as a starting point) are fitted.
std::vector<ModelComponent> structure_arg(const std::string& model, std::optional<double> nu) {
  std::vector<ModelComponent> s;
  if (model.find('(') != std::string::npos) {
    const VariogramModel parsed = VariogramModel::parse(model);  // named: components() must outlive the loop
    for (const auto& c : parsed.components())
      if (c.kind != ModelKind::Nugget) s.push_back(c);
    if (s.empty()) throw ArgumentError("model: '" + model + "' has no component other than a nugget to fit");
    if (nu) throw ArgumentError("nu: give the Matérn smoothness inside the model text, e.g. mat(1,100,1.5)");
    return s;
  }
  ModelComponent c;
  c.kind = model_kind_from_name(model);
  if (c.kind == ModelKind::Nugget) throw ArgumentError("model: 'nug' alone has nothing to fit; use nugget= for the nugget");
  if (c.kind == ModelKind::Matern && !nu) throw ArgumentError("nu: model 'mat' needs nu (the Matérn smoothness, e.g. 1.5)");
  if (nu && !(*nu > 0.0 && *nu <= kMaxMaternNu))
    throw ArgumentError("nu: " + format_number(*nu) + "; expected 0 < nu <= " + format_number(kMaxMaternNu));
  if (nu) c.nu = *nu;
  s.push_back(c);
  return s;
}

const char* fit_status_name(FitStatus s) {
  return s == FitStatus::Converged ? "converged" : s == FitStatus::MaxEvaluations ? "max_evaluations" : "failed";
}

py::dict fit_variogram_py(const py::object& variogram, const std::string& model, const std::string& weights,
                          const py::object& nugget, std::optional<double> nu, double range_max, int starts) {
  for (const char* attr : {"lag_mean", "gamma", "pairs"})
    if (!py::hasattr(variogram, attr))
      throw py::type_error(std::string("variogram: has no attribute '") + attr +
                           "'; expected the result of errfield.variogram (or anything with lag_mean, gamma, pairs)");
  const auto lag = vector_arg(variogram.attr("lag_mean"), "variogram.lag_mean", 1, false);
  const auto gamma = vector_arg(variogram.attr("gamma"), "variogram.gamma", 1, false);
  const auto pairs = vector_arg(variogram.attr("pairs"), "variogram.pairs", 1, true);
  if (gamma.size() != lag.size() || pairs.size() != lag.size())
    throw ArgumentError("variogram: lag_mean, gamma and pairs have " + std::to_string(lag.size()) + ", " +
                        std::to_string(gamma.size()) + " and " + std::to_string(pairs.size()) +
                        " elements; expected one per bin");
  // Empty bins are skipped as `errfield fit-variogram` skips them in the CSV.
  std::vector<double> h, g;
  std::vector<std::uint64_t> n;
  for (std::size_t k = 0; k < lag.size(); ++k) {
    if (pairs[k] < 0.0 || pairs[k] != std::floor(pairs[k]))
      throw ArgumentError("variogram.pairs[" + std::to_string(k) + "] is " + std::to_string(pairs[k]) +
                          "; expected a pair count (an integer >= 0)");
    if (pairs[k] == 0.0) continue;
    if (!std::isfinite(lag[k]) || !std::isfinite(gamma[k]))
      throw ArgumentError("variogram: bin " + std::to_string(k) + " has pairs but a non-finite lag_mean or gamma");
    h.push_back(lag[k]);
    g.push_back(gamma[k]);
    n.push_back(static_cast<std::uint64_t>(pairs[k]));
  }
  if (h.empty()) throw InputError("variogram: no bin with pairs > 0; nothing to fit");
  VariogramFitOptions o;
  o.weighting = weighting_from_name(weights);
  if (nugget.is_none()) {
    o.nugget = NuggetMode::None;
  } else if (py::isinstance<py::str>(nugget)) {
    const auto text = nugget.cast<std::string>();
    if (text == "free") o.nugget = NuggetMode::Free;
    else if (text == "none") o.nugget = NuggetMode::None;
    else throw ArgumentError("nugget: '" + text + "'; expected 'free', 'none' (or None) or a fixed value >= 0 (mm^2)");
  } else {
    o.nugget = NuggetMode::Fixed;
    o.nugget_value = nugget.cast<double>();
    if (!std::isfinite(o.nugget_value) || o.nugget_value < 0.0)
      throw ArgumentError("nugget: " + std::to_string(o.nugget_value) + "; expected a fixed value >= 0");
  }
  o.range_max = range_max;
  o.starts = starts;
  o.validate();
  const auto structure = structure_arg(model, nu);
  VariogramFitResult r;
  {
    py::gil_scoped_release release;
    r = fit_variogram(h, g, n, structure, o);
  }
  if (r.status == FitStatus::Failed) throw Error("fit_variogram: the optimizer failed: " + r.message);
  py::dict d;
  d["model"] = r.model;
  d["weighted_sse"] = r.weighted_sse;
  d["status"] = fit_status_name(r.status);
  d["message"] = r.message;
  d["evaluations"] = r.evaluations;
  d["bins_used"] = r.bins_used;
  return d;
}

void set_likelihood_method(LikelihoodFitOptions& o, const std::string& likelihood, int neighbours,
                           const std::string& ordering) {
  if (likelihood == "auto") o.method = LikelihoodMethod::Auto;
  else if (likelihood == "exact") o.method = LikelihoodMethod::Exact;
  else if (likelihood == "vecchia") o.method = LikelihoodMethod::Vecchia;
  else throw ArgumentError("likelihood: '" + likelihood + "'; expected 'auto', 'exact' or 'vecchia'");
  if (ordering == "maxmin") o.vecchia_ordering = VecchiaOrdering::MaxMin;
  else if (ordering == "random") o.vecchia_ordering = VecchiaOrdering::Random;
  else if (ordering == "coordinate") o.vecchia_ordering = VecchiaOrdering::Coordinate;
  else throw ArgumentError("vecchia_ordering: '" + ordering + "'; expected 'maxmin', 'random' or 'coordinate'");
  o.vecchia_neighbours = neighbours;
  o.validate();
}

LikelihoodFitOptions likelihood_options(const std::string& method, const std::string& kind, int drift_order,
                                        double mean, bool nugget) {
  LikelihoodFitOptions o;
  if (method == "reml") o.restricted = true;
  else if (method == "ml") o.restricted = false;
  else throw ArgumentError("method: '" + method + "'; expected 'reml' or 'ml'");
  // drift_order defaults to 1 here, so it only speaks for kind="universal" (as before).
  const KrigingKindChoice k =
      kriging_kind_from_text(kind, kind == "universal" ? std::optional<int>(drift_order) : std::nullopt);
  o.kind = k.kind;
  o.drift_order = k.drift_order;
  o.simple_mean = mean;
  o.fit_nugget = nugget;
  o.validate();
  return o;
}

struct ScalarSamples {
  Eigen::MatrixXd x;
  Eigen::VectorXd z;
};

ScalarSamples scalar_samples(const py::object& coords, const py::object& values) {
  ScalarSamples s;
  s.x = matrix_arg(coords, "coords", ArraySpec{1, 2, -1, 2}).data;
  const MatrixArg z = matrix_arg(values, "values", ArraySpec{1, 2, 1, 1});
  if (z.data.rows() != s.x.rows())
    throw ArgumentError("values: " + std::to_string(z.data.rows()) + " values but coords has " +
                        std::to_string(s.x.rows()) + " rows; expected one per location");
  s.z = z.data.col(0);
  return s;
}

void bind_empirical_variograms(py::module_& m) {
  py::class_<PyVariogram>(m, "EmpiricalVariogram",
                          "Empirical semivariogram, one entry per lag bin: the columns of the CLI's "
                          "`errfield variogram` CSV as NumPy arrays. Empty bins have pairs 0 and NaN "
                          "lag_mean and gamma.")
      .def_readonly("lag_lo", &PyVariogram::lag_lo, "lower bin edges (lag unit: mm, deg, ...)")
      .def_readonly("lag_hi", &PyVariogram::lag_hi, "upper bin edges (lag unit)")
      .def_readonly("lag_mean", &PyVariogram::lag_mean, "mean lag of the pairs in each bin (lag unit)")
      .def_readonly("gamma", &PyVariogram::gamma,
                    "semivariance (value unit^2, e.g. mm^2), summed over the value components")
      .def_readonly("pairs", &PyVariogram::pairs, "number of pairs per bin (uint64)")
      .def_readonly("component_gamma", &PyVariogram::component_gamma,
                    "(bins, K) semivariance of each value component (value unit^2)")
      .def_readonly("estimator", &PyVariogram::estimator)
      .def_readonly("convention", &PyVariogram::convention)
      .def_readonly("pair_fraction", &PyVariogram::pair_fraction)
      .def("__len__", [](const PyVariogram& v) { return py::len(v.gamma); })
      .def("__repr__", [](const PyVariogram& v) {
        return "EmpiricalVariogram(" + std::to_string(py::len(v.gamma)) + " bins, estimator='" + v.estimator + "')";
      });

  m.def("variogram", &run_variogram, py::arg("coords"), py::arg("values"), py::arg("bins"),
        py::arg("estimator") = "matheron", py::kw_only(), py::arg("convention") = "paper",
        py::arg("pair_fraction") = 1.0, py::arg("seed") = 0, py::arg("threads") = 0, py::arg("covariates") = py::none(),
        "Empirical semivariogram of `values` at `coords`, as `errfield variogram`.\n\n"
        "coords: (N, D) float64, any D (task space mm, joint space deg, ...); (N,) for 1-D.\n"
        "values: (N,) or (N, K); K > 1 is a vector value (gamma is the sum over components).\n"
        "bins: increasing bin edges e0 < e1 < ... (lag unit), at least two.\n"
        "estimator: 'matheron' | 'cressie' | 'dowd'.  convention: 'paper' ([lo, hi)) | 'gstat'.\n"
        "pair_fraction: deterministic fraction of the pairs in (0, 1], seeded by `seed`.\n"
        "covariates: (N,) or (N, k): the variogram of the residuals of the ordinary least-squares trend\n"
        "1 + covariates (gstat's variogram(z ~ cov); `errfield variogram --covariates`).\n"
        "Returns an EmpiricalVariogram with NumPy arrays lag_lo, lag_hi, lag_mean, gamma (value unit^2), pairs.\n"
        "Releases the GIL; runs OpenMP on `threads` threads (0 = default), result independent of it.");

  m.def("variogram_cloud", &run_variogram_cloud, py::arg("coords"), py::arg("values"), py::kw_only(), py::arg("cutoff"),
        py::arg("max_pairs") = VariogramCloudOptions{}.max_pairs,
        "Variogram cloud, as `errfield variogram --cloud` and gstat's variogram(..., cloud = TRUE): every pair (i, j),\n"
        "i > j, at a distance <= cutoff, ordered by i then j.\n\n"
        "coords: (N, D); values: (N,) or (N, K) (gamma summed over components).\n"
        "Returns a dict of NumPy arrays: left, right (0-based rows; gstat's are these + 1), dist, gamma = 0.5 (z_i - z_j)^2.\n"
        "More than max_pairs pairs raises errfield.ResourceError before anything is stored.");
  m.def("variogram_map", &run_variogram_map, py::arg("coords"), py::arg("values"), py::kw_only(), py::arg("cutoff"),
        py::arg("width"),
        "Variogram map of 2-D data, as `errfield variogram --map` and gstat's variogram(..., map = TRUE):\n"
        "cells of width=(DX, DY) centred on -cutoff + k*width, each pair counted at +s and -s.\n\n"
        "coords: (N, 2); values: (N,) or (N, K).\n"
        "Returns a dict: dx (columns,) and dy (rows,, decreasing) cell centres, gamma and pairs (rows, columns)\n"
        "(gamma NaN where pairs is 0); row 0 is the largest dy, as gstat orders its cells.");
  m.def("cross_variogram", &run_cross_variogram, py::arg("coords"), py::arg("values"), py::arg("bins"), py::kw_only(),
        py::arg("convention") = "paper", py::arg("pair_fraction") = 1.0, py::arg("seed") = 0, py::arg("threads") = 0,
        "Direct and cross empirical variograms (Matheron) of P >= 2 value components, as\n"
        "`errfield variogram --cross`: gamma_ab = 1/(2N) sum (z_i[a] - z_j[a]) (z_i[b] - z_j[b]) per bin.\n\n"
        "coords: (N, D); values: (N, P), P >= 2; bins: increasing edges (lag unit).\n"
        "Returns a dict: lag_lo, lag_hi, lag_mean, pairs (uint64) of shape (bins,), gamma (bins, P, P)\n"
        "(symmetric; the diagonal holds the direct variograms; NaN for empty bins), convention.\n"
        "Releases the GIL; the result does not depend on `threads`.");
  m.def("fit_lmc", &run_fit_lmc, py::arg("variogram"), py::arg("model"), py::kw_only(),
        py::arg("method") = "goulard-voltz", py::arg("weights") = "nj_h2", py::arg("nu") = py::none(),
        py::arg("names") = py::none(),
        "Fits a linear model of coregionalization to a cross_variogram result, as `errfield fit-variogram --lmc`.\n\n"
        "model: template 'nug(0)+sph(1,400)' (kinds and ranges kept, sills ignored) or kinds 'nug+sph' (ranges\n"
        "fitted first to the mean direct variogram; 'mat' needs nu).\n"
        "method: 'goulard-voltz' (iterated WLS, each B_k projected onto the PSD matrices) | 'gstat' (gstat's\n"
        "fit.lmc: separate fits, then negative eigenvalues set to 0). weights: 'nj_h2' | 'nj' | 'unweighted'.\n"
        "names: the P component names written into the JSON.\n"
        "Returns a dict: structures (list of dicts kind, range, nu, sills (P, P)), json (the LMC JSON that\n"
        "`fit-variogram --lmc --out` writes, without its 'fit' object), weighted_residual, iterations,\n"
        "converged, smallest_eigenvalue_before_projection (per structure), bins_used, message.");
}

void bind_variogram_model(py::module_& m) {
  py::class_<VariogramModel>(m, "VariogramModel",
                             "A variogram model in gstat's vgm vocabulary, e.g. 'sph(sill=0.3,range=400)+nug(0.002)'. "
                             "sill in value unit^2 (mm^2), range in lag unit (mm or deg); range of exp/gau is the "
                             "scale parameter a, not the practical range.")
      .def(py::init([](const std::string& text) { return VariogramModel::parse(text); }), py::arg("text"),
           "Parses the text form (components joined by '+': kind(sill=S,range=A[,nu=V]), nug(S), "
           "pow(sill=S,exponent=E), lin(slope=S)); raises ArgumentError pointing at bad text.")
      .def_static("parse", &VariogramModel::parse, py::arg("text"), "Same as the constructor.")
      .def("__str__", &VariogramModel::to_string)
      .def("__repr__", [](const VariogramModel& v) { return "VariogramModel('" + v.to_string() + "')"; })
      .def("__eq__", [](const VariogramModel& a, const VariogramModel& b) { return a.to_string() == b.to_string(); })
      .def(
          "gamma",
          [](const VariogramModel& v, const py::object& h) {
            return evaluate(h, "h", [&](double x) { return v.gamma(x); });
          },
          py::arg("h"), "Semivariance gamma(h) (value unit^2) at lags h >= 0 (scalar or array of any shape).")
      .def(
          "__call__",
          [](const VariogramModel& v, const py::object& h) {
            return evaluate(h, "h", [&](double x) { return v.gamma(x); });
          },
          py::arg("h"), "Same as gamma(h).")
      .def(
          "covariance",
          [](const VariogramModel& v, const py::object& h) {
            if (!v.bounded())
              throw ArgumentError("covariance: model '" + v.to_string() + "' is unbounded (pow, lin); it has no covariance");
            return evaluate(h, "h", [&](double x) { return v.covariance(x); });
          },
          py::arg("h"), "Covariance C(h) = sill - gamma(h) (value unit^2); bounded models only.")
      .def_property_readonly("sill", &VariogramModel::sill, "total sill, nugget included (value unit^2)")
      .def_property_readonly("nugget", &VariogramModel::nugget, "sum of the nugget components (value unit^2)")
      .def_property_readonly("bounded", &VariogramModel::bounded)
      .def_property_readonly("compact", &VariogramModel::compact)
      .def_property_readonly("support", &VariogramModel::support, "lag beyond which C(h) = 0 (inf unless compact)")
      .def_property_readonly("components", &components_list, "list of dicts: kind, sill, range (or exponent), nu");

  m.def("fit_variogram", &fit_variogram_py, py::arg("variogram"), py::arg("model"), py::kw_only(),
        py::arg("weights") = "nj_h2", py::arg("nugget") = "free", py::arg("nu") = py::none(),
        py::arg("range_max") = 0.0, py::arg("starts") = 6,
        "Weighted least-squares fit of a model to an empirical variogram, as `errfield fit-variogram`.\n\n"
        "variogram: the result of errfield.variogram (or anything with lag_mean, gamma, pairs; empty bins skipped).\n"
        "model: a kind ('sph', 'exp', 'gau', 'mat', 'wen', 'pow', 'lin'; 'mat' needs nu) or a model text whose\n"
        "  non-nugget components are fitted from their given parameters.\n"
        "weights: 'nj_h2' (gstat's default, N_j/h_j^2) | 'nj' | 'cressie'.\n"
        "nugget: 'free' | 'none' (or None) | a fixed value >= 0 (value unit^2).\n"
        "range_max: upper bound of the ranges (lag unit); 0 = automatic.\n"
        "Returns a dict: model (VariogramModel), weighted_sse, status ('converged' | 'max_evaluations'), message,\n"
        "evaluations, bins_used. Raises errfield.Error when the optimizer fails.");
}

void bind_likelihood(py::module_& m) {
  m.def(
      "fit_likelihood",
      [](const py::object& coords, const py::object& values, const std::string& model, const std::string& method,
         const std::string& kind, int drift_order, double mean, bool nugget, std::optional<double> nu,
         const std::string& anisotropy, const py::object& covariates, const std::string& likelihood,
         int vecchia_neighbours, const std::string& vecchia_ordering) {
        const ScalarSamples s = scalar_samples(coords, values);
        auto o = likelihood_options(method, kind, drift_order, mean, nugget);
        o.covariates = covariates_rows(covariates, s.x.rows());
        set_likelihood_method(o, likelihood, vecchia_neighbours, vecchia_ordering);
        if (anisotropy == "ard") o.anisotropy = LikelihoodFitOptions::Anisotropy::Ard;
        else if (anisotropy == "rotated" || anisotropy == "anis") o.anisotropy = LikelihoodFitOptions::Anisotropy::Rotated;
        else if (anisotropy != "none")
          throw ArgumentError("anisotropy: '" + anisotropy + "'; expected 'none', 'ard' or 'rotated' ('anis')");
        o.validate();
        const auto structure = structure_arg(model, nu);
        LikelihoodFitResult r;
        {
          py::gil_scoped_release release;
          r = fit_likelihood(s.x, s.z, structure, o);
        }
        py::dict d;
        d["model"] = r.model;
        d["negative_log_likelihood"] = r.negative_log_likelihood;
        d["evaluations"] = r.evaluations;
        d["converged"] = r.converged;
        d["message"] = r.message;
        d["ranges"] = to_numpy(r.ranges);
        d["range_standard_errors"] = to_numpy(r.range_standard_errors);
        d["aic"] = r.aic;
        d["bic"] = r.bic;
        d["parameters"] = r.parameters;
        d["angles_deg"] = to_numpy(r.angles_deg);
        d["angle_standard_errors_deg"] = to_numpy(r.angle_standard_errors_deg);
        return d;
      },
      py::arg("coords"), py::arg("values"), py::arg("model"), py::kw_only(), py::arg("method") = "reml",
      py::arg("kind") = "ordinary", py::arg("drift_order") = 1, py::arg("mean") = 0.0, py::arg("nugget") = true,
      py::arg("nu") = py::none(), py::arg("anisotropy") = "none", py::arg("covariates") = py::none(),
      py::arg("likelihood") = "auto",
      py::arg("vecchia_neighbours") = LikelihoodFitOptions{}.vecchia_neighbours, py::arg("vecchia_ordering") = "maxmin",
      "ML or REML estimate of a model's sills and ranges from scalar samples, as\n"
      "`errfield fit-variogram --method reml|ml` (which uses kind='ordinary').\n\n"
      "coords: (N, D); values: (N,) scalar. model: a bounded kind or model text (see fit_variogram).\n"
      "method: 'reml' | 'ml'. kind: 'simple' (known mean) | 'ordinary' | 'universal' (drift_order 0-2).\n"
      "nugget: fit a nugget (True) or none.\n"
      "likelihood: 'auto' (exact up to 3,000 samples, Vecchia above) | 'exact' (O(N^3) per evaluation,\n"
      "up to 3,000 samples) | 'vecchia' (each sample conditioned on its vecchia_neighbours nearest\n"
      "predecessors in the vecchia_ordering 'maxmin' | 'random' | 'coordinate'; O(N m^3)).\n"
      "anisotropy: 'none' | 'ard' (one range per coordinate: the model gets '@ard(s_1,...,s_D)') |\n"
      "'rotated' or 'anis' (2-D/3-D, gstat's anis: angles and ratios fitted too, '@anis(...)').\n"
      "covariates: (N,) or (N, k) external-drift values, one more column of the drift F each (as\n"
      "`fit-variogram --covariates`).\n"
      "Returns a dict: model, negative_log_likelihood, evaluations, converged, message, ranges (one per\n"
      "coordinate with ard, along the principal axes with rotated, in the coordinates' unit),\n"
      "range_standard_errors, aic, bic, parameters, angles_deg and angle_standard_errors_deg (rotated;\n"
      "empty otherwise).");

  m.def(
      "negative_log_likelihood",
      [](const py::object& coords, const py::object& values, const VariogramModel& model, const std::string& method,
         const std::string& kind, int drift_order, double mean, const py::object& covariates) {
        const ScalarSamples s = scalar_samples(coords, values);
        auto o = likelihood_options(method, kind, drift_order, mean, true);
        o.covariates = covariates_rows(covariates, s.x.rows());
        o.validate();
        py::gil_scoped_release release;
        return negative_log_likelihood(s.x, s.z, model, o);
      },
      py::arg("coords"), py::arg("values"), py::arg("model"), py::kw_only(), py::arg("method") = "reml",
      py::arg("kind") = "ordinary", py::arg("drift_order") = 1, py::arg("mean") = 0.0,
      py::arg("covariates") = py::none(),
      "The (restricted) negative log-likelihood of a Gaussian field with covariance `model` at the samples\n"
      "(+inf when the covariance is not positive definite). Formula: include/errfield/kriging_likelihood.hpp.");
}

}  // namespace

void bind_variogram(py::module_& m) {
  // In this order: a signature shows a class's Python name only once the class is registered.
  bind_empirical_variograms(m);
  bind_variogram_model(m);
  bind_likelihood(m);
}

}  // namespace errfield::python
