#include "errfield/sampling_design.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"

namespace errfield {

namespace {

void check_locations(const Eigen::MatrixXd& x, const char* what) {
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    for (Eigen::Index k = 0; k < x.cols(); ++k)
      if (!std::isfinite(x(i, k)))
        throw ArgumentError(std::string(what) + " row " + std::to_string(i) + ", coordinate " + std::to_string(k) +
                            ": " + format_number(x(i, k)) + "; expected a finite number");
}

void check_columns(const Eigen::MatrixXd& candidates, const Eigen::MatrixXd& measured) {
  if (measured.rows() > 0 && measured.cols() != candidates.cols())
    throw ArgumentError("measured locations have " + std::to_string(measured.cols()) + " coordinates, the candidates " +
                        std::to_string(candidates.cols()));
  check_locations(candidates, "candidate");
  check_locations(measured, "measured location");
}

/// Rows of `x` divided by the per-axis scale (its standard deviation over `x` by default).
Eigen::RowVectorXd axis_scales(const Eigen::MatrixXd& x, const std::vector<double>& given) {
  Eigen::RowVectorXd s(x.cols());
  if (!given.empty()) {
    if (static_cast<Eigen::Index>(given.size()) != x.cols())
      throw ArgumentError("axis_scale: " + std::to_string(given.size()) + " scales for " + std::to_string(x.cols()) +
                          " coordinates");
    for (Eigen::Index k = 0; k < x.cols(); ++k) {
      if (!(given[static_cast<std::size_t>(k)] > 0.0 && std::isfinite(given[static_cast<std::size_t>(k)])))
        throw ArgumentError("axis_scale[" + std::to_string(k) + "]: " + format_number(given[static_cast<std::size_t>(k)]) +
                            "; expected a finite scale > 0");
      s[k] = given[static_cast<std::size_t>(k)];
    }
    return s;
  }
  for (Eigen::Index k = 0; k < x.cols(); ++k) {
    const double mean = x.col(k).mean();
    const double sd = x.rows() > 1 ? std::sqrt((x.col(k).array() - mean).square().sum() / static_cast<double>(x.rows() - 1)) : 0.0;
    s[k] = sd > 0.0 ? sd : 1.0;
  }
  return s;
}

/// Greedy farthest-point order on already scaled rows; `start_distance2` (squared distance of each
/// row to the measured set) may be empty, then the first pick is the row nearest the centroid.
std::vector<std::size_t> farthest_points(const Eigen::MatrixXd& z, Eigen::VectorXd nearest2, std::size_t count) {
  const Eigen::Index n = z.rows();
  std::vector<std::size_t> order;
  count = std::min<std::size_t>(count, static_cast<std::size_t>(n));
  if (count == 0) return order;
  std::vector<char> taken(static_cast<std::size_t>(n), 0);
  auto take = [&](Eigen::Index i) {
    order.push_back(static_cast<std::size_t>(i));
    taken[static_cast<std::size_t>(i)] = 1;
    nearest2 = nearest2.cwiseMin((z.rowwise() - z.row(i)).rowwise().squaredNorm());
  };
  if (nearest2.size() == 0) {
    // Nothing measured: start at the row nearest the centroid (a deterministic, central start).
    const Eigen::RowVectorXd centroid = z.colwise().mean();
    Eigen::Index first = 0;
    (z.rowwise() - centroid).rowwise().squaredNorm().minCoeff(&first);
    nearest2 = Eigen::VectorXd::Constant(n, std::numeric_limits<double>::infinity());
    take(first);
  }
  while (order.size() < count) {
    Eigen::Index best = -1;
    double best_d = -1.0;
    for (Eigen::Index i = 0; i < n; ++i)
      if (!taken[static_cast<std::size_t>(i)] && nearest2[i] > best_d) best_d = nearest2[i], best = i;
    take(best);
  }
  return order;
}

Eigen::VectorXd squared_distance_to_set(const Eigen::MatrixXd& z, const Eigen::MatrixXd& set) {
  Eigen::VectorXd d = Eigen::VectorXd::Constant(z.rows(), std::numeric_limits<double>::infinity());
  for (Eigen::Index j = 0; j < set.rows(); ++j) d = d.cwiseMin((z.rowwise() - set.row(j)).rowwise().squaredNorm());
  return d;
}

/// Per-location variance multipliers: `given` (`count` of them, each finite and >= 0; ArgumentError
/// naming `name` otherwise), or 1 everywhere when it is empty.
Eigen::VectorXd variance_multipliers(const std::vector<double>& given, Eigen::Index count, const char* name,
                                     const char* locations) {
  Eigen::VectorXd scale = Eigen::VectorXd::Ones(count);
  if (given.empty()) return scale;
  if (static_cast<Eigen::Index>(given.size()) != count)
    throw ArgumentError(std::string(name) + ": " + std::to_string(given.size()) + " values for " + std::to_string(count) +
                        " " + locations);
  for (Eigen::Index i = 0; i < count; ++i) {
    const double v = given[static_cast<std::size_t>(i)];
    if (!(v >= 0.0 && std::isfinite(v)))
      throw ArgumentError(std::string(name) + "[" + std::to_string(i) + "]: " + format_number(v) + "; expected >= 0");
    scale[i] = v;
  }
  return scale;
}

/// The locations mapped by the model's anisotropy, so that the lag is a plain Euclidean distance.
Eigen::MatrixXd mapped_by_anisotropy(const Eigen::MatrixXd& x, const Anisotropy& a) {
  if (a.isotropic()) return x;
  if (a.dimension() != x.cols())
    throw ArgumentError("the model's anisotropy " + a.to_string() + " is for " + std::to_string(a.dimension()) +
                        " coordinates, the locations have " + std::to_string(x.cols()));
  Eigen::MatrixXd out(x.rows(), x.cols());
  Eigen::VectorXd in(x.cols()), o(x.cols());
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    in = x.row(i).transpose();
    a.apply(in.data(), o.data(), static_cast<int>(x.cols()));
    out.row(i) = o.transpose();
  }
  return out;
}

// Components of a reading in VarianceReductionOptions::linear_term (3 for a position): their
// per-candidate systems live on the stack up to this size.
constexpr int kMaxLinearComponents = 8;

/// Prior covariance of the field plus the constant mean's variance, between the rows of a and b.
struct PriorCovariance {
  VariogramModel isotropic;
  double field_variance = 0.0;  ///< structured sill (nugget excluded): C(0) of the noise-free field
  double mean_variance = 0.0;
  double operator()(double h) const {
    return mean_variance + (h > 0.0 ? isotropic.sill() - isotropic.gamma(h) : field_variance);
  }
  // Columns in parallel: each entry is computed alone, so the result does not depend on the threads.
  Eigen::MatrixXd between(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) const {
    Eigen::MatrixXd k(a.rows(), b.rows());
#pragma omp parallel for schedule(static)
    for (Eigen::Index j = 0; j < b.rows(); ++j)
      for (Eigen::Index i = 0; i < a.rows(); ++i) k(i, j) = (*this)((a.row(i) - b.row(j)).norm());
    return k;
  }
};

/// The linear term beside the field (VarianceReductionOptions::LinearTerm) under the joint model
/// reading = D beta + field + noise. The field's kriging at a location takes back the part of the
/// term's error that its neighbours' readings share: what is left of the design there is
/// D~_c = D_c - k(c,S) K_S^-1 D_S over the set S of measured and picked locations (the drift part of
/// universal kriging's variance), and a reading at b informs beta by D~_b alone. Kept current here:
/// D~ at every candidate and beta's covariance A; each member's rows are kept as they were when it
/// joined (see variance_sum). Rows are component-major: component k of candidate c is row k·C + c,
/// of member i row k·S_max + i.
class LinearTermPosterior {
 public:
  LinearTermPosterior(const VarianceReductionOptions::LinearTerm& term, Eigen::Index candidates, Eigen::Index set_capacity)
      : k_(term.components), c_(candidates), capacity_(set_capacity) {
    const Eigen::Index p = term.covariance.rows();
    // A = F F', F from A's eigenvectors (A may be singular: a coefficient the data barely see).
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(0.5 * (term.covariance + term.covariance.transpose()));
    factor_ = eigen.eigenvectors() * eigen.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal();
    covariance_ = factor_ * factor_.transpose();
    residual_ = component_major(term.candidate_rows, c_);
    member_rows_ = Eigen::MatrixXd::Zero(k_ * capacity_, p);
    covariance_scale_ = term.covariance.cwiseAbs().maxCoeff();
    rows_scale_ = term.candidate_rows.cwiseAbs().maxCoeff();
    refresh();
    check_finite(nullptr);
  }

  /// Conditions D~ on the M measured locations, whose design rows are `measured_rows` (interleaved,
  /// as LinearTerm's): `llt` factors K_DD + noise I, `w` is L^-1 K_DC (M x C) and `inverse`
  /// (K_DD + noise I)^-1. A measured location's own rows are those left given the other measured
  /// ones, (K^-1 D)_i / (K^-1)_ii.
  void condition_on_measured(const Eigen::MatrixXd& measured_rows, const Eigen::LLT<Eigen::MatrixXd>& llt,
                             const Eigen::MatrixXd& w, const Eigen::MatrixXd& inverse) {
    const Eigen::Index m = w.rows();
    const Eigen::MatrixXd design = component_major(measured_rows, m);
    for (Eigen::Index k = 0; k < k_; ++k) {
      const auto d = design.middleRows(k * m, m);
      residual_.middleRows(k * c_, c_).noalias() -= w.transpose() * llt.matrixL().solve(Eigen::MatrixXd(d));
      member_rows_.middleRows(k * capacity_, m) = inverse.diagonal().cwiseInverse().asDiagonal() * (inverse * d);
    }
    refresh();
    check_finite(nullptr);
  }

  /// Per candidate not taken: how much a reading there (field variance var_c + noise) lowers the
  /// term's mean variance tr(A Q~) / K, Q~ the mean of D~_c' D~_c over the candidates, through A
  /// alone: tr((var + noise + G D~')^-1 G Q~ G') / K with G = D~_c A.
  Eigen::VectorXd reductions(const Eigen::VectorXd& var_c, double noise, const std::vector<char>& taken) const {
    Eigen::VectorXd out = Eigen::VectorXd::Zero(c_);
    using Small = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxLinearComponents, kMaxLinearComponents>;
#pragma omp parallel for schedule(static)
    for (Eigen::Index c = 0; c < c_; ++c) {
      if (taken[static_cast<std::size_t>(c)]) continue;
      Small m(k_, k_), t(k_, k_);
      for (Eigen::Index i = 0; i < k_; ++i)
        for (Eigen::Index j = 0; j < k_; ++j) {
          m(i, j) = residual_a_.row(i * c_ + c).dot(residual_.row(j * c_ + c));
          t(i, j) = residual_aq_.row(i * c_ + c).dot(residual_a_.row(j * c_ + c));
        }
      m.diagonal().array() += std::max(var_c[c], 0.0) + noise;
      out[c] = m.llt().solve(t).trace() / static_cast<double>(k_);
    }
    check_finite(&out);
    return out;
  }

  /// After picking candidate b as member `s` of the set: `reading_variance` is its field variance
  /// before the pick plus the noise, and alpha_c = Σ(c, b) / reading_variance the field's weight of
  /// the reading at every candidate.
  void pick(Eigen::Index b, double reading_variance, const Eigen::VectorXd& alpha, Eigen::Index s) {
    const Eigen::Index p = covariance_.rows();
    Eigen::MatrixXd d(k_, p);  // D~_b, before the pick
    for (Eigen::Index k = 0; k < k_; ++k) d.row(k) = residual_.row(k * c_ + b);
    for (Eigen::Index k = 0; k < k_; ++k) member_rows_.row(k * capacity_ + s) = d.row(k);
    // A <- A - G' H, H = (reading_variance I + G D~_b')^-1 G, G = D~_b A, in square-root form: with
    // Z = D~_b F, A's new factor is F U^-1, U'U = I + Z'Z / reading_variance. Subtracting G' H from
    // A itself lost A's positive definiteness within 15 picks on a 40-pose fit, whose coefficient
    // covariance spans 20 orders of magnitude, and the plan's predictions turned negative.
    const Eigen::MatrixXd z = d * factor_;
    const Eigen::MatrixXd g = z * factor_.transpose();
    Eigen::MatrixXd m = z * z.transpose();
    m.diagonal().array() += reading_variance;
    const Eigen::MatrixXd h = m.llt().solve(g);
    Eigen::MatrixXd n = z.transpose() * z / reading_variance;
    n.diagonal().array() += 1.0;
    const Eigen::LLT<Eigen::MatrixXd> n_llt(n);
    n_llt.matrixU().solveInPlace<Eigen::OnTheRight>(factor_);
    covariance_.noalias() = factor_ * factor_.transpose();
    // D~ <- D~ - alpha D~_b per component. D~ A, Q~ and D~ A Q~ follow by the same low-rank
    // changes (recomputing them took three K·C x p x p products per pick, 13.5 s of the 10,000-
    // candidate benchmark); every kRefreshPicks picks they are recomputed whole, so the rounding
    // of the updates does not build up.
    const double alpha2 = alpha.squaredNorm() / static_cast<double>(c_);
    Eigen::MatrixXd v(k_, p);  // v_k = alpha' D~_k / C, before the change
    for (Eigen::Index k = 0; k < k_; ++k) v.row(k) = alpha.transpose() * residual_.middleRows(k * c_, c_) / static_cast<double>(c_);
    // Q~ <- Q~ + dQ, dQ = sum_k -(v_k' d_k + d_k' v_k) + |alpha|^2 / C d_k' d_k.
    const Eigen::MatrixXd dq = -v.transpose() * d - d.transpose() * v + alpha2 * d.transpose() * d;
    const Eigen::MatrixXd g_gram = g * gram_, h_gram = h * gram_;
    // The components' blocks are disjoint: one thread each, the same sums whatever the threads.
#pragma omp parallel for schedule(static)
    for (Eigen::Index k = 0; k < k_; ++k) {
      auto residual = residual_.middleRows(k * c_, c_);
      auto residual_a = residual_a_.middleRows(k * c_, c_);
      auto residual_aq = residual_aq_.middleRows(k * c_, c_);
      residual.noalias() -= alpha * d.row(k);
      // (D~ - alpha d) (A - G' H) = D~ A - alpha g_k - (D~_new G') H.
      const Eigen::MatrixXd lever = residual * g.transpose();  // C x K
      residual_a.noalias() -= alpha * g.row(k);
      residual_a.noalias() -= lever * h;
      // Then (D~ A)_new Q~_new = [D~ A Q~ - alpha g_k Q~ - lever H Q~] + (D~ A)_new dQ, and dQ has
      // rank 2K at most: (D~ A)_new dQ = -(G_new v') d - (G_new d')(v - |alpha|^2 / C d).
      residual_aq.noalias() -= alpha * g_gram.row(k);
      residual_aq.noalias() -= lever * h_gram;
      const Eigen::MatrixXd on_v = residual_a * v.transpose(), on_d = residual_a * d.transpose();
      residual_aq.noalias() -= on_v * d;
      residual_aq.noalias() -= on_d * (v - alpha2 * d);
    }
    gram_ += dq;
    if (++picks_ % kRefreshPicks == 0) refresh();
    check_finite(nullptr);
  }

  /// Sum over the candidates not picked of tr(D~_c A D~_c'), and over the members counted (the
  /// first `measured_counted` measured ones and the `picked` picks after the `measured` ones) of
  /// tr(R_i A R_i') with R_i a member's rows as kept when it joined: a pick's D~ given the members
  /// before it, a measured location's given the other measured ones. A member's rows are not
  /// updated by later picks: the leave-one-out rows (K_S^-1 D_S)_i / (K_S^-1)_ii over the whole
  /// set came out hundreds of times too large on a 40-pose fit whose K_S was near singular (a
  /// Gaussian model of range 10^5 degrees), where the kept rows stay bounded; what later picks
  /// would take back of a member's term is left out, a slight overstatement.
  double variance_sum(const std::vector<Eigen::Index>& set_of_candidate, Eigen::Index measured, Eigen::Index measured_counted,
                      Eigen::Index picked) const {
    const Eigen::VectorXd per_row = (residual_a_.array() * residual_.array()).rowwise().sum();
    double sum = 0.0;
    for (Eigen::Index c = 0; c < c_; ++c)
      if (set_of_candidate[static_cast<std::size_t>(c)] < 0)
        for (Eigen::Index k = 0; k < k_; ++k) sum += per_row[k * c_ + c];
    auto member = [&](Eigen::Index i) {
      for (Eigen::Index k = 0; k < k_; ++k) sum += member_rows_.row(k * capacity_ + i) * covariance_ * member_rows_.row(k * capacity_ + i).transpose();
    };
    for (Eigen::Index i = 0; i < measured_counted; ++i) member(i);
    for (Eigen::Index i = measured; i < measured + picked; ++i) member(i);
    return sum;
  }

 private:
  // Interleaved rows (component k of location i at row K·i + k) to component-major.
  Eigen::MatrixXd component_major(const Eigen::MatrixXd& rows, Eigen::Index locations) const {
    Eigen::MatrixXd out(rows.rows(), rows.cols());
    for (Eigen::Index i = 0; i < locations; ++i)
      for (Eigen::Index k = 0; k < k_; ++k) out.row(k * locations + i) = rows.row(k_ * i + k);
    return out;
  }
  void refresh() {
    residual_a_.noalias() = residual_ * covariance_;
    gram_.noalias() = residual_.transpose() * residual_;
    gram_ /= static_cast<double>(c_);
    residual_aq_.noalias() = residual_a_ * gram_;
  }
  static constexpr int kRefreshPicks = 64;

  /// Finite inputs can still overflow on the way (a hand-edited covariance of 1e300 squared in
  /// D~ A Q~, or design rows divided by a gravity scale of 1e-300): every score after it would be
  /// NaN, and plan corrupted its heap picking "none" (index -1). Refused as the input it is.
  void check_finite(const Eigen::VectorXd* reductions) const {
    if (residual_a_.allFinite() && residual_aq_.allFinite() && gram_.allFinite() && covariance_.allFinite() &&
        (!reductions || reductions->allFinite()))
      return;
    throw ArgumentError("linear_term: its variances overflow double precision (covariance up to " +
                        format_number(covariance_scale_) + ", design rows up to " + format_number(rows_scale_) +
                        "); no choice can be made from them");
  }

  // Row-major: a candidate's K rows are read one by one in its K x K systems.
  using RowMajorMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  Eigen::Index k_, c_, capacity_;
  Eigen::MatrixXd factor_;       // F, A = F F'
  Eigen::MatrixXd covariance_;   // A, p x p
  RowMajorMatrix residual_;      // D~_c, K·C x p
  RowMajorMatrix residual_a_;    // D~_c A
  Eigen::MatrixXd gram_;         // Q~ = mean over the candidates of D~_c' D~_c (components summed)
  RowMajorMatrix residual_aq_;   // D~_c A Q~
  Eigen::MatrixXd member_rows_;  // each member's rows as kept when it joined, K·S_max x p
  long picks_ = 0;
  double covariance_scale_ = 0.0, rows_scale_ = 0.0;  // for check_finite's message
};

}  // namespace

std::vector<std::size_t> select_maximin(const Eigen::MatrixXd& candidates, const Eigen::MatrixXd& measured,
                                        const MaximinOptions& options) {
  check_columns(candidates, measured);
  if (candidates.rows() == 0) return {};
  const Eigen::RowVectorXd s = axis_scales(candidates, options.axis_scale);
  const Eigen::MatrixXd z = candidates.array().rowwise() / s.array();
  Eigen::VectorXd nearest2;
  if (measured.rows() > 0) nearest2 = squared_distance_to_set(z, measured.array().rowwise() / s.array());
  return farthest_points(z, nearest2, options.count);
}

namespace {

void check_variance_reduction_inputs(const Eigen::MatrixXd& candidates, const Eigen::MatrixXd& measured,
                                     const VariogramModel& model, const VarianceReductionOptions& options) {
  check_columns(candidates, measured);
  if (!model.bounded())
    throw ArgumentError("variance reduction needs a bounded variogram model (a covariance), got " + model.to_string());
  if (!(options.mean_variance_factor > 0.0 && std::isfinite(options.mean_variance_factor)))
    throw ArgumentError("mean_variance_factor: " + format_number(options.mean_variance_factor) + "; expected > 0");
  if (options.max_references == 0) throw ArgumentError("max_references: expected at least 1");
}

void check_first_picks(const VarianceReductionOptions& options, Eigen::Index C) {
  if (options.first_picks.size() > options.count)
    throw ArgumentError("first_picks: " + std::to_string(options.first_picks.size()) + " rows for a count of " +
                        std::to_string(options.count));
  for (std::size_t f = 0; f < options.first_picks.size(); ++f) {
    const std::size_t row = options.first_picks[f];
    if (row >= static_cast<std::size_t>(C) ||
        std::find(options.first_picks.begin(), options.first_picks.begin() + static_cast<std::ptrdiff_t>(f), row) !=
            options.first_picks.begin() + static_cast<std::ptrdiff_t>(f))
      throw ArgumentError("first_picks[" + std::to_string(f) + "]: row " + std::to_string(row) +
                          " is beyond the candidates or given twice");
  }
}

// The greedy batch's state: the field's posterior covariance between the references and the
// candidates, the candidates' variances, the set S of measured and picked locations with its
// inverse covariance, the linear term's posterior and the spacing floor's distances. Built in the
// order the inputs are checked (the first bad input is the one reported).
class GreedyVarianceReduction {
 public:
  GreedyVarianceReduction(const Eigen::MatrixXd& candidates, const Eigen::MatrixXd& measured,
                          const VariogramModel& model, const VarianceReductionOptions& options)
      : model_(model), o_(options), C(candidates.rows()), nugget(model.nugget()),
        k{model.isotropic_part(), model.sill() - nugget, 0.0} {
    if (!(k.field_variance > 0.0)) throw ArgumentError("the model has no structured variance (a pure nugget): " + model.to_string());
    k.mean_variance = options.mean_variance_factor * k.field_variance;
    // A measurement's noise; a nugget-free model gets a relative jitter so the systems stay solvable.
    noise = nugget > 0.0 ? nugget : 1e-10 * k.field_variance;
    xc = mapped_by_anisotropy(candidates, model.anisotropy());
    xd = mapped_by_anisotropy(measured, model.anisotropy());
    choose_references();
    condition_on_measured();
    start_set();
    start_linear_term();
  }

  std::size_t references() const { return ref_rows.size(); }
  Eigen::Index measured() const { return xd.rows(); }
  // Picks to make: the count and the lookahead, at most every candidate.
  std::size_t total() const { return total_; }

  // The mean predictive variance of a new measurement over the candidates (and measured locations).
  double mse() const {
    double sum = 0.0;
    for (Eigen::Index c = 0; c < C; ++c) {
      const Eigen::Index i = set_of_candidate[static_cast<std::size_t>(c)];
      sum += scale_c[c] * (i >= 0 ? loo(i) : std::max(var_c[c], 0.0));
    }
    for (Eigen::Index e = 0; e < E; ++e) sum += scale_e[e] * loo(e);
    if (linear_posterior)
      sum += linear_posterior->variance_sum(set_of_candidate, M, E, S - M) / static_cast<double>(K);
    return sum / static_cast<double>(C + E) + scale_all * nugget;
  }

  // The spacing floor's distances: each candidate's squared (scaled) distance to the nearest
  // measured or picked location, infinite while there is none.
  void start_spacing(const Eigen::MatrixXd& candidates, const Eigen::MatrixXd& measured) {
    if (!(o_.spacing_floor >= 0.0 && o_.spacing_floor < 1.0))
      throw ArgumentError("spacing_floor: " + format_number(o_.spacing_floor) + "; expected a fraction in [0, 1)");
    if (o_.spacing_floor > 0.0) {
      const Eigen::RowVectorXd s = axis_scales(candidates, {});
      z_spacing = candidates.array().rowwise() / s.array();
      nearest2_spacing = measured.rows() > 0 ? squared_distance_to_set(z_spacing, measured.array().rowwise() / s.array())
                                             : Eigen::VectorXd::Constant(C, std::numeric_limits<double>::infinity());
    }
  }

  Eigen::Index best_candidate(std::size_t pick) const;
  void take(Eigen::Index best);

 private:
  // Leave-one-out variance of member i of the set, capped (see member_cap).
  double loo(Eigen::Index i) const {
    const double cap = member_cap[static_cast<std::size_t>(i)];
    return k_inverse(i, i) > 0.0 ? std::clamp(1.0 / k_inverse(i, i) - noise, 0.0, cap) : cap;
  }
  void choose_references();
  void condition_on_measured();
  void start_set();
  void start_linear_term();

  const VariogramModel& model_;
  const VarianceReductionOptions& o_;
  Eigen::Index C, R = 0, M = 0, E = 0, K = 1, S_max = 0, S = 0;
  double nugget, noise = 0.0, scale_all = 0.0;
  PriorCovariance k;
  std::size_t total_ = 0;
  Eigen::MatrixXd xc, xd, xr;
  std::vector<std::size_t> ref_rows;
  Eigen::VectorXd scale_c, scale_r, scale_e;
  Eigen::MatrixXd cross;             // Σ(R, C), updated in place
  Eigen::VectorXd var_c;             // Σ(c, c)
  Eigen::MatrixXd w_c;               // M x C, kept for the candidate-candidate covariances of later picks
  Eigen::MatrixXd measured_inverse;  // (K_DD + noise I)^-1, for the leave-one-out variances
  Eigen::LLT<Eigen::MatrixXd> llt;
  Eigen::MatrixXd k_inverse;  // top-left |S| x |S| in use
  Eigen::MatrixXd x_set;
  std::vector<Eigen::Index> set_of_candidate;  // a pick's index in S
  std::vector<double> member_cap;
  std::vector<char> taken;
  std::optional<LinearTermPosterior> linear_posterior;
  Eigen::MatrixXd z_spacing;
  Eigen::VectorXd nearest2_spacing;
  std::vector<Eigen::VectorXd> u_c;  // the picks' rank-one updates over the candidates
};

// References: every candidate, or an evenly spread subset (maximin in the mapped coordinates).
void GreedyVarianceReduction::choose_references() {
  if (static_cast<std::size_t>(C) <= o_.max_references) {
    for (Eigen::Index i = 0; i < C; ++i) ref_rows.push_back(static_cast<std::size_t>(i));
  } else {
    MaximinOptions mo;
    mo.count = o_.max_references;
    mo.axis_scale.assign(static_cast<std::size_t>(xc.cols()), 1.0);
    ref_rows = select_maximin(xc, Eigen::MatrixXd(0, xc.cols()), mo);
    std::sort(ref_rows.begin(), ref_rows.end());
  }
  R = static_cast<Eigen::Index>(ref_rows.size());
  scale_c = variance_multipliers(o_.variance_scale, C, "variance_scale", "candidates");
  scale_r.resize(R);
  for (Eigen::Index i = 0; i < R; ++i) scale_r[i] = scale_c[static_cast<Eigen::Index>(ref_rows[static_cast<std::size_t>(i)])];
  constexpr double kMaxBytes = 4.0 * 1024 * 1024 * 1024;
  if (static_cast<double>(R) * static_cast<double>(C) * 8.0 > kMaxBytes)
    throw ResourceError("variance reduction over " + std::to_string(R) + " references x " + std::to_string(C) +
                        " candidates needs more than 4 GiB; lower max_references or the number of candidates");
  xr.resize(R, xc.cols());
  for (Eigen::Index i = 0; i < R; ++i) xr.row(i) = xc.row(static_cast<Eigen::Index>(ref_rows[static_cast<std::size_t>(i)]));
}

// Posterior after the measured locations: Σ(a,b) = k(a,b) − W_a' W_b, W = L⁻¹ K_D·, L L' = K_DD + noise I.
void GreedyVarianceReduction::condition_on_measured() {
  cross = k.between(xr, xc);
  var_c = Eigen::VectorXd::Constant(C, k(0.0));
  if (xd.rows() > 0) {
    Eigen::MatrixXd kdd = k.between(xd, xd);
    kdd.diagonal().array() += noise;
    llt.compute(kdd);
    if (llt.info() != Eigen::Success)
      throw ArgumentError("the measured locations' covariance is not positive definite under " + model_.to_string());
    w_c = llt.matrixL().solve(k.between(xd, xc));
    const Eigen::MatrixXd w_r = llt.matrixL().solve(k.between(xd, xr));
    cross.noalias() -= w_r.transpose() * w_c;
    var_c -= w_c.colwise().squaredNorm().transpose();
    measured_inverse = llt.solve(Eigen::MatrixXd::Identity(xd.rows(), xd.rows()));
  }
}

// Leave-one-out variances: a measured or picked location counts in the prediction with the
// field's variance there given every other reading, 1 / (K_S^-1)_ii - noise over the set S of
// measured and picked locations (what a new pose near it, not on it, would see). K_S^-1 is kept
// explicitly and grown by one row and column per pick (a bordered inverse, O(|S|^2) each).
void GreedyVarianceReduction::start_set() {
  M = xd.rows();
  E = o_.measured_in_prediction ? M : 0;
  scale_e = variance_multipliers(E > 0 ? o_.measured_scale : std::vector<double>{}, E, "measured_scale", "measured locations");
  total_ = std::min<std::size_t>(o_.count + o_.lookahead, static_cast<std::size_t>(C));
  S_max = M + static_cast<Eigen::Index>(total_);
  k_inverse.resize(S_max, S_max);
  x_set.resize(S_max, xc.cols());
  S = M;
  if (M > 0) {
    k_inverse.topLeftCorner(M, M) = measured_inverse;
    x_set.topRows(M) = xd;
  }
  set_of_candidate.assign(static_cast<std::size_t>(C), -1);
  // A member's variance can only fall as readings are added: at most what it was when the member
  // joined (a pick: its variance before its pick; a measured location: given the other measured
  // ones). The bordered inverse's rounding breaks that where K_S is near singular (a Gaussian
  // model of range 10^5 degrees fitted on 40 poses gave (K_S^-1)_ii of either sign, and the
  // prediction jumped by 20 % between two picks); the cap keeps what exact arithmetic guarantees.
  member_cap.assign(static_cast<std::size_t>(S_max), 0.0);
  for (Eigen::Index i = 0; i < M; ++i) member_cap[static_cast<std::size_t>(i)] = std::max(1.0 / measured_inverse(i, i) - noise, 0.0);
  // A new reading's error variance, (field + nugget) times the local scale, averaged over every
  // candidate (and measured location): the pool as a whole, which the poses asked for later
  // resemble. Averaged over the candidates not picked alone it was biased low after a greedy
  // batch, which leaves the candidates whose variance it did not need to reduce.
  taken.assign(static_cast<std::size_t>(C), 0);
  scale_all = (scale_c.sum() + scale_e.sum()) / static_cast<double>(C + E);
}

// The linear term, conditioned on the measured locations (LinearTermPosterior).
void GreedyVarianceReduction::start_linear_term() {
  const auto& lin = o_.linear_term;
  const bool linear = lin.covariance.size() > 0;
  K = linear ? lin.components : 1;
  if (!linear) return;
  const Eigen::Index p = lin.covariance.rows();
  if (K < 1 || K > kMaxLinearComponents || lin.covariance.cols() != p || lin.candidate_rows.rows() != K * C || lin.candidate_rows.cols() != p ||
      !lin.covariance.allFinite() || !lin.candidate_rows.allFinite())
    throw ArgumentError("linear_term: expected 1 to " + std::to_string(kMaxLinearComponents) +
                        " components, a finite p x p covariance and " + std::to_string(K) + " x " +
                        std::to_string(C) + " candidate rows of p columns, got " + std::to_string(lin.covariance.rows()) +
                        " x " + std::to_string(lin.covariance.cols()) + " and " + std::to_string(lin.candidate_rows.rows()) +
                        " x " + std::to_string(lin.candidate_rows.cols()));
  if (lin.measured_rows.rows() != K * M || (M > 0 && lin.measured_rows.cols() != p) || !lin.measured_rows.allFinite())
    throw ArgumentError("linear_term.measured_rows: expected " + std::to_string(K) + " x " + std::to_string(M) +
                        " finite rows of " + std::to_string(p) + " columns (the term's design at the measured locations), got " +
                        std::to_string(lin.measured_rows.rows()) + " x " + std::to_string(lin.measured_rows.cols()));
  linear_posterior.emplace(lin, C, S_max);
  if (M > 0) linear_posterior->condition_on_measured(lin.measured_rows, llt, w_c, measured_inverse);
}

// The candidate whose reading lowers the summed variance most, among those the spacing floor allows.
Eigen::Index GreedyVarianceReduction::best_candidate(std::size_t pick) const {
  // The R x C work of a pick, one candidate column per iteration: each column's sum runs over
  // the references in their order, whatever the thread count.
  Eigen::VectorXd reduction(C);
#pragma omp parallel for schedule(static)
  for (Eigen::Index c = 0; c < C; ++c) reduction[c] = (cross.col(c).array().square() * scale_r.array()).sum();
  // The linear term's reduction of its mean variance over the candidates, times the
  // references (the field's reduction is summed over them), each candidate alone.
  const Eigen::VectorXd linear_reduction = linear_posterior
                                               ? Eigen::VectorXd(linear_posterior->reductions(var_c, noise, taken) * static_cast<double>(R))
                                               : Eigen::VectorXd::Zero(C);
  // Eligible under the spacing floor: at least the floor's fraction of the largest distance.
  double min_spacing2 = -1.0;
  if (nearest2_spacing.size() > 0) {
    double largest2 = 0.0;
    for (Eigen::Index c = 0; c < C; ++c)
      if (!taken[static_cast<std::size_t>(c)]) largest2 = std::max(largest2, nearest2_spacing[c]);
    if (std::isfinite(largest2)) min_spacing2 = o_.spacing_floor * o_.spacing_floor * largest2;
  }
  Eigen::Index best = -1;
  double best_score = -1.0;
  for (Eigen::Index c = 0; c < C; ++c) {
    if (taken[static_cast<std::size_t>(c)]) continue;
    if (min_spacing2 > 0.0 && nearest2_spacing[c] < min_spacing2) continue;
    const double score = reduction[c] / (std::max(var_c[c], 0.0) + noise) + linear_reduction[c];
    if (score > best_score) best_score = score, best = c;
  }
  // Every score NaN (variances that overflowed on the way) chose nothing: index -1 was written
  // as taken, a heap corruption (plan --candidates aborted with "double free").
  if (best < 0)
    throw Error("variance reduction: no candidate has a finite score at pick " + std::to_string(pick + 1) +
                " (the model's variances overflow double precision: " + model_.to_string() + ")");
  return best;
}

// A reading at candidate `best`: every covariance, variance and the set's inverse conditioned on it.
void GreedyVarianceReduction::take(Eigen::Index best) {
  taken[static_cast<std::size_t>(best)] = 1;
  if (nearest2_spacing.size() > 0)
    nearest2_spacing = nearest2_spacing.cwiseMin((z_spacing.rowwise() - z_spacing.row(best)).rowwise().squaredNorm());
  // Σ(C, best): prior, minus the measured locations' part, minus the earlier picks' parts.
  Eigen::VectorXd col(C);
  for (Eigen::Index c = 0; c < C; ++c) col[c] = k((xc.row(c) - xc.row(best)).norm());
  if (w_c.size()) col.noalias() -= w_c.transpose() * w_c.col(best);
  for (const Eigen::VectorXd& u : u_c) col -= u[best] * u;
  const double denominator = std::sqrt(std::max(var_c[best], 0.0) + noise);
  const Eigen::VectorXd uc = col / denominator;
  const Eigen::VectorXd ur = cross.col(best) / denominator;
#pragma omp parallel for schedule(static)
  for (Eigen::Index c = 0; c < C; ++c) cross.col(c) -= uc[c] * ur;
  // The linear term sees the pick's reading with the field's variance before it.
  if (linear_posterior) linear_posterior->pick(best, denominator * denominator, uc / denominator, S);
  {
    // K_S^-1 bordered by the pick: b = k(S, pick), a = K_S^-1 b, s = k(pick, pick) + noise - b'a.
    Eigen::VectorXd b(S);
    for (Eigen::Index i = 0; i < S; ++i) b[i] = k((x_set.row(i) - xc.row(best)).norm());
    const Eigen::VectorXd a = k_inverse.topLeftCorner(S, S) * b;
    const double schur = k(0.0) + noise - b.dot(a);
    k_inverse.topLeftCorner(S, S).noalias() += (a / schur) * a.transpose();
    k_inverse.block(0, S, S, 1) = -a / schur;
    k_inverse.block(S, 0, 1, S) = (-a / schur).transpose();
    k_inverse(S, S) = 1.0 / schur;
    x_set.row(S) = xc.row(best);
    member_cap[static_cast<std::size_t>(S)] = std::max(var_c[best], 0.0);
    set_of_candidate[static_cast<std::size_t>(best)] = S++;
  }
  var_c -= uc.cwiseAbs2();
  u_c.push_back(uc);
}

}  // namespace

VarianceReductionPlan select_by_variance_reduction(const Eigen::MatrixXd& candidates, const Eigen::MatrixXd& measured,
                                                   const VariogramModel& model,
                                                   const VarianceReductionOptions& options) {
  check_variance_reduction_inputs(candidates, measured, model, options);
  VarianceReductionPlan plan;
  if (candidates.rows() == 0) return plan;
  GreedyVarianceReduction greedy(candidates, measured, model, options);
  plan.references = greedy.references();
  plan.predicted_mse.push_back(greedy.measured() > 0 ? greedy.mse() : std::numeric_limits<double>::quiet_NaN());
  greedy.start_spacing(candidates, measured);
  check_first_picks(options, candidates.rows());
  for (std::size_t pick = 0; pick < greedy.total(); ++pick) {
    const Eigen::Index best = pick < options.first_picks.size() ? static_cast<Eigen::Index>(options.first_picks[pick])
                                                                : greedy.best_candidate(pick);
    (pick < options.count ? plan.chosen : plan.lookahead_rows).push_back(static_cast<std::size_t>(best));
    greedy.take(best);
    plan.predicted_mse.push_back(greedy.mse());
    if (pick + 1 >= options.count && options.lookahead_done && options.lookahead_done(plan.predicted_mse.back())) break;
  }
  return plan;
}

std::vector<std::size_t> box_extending_picks(const Eigen::MatrixXd& candidates, const Eigen::MatrixXd& measured,
                                             double margin, std::size_t limit) {
  check_columns(candidates, measured);
  if (!(margin >= 0.0 && std::isfinite(margin)))
    throw ArgumentError("box_extending_picks: margin " + format_number(margin) + "; expected a finite margin >= 0");
  std::vector<std::size_t> picks;
  if (measured.rows() == 0) return picks;
  Eigen::RowVectorXd lower = measured.colwise().minCoeff().array() - margin;
  Eigen::RowVectorXd upper = measured.colwise().maxCoeff().array() + margin;
  std::vector<char> taken(static_cast<std::size_t>(candidates.rows()), 0);
  while (picks.size() < limit) {
    Eigen::Index best = -1;
    double best_beyond = 0.0;
    for (Eigen::Index a = 0; a < candidates.cols() && best < 0; ++a)
      for (int side = 0; side < 2; ++side) {
        for (Eigen::Index c = 0; c < candidates.rows(); ++c) {
          if (taken[static_cast<std::size_t>(c)]) continue;
          const double beyond = side == 0 ? lower[a] - candidates(c, a) : candidates(c, a) - upper[a];
          if (beyond > best_beyond) best_beyond = beyond, best = c;
        }
        if (best >= 0) break;
      }
    if (best < 0) break;
    picks.push_back(static_cast<std::size_t>(best));
    taken[static_cast<std::size_t>(best)] = 1;
    lower = lower.cwiseMin((candidates.row(best).array() - margin).matrix());
    upper = upper.cwiseMax((candidates.row(best).array() + margin).matrix());
  }
  return picks;
}

std::vector<double> leave_one_out_squared_z(const Eigen::MatrixXd& samples, const Eigen::MatrixXd& values,
                                            const VariogramModel& model, double mean_variance_factor) {
  check_locations(samples, "sample");
  if (values.rows() != samples.rows() || values.cols() < 1)
    throw ArgumentError("leave_one_out_squared_z: " + std::to_string(values.rows()) + " value rows for " +
                        std::to_string(samples.rows()) + " samples");
  if (!model.bounded()) throw ArgumentError("leave-one-out z^2 needs a bounded variogram model, got " + model.to_string());
  const Eigen::Index n = samples.rows();
  if (n < 3) return {};
  const double nugget = model.nugget();
  PriorCovariance k{model.isotropic_part(), model.sill() - nugget, 0.0};
  if (!(k.field_variance > 0.0)) return {};
  k.mean_variance = mean_variance_factor * k.field_variance;
  const Eigen::MatrixXd xs = mapped_by_anisotropy(samples, model.anisotropy());
  Eigen::MatrixXd kk = k.between(xs, xs);
  kk.diagonal().array() += nugget > 0.0 ? nugget : 1e-10 * k.field_variance;
  const Eigen::LLT<Eigen::MatrixXd> llt(kk);
  if (llt.info() != Eigen::Success) return {};
  const Eigen::MatrixXd inverse = llt.solve(Eigen::MatrixXd::Identity(n, n));
  const Eigen::MatrixXd alpha = inverse * values;
  // Leave-one-out (Dubrule): residual_i = alpha_i / inv_ii, predictive variance 1 / inv_ii.
  std::vector<double> z2(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    const double d = inverse(i, i);
    z2[static_cast<std::size_t>(i)] = (alpha.row(i) / d).squaredNorm() * d / static_cast<double>(values.cols());
  }
  return z2;
}

std::vector<double> local_error_scale(const Eigen::MatrixXd& samples, const Eigen::MatrixXd& values,
                                      const VariogramModel& model, const Eigen::MatrixXd& query,
                                      std::size_t neighbours, double mean_variance_factor) {
  check_columns(query, samples);
  return local_error_scale(samples, leave_one_out_squared_z(samples, values, model, mean_variance_factor), model, query,
                           neighbours);
}

std::vector<double> local_error_scale(const Eigen::MatrixXd& samples, const std::vector<double>& z2,
                                      const VariogramModel& model, const Eigen::MatrixXd& query,
                                      std::size_t neighbours) {
  check_columns(query, samples);
  if (!z2.empty() && z2.size() != static_cast<std::size_t>(samples.rows()))
    throw ArgumentError("local_error_scale: " + std::to_string(z2.size()) + " z^2 for " +
                        std::to_string(samples.rows()) + " samples");
  std::vector<double> scale(static_cast<std::size_t>(query.rows()), 1.0);
  if (z2.empty() || neighbours == 0) return scale;
  const Eigen::Index n = samples.rows();
  const Eigen::MatrixXd xs = mapped_by_anisotropy(samples, model.anisotropy()), xq = mapped_by_anisotropy(query, model.anisotropy());
  const std::size_t m = std::min<std::size_t>(neighbours, static_cast<std::size_t>(n));
  std::vector<std::pair<double, Eigen::Index>> d(static_cast<std::size_t>(n));
  for (Eigen::Index q = 0; q < xq.rows(); ++q) {
    for (Eigen::Index i = 0; i < n; ++i) d[static_cast<std::size_t>(i)] = {(xs.row(i) - xq.row(q)).squaredNorm(), i};
    std::partial_sort(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(m), d.end());
    double sum = 0.0;
    for (std::size_t j = 0; j < m; ++j) sum += z2[static_cast<std::size_t>(d[j].second)];
    scale[static_cast<std::size_t>(q)] = std::clamp(sum / static_cast<double>(m), 0.1, 10.0);
  }
  return scale;
}

}  // namespace errfield
