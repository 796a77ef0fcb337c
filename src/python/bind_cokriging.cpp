// errfield.Cokriging: cokriging under a linear model of coregionalization (errfield/cokriging.hpp),
// with the options spelled as `errfield interpolate --method kriging --model lmc.json` spells them.

#include <memory>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "errfield/cokriging.hpp"
#include "errfield/error.hpp"
#include "errfield/interpolation_options.hpp"
#include "errfield/value_rows.hpp"
#include "python/arrays.hpp"
#include "python/bindings.hpp"
#include "python/kriging_report.hpp"
#include "python/options.hpp"

namespace errfield::python {

namespace {

// Type-erased over the value type (P = 1..3 components), results as P-column matrices and
// P x P covariances packed one row per point (entry (a, b) in column a + P b).
struct CokrigingResult_ {
  Eigen::MatrixXd mean, covariance, residual;
  KrigingStatus status = KrigingStatus::Ok;
  std::string message;
  std::size_t failed = 0;
};

struct CokrigingBase {
  virtual ~CokrigingBase() = default;
  virtual const KrigingReport& report() const = 0;
  virtual CokrigingResult_ predict(const Eigen::Map<const RowMatrixXd>& targets) const = 0;
  virtual CokrigingResult_ leave_one_out() const = 0;
};

template <class V>
struct CokrigingImpl final : CokrigingBase {
  static constexpr int kP = ValueTraits<V>::kComponents;
  std::unique_ptr<Cokriging<Eigen::VectorXd, V>> cokriging;

  CokrigingImpl(const Eigen::MatrixXd& x, const Eigen::MatrixXd& z, const CoregionalizationModel& m, const KrigingOptions& o) {
    const auto points = rows_as_points(x);
    const auto values = rows_as_values<V>(z);
    cokriging = std::make_unique<Cokriging<Eigen::VectorXd, V>>(points, values, m, o);
  }
  const KrigingReport& report() const override { return cokriging->report(); }
  static Eigen::MatrixXd pack(const std::vector<Eigen::MatrixXd>& c) {
    Eigen::MatrixXd out(static_cast<Eigen::Index>(c.size()), kP * kP);
    for (std::size_t t = 0; t < c.size(); ++t)
      for (int a = 0; a < kP; ++a)
        for (int b = 0; b < kP; ++b) out(static_cast<Eigen::Index>(t), a * kP + b) = c[t](a, b);
    return out;
  }
  CokrigingResult_ predict(const Eigen::Map<const RowMatrixXd>& targets) const override {
    const auto p = cokriging->predict(rows_as_points(targets));
    CokrigingResult_ r;
    r.mean = values_as_rows(p.mean);
    r.covariance = pack(p.covariance);
    r.status = p.status;
    r.message = p.message;
    r.failed = p.failed_targets;
    return r;
  }
  CokrigingResult_ leave_one_out() const override {
    const auto cv = cokriging->leave_one_out();
    CokrigingResult_ r;
    r.mean = values_as_rows(cv.prediction);
    r.residual = values_as_rows(cv.residual);
    r.covariance = pack(cv.covariance);
    r.status = cv.status;
    r.message = cv.message;
    return r;
  }
};

// (M, P) variances and (M, P, P) covariances from the packed rows (row-major a * P + b).
py::tuple cokriging_covariance_arrays(const Eigen::MatrixXd& packed, Eigen::Index p) {
  const Eigen::Index m = packed.rows();
  py::array_t<double> var({static_cast<py::ssize_t>(m), static_cast<py::ssize_t>(p)});
  py::array_t<double> cov({static_cast<py::ssize_t>(m), static_cast<py::ssize_t>(p), static_cast<py::ssize_t>(p)});
  double* v = var.mutable_data();
  double* c = cov.mutable_data();
  for (Eigen::Index t = 0; t < m; ++t) {
    for (Eigen::Index a = 0; a < p; ++a) v[t * p + a] = packed(t, a * p + a);
    for (Eigen::Index k = 0; k < p * p; ++k) c[t * p * p + k] = packed(t, k);
  }
  return py::make_tuple(var, cov);
}

CoregionalizationModel cokriging_model_arg(const py::object& model) {
  std::string text;
  if (py::isinstance<py::dict>(model)) text = py::module_::import("json").attr("dumps")(model).cast<std::string>();
  else if (py::isinstance<py::str>(model)) text = model.cast<std::string>();
  else throw ArgumentError("model: expected the LMC as a JSON string or a dict ({\"type\": \"lmc\", ...})");
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) throw ArgumentError("model: not valid JSON; expected an LMC ({\"type\": \"lmc\", ...})");
  return j.get<CoregionalizationModel>();
}

class PyCokriging {
 public:
  PyCokriging(const py::object& coords, const py::object& values, const py::object& model, const std::string& kind,
              const std::optional<std::string>& backend, const py::object& mean, const std::optional<int>& drift_order,
              const std::string& nugget, const std::optional<std::size_t>& neighbors, const std::optional<double>& radius,
              int threads, const std::optional<std::string>& neighbour_metric,
              const std::optional<std::size_t>& min_neighbours, const std::optional<std::size_t>& octant_max) {
    x_ = matrix_arg(coords, "coords", ArraySpec{1, 2, -1, 1}).data;
    // NaN: the component was not measured at that location (heterotopic cokriging); the library
    // refuses infinities and samples with every component NaN.
    ArraySpec value_spec{1, 2, -1, 1};
    value_spec.finite = false;
    const MatrixArg z = matrix_arg(values, "values", value_spec);
    if (z.data.rows() != x_.rows())
      throw ArgumentError("values: " + std::to_string(z.data.rows()) + " rows but coords has " + std::to_string(x_.rows()) +
                          "; expected one row of components per location");
    const CoregionalizationModel lmc = cokriging_model_arg(model);
    if (lmc.components() != z.data.cols())
      throw ArgumentError("values: " + std::to_string(z.data.cols()) + " columns but the model has " +
                          std::to_string(lmc.components()) + " components; expected one column per component");
    components_ = z.data.cols();
    KrigingOptionText text;
    text.kind = kind;
    text.drift_order = drift_order;
    if (!mean.is_none())
      text.mean = py::isinstance<py::float_>(mean) || py::isinstance<py::int_>(mean) ? std::vector<double>{mean.cast<double>()}
                                                                                     : vector_arg(mean, "mean");
    text.backend = backend;
    text.neighbors = neighbors;
    text.radius = radius;
    text.neighbour_metric = neighbour_metric;
    text.min_neighbours = min_neighbours;
    text.octant_max = octant_max;
    text.nugget = nugget;
    KrigingOptions o = kriging_options_from_text(text);
    o.threads = threads;
    {
      py::gil_scoped_release release;
      impl_ = with_components(components_, "values", [&]<class V>() -> std::shared_ptr<CokrigingBase> {
        return std::make_shared<CokrigingImpl<V>>(x_, z.data, lmc, o);
      });
    }
    raise_or_warn(impl_->report(), "cokriging");
  }

  py::tuple predict(const py::object& targets) const {
    const RowsArg t = rows_arg(targets, "targets", ArraySpec{1, 2, x_.cols(), 0});
    CokrigingResult_ r;
    {
      py::gil_scoped_release release;
      r = impl_->predict(t.data);
    }
    warn_failed_targets(r.failed, static_cast<std::size_t>(t.data.rows()), r.status, "cokriged", "predictions");
    const py::tuple vc = cokriging_covariance_arrays(r.covariance, components_);
    return py::make_tuple(to_numpy(r.mean), vc[0], vc[1]);
  }

  py::tuple cross_validate() const {
    CokrigingResult_ r;
    {
      py::gil_scoped_release release;
      r = impl_->leave_one_out();
    }
    if (r.mean.rows() != x_.rows())
      throw Error("cokriging cross-validation failed: " + std::string(kriging_status_name(r.status)) + ": " + r.message);
    const py::tuple vc = cokriging_covariance_arrays(r.covariance, components_);
    return py::make_tuple(to_numpy(r.mean), to_numpy(r.residual), vc[1]);
  }

  py::dict report() const {
    const auto& rep = impl_->report();
    py::dict d = report_dict(rep);
    d["drift_terms"] = rep.drift_terms;
    return d;
  }

 private:
  Eigen::MatrixXd x_;
  Eigen::Index components_ = 0;
  std::shared_ptr<const CokrigingBase> impl_;
};

}  // namespace

void bind_cokriging(py::module_& m) {
  py::class_<PyCokriging>(m, "Cokriging",
                          "Cokriging of P = 1..3 value components under a linear model of coregionalization (docs/kriging.md,\n"
                          "Cokriging): NaN in values where a component was not measured (heterotopic: each\n"
                          "component taken where it exists; at least one per sample). model: the LMC as a JSON string or dict\n"
                          "({'type': 'lmc', 'components': [...], 'structures': [{'kind': 'nug', 'sills': [[...]]}, ...]}, what\n"
                          "fit-variogram --lmc writes). Options as Kriging's: kind simple | ordinary | universal1 | universal2\n"
                          "(one mean or drift per component), nugget micro | error, backend dense | local (neighbors, radius,\n"
                          "min_neighbours, octant_max).")
      .def(py::init<const py::object&, const py::object&, const py::object&, const std::string&,
                    const std::optional<std::string>&, const py::object&, const std::optional<int>&, const std::string&,
                    const std::optional<std::size_t>&, const std::optional<double>&, int, const std::optional<std::string>&,
                    const std::optional<std::size_t>&, const std::optional<std::size_t>&>(),
           py::arg("coords"), py::arg("values"), py::arg("model"), py::kw_only(), py::arg("kind") = "ordinary",
           py::arg("backend") = py::none(), py::arg("mean") = py::none(), py::arg("drift_order") = py::none(),
           py::arg("nugget") = "micro", py::arg("neighbors") = py::none(), py::arg("radius") = py::none(),
           py::arg("threads") = 0, py::arg("neighbour_metric") = py::none(), py::arg("min_neighbours") = py::none(),
           py::arg("octant_max") = py::none())
      .def("predict", &PyCokriging::predict, py::arg("targets"),
           "At targets (M, D): returns (mean, var, cov): mean (M, P), var (M, P) the prediction variance of each\n"
           "component, cov (M, P, P) the prediction error covariance (var on its diagonal).")
      .def("cross_validate", &PyCokriging::cross_validate,
           "Leave-one-out (all components of a sample left out together): returns (prediction, residual, cov),\n"
           "(N, P), (N, P) and (N, P, P) the covariance of each residual.")
      .def_property_readonly("report", &PyCokriging::report, "Outcome of the set-up: status, message, condition_number, ...");
}

}  // namespace errfield::python
