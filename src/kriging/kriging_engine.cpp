#include "kriging/kriging_engine.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include <Eigen/SVD>
#include <omp.h>

#include "errfield/thread_count.hpp"
#include "errfield/csv_table.hpp"
#include "kriging/cholmod_factor.hpp"
#include "kriging/duplicate_samples.hpp"
#include "kriging/simple_mean.hpp"

namespace errfield {

std::string_view kriging_status_name(KrigingStatus status) {
  switch (status) {
    case KrigingStatus::Ok: return "ok";
    case KrigingStatus::IllConditioned: return "ill-conditioned";
    case KrigingStatus::NotPositiveDefinite: return "not positive definite";
    case KrigingStatus::SingularDrift: return "singular drift";
    case KrigingStatus::TooFewSamples: return "too few samples";
  }
  return "?";
}

std::string_view kriging_kind_name(KrigingKind kind) {
  switch (kind) {
    case KrigingKind::Simple: return "simple";
    case KrigingKind::Ordinary: return "ordinary";
    case KrigingKind::Universal: return "universal";
  }
  return "?";
}

std::string_view kriging_backend_name(KrigingBackend backend) {
  switch (backend) {
    case KrigingBackend::Dense: return "dense";
    case KrigingBackend::Local: return "local";
    case KrigingBackend::Sparse: return "sparse";
  }
  return "?";
}

KrigingBackend kriging_backend_from_name(std::string_view name) {
  for (auto b : {KrigingBackend::Dense, KrigingBackend::Local, KrigingBackend::Sparse})
    if (kriging_backend_name(b) == name) return b;
  throw ArgumentError("kriging: unknown back end '" + std::string(name) + "'; expected dense, local or sparse");
}

std::string_view neighbour_metric_name(NeighbourMetric metric) {
  return metric == NeighbourMetric::Model ? "model" : "euclidean";
}

NeighbourMetric neighbour_metric_from_name(std::string_view name) {
  if (name == "model") return NeighbourMetric::Model;
  if (name == "euclidean") return NeighbourMetric::Euclidean;
  throw ArgumentError("neighbour metric: '" + std::string(name) + "'; expected model or euclidean");
}

void KrigingOptions::validate() const {
  auto fail = [](const std::string& field, const std::string& value, const std::string& expected) {
    throw ArgumentError("kriging options: " + field + " = " + value + "; expected " + expected);
  };
  if (kind == KrigingKind::Universal && (drift_order < 0 || drift_order > 2))
    fail("drift_order", std::to_string(drift_order), "0, 1 or 2");
  if (kind == KrigingKind::Simple && !covariates.empty())
    fail("covariates", std::to_string(covariates.size()) + " covariate(s)",
         "none with simple kriging (a known mean has no drift); use ordinary kriging (external drift) or universal");
  for (std::size_t i = 0; i < covariates.size(); ++i) {
    if (covariates[i].empty()) fail("covariates[" + std::to_string(i) + "]", "an empty name", "a name");
    for (std::size_t j = 0; j < i; ++j)
      if (covariates[j] == covariates[i])
        fail("covariates[" + std::to_string(i) + "]", "'" + covariates[i] + "'", "a name not given twice");
  }
  if (kind != KrigingKind::Universal && !drift_functions.empty())
    fail("drift_functions", std::to_string(drift_functions.size()) + " functions",
         "none unless kind is Universal");
  for (std::size_t i = 0; i < drift_functions.size(); ++i)
    if (!drift_functions[i]) fail("drift_functions[" + std::to_string(i) + "]", "empty", "a callable");
  for (double m : simple_mean)
    if (!std::isfinite(m)) fail("simple_mean", format_number(m), "finite numbers");
  if (!(radius > 0.0)) fail("radius", format_number(radius), "a value > 0 (infinity = no limit)");
  if (backend == KrigingBackend::Local && neighbors == 0 && !std::isfinite(radius))
    fail("neighbors", "0 with radius = infinity", "a neighbour count k > 0 or a finite radius for the local back end");
  if (backend != KrigingBackend::Local && min_neighbours > 0)
    fail("min_neighbours", std::to_string(min_neighbours), "0 unless the back end is Local");
  if (backend != KrigingBackend::Local && octant_max > 0)
    fail("octant_max", std::to_string(octant_max), "0 unless the back end is Local");
  if (backend == KrigingBackend::Sparse && keep_weights)
    fail("keep_weights", "true", "false with the sparse back end (its weights are dense); use dense or local");
  if (!(duplicate_distance >= 0.0) || !std::isfinite(duplicate_distance))
    fail("duplicate_distance", format_number(duplicate_distance), "a finite value >= 0");
  if (max_jitter_retries < 0) fail("max_jitter_retries", std::to_string(max_jitter_retries), ">= 0");
  if (!(initial_jitter > 0.0) || !std::isfinite(initial_jitter))
    fail("initial_jitter", format_number(initial_jitter), "a finite value > 0");
  if (!(jitter_growth > 1.0) || !std::isfinite(jitter_growth))
    fail("jitter_growth", format_number(jitter_growth), "a finite value > 1");
  if (!(max_condition_number > 1.0)) fail("max_condition_number", format_number(max_condition_number), "> 1");
  if (target_batch == 0) fail("target_batch", "0", ">= 1");
  check_thread_count("kriging options: threads", threads);
}

namespace detail {

KrigingEngine::KrigingEngine(Eigen::MatrixXd embedded, Eigen::MatrixXd raw, Eigen::MatrixXd values,
                             Eigen::VectorXd measurement_variance, const VariogramModel& model,
                             const KrigingOptions& options, Eigen::VectorXd replicates)
    : options_(options),
      model_(model),
      kernel_(model),
      points_(std::move(embedded)),
      raw_(std::move(raw)),
      values_(std::move(values)),
      meas_(std::move(measurement_variance)),
      replicates_(std::move(replicates)) {
  options_.validate();
  dimension_ = static_cast<int>(points_.rows());
  covariates_ = static_cast<int>(options_.covariates.size());
  if (raw_.rows() != dimension_ + covariates_)
    throw ArgumentError("kriging: " + std::to_string(raw_.rows() - dimension_) + " covariate rows for the " +
                        std::to_string(covariates_) + " covariates of the options");
  components_ = static_cast<int>(values_.cols());
  const auto n = static_cast<std::size_t>(points_.cols());
  if (meas_.size() == 0) meas_ = Eigen::VectorXd::Zero(points_.cols());
  if (replicates_.size() == 0) replicates_ = Eigen::VectorXd::Ones(points_.cols());
  for (Eigen::Index i = 0; i < meas_.size(); ++i)
    if (!(meas_[i] >= 0.0) || !std::isfinite(meas_[i]))
      throw InputError("kriging: measurement variance of sample " + std::to_string(i) + " is " +
                       format_number(meas_[i]) + "; expected a finite value >= 0");
  if (options_.backend == KrigingBackend::Sparse && !model_.compact())
    throw ArgumentError("kriging: the sparse back end needs a compactly supported model (sph or wen, "
                        "plus nugget); got '" + model_.to_string() + "'. Use the dense or local back end");

  simple_mean_ = Eigen::VectorXd::Zero(components_);
  if (options_.kind == KrigingKind::Simple)
    simple_mean_ = simple_mean_per_component(options_.simple_mean, components_, "kriging");

  original_index_.resize(n);
  std::iota(original_index_.begin(), original_index_.end(), std::size_t{0});
  tree_ = std::make_unique<PointTree>(points_);
  merge_duplicates();
  // gstat's neighbourhoods: the coordinates as given (raw_ is rebuilt by merge_duplicates).
  if (options_.backend == KrigingBackend::Local && options_.neighbour_metric == NeighbourMetric::Euclidean) {
    search_points_ = raw_.topRows(dimension_);  // without the covariates
    search_tree_ = std::make_unique<PointTree>(search_points_);
  }
  set_observation_noise();
  observed_ = values_;
  if (options_.kind == KrigingKind::Simple) values_.rowwise() -= simple_mean_.transpose();

  if (options_.octant_max > 0 && (search_tree_ ? *search_tree_ : *tree_).dimension() > 3)
    throw ArgumentError("kriging options: octant_max = " + std::to_string(options_.octant_max) + " with " +
                        std::to_string((search_tree_ ? *search_tree_ : *tree_).dimension()) +
                        " coordinates; octant search is defined for 1 to 3 coordinates");
  build_drift();
  report_.samples_used = static_cast<std::size_t>(points_.cols());
  report_.drift_terms = static_cast<std::size_t>(drift_terms_);
  if (options_.backend == KrigingBackend::Local && options_.neighbors > 0 &&
      options_.neighbors < static_cast<std::size_t>(std::max(drift_terms_, 1)))
    throw ArgumentError("kriging options: neighbors = " + std::to_string(options_.neighbors) + " but " +
                        std::string(kriging_kind_name(options_.kind)) + " kriging here has " +
                        std::to_string(drift_terms_) + " drift terms; expected neighbors >= " +
                        std::to_string(std::max(drift_terms_, 1)));
  if (points_.cols() < std::max(drift_terms_, 1)) {
    report_.status = KrigingStatus::TooFewSamples;
    report_.message = std::to_string(points_.cols()) + " samples for the " + std::to_string(drift_terms_) +
                      " drift terms of the " + drift_description() +
                      "; need at least as many samples as drift terms (use a lower drift order)";
    return;
  }
  if (options_.backend == KrigingBackend::Dense) setup_dense();
  else if (options_.backend == KrigingBackend::Sparse) setup_sparse();
}

KrigingEngine::~KrigingEngine() = default;

int KrigingEngine::thread_count() const {
  return options_.threads > 0 ? options_.threads : omp_get_max_threads();
}

double KrigingEngine::target_variance() const {
  return options_.nugget == NuggetTreatment::MicroScale ? kernel_.sill() : kernel_.sill() - kernel_.nugget();
}

void KrigingEngine::merge_duplicates() {
  const auto n = static_cast<std::size_t>(points_.cols());
  if (n < 2) return;
  const double tol = options_.duplicate_distance;
  const double tol2 = tol * tol;
  if (options_.duplicates == DuplicatePolicy::Error) {
    if (const auto pair = first_duplicate(*tree_, points_, tol))
      throw_duplicate(*pair, options_.sample_labels, n, "kriging",
                      (tol > 0 ? " <= duplicate_distance " + format_number(tol) : std::string(", same location")) +
                          "); remove one, or merge them: DuplicatePolicy::Average (errfield interpolate and cv: "
                          "--duplicates average)");
    return;
  }
  // Average: union of all pairs within tol, each group represented by its lowest index.
  std::vector<std::size_t> parent(n);
  std::iota(parent.begin(), parent.end(), std::size_t{0});
  auto find = [&](std::size_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  std::vector<std::pair<std::size_t, double>> hits;
  // radius search is strict (<); nudge so that lag == tol counts, and lag 0 when tol == 0.
  const double r2 = tol2 > 0.0 ? tol2 * (1.0 + 1e-12) : std::numeric_limits<double>::min();
  for (std::size_t i = 0; i < n; ++i) {
    tree_->within(points_.col(static_cast<Eigen::Index>(i)).data(), r2, hits);
    for (const auto& [j, d2] : hits) {
      const std::size_t a = find(i), b = find(j);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  }
  std::vector<std::size_t> group_of(n), count;
  std::vector<std::size_t> keep;
  std::vector<std::size_t> slot(n, n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t root = find(i);
    if (slot[root] == n) {
      slot[root] = keep.size();
      keep.push_back(root);
      count.push_back(0);
    }
    group_of[i] = slot[root];
    ++count[slot[root]];
  }
  if (keep.size() == n) return;
  const auto m = static_cast<Eigen::Index>(keep.size());
  Eigen::MatrixXd pts(dimension_, m), raw(raw_.rows(), m), vals = Eigen::MatrixXd::Zero(m, components_);
  Eigen::VectorXd meas = Eigen::VectorXd::Zero(m), reps = Eigen::VectorXd::Zero(m);
  for (Eigen::Index g = 0; g < m; ++g) {
    pts.col(g) = points_.col(static_cast<Eigen::Index>(keep[static_cast<std::size_t>(g)]));
    raw.col(g) = raw_.col(static_cast<Eigen::Index>(keep[static_cast<std::size_t>(g)]));
  }
  for (std::size_t i = 0; i < n; ++i) {
    const auto g = static_cast<Eigen::Index>(group_of[i]);
    vals.row(g) += values_.row(static_cast<Eigen::Index>(i));
    meas[g] += meas_[static_cast<Eigen::Index>(i)];
    reps[g] += replicates_[static_cast<Eigen::Index>(i)];
  }
  for (Eigen::Index g = 0; g < m; ++g) {
    const double c = static_cast<double>(count[static_cast<std::size_t>(g)]);
    vals.row(g) /= c;
    meas[g] /= c * c;  // variance of the mean of independent measurements
  }
  report_.merged_duplicates = n - keep.size();
  points_ = std::move(pts);
  raw_ = std::move(raw);
  values_ = std::move(vals);
  meas_ = std::move(meas);
  replicates_ = std::move(reps);
  original_index_ = std::move(keep);
  tree_ = std::make_unique<PointTree>(points_);
}

void KrigingEngine::set_observation_noise() {
  // Measurement-error nugget: independent noise on every observation, so the mean of r repeats
  // carries nugget/r. Micro-scale nugget: part of the field itself, the same for every repeat at
  // one location, so averaging leaves it whole (it stays in C(0) of the signal, sill). Written so
  // that an unmerged sample's diagonal is exactly sill + measurement variance.
  const bool noise_nugget = options_.nugget == NuggetTreatment::MeasurementError;
  const double nugget = kernel_.nugget();
  noise_.resize(meas_.size());
  obs_var_.resize(meas_.size());
  for (Eigen::Index i = 0; i < meas_.size(); ++i) {
    const double r = replicates_[i];
    noise_[i] = meas_[i] + (noise_nugget ? nugget / r : 0.0);
    obs_var_[i] = kernel_.sill() + meas_[i] - (noise_nugget && r != 1.0 ? nugget * (1.0 - 1.0 / r) : 0.0);
  }
}

void KrigingEngine::build_drift() {
  const int d = dimension_;
  switch (options_.kind) {
    case KrigingKind::Simple: drift_terms_ = 0; break;
    case KrigingKind::Ordinary: drift_terms_ = 1; break;
    case KrigingKind::Universal:
      drift_terms_ = 1 + (options_.drift_order >= 1 ? d : 0) + (options_.drift_order >= 2 ? d * (d + 1) / 2 : 0) +
                     static_cast<int>(options_.drift_functions.size());
      break;
  }
  if (options_.kind != KrigingKind::Simple) drift_terms_ += covariates_;
  // Polynomial terms in centred, scaled coordinates: same span as the raw monomials (so the same
  // predictions), far better conditioned for coordinates in the thousands of mm.
  // Covariates too: an affine change of a drift column leaves its span with the constant, and so
  // the predictions, unchanged.
  const auto rows = raw_.rows();
  drift_center_ = Eigen::VectorXd::Zero(rows);
  drift_scale_ = Eigen::VectorXd::Ones(rows);
  if (raw_.cols() > 0) {
    drift_center_ = raw_.rowwise().mean();
    for (Eigen::Index k = 0; k < rows; ++k) {
      const double s = (raw_.row(k).array() - drift_center_[k]).abs().maxCoeff();
      drift_scale_[k] = s > 0.0 ? s : 1.0;
    }
  }
  f_ = drift_matrix(raw_).transpose();
}

std::string KrigingEngine::drift_description() const {
  const int d = dimension_;
  std::string s;
  if (options_.kind != KrigingKind::Universal) s = "constant mean (1 term)";
  else if (options_.drift_order == 0) s = "constant drift (order 0, 1 term)";
  else if (options_.drift_order == 1) s = "linear drift (order 1: 1 + " + std::to_string(d) + " coordinate terms)";
  else
    s = "quadratic drift (order 2: 1 + " + std::to_string(d) + " linear + " + std::to_string(d * (d + 1) / 2) +
        " quadratic terms)";
  if (!options_.drift_functions.empty())
    s += " plus " + std::to_string(options_.drift_functions.size()) + " drift function(s)";
  if (covariates_ > 0) {
    s += " plus the covariate" + std::string(covariates_ > 1 ? "s " : " ");
    for (int j = 0; j < covariates_; ++j)
      s += (j ? ", '" : "'") + options_.covariates[static_cast<std::size_t>(j)] + "'";
  }
  return s;
}

std::string KrigingEngine::singular_drift_message(double rcond) const {
  // The geometry behind it: how many coordinate directions the samples span (singular values of
  // the centred, scaled coordinates, relative to the largest).
  const Eigen::Index d = dimension_, n = raw_.cols();
  if (covariates_ > 0) {
    const std::string named = collinear_covariate_message();
    if (!named.empty())
      return "the " + std::to_string(drift_terms_) + " drift terms of the " + drift_description() +
             " are (nearly) linearly dependent at the " + std::to_string(n) + " samples (reciprocal condition " +
             format_number(rcond) + "): " + named;
  }
  int spanned = 0;
  if (n > 1) {
    Eigen::MatrixXd c(d, n);
    for (Eigen::Index k = 0; k < d; ++k)
      c.row(k) = (raw_.row(k).array() - drift_center_[k]) / drift_scale_[k];
    const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(c).singularValues();
    for (Eigen::Index k = 0; k < sv.size(); ++k) spanned += sv[k] > 1e-7 * sv[0] ? 1 : 0;
  }
  std::string geometry;
  if (spanned == 0) geometry = "all samples are at one location";
  else if (spanned == 1) geometry = "the samples are collinear (all on one line)";
  else if (spanned == 2 && d == 3) geometry = "the samples are coplanar (all on one plane)";
  else if (spanned < d)
    geometry = "the samples span only " + std::to_string(spanned) + " of the " + std::to_string(d) + " coordinate directions";
  else if (options_.kind == KrigingKind::Universal && options_.drift_order == 2)
    geometry = "the samples spread in all " + std::to_string(d) +
               " coordinate directions but lie on a quadric surface (e.g. a sphere, a cylinder or two planes)";
  else if (!options_.drift_functions.empty())
    geometry = "the drift functions are (nearly) combinations of the polynomial terms at the samples";
  else
    geometry = "the samples are (nearly) degenerate for this drift";
  return "the " + std::to_string(drift_terms_) + " drift terms of the " + drift_description() +
         " are (nearly) linearly dependent at the " + std::to_string(n) + " samples (reciprocal condition " +
         format_number(rcond) + "): " + geometry + "; use a lower drift order (or ordinary kriging), or samples " +
         "that span the drift's coordinates";
}

void KrigingEngine::drift_row(const double* raw_point, double* out) const {
  if (drift_terms_ == 0) return;
  int t = 0;
  out[t++] = 1.0;
  const int d = dimension_;
  if (options_.kind == KrigingKind::Universal) {
    if (options_.drift_order >= 1)
      for (int k = 0; k < d; ++k) out[t++] = (raw_point[k] - drift_center_[k]) / drift_scale_[k];
    if (options_.drift_order >= 2)
      for (int k = 0; k < d; ++k)
        for (int l = k; l < d; ++l)
          out[t++] = (raw_point[k] - drift_center_[k]) / drift_scale_[k] * (raw_point[l] - drift_center_[l]) /
                     drift_scale_[l];
    for (const auto& f : options_.drift_functions)
      out[t++] = f(std::span<const double>(raw_point, static_cast<std::size_t>(d)));
  }
  // External drift: the covariates stored after the coordinates.
  for (int j = 0; j < covariates_; ++j) out[t++] = (raw_point[d + j] - drift_center_[d + j]) / drift_scale_[d + j];
}

std::string KrigingEngine::collinear_covariate_message() const {
  // Add the covariate columns one at a time to the drift terms before them; the first that does
  // not raise the numerical rank of F is the culprit.
  const Eigen::Index n = f_.rows(), p = f_.cols(), first = p - covariates_;
  auto rank_of = [&](Eigen::Index cols) {
    if (cols == 0) return Eigen::Index{0};
    Eigen::MatrixXd f = f_.leftCols(cols);
    for (Eigen::Index c = 0; c < cols; ++c) {
      const double norm = f.col(c).norm();
      if (norm > 0.0) f.col(c) /= norm;
    }
    const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(f).singularValues();
    Eigen::Index r = 0;
    for (Eigen::Index k = 0; k < sv.size(); ++k) r += sv[k] > 1e-7 * sv[0] ? 1 : 0;
    return r;
  };
  if (n == 0) return {};
  Eigen::Index before = rank_of(first);
  for (Eigen::Index j = 0; j < covariates_; ++j) {
    const Eigen::Index after = rank_of(first + j + 1);
    const std::string& name = options_.covariates[static_cast<std::size_t>(j)];
    if (after == before) {
      const auto row = static_cast<Eigen::Index>(dimension_ + j);
      const bool constant = raw_.row(row).maxCoeff() == raw_.row(row).minCoeff();
      return "the covariate '" + name + "' is " +
             (constant ? "constant (" + format_number(raw_(row, 0)) + ") at the samples, like the mean term"
                       : std::string("(nearly) a linear combination of the drift terms before it at the samples")) +
             "; drop it, or use samples where it varies independently";
    }
    before = after;
  }
  return {};
}

double KrigingEngine::block_variance(const Eigen::MatrixXd& embedded, const Eigen::VectorXd& block_weights) const {
  const Eigen::Index group = block_weights.size();
  if (group == 0 || embedded.cols() < group) return target_variance();
  // The nugget is micro-scale variation (or noise): its average over a block's continuum is 0.
  const double structured = kernel_.sill() - kernel_.nugget();
  double sum = 0.0;
  for (Eigen::Index j = 0; j < group; ++j)
    for (Eigen::Index k = 0; k < group; ++k)
      sum += block_weights[j] * block_weights[k] *
             kernel_(kernels::column_distance(embedded.col(j).data(), embedded.col(k).data(), dimension_), structured);
  return sum;
}

Eigen::MatrixXd KrigingEngine::block_drift_matrix(const Eigen::MatrixXd& raw, const Eigen::VectorXd& block_weights) const {
  const Eigen::MatrixXd f = drift_matrix(raw);
  const Eigen::Index group = block_weights.size();
  if (group == 0) return f;
  const Eigen::Index blocks = raw.cols() / group;
  Eigen::MatrixXd mean(f.rows(), blocks);
  for (Eigen::Index b = 0; b < blocks; ++b) mean.col(b) = f.middleCols(b * group, group) * block_weights;
  return mean;
}

Eigen::MatrixXd KrigingEngine::drift_matrix(const Eigen::MatrixXd& raw) const {
  Eigen::MatrixXd f(drift_terms_, raw.cols());
  for (Eigen::Index j = 0; j < raw.cols(); ++j) {
    drift_row(raw.col(j).data(), f.col(j).data());
    for (int t = 0; t < drift_terms_; ++t)
      if (!std::isfinite(f(t, j)))
        throw InputError("kriging: drift term " + std::to_string(t) + " at point " + std::to_string(j) +
                         " is " + format_number(f(t, j)) + "; drift functions must return finite values");
  }
  return f;
}

bool KrigingEngine::check_condition(double rcond) {
  report_.condition_number = rcond > 0.0 ? 1.0 / rcond : std::numeric_limits<double>::infinity();
  if (report_.condition_number > options_.max_condition_number) {
    report_.status = KrigingStatus::IllConditioned;
    report_.message = "covariance matrix condition number ~" + format_number(report_.condition_number) +
                      " exceeds max_condition_number " + format_number(options_.max_condition_number) +
                      " (near-duplicate samples, or a range far larger than the sample spacing with a "
                      "smooth model); predictions are returned but may be inaccurate";
    return false;
  }
  return true;
}

KrigingOutput KrigingEngine::unusable_output() const {
  KrigingOutput out;
  out.status = report_.status;
  out.message = report_.message;
  return out;
}

void KrigingEngine::add_simple_mean(Eigen::MatrixXd& mean) const {
  if (options_.kind == KrigingKind::Simple) mean.rowwise() += simple_mean_.transpose();
}

KrigingOutput KrigingEngine::predict(const Eigen::MatrixXd& embedded, const Eigen::MatrixXd& raw,
                                     const Eigen::VectorXd& block_weights, bool with_weights) const {
  const Eigen::Index group = std::max<Eigen::Index>(1, block_weights.size());
  if (embedded.rows() != dimension_)
    throw ArgumentError("kriging: targets have " + std::to_string(embedded.rows()) + " coordinates; samples have " +
                        std::to_string(dimension_));
  if (raw.rows() != dimension_ + covariates_ || raw.cols() != embedded.cols())
    throw ArgumentError("kriging: targets come with " + std::to_string(raw.rows() - dimension_) +
                        " covariate values each; the drift has " + std::to_string(covariates_) + " covariates");
  if (group < 1 || embedded.cols() % group != 0)
    throw ArgumentError("kriging: " + std::to_string(embedded.cols()) + " block points are not whole blocks of " +
                        std::to_string(group));
  if (group > 1 && options_.backend == KrigingBackend::Sparse)
    throw ArgumentError("kriging: block kriging is offered by the dense and local back ends, not the sparse one");
  if (with_weights && options_.backend == KrigingBackend::Sparse)
    throw ArgumentError("kriging: weights are offered by the dense and local back ends, not the sparse one (its weights are dense)");
  if (!report_.usable()) return unusable_output();
  switch (options_.backend) {
    case KrigingBackend::Dense: return predict_dense(embedded, raw, block_weights, with_weights);
    case KrigingBackend::Local: return predict_local(embedded, raw, false, block_weights, with_weights);
    case KrigingBackend::Sparse: return predict_sparse(embedded, raw);
  }
  return unusable_output();
}

KrigingOutput KrigingEngine::leave_one_out() const {
  if (!report_.usable()) return unusable_output();
  if (points_.cols() < 2) {
    KrigingOutput out;
    out.status = KrigingStatus::TooFewSamples;
    out.message = "leave-one-out needs at least 2 samples";
    return out;
  }
  switch (options_.backend) {
    case KrigingBackend::Dense: return loo_dense();
    case KrigingBackend::Local: return predict_local(points_, raw_, true);
    case KrigingBackend::Sparse:
      throw ArgumentError("kriging: leave-one-out is not offered by the sparse back end (it would refactor "
                          "N times); use k_fold, or the dense or local back end");
  }
  return unusable_output();
}

KrigingOutput KrigingEngine::k_fold(int folds, std::uint64_t seed) const {
  const auto n = static_cast<std::size_t>(points_.cols());
  if (folds < 2 || static_cast<std::size_t>(folds) > n)
    throw ArgumentError("kriging: k_fold folds = " + std::to_string(folds) + "; expected 2 <= folds <= " +
                        std::to_string(n) + " (the number of samples)");
  // Deterministic Fisher-Yates with a fixed generator, so folds do not depend on the library.
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::mt19937_64 rng(seed);
  for (std::size_t i = n - 1; i > 0; --i) std::swap(order[i], order[rng() % (i + 1)]);
  std::vector<int> fold(n);
  for (std::size_t r = 0; r < n; ++r) fold[order[r]] = static_cast<int>(r % static_cast<std::size_t>(folds));

  KrigingOutput out;
  out.mean = Eigen::MatrixXd::Constant(static_cast<Eigen::Index>(n), components_, std::nan(""));
  out.residual = out.mean;
  out.variance = Eigen::VectorXd::Constant(static_cast<Eigen::Index>(n), std::nan(""));
  KrigingOptions sub = options_;
  sub.duplicates = DuplicatePolicy::Error;
  sub.duplicate_distance = 0.0;
  sub.keep_weights = false;
  for (int f = 0; f < folds; ++f) {
    std::vector<Eigen::Index> train, test;
    for (std::size_t i = 0; i < n; ++i) (fold[i] == f ? test : train).push_back(static_cast<Eigen::Index>(i));
    auto pick_cols = [](const Eigen::MatrixXd& m, const std::vector<Eigen::Index>& idx) {
      Eigen::MatrixXd r(m.rows(), static_cast<Eigen::Index>(idx.size()));
      for (std::size_t k = 0; k < idx.size(); ++k) r.col(static_cast<Eigen::Index>(k)) = m.col(idx[k]);
      return r;
    };
    Eigen::MatrixXd vals(static_cast<Eigen::Index>(train.size()), components_);
    Eigen::VectorXd meas(static_cast<Eigen::Index>(train.size())), reps(meas.size());
    for (std::size_t k = 0; k < train.size(); ++k) {
      vals.row(static_cast<Eigen::Index>(k)) = observed_.row(train[k]);
      meas[static_cast<Eigen::Index>(k)] = meas_[train[k]];
      reps[static_cast<Eigen::Index>(k)] = replicates_[train[k]];
    }
    // merged samples keep their own noise in the folds (replicates)
    KrigingEngine engine(pick_cols(points_, train), pick_cols(raw_, train), std::move(vals), std::move(meas), model_,
                         sub, std::move(reps));
    if (!engine.report().usable()) {
      out.status = engine.report().status;
      out.message = "fold " + std::to_string(f) + ": " + engine.report().message;
      return out;
    }
    KrigingOutput p = engine.predict(pick_cols(points_, test), pick_cols(raw_, test));
    if (p.status != KrigingStatus::Ok && out.status == KrigingStatus::Ok) {
      out.status = p.status;
      out.message = "fold " + std::to_string(f) + ": " + p.message;
    }
    for (std::size_t k = 0; k < test.size(); ++k) {
      const Eigen::Index i = test[k], r = static_cast<Eigen::Index>(k);
      out.mean.row(i) = p.mean.row(r);
      out.residual.row(i) = observed_.row(i) - p.mean.row(r);
      if (p.variance.size() > 0) {
        // residual of the observation: add the observation's own noise, which the prediction of
        // the signal leaves out
        out.variance[i] = p.variance[r] + noise_[i];
      }
    }
  }
  return out;
}

}  // namespace detail

// ---- glue for the template front end ----

namespace detail {
std::shared_ptr<const KrigingEngine> make_kriging_engine(Eigen::MatrixXd embedded, Eigen::MatrixXd raw,
                                                         Eigen::MatrixXd values, Eigen::VectorXd measurement_variance,
                                                         const VariogramModel& model, const KrigingOptions& options) {
  return std::make_shared<const KrigingEngine>(std::move(embedded), std::move(raw), std::move(values),
                                               std::move(measurement_variance), model, options);
}
const KrigingReport& engine_report(const KrigingEngine& engine) { return engine.report(); }
const KrigingOptions& engine_options(const KrigingEngine& engine) { return engine.options(); }

Eigen::MatrixXd append_covariates(Eigen::MatrixXd raw, const Eigen::MatrixXd& covariates, const KrigingOptions& options,
                                  const char* what, const RowLabels* labels) {
  const auto k = static_cast<Eigen::Index>(options.covariates.size());
  const Eigen::Index m = raw.cols(), d = raw.rows();
  if (covariates.cols() != k || (k > 0 && covariates.rows() != m))
    throw ArgumentError("kriging: covariates given as a " + std::to_string(covariates.rows()) + " x " +
                        std::to_string(covariates.cols()) + " matrix for " + std::to_string(m) + " " + what +
                        "s; expected " + std::to_string(m) + " x " + std::to_string(k) + " (one row per " + what +
                        ", one column per name in KrigingOptions::covariates)");
  if (k == 0) return raw;
  const bool labelled = labels != nullptr && labels->lines.size() == static_cast<std::size_t>(m) && !labels->source.empty();
  for (Eigen::Index i = 0; i < m; ++i)
    for (Eigen::Index j = 0; j < k; ++j) {
      const double v = covariates(i, j);
      if (std::isfinite(v)) continue;
      const std::string& name = options.covariates[static_cast<std::size_t>(j)];
      const auto row = static_cast<std::size_t>(i);
      const std::string where = labelled ? (*labels)(row) + ": kriging: covariate '" + name + "'"
                                         : std::string("kriging: covariate '") + name + "' of " + what + " " +
                                               std::to_string(i);
      throw InputError(where + " is " + format_number(v) + "; expected a finite number", labelled ? labels->source : "",
                       labelled ? labels->line(row) : 0, name);
    }
  raw.conservativeResize(d + k, Eigen::NoChange);
  raw.bottomRows(k) = covariates.transpose();
  return raw;
}
KrigingOutput engine_predict(const KrigingEngine& engine, const Eigen::MatrixXd& embedded, const Eigen::MatrixXd& raw) {
  return engine.predict(embedded, raw);
}
KrigingOutput engine_predict_with_weights(const KrigingEngine& engine, const Eigen::MatrixXd& embedded,
                                          const Eigen::MatrixXd& raw) {
  return engine.predict(embedded, raw, Eigen::VectorXd(), true);
}
KrigingOutput engine_predict_blocks(const KrigingEngine& engine, const Eigen::MatrixXd& embedded,
                                    const Eigen::MatrixXd& raw, const Eigen::VectorXd& block_weights) {
  return engine.predict(embedded, raw, block_weights);
}
KrigingOutput engine_leave_one_out(const KrigingEngine& engine) { return engine.leave_one_out(); }
Eigen::MatrixXd engine_leave_one_out_residuals_of(const KrigingEngine& engine, const Eigen::MatrixXd& values) {
  return engine.leave_one_out_residuals_of(values);
}
KrigingOutput engine_k_fold(const KrigingEngine& engine, int folds, std::uint64_t seed) {
  return engine.k_fold(folds, seed);
}
}  // namespace detail

namespace {

// Nodes (on [-1, 1]) and weights (summing to 2) of the n-point Gauss-Legendre rule: Newton's method
// on the Legendre polynomial from the usual cosine guesses.
void gauss_legendre(int n, std::vector<double>& node, std::vector<double>& weight) {
  node.assign(static_cast<std::size_t>(n), 0.0);
  weight.assign(static_cast<std::size_t>(n), 0.0);
  for (int i = 0; i < (n + 1) / 2; ++i) {
    double x = std::cos(M_PI * (i + 0.75) / (n + 0.5)), dp = 0.0;
    for (int iteration = 0; iteration < 100; ++iteration) {
      double p0 = 1.0, p1 = 0.0;
      for (int k = 1; k <= n; ++k) {  // P_k(x) by the three-term recurrence
        const double p2 = p1;
        p1 = p0;
        p0 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p2) / k;
      }
      dp = n * (x * p0 - p1) / (x * x - 1.0);
      const double step = p0 / dp;
      x -= step;
      if (std::abs(step) < 1e-16) break;
    }
    const double w = 2.0 / ((1.0 - x * x) * dp * dp);
    node[static_cast<std::size_t>(i)] = -x;
    node[static_cast<std::size_t>(n - 1 - i)] = x;
    weight[static_cast<std::size_t>(i)] = weight[static_cast<std::size_t>(n - 1 - i)] = w;
  }
  if (n % 2 == 1) node[static_cast<std::size_t>(n / 2)] = 0.0;
}

void check_block(const BlockDiscretization& b, int dimension) {
  if (static_cast<int>(b.size.size()) != dimension)
    throw ArgumentError("block kriging: a block size with " + std::to_string(b.size.size()) + " entries for " +
                        std::to_string(dimension) + " coordinates; expected one size per coordinate");
  for (std::size_t k = 0; k < b.size.size(); ++k)
    if (!(b.size[k] > 0.0 && std::isfinite(b.size[k])))
      throw ArgumentError("block kriging: block size " + format_number(b.size[k]) + " along coordinate " +
                          std::to_string(k) + "; expected a positive number (the coordinates' unit)");
  if (b.points_per_axis < 1 || b.points_per_axis > 64)
    throw ArgumentError("block kriging: " + std::to_string(b.points_per_axis) +
                        " points per axis; expected 1 to 64 (gstat's default is 4)");
  const double total = std::pow(static_cast<double>(b.points_per_axis), dimension);
  if (total > 4096)
    throw ArgumentError("block kriging: " + std::to_string(b.points_per_axis) + " points per axis in " +
                        std::to_string(dimension) + " coordinates make " + format_number(total) +
                        " points per block; at most 4096 (use fewer points per axis)");
}

// Per-axis nodes on [-1/2, 1/2] and weights summing to 1.
void axis_rule(const BlockDiscretization& b, std::vector<double>& node, std::vector<double>& weight) {
  const int n = b.points_per_axis;
  if (b.rule == BlockDiscretization::Rule::GaussLegendre) {
    gauss_legendre(n, node, weight);
    for (double& x : node) x *= 0.5;
    for (double& w : weight) w *= 0.5;
  } else {
    node.resize(static_cast<std::size_t>(n));
    weight.assign(static_cast<std::size_t>(n), 1.0 / n);
    for (int i = 0; i < n; ++i) node[static_cast<std::size_t>(i)] = -0.5 + (i + 0.5) / n;
  }
}

}  // namespace

Eigen::MatrixXd BlockDiscretization::offsets(int dimension) const {
  check_block(*this, dimension);
  std::vector<double> node, weight;
  axis_rule(*this, node, weight);
  const auto g = static_cast<Eigen::Index>(std::pow(static_cast<double>(points_per_axis), dimension) + 0.5);
  Eigen::MatrixXd out(dimension, g);
  for (Eigen::Index j = 0; j < g; ++j) {
    Eigen::Index rest = j;
    for (int k = 0; k < dimension; ++k) {
      out(k, j) = size[static_cast<std::size_t>(k)] * node[static_cast<std::size_t>(rest % points_per_axis)];
      rest /= points_per_axis;
    }
  }
  return out;
}

Eigen::VectorXd BlockDiscretization::weights(int dimension) const {
  check_block(*this, dimension);
  std::vector<double> node, weight;
  axis_rule(*this, node, weight);
  const auto g = static_cast<Eigen::Index>(std::pow(static_cast<double>(points_per_axis), dimension) + 0.5);
  Eigen::VectorXd out(g);
  for (Eigen::Index j = 0; j < g; ++j) {
    Eigen::Index rest = j;
    double w = 1.0;
    for (int k = 0; k < dimension; ++k) {
      w *= weight[static_cast<std::size_t>(rest % points_per_axis)];
      rest /= points_per_axis;
    }
    out[j] = w;
  }
  return out;
}

}  // namespace errfield
