// errfield.Kriging, errfield.ScatteredIdw and errfield.GridIdw, with cross-validation as
// `errfield cv` does it (leave-one-out in closed form for dense/local kriging, else the folds of
// errfield::cross_validate).

#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "errfield/conditional_simulation.hpp"
#include "errfield/cross_validation.hpp"
#include "errfield/error.hpp"
#include "errfield/grid_idw.hpp"
#include "errfield/interpolation_options.hpp"
#include "errfield/indicator_kriging.hpp"
#include "errfield/kriging.hpp"
#include "errfield/scattered_idw.hpp"
#include "errfield/value_rows.hpp"
#include "python/arrays.hpp"
#include "python/bindings.hpp"
#include "python/kriging_report.hpp"
#include "python/options.hpp"

namespace errfield::python {

namespace {

/// Samples checked once for every estimator: coords (N, D), values (N,) or (N, K), K in 1..3.
struct Samples {
  Eigen::MatrixXd x, z;
  bool scalar = true;  // values came 1-D: predictions are 1-D too
};

Samples samples_arg(const py::object& coords, const py::object& values, Eigen::Index dims = -1) {
  Samples s;
  s.x = matrix_arg(coords, "coords", ArraySpec{1, 2, dims, 1}).data;
  const MatrixArg z = matrix_arg(values, "values", ArraySpec{1, 2, -1, 1});
  if (z.data.rows() != s.x.rows())
    throw ArgumentError("values: " + std::to_string(z.data.rows()) + " rows but coords has " +
                        std::to_string(s.x.rows()) + "; expected one value (row) per location");
  if (z.data.cols() < 1 || z.data.cols() > 3)
    throw ArgumentError("values: " + std::to_string(z.data.cols()) + " columns; expected 1, 2 or 3 value components");
  s.z = z.data;
  s.scalar = z.one_d;
  return s;
}

/// Covariate values: (rows,) for one covariate or (rows, k).
Eigen::MatrixXd covariates_arg(const py::object& a, const char* name, Eigen::Index rows) {
  const MatrixArg m = matrix_arg(a, name, ArraySpec{1, 2, -1, 1});
  if (m.data.rows() != rows)
    throw ArgumentError(std::string(name) + ": " + std::to_string(m.data.rows()) + " rows for " + std::to_string(rows) +
                        " points; expected one row of covariate values per point");
  return m.data;
}

/// Read in place when C-contiguous float64 (the estimators copy them into their own points).
RowsArg targets_arg(const py::object& targets, Eigen::Index dims) {
  return rows_arg(targets, "targets", ArraySpec{1, 2, dims, 0});
}

using TargetRows = Eigen::Map<const RowMatrixXd>;

/// errfield.indicator_kriging: P(z < T) per threshold, as `errfield interpolate --indicator`.
py::dict indicator_kriging_py(const py::object& coords, const py::object& values, const py::object& targets,
                              const std::vector<double>& thresholds, const py::object& models, const std::string& kind,
                              const std::optional<std::string>& backend, const std::optional<std::size_t>& neighbors,
                              const std::optional<double>& radius, bool order_correction) {
  const Samples s = samples_arg(coords, values);
  if (s.z.cols() != 1) throw ArgumentError("values: " + std::to_string(s.z.cols()) + " columns; indicator kriging takes one value per sample");
  const auto model_of = [](const py::handle& m) {
    return py::isinstance<py::str>(m) ? VariogramModel::parse(m.cast<std::string>()) : m.cast<VariogramModel>();
  };
  std::vector<VariogramModel> ms;
  if (py::isinstance<py::str>(models) || py::isinstance<VariogramModel>(models)) {
    ms.push_back(model_of(models));
  } else {
    for (const py::handle m : models) ms.push_back(model_of(m));
  }
  KrigingOptionText text;
  text.kind = kind;
  text.backend = backend;
  text.neighbors = neighbors;
  text.radius = radius;
  const KrigingOptions o = kriging_options_from_text(text);
  const RowsArg t = targets_arg(targets, s.x.cols());
  const auto points = rows_as_points(s.x);
  const auto target_points = rows_as_points(Eigen::MatrixXd(t.data));
  const Eigen::VectorXd z = s.z.col(0);
  IndicatorKrigingOptions io;
  io.correct_order = order_correction;
  IndicatorKrigingResult r;
  {
    py::gil_scoped_release release;
    r = indicator_kriging<Eigen::VectorXd>(std::span<const Eigen::VectorXd>(points),
                                           std::span<const double>(z.data(), static_cast<std::size_t>(z.size())),
                                           std::span<const Eigen::VectorXd>(target_points), std::span<const double>(thresholds),
                                           std::span<const VariogramModel>(ms), o, io);
  }
  if (!r.usable()) throw Error("indicator kriging failed: " + std::string(kriging_status_name(r.status)) + ": " + r.message);
  py::dict d;
  d["probability"] = to_numpy(r.probability);
  d["raw"] = to_numpy(r.raw);
  d["variance"] = to_numpy(r.variance);
  d["targets_corrected"] = r.correction.rows_changed;
  d["max_correction"] = r.correction.max_change;
  d["message"] = r.message;
  return d;
}

/// Cross-validation output, with the summary `errfield cv` prints.
struct PyCrossValidation {
  py::object fold, prediction, residual, variance;
  std::size_t samples = 0, predicted = 0;
  py::object mean_error;
  double mean_abs_error = 0, max_abs_error = 0, rms_error = 0;
  py::object mean_z, mean_squared_z;
  std::size_t max_abs_index = 0;
};

PyCrossValidation make_cv(const Eigen::MatrixXd& observed, const std::vector<std::size_t>& fold,
                          const Eigen::MatrixXd& pred, const std::vector<double>& variance, bool scalar) {
  const Eigen::MatrixXd residual = observed - pred;
  const CrossValidationSummary s = summarize_residuals(residual, variance);
  PyCrossValidation cv;
  py::array_t<std::int64_t> f(static_cast<py::ssize_t>(fold.size()));
  for (std::size_t i = 0; i < fold.size(); ++i) f.mutable_data()[i] = static_cast<std::int64_t>(fold[i]);
  cv.fold = f;
  cv.prediction = to_numpy(pred, scalar);
  cv.residual = to_numpy(residual, scalar);
  cv.variance = variance.empty() ? py::object(py::none()) : py::object(to_numpy(variance));
  cv.samples = s.samples;
  cv.predicted = s.predicted;
  cv.mean_error = to_numpy(s.mean_error);
  cv.mean_abs_error = s.mean_abs_error;
  cv.max_abs_error = s.max_abs_error;
  cv.max_abs_index = s.max_abs_index;
  cv.rms_error = s.rms_error;
  cv.mean_z = s.mean_z ? py::object(py::float_(*s.mean_z)) : py::object(py::none());
  cv.mean_squared_z = s.mean_squared_z ? py::object(py::float_(*s.mean_squared_z)) : py::object(py::none());
  return cv;
}

std::size_t folds_arg(const py::object& folds) {
  if (py::isinstance<py::str>(folds)) {
    if (folds.cast<std::string>() != "loo") throw ArgumentError("folds: expected 'loo' or a number of folds >= 2");
    return 0;
  }
  const long f = folds.cast<long>();
  if (f < 0) throw ArgumentError("folds: " + std::to_string(f) + "; expected 'loo' (or 0) or a number >= 2");
  return static_cast<std::size_t>(f);
}

// ---- Kriging ------------------------------------------------------------------------------------

struct KrigingPrediction_ {
  Eigen::MatrixXd mean;
  std::vector<double> variance;
  KrigingStatus status = KrigingStatus::Ok;
  std::string message;
  std::size_t failed = 0;
};

struct CvRaw {
  std::vector<std::size_t> fold;
  Eigen::MatrixXd pred;
  std::vector<double> variance;
};

struct SimulationRaw {
  std::vector<Eigen::MatrixXd> draws;  // M x K each
  std::string method;
  KrigingStatus status = KrigingStatus::Ok;
  std::string message;
  std::size_t failed = 0;
};

struct KrigingBase {
  virtual ~KrigingBase() = default;
  virtual const KrigingReport& report() const = 0;
  /// `block` non-null: block kriging of blocks centred on the targets.
  virtual KrigingPrediction_ predict(const TargetRows& targets, const Eigen::MatrixXd& covariates,
                                     const BlockDiscretization* block) const = 0;
  virtual CvRaw cross_validate(std::size_t folds, std::uint64_t seed) const = 0;
  virtual SimulationRaw simulate(const TargetRows& targets, const Eigen::MatrixXd& covariates,
                                 const SimulationOptions& options) const = 0;
};

template <class V>
struct KrigingImpl final : KrigingBase {
  std::vector<Eigen::VectorXd> points;
  std::vector<V> values;
  VariogramModel model;
  KrigingOptions options;
  Eigen::VectorXd measurement_variance;
  Eigen::MatrixXd covariates;  // N x k (external drift)
  Eigen::Index dimension = 0;
  std::unique_ptr<Kriging<Eigen::VectorXd, V>> kriging;

  KrigingImpl(const Samples& s, const VariogramModel& m, const KrigingOptions& o, const Eigen::VectorXd& meas,
              const Eigen::MatrixXd& cov)
      : points(rows_as_points(s.x)), values(rows_as_values<V>(s.z)), model(m), options(o), measurement_variance(meas),
        covariates(cov), dimension(s.x.cols()) {
    std::span<const double> mv(meas.data(), static_cast<std::size_t>(meas.size()));
    kriging = std::make_unique<Kriging<Eigen::VectorXd, V>>(points, values, covariates, model, options,
                                                            EuclideanMetric{}, mv);
  }
  SimulationRaw simulate(const TargetRows& targets, const Eigen::MatrixXd& cov, const SimulationOptions& so) const override {
    std::span<const double> mv(measurement_variance.data(), static_cast<std::size_t>(measurement_variance.size()));
    const auto r = simulate_conditional<Eigen::VectorXd, V>(points, values, covariates, rows_as_points(targets), cov, model,
                                                            options, so, EuclideanMetric{}, mv);
    SimulationRaw out;
    for (const auto& d : r.draws) out.draws.push_back(values_as_rows(d));
    out.method = r.method;
    out.status = r.status;
    out.message = r.message;
    out.failed = r.failed_targets;
    return out;
  }
  const KrigingReport& report() const override { return kriging->report(); }
  KrigingPrediction_ predict(const TargetRows& targets, const Eigen::MatrixXd& cov,
                             const BlockDiscretization* block) const override {
    const auto p = block ? kriging->predict_blocks(rows_as_points(targets), *block, cov)
                   : options.covariates.empty() ? kriging->predict(rows_as_points(targets))
                                                : kriging->predict(rows_as_points(targets), cov);
    KrigingPrediction_ out;
    out.mean = values_as_rows(p.mean);
    out.variance = p.variance;
    out.status = p.status;
    out.message = p.message;
    out.failed = p.failed_targets;
    return out;
  }
  CvRaw cross_validate(std::size_t folds, std::uint64_t seed) const override {
    CvRaw out;
    if (folds == 0 && options.backend != KrigingBackend::Sparse) {
      if (kriging->report().merged_duplicates)
        throw InputError("cross_validate: duplicate samples; remove them first");
      const auto cv = kriging->leave_one_out();
      if (cv.prediction.size() != values.size())
        throw Error("kriging failed: " + std::string(kriging_status_name(cv.status)) + ": " + cv.message);
      out.fold.resize(values.size());
      for (std::size_t i = 0; i < values.size(); ++i) out.fold[i] = i;
      out.pred = values_as_rows(cv.prediction);
      out.variance = cv.variance;
      return out;
    }
    CrossValidationOptions cvo;
    cvo.folds = folds;
    cvo.seed = seed;
    CrossValidationResult<V> r;
    if (options.covariates.empty()) {
      KrigingEstimator<Eigen::VectorXd, V> estimator{model, options, {}};
      r = errfield::cross_validate(estimator, std::span<const Eigen::VectorXd>(points), std::span<const V>(values), cvo);
    } else {
      // as `errfield cv --covariates`: the covariates travel with their samples through the folds
      std::vector<Eigen::VectorXd> joined;
      for (std::size_t i = 0; i < points.size(); ++i) {
        Eigen::VectorXd j(dimension + covariates.cols());
        j << points[i], covariates.row(static_cast<Eigen::Index>(i)).transpose();
        joined.push_back(std::move(j));
      }
      const ExternalDriftKrigingEstimator<V> estimator{model, options, dimension};
      r = errfield::cross_validate(estimator, std::span<const Eigen::VectorXd>(joined), std::span<const V>(values), cvo);
    }
    out.fold = r.fold;
    out.pred = values_as_rows(r.predicted);
    out.variance = r.variance;
    return out;
  }
};

class PyKriging {
 public:
  PyKriging(const py::object& coords, const py::object& values, const py::object& model_arg, const std::string& kind,
            const std::optional<std::string>& backend, const py::object& mean, const std::optional<int>& drift_order,
            const std::string& nugget, const std::optional<std::size_t>& neighbors,
            const std::optional<double>& radius, const py::object& measurement_variance,
            const std::string& duplicates, double duplicate_distance, int threads,
            const std::optional<std::string>& neighbour_metric, const py::object& covariates,
            const std::optional<std::vector<std::string>>& covariate_names,
            const std::optional<std::size_t>& min_neighbours, const std::optional<std::size_t>& octant_max)
      : samples_(samples_arg(coords, values)) {
    const VariogramModel model = py::isinstance<py::str>(model_arg)
                                     ? VariogramModel::parse(model_arg.cast<std::string>())
                                     : model_arg.cast<VariogramModel>();
    KrigingOptionText text;
    text.kind = kind;
    text.drift_order = drift_order;
    if (!mean.is_none())
      text.mean = py::isinstance<py::float_>(mean) || py::isinstance<py::int_>(mean)
                      ? std::vector<double>{mean.cast<double>()}
                      : vector_arg(mean, "mean");
    text.backend = backend;
    text.neighbors = neighbors;
    text.radius = radius;
    text.neighbour_metric = neighbour_metric;
    text.min_neighbours = min_neighbours;
    text.octant_max = octant_max;
    text.nugget = nugget;
    text.duplicates = duplicates;
    KrigingOptions o = kriging_options_from_text(text);
    o.duplicate_distance = duplicate_distance;
    o.threads = threads;
    Eigen::MatrixXd cov;
    if (!covariates.is_none()) {
      cov = covariates_arg(covariates, "covariates", samples_.x.rows());
      if (covariate_names) {
        if (covariate_names->size() != static_cast<std::size_t>(cov.cols()))
          throw ArgumentError("covariate_names: " + std::to_string(covariate_names->size()) + " names for " +
                              std::to_string(cov.cols()) + " covariate columns; expected one per column");
        o.covariates = *covariate_names;
      } else {
        for (Eigen::Index j = 0; j < cov.cols(); ++j) o.covariates.push_back("covariate" + std::to_string(j));
      }
    } else if (covariate_names) {
      throw ArgumentError("covariate_names given without covariates");
    }
    o.validate();
    Eigen::VectorXd meas;
    if (!measurement_variance.is_none()) {
      const auto mv = vector_arg(measurement_variance, "measurement_variance");
      if (mv.size() != static_cast<std::size_t>(samples_.x.rows()))
        throw ArgumentError("measurement_variance: " + std::to_string(mv.size()) + " values for " +
                            std::to_string(samples_.x.rows()) + " samples; expected one per sample");
      meas = Eigen::Map<const Eigen::VectorXd>(mv.data(), static_cast<Eigen::Index>(mv.size()));
    }
    {
      py::gil_scoped_release release;
      impl_ = with_components(samples_.z.cols(), "values", [&]<class V>() -> std::shared_ptr<KrigingBase> {
        return std::make_shared<KrigingImpl<V>>(samples_, model, o, meas, cov);
      });
    }
    model_ = model;
    covariate_count_ = o.covariates.size();
    raise_or_warn(impl_->report(), "kriging");
  }

  py::tuple predict(const py::object& targets, const py::object& covariates, const py::object& block, int block_points,
                    const std::string& block_rule) const {
    const RowsArg t = targets_arg(targets, samples_.x.cols());
    const std::size_t k = impl_report_covariates();
    if (k > 0 && covariates.is_none())
      throw ArgumentError("predict: the kriging has " + std::to_string(k) +
                          " covariate(s) (external drift); pass covariates=(M, k) values at the targets");
    if (k == 0 && !covariates.is_none())
      throw ArgumentError("predict: covariates given, but the Kriging was built without covariates");
    const Eigen::MatrixXd cov = k > 0 ? covariates_arg(covariates, "covariates", t.data.rows()) : Eigen::MatrixXd();
    std::optional<BlockDiscretization> discretization;
    if (!block.is_none()) {
      if (block_rule != "gauss" && block_rule != "regular")
        throw ArgumentError("predict: block_rule '" + block_rule + "'; expected 'gauss' or 'regular'");
      discretization = BlockDiscretization{vector_arg(block, "block"), block_points,
                                           block_rule == "regular" ? BlockDiscretization::Rule::Regular
                                                                   : BlockDiscretization::Rule::GaussLegendre};
    }
    const BlockDiscretization* block_ptr = discretization ? &*discretization : nullptr;
    KrigingPrediction_ p;
    {
      py::gil_scoped_release release;
      p = impl_->predict(t.data, cov, block_ptr);
    }
    warn_failed_targets(p.failed, static_cast<std::size_t>(t.data.rows()), p.status, "kriged", "predictions");
    return py::make_tuple(to_numpy(p.mean, samples_.scalar), to_numpy(p.variance));
  }

  PyCrossValidation cross_validate(const py::object& folds, std::uint64_t seed) const {
    const std::size_t k = folds_arg(folds);
    CvRaw r;
    {
      py::gil_scoped_release release;
      r = impl_->cross_validate(k, seed);
    }
    return make_cv(samples_.z, r.fold, r.pred, r.variance, samples_.scalar);
  }

  py::array_t<double> simulate(const py::object& targets, std::size_t n, std::uint64_t seed, const std::string& method,
                               std::size_t neighbours, std::size_t draws_per_path, const py::object& covariates) const {
    const RowsArg t = targets_arg(targets, samples_.x.cols());
    const std::size_t drift_covariates = impl_report_covariates();
    if (drift_covariates > 0 && covariates.is_none())
      throw ArgumentError("simulate: the kriging has " + std::to_string(drift_covariates) +
                          " covariate(s) (external drift); pass covariates=(M, k) values at the targets");
    if (drift_covariates == 0 && !covariates.is_none())
      throw ArgumentError("simulate: covariates given, but the Kriging was built without covariates");
    const Eigen::MatrixXd cov =
        drift_covariates > 0 ? covariates_arg(covariates, "covariates", t.data.rows()) : Eigen::MatrixXd();
    SimulationOptions so;
    so.draws = n;
    so.seed = seed;
    so.method = unconditional_method_from_name(method);
    so.neighbours = neighbours;
    so.draws_per_path = draws_per_path;
    so.validate();
    SimulationRaw r;
    {
      py::gil_scoped_release release;
      r = impl_->simulate(t.data, cov, so);
    }
    warn_failed_targets(r.failed, static_cast<std::size_t>(t.data.rows()), r.status, "kriged", "draws");
    const auto m = static_cast<py::ssize_t>(t.data.rows());
    const auto k = static_cast<py::ssize_t>(samples_.z.cols());
    py::array_t<double> out = samples_.scalar ? py::array_t<double>({static_cast<py::ssize_t>(n), m})
                                              : py::array_t<double>({static_cast<py::ssize_t>(n), m, k});
    double* data = out.mutable_data();
    for (std::size_t d = 0; d < r.draws.size(); ++d)
      for (py::ssize_t i = 0; i < m; ++i)
        for (py::ssize_t c = 0; c < k; ++c)
          data[(static_cast<py::ssize_t>(d) * m + i) * k + c] = r.draws[d](i, c);
    return out;
  }

  py::dict report() const {
    const auto& r = impl_->report();
    py::dict d = report_dict(r);
    d["merged_duplicates"] = r.merged_duplicates;
    d["drift_terms"] = r.drift_terms;
    return d;
  }
  const VariogramModel& model() const { return model_; }

 private:
  std::size_t impl_report_covariates() const { return covariate_count_; }
  std::size_t covariate_count_ = 0;
  Samples samples_;
  VariogramModel model_;
  std::shared_ptr<const KrigingBase> impl_;
};

// ---- IDW ----------------------------------------------------------------------------------------

struct IdwBase {
  virtual ~IdwBase() = default;
  virtual Eigen::MatrixXd predict(const TargetRows& targets) const = 0;
  virtual CvRaw cross_validate(std::size_t folds, std::uint64_t seed) const = 0;
};

template <class V>
struct ScatteredImpl final : IdwBase {
  std::vector<Eigen::VectorXd> points;
  std::vector<V> values;
  ScatteredIdwOptions options;
  ScatteredIdw<Eigen::VectorXd, V> idw;
  ScatteredImpl(const Samples& s, const ScatteredIdwOptions& o)
      : points(rows_as_points(s.x)), values(rows_as_values<V>(s.z)), options(o), idw(points, values, o) {}
  Eigen::MatrixXd predict(const TargetRows& targets) const override {
    const auto t = rows_as_points(targets);
    return values_as_rows(idw.predict(t));
  }
  CvRaw cross_validate(std::size_t folds, std::uint64_t seed) const override {
    ScatteredIdwEstimator<Eigen::VectorXd, V> estimator{options, {}};
    CrossValidationOptions cvo;
    cvo.folds = folds;
    cvo.seed = seed;
    const auto r = errfield::cross_validate(estimator, std::span<const Eigen::VectorXd>(points),
                                            std::span<const V>(values), cvo);
    CvRaw out;
    out.fold = r.fold;
    out.pred = values_as_rows(r.predicted);
    return out;
  }
};

class PyScatteredIdw {
 public:
  PyScatteredIdw(const py::object& coords, const py::object& values, const std::optional<double>& power,
                 const std::optional<std::size_t>& neighbors, const std::optional<double>& radius,
                 double exact_distance, int threads)
      : samples_(samples_arg(coords, values)) {
    ScatteredIdwOptions o = scattered_idw_options_from_text({power, neighbors, radius});
    o.exact_distance = exact_distance;
    o.threads = threads;
    o.validate();
    py::gil_scoped_release release;
    impl_ = with_components(samples_.z.cols(), "values", [&]<class V>() -> std::shared_ptr<IdwBase> {
      return std::make_shared<ScatteredImpl<V>>(samples_, o);
    });
  }
  py::object predict(const py::object& targets) const {
    const RowsArg t = targets_arg(targets, samples_.x.cols());
    Eigen::MatrixXd out;
    {
      py::gil_scoped_release release;
      out = impl_->predict(t.data);
    }
    return to_numpy(out, samples_.scalar);
  }
  PyCrossValidation cross_validate(const py::object& folds, std::uint64_t seed) const {
    const std::size_t k = folds_arg(folds);
    CvRaw r;
    {
      py::gil_scoped_release release;
      r = impl_->cross_validate(k, seed);
    }
    return make_cv(samples_.z, r.fold, r.pred, r.variance, samples_.scalar);
  }

 private:
  Samples samples_;
  std::shared_ptr<const IdwBase> impl_;
};

struct GridBase {
  virtual ~GridBase() = default;
  virtual const RegularGrid3& grid() const = 0;
  virtual Eigen::MatrixXd predict(const Eigen::MatrixXd& targets, std::vector<GridIdwStatus>& status) const = 0;
};

template <class V>
struct GridImpl final : GridBase {
  GridIdw<V> idw;
  GridImpl(const Samples& s, const GridIdwOptions& o) : idw(GridIdw<V>::from_samples(s.x, rows_as_values<V>(s.z), o)) {}
  const RegularGrid3& grid() const override { return idw.grid(); }
  Eigen::MatrixXd predict(const Eigen::MatrixXd& targets, std::vector<GridIdwStatus>& status) const override {
    if (!idw.options().clamp) return values_as_rows(idw.predict(targets));  // throws OutsideGridError
    std::vector<V> out(static_cast<std::size_t>(targets.rows()), ValueTraits<V>::zero());
    status.resize(out.size());
    idw.predict_with_status(targets, out, status);
    return values_as_rows(out);
  }
};

class PyGridIdw {
 public:
  PyGridIdw(const py::object& coords, const py::object& values, double power, bool clamp, int threads)
      : samples_(samples_arg(coords, values, 3)) {
    GridIdwOptions o;
    o.power = power;
    o.clamp = clamp;
    o.threads = threads;
    o.validate();
    py::gil_scoped_release release;
    impl_ = with_components(samples_.z.cols(), "values", [&]<class V>() -> std::shared_ptr<GridBase> {
      return std::make_shared<GridImpl<V>>(samples_, o);
    });
  }
  py::object predict(const py::object& targets) const {
    const Eigen::MatrixXd t = matrix_arg(targets, "targets", ArraySpec{1, 2, 3, 0}).data;
    Eigen::MatrixXd out;
    std::vector<GridIdwStatus> status;
    {
      py::gil_scoped_release release;
      out = impl_->predict(t, status);
    }
    return to_numpy(out, samples_.scalar);
  }
  py::dict grid() const {
    const auto& g = impl_->grid();
    py::dict d;
    d["origin"] = to_numpy(Eigen::MatrixXd(g.origin().transpose()), false)[py::int_(0)];
    d["step"] = to_numpy(Eigen::MatrixXd(g.step().transpose()), false)[py::int_(0)];
    d["counts"] = py::make_tuple(g.counts()[0], g.counts()[1], g.counts()[2]);
    d["description"] = g.describe();
    return d;
  }

 private:
  Samples samples_;
  std::shared_ptr<const GridBase> impl_;
};

void bind_cross_validation(py::module_& m) {
  py::class_<PyCrossValidation>(m, "CrossValidation",
                                "Per-sample cross-validation results and the summary `errfield cv` prints. "
                                "residual = observed - predicted (value unit, e.g. mm).")
      .def_readonly("fold", &PyCrossValidation::fold, "fold of each sample (leave-one-out: its own index)")
      .def_readonly("prediction", &PyCrossValidation::prediction, "(N,) or (N, K) held-out predictions (NaN: none)")
      .def_readonly("residual", &PyCrossValidation::residual, "observed - predicted, shaped as prediction")
      .def_readonly("variance", &PyCrossValidation::variance, "(N,) prediction variances (value unit^2) or None")
      .def_readonly("samples", &PyCrossValidation::samples)
      .def_readonly("predicted", &PyCrossValidation::predicted, "samples that got a prediction")
      .def_readonly("mean_error", &PyCrossValidation::mean_error, "(K,) mean residual per component")
      .def_readonly("mean_abs_error", &PyCrossValidation::mean_abs_error, "mean |residual|")
      .def_readonly("max_abs_error", &PyCrossValidation::max_abs_error, "max |residual|")
      .def_readonly("max_abs_index", &PyCrossValidation::max_abs_index, "sample with the largest |residual|")
      .def_readonly("rms_error", &PyCrossValidation::rms_error, "sqrt(mean |residual|^2)")
      .def_readonly("mean_z", &PyCrossValidation::mean_z, "mean residual/sqrt(variance), or None")
      .def_readonly("mean_squared_z", &PyCrossValidation::mean_squared_z, "mean residual^2/variance (MSDR), or None");
}

void bind_indicator_kriging(py::module_& m) {
  m.def("indicator_kriging", &indicator_kriging_py, py::arg("coords"), py::arg("values"), py::arg("targets"),
        py::arg("thresholds"), py::arg("models"), py::kw_only(), py::arg("kind") = "ordinary",
        py::arg("backend") = py::none(), py::arg("neighbors") = py::none(), py::arg("radius") = py::none(),
        py::arg("order_correction") = true,
        "Indicator kriging, as `errfield interpolate --method kriging --indicator`: for each increasing threshold T,\n"
        "the samples' indicators I(z < T) (strict, gstat's krige(I(z < T) ~ 1)) kriged with that threshold's model.\n\n"
        "coords: (N, D); values: (N,); targets: (M, D); thresholds: increasing; models: one model (str or\n"
        "VariogramModel) for all, or a list with one per threshold.\n"
        "Returns a dict: probability (M, K), P(z < T) with order relations corrected as GSLIB (clip to [0, 1],\n"
        "average of upward and downward passes) unless order_correction=False; raw (M, K) as kriged; variance\n"
        "(M, K); targets_corrected, max_correction, message. docs/kriging.md, \"Indicator kriging\".");
}

void bind_kriging(py::module_& m) {
  py::class_<PyKriging>(m, "Kriging",
                        "Simple, ordinary or universal kriging (best linear unbiased prediction with its variance), "
                        "as `errfield interpolate --method kriging`. Construction factors the covariance once "
                        "(dense, sparse); predict() may then be called many times. docs/kriging.md.")
      .def(py::init<const py::object&, const py::object&, const py::object&, const std::string&,
                    const std::optional<std::string>&, const py::object&, const std::optional<int>&, const std::string&,
                    const std::optional<std::size_t>&, const std::optional<double>&, const py::object&,
                    const std::string&, double, int, const std::optional<std::string>&, const py::object&,
                    const std::optional<std::vector<std::string>>&, const std::optional<std::size_t>&,
                    const std::optional<std::size_t>&>(),
           py::arg("coords"), py::arg("values"), py::arg("model"), py::kw_only(), py::arg("kind") = "ordinary",
           py::arg("backend") = py::none(), py::arg("mean") = py::none(), py::arg("drift_order") = py::none(),
           py::arg("nugget") = "micro", py::arg("neighbors") = py::none(), py::arg("radius") = py::none(),
           py::arg("measurement_variance") = py::none(),
           py::arg("duplicates") = "error", py::arg("duplicate_distance") = 0.0, py::arg("threads") = 0,
           py::arg("neighbour_metric") = py::none(), py::arg("covariates") = py::none(),
           py::arg("covariate_names") = py::none(), py::arg("min_neighbours") = py::none(),
           py::arg("octant_max") = py::none(),
           "coords: (N, D) sample locations (mm, deg, ...). values: (N,) or (N, K), K <= 3 (mm).\n"
           "model: VariogramModel or its text (sill mm^2, range in the coordinates' unit).\n"
           "kind: 'simple' (needs mean) | 'ordinary' | 'universal' (drift_order 0, 1, 2; default 1) | 'universal1' | 'universal2'.\n"
           "backend: 'dense' | 'local' (neighbors=K and/or radius=R) | 'sparse' (sph/wen + nugget only);\n"
           "None: 'local' when neighbors or radius is given, else 'dense' (as the CLI's --backend).\n"
           "nugget: 'micro' (exact at the data, gstat's krige) | 'error' (measurement error, smoothing).\n"
           "measurement_variance: (N,) per-sample variances (value unit^2) or None.\n"
           "duplicates: 'error' | 'average' samples closer than duplicate_distance.\n"
           "neighbour_metric (local back end): 'model' (default: neighbours by the model's lag) | 'euclidean' (gstat's).\n"
           "radius (local): samples at distance <= radius (gstat's maxdist). min_neighbours (local): fewer -> NaN\n"
           "(gstat's nmin). octant_max (local): at most this many per quadrant/octant (gstat's omax).\n"
           "covariates: (N,) or (N, k) external-drift covariate values at the samples, each one more drift term\n"
           "(kind='ordinary': kriging with external drift, gstat's krige(z ~ cov)); predict() then needs them at the\n"
           "targets. covariate_names: their names for messages (default covariate0, ...).\n"
           "Raises errfield.Error when the covariance cannot be factored; warns (RuntimeWarning) when ill-conditioned.")
      .def("predict", &PyKriging::predict, py::arg("targets"), py::arg("covariates") = py::none(), py::kw_only(),
           py::arg("block") = py::none(), py::arg("block_points") = 4, py::arg("block_rule") = "gauss",
           "Kriging mean and variance at targets (M, D): returns (mean, var), mean (M,) or (M, K) in the value unit,\n"
           "var (M,) in value unit^2 (shared by all components). NaN (with a RuntimeWarning) where a target could not\n"
           "be kriged. covariates: (M,) or (M, k) values at the targets, required with external drift.\n"
           "block: (D,) block size in the coordinates' unit: block kriging of blocks centred on the targets, as\n"
           "`interpolate --block` (block_points per axis, block_rule 'gauss' | 'regular'; dense and local back ends).\n"
           "Releases the GIL.")
      .def("cross_validate", &PyKriging::cross_validate, py::arg("folds") = "loo", py::arg("seed") = 1,
           "Cross-validation as `errfield cv --method kriging`: folds='loo' (closed form for dense, one local solve\n"
           "per sample for local; sparse uses folds) or k >= 2 folds shuffled by seed. Returns CrossValidation.")
      .def("simulate", &PyKriging::simulate, py::arg("targets"), py::arg("n"), py::kw_only(), py::arg("seed") = 1,
           py::arg("method") = "auto", py::arg("neighbours") = 60, py::arg("draws_per_path") = 100,
           py::arg("covariates") = py::none(),
           "n conditional Gaussian realisations at targets (M, D), as `errfield interpolate --simulations n --seed S`:\n"
           "shape (n, M) for scalar values, (n, M, K) for vectors; same seed, same draws for any thread count.\n"
           "Their mean over draws is predict()'s mean and their variance its variance (conditioning by kriging).\n"
           "method: 'auto' (exact Cholesky up to 2,000 distinct locations, samples + targets) | 'cholesky' |\n"
           "'sequential' (random path, each location from its `neighbours` nearest earlier ones).\n"
           "covariates: (M, k) values at the targets when the Kriging has covariates (external drift). docs/kriging.md.")
      .def_property_readonly("report", &PyKriging::report,
                             "dict: status, message, condition_number, jitter, samples_used, merged_duplicates, drift_terms")
      .def_property_readonly("model", &PyKriging::model);
}

void bind_idw(py::module_& m) {
  py::class_<PyScatteredIdw>(m, "ScatteredIdw",
                             "Inverse-distance weighting over scattered samples, as `errfield interpolate --method idw`: "
                             "v(x) = sum w_i v_i / sum w_i with w_i = 1/d^power over the k nearest (neighbors) and/or "
                             "within radius. docs/idw.md.")
      .def(py::init<const py::object&, const py::object&, const std::optional<double>&,
                    const std::optional<std::size_t>&, const std::optional<double>&, double, int>(),
           py::arg("coords"), py::arg("values"), py::kw_only(), py::arg("power") = py::none(),
           py::arg("neighbors") = py::none(), py::arg("radius") = py::none(), py::arg("exact_distance") = 0.0,
           py::arg("threads") = 0,
           "coords: (N, D); values: (N,) or (N, K), K <= 3. power: None = 2 (gstat's idw). neighbors: None or 0 = all.\n"
           "radius in the coordinates' unit, None = no limit.")
      .def("predict", &PyScatteredIdw::predict, py::arg("targets"),
           "Values at targets (M, D): (M,) or (M, K); NaN where no sample lies within radius. Releases the GIL.")
      .def("cross_validate", &PyScatteredIdw::cross_validate, py::arg("folds") = "loo", py::arg("seed") = 1,
           "Cross-validation as `errfield cv --method idw`. Returns CrossValidation (variance None).");

  py::class_<PyGridIdw>(m, "GridIdw",
                        "The paper's IDW on a complete regular 3-D grid (8 vertices of the target's cell, w = 1/d^power), "
                        "as `errfield interpolate --method idw-grid`. docs/idw.md.")
      .def(py::init<const py::object&, const py::object&, double, bool, int>(), py::arg("coords"), py::arg("values"),
           py::kw_only(), py::arg("power") = 1.0, py::arg("clamp") = false, py::arg("threads") = 0,
           "coords: (N, 3) grid nodes in any order (mm), forming a complete regular grid; values: (N,) or (N, K).")
      .def("predict", &PyGridIdw::predict, py::arg("targets"),
           "Values at targets (M, 3). Raises OutsideGridError for a target outside the grid unless clamp=True.")
      .def_property_readonly("grid", &PyGridIdw::grid, "dict: origin, step (mm), counts, description");
}

}  // namespace

void bind_interpolation(py::module_& m) {
  // In this order: a signature shows a class's Python name only once the class is registered.
  bind_cross_validation(m);
  bind_indicator_kriging(m);
  bind_kriging(m);
  bind_idw(m);
}

}  // namespace errfield::python
