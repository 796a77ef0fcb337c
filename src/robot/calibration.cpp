#include "robot/rigid_fit.hpp"
#include "errfield/robot/calibration.hpp"

#include <algorithm>
#include <limits>
#include <cmath>
#include <numbers>
#include <sstream>

#include <Eigen/Dense>

#include "errfield/error.hpp"

namespace errfield::robot {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
/// IGG3 weights are considered settled when no weight moves by more than this in a round.
constexpr double kWeightsSettled = 1e-3;

template <class Vector>
std::size_t count_distinct(std::vector<Vector> v) {
  const auto less = [](const Vector& a, const Vector& b) {
    return std::lexicographical_compare(a.begin(), a.end(), b.begin(), b.end());
  };
  std::sort(v.begin(), v.end(), less);
  return static_cast<std::size_t>(std::unique(v.begin(), v.end()) - v.begin());
}

// What is identified: the robot model and extra parameters (the fixed base points' coordinates,
// 3 per point, mm). Candidate indices below param::kCount are model parameters, index
// param::kCount + e is extra[e].
struct State {
  MdhModel model;
  Eigen::VectorXd extra;
};

std::string candidate_name(int index) {
  if (index < param::kCount) return parameter_name(index);
  const int e = index - param::kCount;
  return "base point " + std::to_string(e / 3) + " " + "xyz"[e % 3];
}

// A measurement model: residuals (measured − predicted), `dim` rows per measurement, and the
// Jacobian of the predictions with respect to the candidate parameters (columns = `active`).
class Problem {
 public:
  virtual ~Problem() = default;
  virtual int dim() const = 0;
  virtual std::size_t count() const = 0;
  // Measurements at distinct configurations (a repeated pose or pair adds no equation).
  virtual std::size_t distinct() const = 0;
  virtual void evaluate(const State& s, const std::vector<int>& active, Eigen::VectorXd& r,
                        Eigen::MatrixXd* jac) const = 0;
  // The Jacobian of measurements of the same kind (same base points) at generic configurations
  // `q` (several hundred equations), for the "too few poses" guard.
  virtual Eigen::MatrixXd generic_jacobian(const State& s, const std::vector<int>& candidates,
                                           const std::vector<JointVector>& q) const = 0;
};

class PositionProblem final : public Problem {
 public:
  explicit PositionProblem(const std::vector<PositionMeasurement>& d) : data_(d) {}
  int dim() const override { return 3; }
  std::size_t count() const override { return data_.size(); }
  std::size_t distinct() const override {
    std::vector<JointVector> q;
    for (const auto& d : data_) q.push_back(d.q_deg);
    return count_distinct(std::move(q));
  }
  void evaluate(const State& s, const std::vector<int>& active, Eigen::VectorXd& r,
                Eigen::MatrixXd* jac) const override {
    const MdhModel& m = s.model;
    const auto n = static_cast<Eigen::Index>(data_.size());
    r.resize(3 * n);
    if (jac) jac->resize(3 * n, static_cast<Eigen::Index>(active.size()));
    for (Eigen::Index i = 0; i < n; ++i) {
      const auto& d = data_[static_cast<std::size_t>(i)];
      r.segment<3>(3 * i) = d.measured_mm - forward_position(m, d.q_deg);
      if (jac) {
        const IdentificationJacobian j = identification_jacobian(m, d.q_deg);
        for (std::size_t c = 0; c < active.size(); ++c)
          jac->block<3, 1>(3 * i, static_cast<Eigen::Index>(c)) = j.col(active[c]);
      }
    }
  }
  Eigen::MatrixXd generic_jacobian(const State& s, const std::vector<int>& candidates,
                                   const std::vector<JointVector>& q) const override {
    std::vector<PositionMeasurement> d;
    for (const auto& qk : q) d.push_back({qk, forward_position(s.model, qk)});
    Eigen::VectorXd r;
    Eigen::MatrixXd jac;
    PositionProblem(d).evaluate(s, candidates, r, &jac);
    return jac;
  }

 private:
  const std::vector<PositionMeasurement>& data_;
};

class DistanceProblem final : public Problem {
 public:
  // `fixed_count` fixed base points; their coordinates are State::extra.
  DistanceProblem(const std::vector<DistanceMeasurement>& d, int fixed_count) : data_(d), fixed_count_(fixed_count) {}
  int dim() const override { return 1; }
  std::size_t count() const override { return data_.size(); }
  std::size_t distinct() const override {
    std::vector<Eigen::Matrix<double, 2 * kJointCount, 1>> pairs;
    for (const auto& d : data_) {
      pairs.emplace_back();
      if (d.fixed_base >= 0) {  // (pose, point k): the point as a joint vector no robot reaches
        pairs.back() << d.q_a_deg, JointVector::Constant(1e9 + d.fixed_base);
        continue;
      }
      const bool swap = std::lexicographical_compare(d.q_b_deg.begin(), d.q_b_deg.end(), d.q_a_deg.begin(), d.q_a_deg.end());
      pairs.back() << (swap ? d.q_b_deg : d.q_a_deg), (swap ? d.q_a_deg : d.q_b_deg);
    }
    return count_distinct(std::move(pairs));
  }
  void evaluate(const State& s, const std::vector<int>& active, Eigen::VectorXd& r,
                Eigen::MatrixXd* jac) const override {
    const MdhModel& m = s.model;
    const auto n = static_cast<Eigen::Index>(data_.size());
    r.resize(n);
    if (jac) jac->resize(n, static_cast<Eigen::Index>(active.size()));
    for (Eigen::Index i = 0; i < n; ++i) {
      const auto& d = data_[static_cast<std::size_t>(i)];
      const bool fixed = d.fixed_base >= 0;
      const Eigen::Vector3d pa = forward_position(m, d.q_a_deg);
      const Eigen::Vector3d pb = fixed ? Eigen::Vector3d(s.extra.segment<3>(3 * d.fixed_base)) : forward_position(m, d.q_b_deg);
      const Eigen::Vector3d diff = pa - pb;
      const double len = diff.norm();
      r[i] = d.distance_mm - len;
      if (jac) {
        // d|Pa − Pb| = u · (dPa − dPb); a fixed point's own coordinates: dPb = dB, column −uᵀ.
        const Eigen::Vector3d u = len > 0 ? Eigen::Vector3d(diff / len) : Eigen::Vector3d::Zero();
        const IdentificationJacobian ja = identification_jacobian(m, d.q_a_deg);
        const IdentificationJacobian jb = fixed ? IdentificationJacobian::Zero().eval() : identification_jacobian(m, d.q_b_deg);
        for (std::size_t c = 0; c < active.size(); ++c) {
          const int k = active[c];
          double v;
          if (k < param::kCount) {
            v = u.dot(ja.col(k) - jb.col(k));
          } else {
            const int e = k - param::kCount;
            v = fixed && e / 3 == d.fixed_base ? -u[e % 3] : 0.0;
          }
          (*jac)(i, static_cast<Eigen::Index>(c)) = v;
        }
      }
    }
  }
  // Pairs of consecutive configurations if the data have robot-position pairs, and every
  // configuration to every fixed point.
  Eigen::MatrixXd generic_jacobian(const State& s, const std::vector<int>& candidates,
                                   const std::vector<JointVector>& q) const override {
    const bool pairs = std::any_of(data_.begin(), data_.end(), [](const DistanceMeasurement& d) { return d.fixed_base < 0; });
    std::vector<DistanceMeasurement> d;
    for (std::size_t k = 0; k + 1 < q.size(); ++k) {
      if (pairs) d.push_back({q[k], q[k + 1], (forward_position(s.model, q[k]) - forward_position(s.model, q[k + 1])).norm()});
      for (int b = 0; b < fixed_count_; ++b)
        d.push_back({q[k], JointVector::Zero(), (forward_position(s.model, q[k]) - s.extra.segment<3>(3 * b)).norm(), b});
    }
    Eigen::VectorXd r;
    Eigen::MatrixXd jac;
    DistanceProblem(d, fixed_count_).evaluate(s, candidates, r, &jac);
    return jac;
  }

 private:
  const std::vector<DistanceMeasurement>& data_;
  int fixed_count_ = 0;
};

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  double m = *mid;
  if (v.size() % 2 == 0) m = 0.5 * (m + *std::max_element(v.begin(), mid));
  return m;
}

// Per-measurement residual size: |v| (distance) or the 3-D norm (position).
std::vector<double> residual_sizes(const Eigen::VectorXd& r, int dim) {
  std::vector<double> s(static_cast<std::size_t>(r.size() / dim));
  for (std::size_t i = 0; i < s.size(); ++i) s[i] = r.segment(static_cast<Eigen::Index>(i) * dim, dim).norm();
  return s;
}

ResidualSummary summarize(const std::vector<double>& sizes) {
  ResidualSummary s;
  s.count = sizes.size();
  if (sizes.empty()) return s;
  double sq = 0;
  for (double v : sizes) {
    sq += v * v;
    s.mean_abs_mm += v;
    s.max_abs_mm = std::max(s.max_abs_mm, v);
  }
  s.mean_abs_mm /= static_cast<double>(sizes.size());
  s.rms_mm = std::sqrt(sq / static_cast<double>(sizes.size()));
  return s;
}

std::vector<double> igg3_weights(const std::vector<double>& sizes, int dim, const RobustOptions& o) {
  constexpr double kSigmaFloorMm = 1e-6;  // 1 nm: below any tracker's resolution
  double sigma0;
  double scale;  // turns a residual size into u
  if (dim == 1) {
    sigma0 = std::max(1.4826 * median(sizes), kSigmaFloorMm);
    scale = sigma0;
  } else {
    // |r| of a 3-D Gaussian residual with per-axis sigma has median 1.5382 sigma (chi, 3 dof);
    // u = |r| / (sqrt(3) sigma) has RMS 1 like a standardized scalar.
    sigma0 = std::max(median(sizes) / 1.5382, kSigmaFloorMm);
    scale = std::sqrt(3.0) * sigma0;
  }
  std::vector<double> w(sizes.size());
  for (std::size_t i = 0; i < sizes.size(); ++i) w[i] = igg3_weight(sizes[i] / scale, o.k0, o.k1);
  return w;
}

struct Selection {
  std::vector<int> kept;
  std::vector<RemovedParameter> removed;
};

// Greedy identifiability in candidate order on the column-normalized Jacobian: a candidate whose
// normalized column keeps less than `tol` of its norm after projection on the kept ones is a
// combination of them (reported with its largest coefficients).
Selection select_parameters(const Eigen::MatrixXd& jac, const std::vector<int>& candidates, double tol) {
  Selection s;
  const Eigen::Index rows = jac.rows();
  Eigen::MatrixXd basis(rows, 0);
  Eigen::MatrixXd kept_cols(rows, 0);
  double typical = 0;
  for (Eigen::Index c = 0; c < jac.cols(); ++c) typical = std::max(typical, jac.col(c).norm());
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    const Eigen::VectorXd col = jac.col(static_cast<Eigen::Index>(c));
    const double norm = col.norm();
    // Angular columns are mm/rad (~1e3), lengths mm/mm (~1): "no effect" relative to 1 mm/unit.
    if (norm < 1e-9 * std::max(1.0, typical / 1e3)) {
      s.removed.push_back({candidates[c], candidate_name(candidates[c]),
                           "no effect on the measured quantity at these configurations"});
      continue;
    }
    const Eigen::VectorXd u = col / norm;
    Eigen::VectorXd w = u;
    if (basis.cols() > 0) {
      w -= basis * (basis.transpose() * w);
      w -= basis * (basis.transpose() * w);  // second pass: re-orthogonalization
    }
    const double left = w.norm();
    if (left < tol) {
      std::ostringstream why;
      why << "redundant: its column is a combination of ";
      const Eigen::VectorXd coef = kept_cols.colPivHouseholderQr().solve(u);
      std::vector<std::pair<double, int>> order;
      for (Eigen::Index k = 0; k < coef.size(); ++k) order.emplace_back(-std::abs(coef[k]), static_cast<int>(k));
      std::sort(order.begin(), order.end());
      for (std::size_t k = 0; k < std::min<std::size_t>(3, order.size()); ++k)
        why << (k ? ", " : "") << candidate_name(s.kept[static_cast<std::size_t>(order[k].second)]);
      why << " (residual " << left << " of its norm)";
      s.removed.push_back({candidates[c], candidate_name(candidates[c]), why.str()});
      continue;
    }
    basis.conservativeResize(rows, basis.cols() + 1);
    basis.col(basis.cols() - 1) = w / left;
    kept_cols.conservativeResize(rows, kept_cols.cols() + 1);
    kept_cols.col(kept_cols.cols() - 1) = u;
    s.kept.push_back(candidates[c]);
  }
  return s;
}

double weighted_cost(const Eigen::VectorXd& r, const std::vector<double>& w, int dim) {
  double c = 0;
  for (std::size_t i = 0; i < w.size(); ++i)
    c += w[i] * r.segment(static_cast<Eigen::Index>(i) * dim, dim).squaredNorm();
  return c;
}

// The state moved by `delta` (one entry per active candidate).
State apply_step(const State& s, const std::vector<int>& active, const Eigen::VectorXd& delta) {
  ParameterVector full = ParameterVector::Zero();
  State t{s.model, s.extra};
  for (std::size_t c = 0; c < active.size(); ++c) {
    const double v = delta[static_cast<Eigen::Index>(c)];
    if (active[c] < param::kCount) full[active[c]] = v;
    else t.extra[active[c] - param::kCount] += v;
  }
  t.model = apply_parameter_increment(s.model, full);
  return t;
}

// Value of parameter `index` in report units (deg / mm) relative to `reference` (for base
// rotation: the rotation vector of R · R_ref^T in deg; base/tool translations: the difference).
double report_value(const MdhModel& m, const MdhModel& reference, int index) {
  if (index < param::kBaseTranslation) {
    const MdhLink& l = m.link(index / param::kPerLink);
    switch (index % param::kPerLink) {
      case param::kAlpha: return l.alpha_deg;
      case param::kA: return l.a_mm;
      case param::kTheta0: return l.theta0_deg;
      case param::kD: return l.d_mm;
      default: return l.beta_deg;
    }
  }
  if (index < param::kBaseRotation)
    return m.base().translation()[index - param::kBaseTranslation] -
           reference.base().translation()[index - param::kBaseTranslation];
  if (index < param::kToolTranslation)
    return rotation_log(m.base().linear() * reference.base().linear().transpose())[index - param::kBaseRotation] / kDeg;
  return m.tool().translation()[index - param::kToolTranslation] -
         reference.tool().translation()[index - param::kToolTranslation];
}


// How many of `candidates` measurements of this kind identify at all on this robot: the
// redundancy selection on a generic, well-spread set (joints on a Kronecker sequence over the
// limits; positions, or distances between consecutive poses and to every fixed point). Data with
// no more equations than that cannot identify the model, however they are placed.
std::size_t generically_identifiable(const Problem& problem, const State& s, const std::vector<int>& candidates,
                                     double tol) {
  constexpr int kPoses = 64;
  const MdhModel& m = s.model;
  const JointVector lo = m.q_min_deg(), hi = m.q_max_deg();
  const double step[kJointCount] = {0.6180339887, 0.4142135624, 0.7320508076, 0.2360679775, 0.6457513111, 0.1622776602};
  std::vector<JointVector> q(kPoses + 1);
  for (int k = 0; k <= kPoses; ++k)
    for (int j = 0; j < kJointCount; ++j) {
      const double u = std::fmod(0.5 + (k + 1) * step[j], 1.0);
      q[static_cast<std::size_t>(k)][j] = lo[j] + (0.05 + 0.9 * u) * (hi[j] - lo[j]);
    }
  if (problem.dim() == 3) q.pop_back();  // 64 positions, as 64 distances between 65 poses
  return select_parameters(problem.generic_jacobian(s, candidates, q), candidates, tol).kept.size();
}

CalibrationResult solve(const Problem& problem, const State& start, std::vector<int> candidates,
                        const CalibrationOptions& o) {
  o.validate();
  const MdhModel& initial = start.model;
  CalibrationResult out;
  out.model = initial;
  const int dim = problem.dim();
  const std::size_t n = problem.count();
  // Too few poses: fail here, naming the count needed, rather than fit the few parameters these
  // data happen to move and claim convergence.
  const std::size_t identifiable = generically_identifiable(problem, start, candidates, o.redundancy_tolerance);
  const std::size_t needed = identifiable / static_cast<std::size_t>(dim) + 1;  // more equations than unknowns
  const std::size_t distinct = problem.distinct();
  if (distinct < needed) {
    const std::string kind = dim == 3 ? "position" : "distance";
    const std::string repeats =
        distinct < n ? " at " + std::to_string(distinct) + " distinct " + (dim == 3 ? "pose(s)" : "pose pair(s)") +
                           " (the others repeat one)"
                     : std::string();
    throw InputError("calibration: " + std::to_string(n) + " measured " + kind + "(s)" + repeats + " give " +
                     std::to_string(distinct * static_cast<std::size_t>(dim)) + " equation(s), but " + kind +
                     " measurements identify " + std::to_string(identifiable) + " parameters of robot '" +
                     initial.name() + "' (of " + std::to_string(candidates.size()) + " candidates); need at least " +
                     std::to_string(needed) + " measured " + kind +
                     "s at distinct poses (more equations than parameters), in practice several times as many, "
                     "spread over the workspace");
  }

  Eigen::VectorXd r;
  Eigen::MatrixXd jac;
  problem.evaluate(start, candidates, r, &jac);
  if (!r.allFinite() || !jac.allFinite()) throw ArgumentError("calibration: non-finite residual or Jacobian at the initial model");
  out.before = summarize(residual_sizes(r, dim));

  Selection sel = select_parameters(jac, candidates, o.redundancy_tolerance);
  // Weakly identifiable directions: while the column-normalized Jacobian of the kept parameters is
  // worse conditioned than allowed, drop the parameter that dominates its weakest direction (the
  // right singular vector of the smallest singular value). Noise would move such a parameter far
  // with no benefit inside the measured region and wild values outside it.
  while (sel.kept.size() > 1) {
    Eigen::MatrixXd kept(jac.rows(), static_cast<Eigen::Index>(sel.kept.size()));
    for (std::size_t c = 0; c < sel.kept.size(); ++c) {
      const auto pos = std::find(candidates.begin(), candidates.end(), sel.kept[c]) - candidates.begin();
      kept.col(static_cast<Eigen::Index>(c)) = jac.col(pos).normalized();
    }
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(kept, Eigen::ComputeThinV);
    const Eigen::VectorXd sv = svd.singularValues();
    const double cond = sv[sv.size() - 1] > 0 ? sv[0] / sv[sv.size() - 1] : std::numeric_limits<double>::infinity();
    if (cond <= o.max_condition_number) break;
    Eigen::Index worst = 0;
    svd.matrixV().col(sv.size() - 1).cwiseAbs().maxCoeff(&worst);
    std::ostringstream why;
    why << "weakly identifiable: dominates the weakest direction of the scaled Jacobian (condition number "
        << cond << " > " << o.max_condition_number << ")";
    sel.removed.push_back({sel.kept[static_cast<std::size_t>(worst)], candidate_name(sel.kept[static_cast<std::size_t>(worst)]),
                           why.str()});
    sel.kept.erase(sel.kept.begin() + worst);
  }
  out.removed = sel.removed;
  const std::vector<int>& active = sel.kept;
  const auto p = static_cast<Eigen::Index>(active.size());
  if (static_cast<std::size_t>(p) >= n * static_cast<std::size_t>(dim))
    throw ArgumentError("calibration: " + std::to_string(p) + " identifiable parameters but only " +
                        std::to_string(n * static_cast<std::size_t>(dim)) + " equations; measure more points");

  State state = start;
  std::vector<double> w(n, 1.0);
  problem.evaluate(state, active, r, &jac);
  // Column scaling, fixed at the start: every parameter moves in units of its column norm.
  Eigen::VectorXd scale(p);
  for (Eigen::Index c = 0; c < p; ++c) scale[c] = jac.col(c).norm();
  double cost = weighted_cost(r, w, dim);
  double lambda = 1e-6;
  const int rounds = o.robust.enabled ? o.robust.max_rounds : 1;
  bool converged_lm = false;
  // IGG3 re-estimates sigma0 every round, so the weights can keep moving (points near k0/k1 flip,
  // or the rejection creeps as the fit tightens). Such a solution is the last round's, not a fixed
  // point, and is reported as not converged.
  bool weights_settled = !o.robust.enabled;
  for (int round = 0; round < rounds; ++round) {
    ++out.rounds;
    converged_lm = false;
    for (int it = 0; it < o.max_iterations; ++it) {
      ++out.iterations;
      Eigen::MatrixXd js = jac * scale.cwiseInverse().asDiagonal();
      Eigen::MatrixXd a = Eigen::MatrixXd::Zero(p, p);
      Eigen::VectorXd g = Eigen::VectorXd::Zero(p);
      for (std::size_t i = 0; i < n; ++i) {
        if (w[i] == 0) continue;
        const auto rows = js.middleRows(static_cast<Eigen::Index>(i) * dim, dim);
        a.noalias() += w[i] * rows.transpose() * rows;
        g.noalias() += w[i] * rows.transpose() * r.segment(static_cast<Eigen::Index>(i) * dim, dim);
      }
      bool accepted = false;
      double new_cost = cost;
      for (int tries = 0; tries < 20 && !accepted; ++tries) {
        Eigen::MatrixXd damped = a;
        damped.diagonal().array() += lambda * std::max(a.diagonal().maxCoeff(), 1e-300);
        const Eigen::VectorXd step = damped.ldlt().solve(g).cwiseQuotient(scale);
        if (!step.allFinite()) {
          lambda *= 10;
          continue;
        }
        const State trial = apply_step(state, active, step);
        Eigen::VectorXd r_trial;
        problem.evaluate(trial, active, r_trial, nullptr);
        new_cost = weighted_cost(r_trial, w, dim);
        if (new_cost <= cost) {
          state = trial;
          accepted = true;
          lambda = std::max(lambda / 10, 1e-12);
        } else {
          lambda *= 10;
        }
      }
      if (!accepted) {
        converged_lm = true;  // no decrease possible: at a minimum to working precision
        break;
      }
      const double decrease = cost - new_cost;
      cost = new_cost;
      problem.evaluate(state, active, r, &jac);
      if (decrease <= o.cost_tolerance * std::max(cost, 1e-300) || cost < 1e-24) {
        converged_lm = true;
        break;
      }
    }
    if (!o.robust.enabled) break;
    const std::vector<double> nw = igg3_weights(residual_sizes(r, dim), dim, o.robust);
    double change = 0;
    for (std::size_t i = 0; i < n; ++i) change = std::max(change, std::abs(nw[i] - w[i]));
    w = nw;
    cost = weighted_cost(r, w, dim);
    out.weight_change = change;
    if (change < kWeightsSettled) {
      weights_settled = true;
      break;
    }
  }
  out.converged = converged_lm && weights_settled;
  if (!converged_lm) {
    out.message = "LM iteration limit reached";
  } else if (!weights_settled) {
    std::ostringstream m;
    m << "not converged: IGG3 weights still changing after " << out.rounds
      << " weighting rounds (largest weight change in the last round " << out.weight_change << ", settled below "
      << kWeightsSettled << "); the model is the last round's";
    out.message = m.str();
  } else {
    out.message = "converged";
  }
  const MdhModel& model = state.model;
  out.model = model;
  out.weights = w;
  out.rejected = static_cast<std::size_t>(std::count(w.begin(), w.end(), 0.0));
  out.after = summarize(residual_sizes(r, dim));

  // Conditioning and standard errors at the solution (weighted, column-scaled).
  Eigen::MatrixXd js = jac * scale.cwiseInverse().asDiagonal();
  for (std::size_t i = 0; i < n; ++i) js.middleRows(static_cast<Eigen::Index>(i) * dim, dim) *= std::sqrt(w[i]);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(js, Eigen::ComputeThinV);
  const Eigen::VectorXd sv = svd.singularValues();
  out.condition_number = sv[sv.size() - 1] > 0 ? sv[0] / sv[sv.size() - 1] : std::numeric_limits<double>::infinity();
  double used = 0;
  for (double wi : w) used += wi > 0 ? 1.0 : 0.0;
  const double dof = used * dim - static_cast<double>(p);
  const double sigma2 = dof > 0 ? cost / dof : 0.0;
  // Cov(scaled) = sigma² V S⁻² Vᵀ; unscale by the column norms.
  const Eigen::MatrixXd v = svd.matrixV();
  const Eigen::VectorXd inv_s2 = sv.array().square().inverse();
  out.base_points.resize(static_cast<std::size_t>(start.extra.size() / 3));
  for (std::size_t k = 0; k < out.base_points.size(); ++k) {
    out.base_points[k].nominal_mm = start.extra.segment<3>(3 * static_cast<Eigen::Index>(k));
    out.base_points[k].position_mm = state.extra.segment<3>(3 * static_cast<Eigen::Index>(k));
  }
  for (Eigen::Index c = 0; c < p; ++c) {
    const double var_scaled_c = (v.row(c).array().square() * inv_s2.transpose().array()).sum();
    if (active[static_cast<std::size_t>(c)] >= param::kCount) {  // a fixed base point's coordinate (mm)
      const int e = active[static_cast<std::size_t>(c)] - param::kCount;
      BasePointEstimate& b = out.base_points[static_cast<std::size_t>(e / 3)];
      b.identified[e % 3] = true;
      b.standard_error_mm[e % 3] = std::sqrt(sigma2 * var_scaled_c) / scale[c];
      continue;
    }
    ParameterEstimate e;
    e.index = active[static_cast<std::size_t>(c)];
    e.name = parameter_name(e.index);
    const bool angle = parameter_is_angle(e.index);
    e.unit = angle ? "deg" : "mm";
    const bool relative = e.index >= param::kBaseTranslation;
    e.nominal = relative ? 0.0 : report_value(initial, initial, e.index);
    e.increment = report_value(model, initial, e.index) - e.nominal;
    const double var_scaled = (v.row(c).array().square() * inv_s2.transpose().array()).sum();
    e.standard_error = std::sqrt(sigma2 * var_scaled) / scale[c] / (angle ? kDeg : 1.0);
    out.parameters.push_back(e);
  }
  return out;
}

}  // namespace

IkResult compensated_joints(const MdhModel& nominal, const MdhModel& identified, const Eigen::Isometry3d& target,
                            const JointVector& seed_deg, int iterations) {
  Eigen::Isometry3d command = target;
  IkResult r = inverse_kinematics(nominal, command, seed_deg);
  for (int it = 0; it < iterations && r.ok(); ++it) {
    const Eigen::Vector3d gap = forward_position(identified, r.q_deg) - target.translation();
    if (gap.norm() < 1e-7) break;
    command.translation() -= gap;
    r = inverse_kinematics(nominal, command, r.q_deg);
  }
  if (r.ok()) {
    r.position_residual_mm = (forward_position(identified, r.q_deg) - target.translation()).norm();
    if (r.position_residual_mm > 1e-4) r.status = IkStatus::max_iterations;
  }
  return r;
}

double igg3_weight(double u, double k0, double k1) {
  if (u <= k0) return 1.0;
  if (u > k1) return 0.0;
  const double t = (k1 - u) / (k1 - k0);
  return (k0 / u) * t * t;
}

void CalibrationOptions::validate() const {
  if (!(redundancy_tolerance > 0 && redundancy_tolerance < 1))
    throw ArgumentError("CalibrationOptions::redundancy_tolerance = " + std::to_string(redundancy_tolerance) +
                        ", expected in (0, 1)");
  if (!(max_condition_number > 1))
    throw ArgumentError("CalibrationOptions::max_condition_number = " + std::to_string(max_condition_number) +
                        ", expected > 1");
  if (max_iterations < 1) throw ArgumentError("CalibrationOptions::max_iterations must be >= 1");
  if (!(cost_tolerance >= 0)) throw ArgumentError("CalibrationOptions::cost_tolerance must be >= 0");
  if (robust.enabled) {
    if (!(robust.k0 > 0 && robust.k1 > robust.k0))
      throw ArgumentError("CalibrationOptions::robust: need 0 < k0 < k1, got k0 = " + std::to_string(robust.k0) +
                          ", k1 = " + std::to_string(robust.k1));
    if (robust.max_rounds < 1) throw ArgumentError("CalibrationOptions::robust.max_rounds must be >= 1");
  }
  for (int c : candidates)
    if (c < 0 || c >= param::kCount)
      throw ArgumentError("CalibrationOptions::candidates: index " + std::to_string(c) + " outside [0, " +
                          std::to_string(param::kCount) + ")");
}

std::vector<int> default_candidates(const MdhModel& model, bool with_base) {
  std::vector<int> c;
  if (with_base)
    for (int k = 0; k < 6; ++k) c.push_back(param::kBaseTranslation + k);
  for (int k = 0; k < 3; ++k) c.push_back(param::kToolTranslation + k);
  for (int i = 0; i < kJointCount; ++i) {
    c.push_back(param::link_index(i, param::kAlpha));
    c.push_back(param::link_index(i, param::kA));
    c.push_back(param::link_index(i, param::kTheta0));
    c.push_back(param::link_index(i, param::kD));
    if (i > 0 && std::abs(model.link(i).alpha_deg) < 1e-6) c.push_back(param::link_index(i, param::kBeta));
  }
  return c;
}

CalibrationResult register_tracker(const MdhModel& model, const std::vector<PositionMeasurement>& data,
                                   const CalibrationOptions& options) {
  if (data.size() < 3)
    throw InputError("register_tracker: " + std::to_string(data.size()) +
                     " measured positions; need at least 4 (9 parameters: base 6, reflector offset 3)");
  // Closed-form start: the rigid motion taking nominal robot-frame positions onto the measured ones.
  const MdhModel robot_frame = model.with_base(Eigen::Isometry3d::Identity());
  std::vector<Eigen::Vector3d> a(data.size()), b(data.size());
  for (std::size_t i = 0; i < data.size(); ++i) {
    a[i] = forward_position(robot_frame, data[i].q_deg);
    b[i] = data[i].measured_mm;
  }
  const Eigen::Isometry3d base = fit_rigid(a, b);
  const MdhModel start = model.with_base(base);
  std::vector<int> candidates;
  for (int k = 0; k < 6; ++k) candidates.push_back(param::kBaseTranslation + k);
  for (int k = 0; k < 3; ++k) candidates.push_back(param::kToolTranslation + k);
  PositionProblem problem(data);
  CalibrationResult r = solve(problem, State{start, Eigen::VectorXd()}, candidates, options);
  // Report the base relative to the closed-form start? Users want the absolute transform; it is
  // in r.model.base(). The increments listed are relative to the closed-form start.
  return r;
}

CalibrationResult calibrate_positions(const MdhModel& model, const std::vector<PositionMeasurement>& data,
                                      const CalibrationOptions& options) {
  PositionProblem problem(data);
  return solve(problem, State{model, Eigen::VectorXd()}, options.candidates.empty() ? default_candidates(model, true) : options.candidates,
               options);
}

Eigen::MatrixXd distance_identification_jacobian(const MdhModel& model, const std::vector<DistanceMeasurement>& data,
                                                const std::vector<Eigen::Vector3d>& fixed_bases_mm,
                                                const std::vector<int>& candidates) {
  const int fixed_count = static_cast<int>(fixed_bases_mm.size());
  for (int c : candidates)
    if (c < 0 || c >= param::kCount + 3 * fixed_count)
      throw ArgumentError("distance_identification_jacobian: candidate " + std::to_string(c) + " outside [0, " +
                          std::to_string(param::kCount + 3 * fixed_count) + ")");
  for (std::size_t i = 0; i < data.size(); ++i)
    if (data[i].fixed_base >= fixed_count)
      throw InputError("distance_identification_jacobian: measurement " + std::to_string(i) + " names fixed base point " +
                       std::to_string(data[i].fixed_base) + " of " + std::to_string(fixed_count));
  State s{model, Eigen::VectorXd(3 * fixed_count)};
  for (int k = 0; k < fixed_count; ++k) s.extra.segment<3>(3 * k) = fixed_bases_mm[static_cast<std::size_t>(k)];
  Eigen::VectorXd r;
  Eigen::MatrixXd jac;
  DistanceProblem(data, fixed_count).evaluate(s, candidates, r, &jac);
  return jac;
}

CalibrationResult calibrate_distances(const MdhModel& model, const std::vector<DistanceMeasurement>& data,
                                      const CalibrationOptions& options) {
  return calibrate_distances(model, data, std::vector<Eigen::Vector3d>{}, options);
}

CalibrationResult calibrate_distances(const MdhModel& model, const std::vector<DistanceMeasurement>& data,
                                      const std::vector<Eigen::Vector3d>& fixed_bases_nominal_mm,
                                      const CalibrationOptions& options) {
  const int fixed_count = static_cast<int>(fixed_bases_nominal_mm.size());
  for (int k = 0; k < fixed_count; ++k)
    if (!fixed_bases_nominal_mm[static_cast<std::size_t>(k)].allFinite())
      throw InputError("calibrate_distances: fixed base point " + std::to_string(k) + " is not finite");
  for (std::size_t i = 0; i < data.size(); ++i)
    if (data[i].fixed_base >= fixed_count)
      throw InputError("calibrate_distances: measurement " + std::to_string(i) + " names fixed base point " +
                       std::to_string(data[i].fixed_base) + ", but " + std::to_string(fixed_count) +
                       " fixed base point(s) were given");
  std::vector<int> candidates = options.candidates.empty() ? default_candidates(model, false) : options.candidates;
  // The base is invisible to distances: drop it even if asked for, and say so.
  std::vector<int> kept;
  std::vector<RemovedParameter> dropped;
  // Fixed points first: they are what the user asked to identify, so the robot parameters that
  // duplicate them (the robot's placement in the world) are the ones reported redundant.
  for (int e = 0; e < 3 * fixed_count; ++e) kept.push_back(param::kCount + e);
  for (int c : candidates) {
    if (c >= param::kBaseTranslation && c < param::kToolTranslation)
      dropped.push_back({c, parameter_name(c), "base frame: distances are invariant under it"});
    else
      kept.push_back(c);
  }
  State start{model, Eigen::VectorXd(3 * fixed_count)};
  for (int k = 0; k < fixed_count; ++k) start.extra.segment<3>(3 * k) = fixed_bases_nominal_mm[static_cast<std::size_t>(k)];
  DistanceProblem problem(data, fixed_count);
  CalibrationResult r = solve(problem, start, kept, options);
  if (fixed_count == 0) {
    // Gauge: distances fix the model only up to a rigid motion of its world frame. Choose the one
    // that best aligns the identified model's positions with the initial model's at the measured
    // configurations, so the identified model keeps the robot's frame (compensation commands
    // targets in it). With fixed points the frame is the one the points were identified in.
    std::vector<Eigen::Vector3d> ident, init;
    for (const auto& d : data)
      for (const JointVector* q : {&d.q_a_deg, &d.q_b_deg}) {
        ident.push_back(forward_position(r.model, *q));
        init.push_back(forward_position(model, *q));
      }
    r.model = r.model.with_base(fit_rigid(ident, init) * r.model.base());
  }
  r.removed.insert(r.removed.begin(), dropped.begin(), dropped.end());
  return r;
}

std::string CalibrationResult::report() const {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(4);
  s << "identified parameters (" << parameters.size() << "), increment +- 1-sigma standard error:\n";
  for (const auto& p : parameters) {
    s << "  " << p.name;
    for (std::size_t k = p.name.size(); k < 14; ++k) s << ' ';
    s << (p.increment >= 0 ? " +" : " ") << p.increment << " " << p.unit << "  +- " << p.standard_error << " "
      << p.unit;
    if (p.index < param::kBaseTranslation) s << "   (" << p.nominal << " -> " << p.nominal + p.increment << ")";
    s << "\n";
  }
  for (std::size_t k = 0; k < base_points.size(); ++k) {
    const BasePointEstimate& b = base_points[k];
    s << "fixed base point " << k << " (robot frame, mm):";
    for (int c = 0; c < 3; ++c) {
      s << "  " << "xyz"[c] << " " << b.position_mm[c];
      if (b.identified[c]) s << " +- " << b.standard_error_mm[c];
      else s << " (not identified, nominal)";
    }
    s << "   (nominal " << b.nominal_mm.x() << ", " << b.nominal_mm.y() << ", " << b.nominal_mm.z() << ")\n";
  }
  if (!removed.empty()) {
    s << "removed candidates (" << removed.size() << "):\n";
    for (const auto& r : removed) s << "  " << r.name << ": " << r.reason << "\n";
  }
  s.precision(1);
  s << "condition number of the scaled identification Jacobian: " << condition_number << "\n";
  s.precision(4);
  s << "residuals before: rms " << before.rms_mm << " mm, mean " << before.mean_abs_mm << " mm, max "
    << before.max_abs_mm << " mm (" << before.count << " measurements)\n";
  s << "residuals after:  rms " << after.rms_mm << " mm, mean " << after.mean_abs_mm << " mm, max " << after.max_abs_mm
    << " mm; " << rejected << " rejected by IGG3\n";
  s << "status: " << message << " (" << iterations << " LM iterations, " << rounds << " weighting rounds)\n";
  return s.str();
}

}  // namespace errfield::robot
