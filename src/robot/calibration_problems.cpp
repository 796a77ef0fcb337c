#include "robot/calibration_problems.hpp"

#include <algorithm>

namespace errfield::robot::detail {

namespace {

template <class Vector>
bool lexicographic_less(const Vector& a, const Vector& b) {
  return std::lexicographical_compare(a.begin(), a.end(), b.begin(), b.end());
}

template <class Vector>
std::size_t count_distinct(std::vector<Vector> v) {
  std::sort(v.begin(), v.end(), lexicographic_less<Vector>);
  return static_cast<std::size_t>(std::unique(v.begin(), v.end()) - v.begin());
}

}  // namespace

std::string candidate_name(int index) {
  if (index < param::kCount) return parameter_name(index);
  const int e = extra_index(index);
  const std::string what = index >= kFlangePointCandidateBase ? "flange point " + std::to_string(e / 3 + 1)
                                                               : "base point " + std::to_string(e / 3);
  return what + " " + "xyz"[e % 3];
}

bool candidate_is_angle(int index) { return index < param::kCount && parameter_is_angle(index); }

std::vector<JointVector> distinct_configurations(const std::vector<JointVector>& q) {
  std::vector<JointVector> sorted = q, out;
  std::sort(sorted.begin(), sorted.end(), lexicographic_less<JointVector>);
  sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
  std::vector<bool> taken(sorted.size(), false);
  for (const auto& v : q) {
    const auto it = std::lower_bound(sorted.begin(), sorted.end(), v, lexicographic_less<JointVector>);
    const auto k = static_cast<std::size_t>(it - sorted.begin());
    if (!taken[k]) {
      taken[k] = true;
      out.push_back(v);
    }
  }
  return out;
}

// ---- positions -----------------------------------------------------------------------------------

std::size_t PositionProblem::distinct() const {
  // A pose read at two points gives two independent readings: the pair (joints, point) counts.
  std::vector<Eigen::Matrix<double, 7, 1>> q;
  for (const auto& d : data_) {
    Eigen::Matrix<double, 7, 1> v;
    v << d.q_deg, static_cast<double>(d.flange_point);
    q.push_back(v);
  }
  return count_distinct(std::move(q));
}

int PositionProblem::flange_point_count() const {
  int k = 0;
  for (const auto& d : data_) k = std::max(k, d.flange_point);
  return k;
}

void PositionProblem::evaluate(const CalibrationState& s, const std::vector<int>& active, Eigen::VectorXd& r,
                               Eigen::MatrixXd* jac) const {
  const MdhModel& m = s.model;
  const auto n = static_cast<Eigen::Index>(data_.size());
  r.resize(3 * n);
  if (jac) jac->resize(3 * n, static_cast<Eigen::Index>(active.size()));
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto& d = data_[static_cast<std::size_t>(i)];
    if (d.flange_point == 0) {
      r.segment<3>(3 * i) = d.measured_mm - forward_position(m, d.q_deg);
      if (jac) {
        const IdentificationJacobian j = identification_jacobian(m, d.q_deg);
        for (std::size_t c = 0; c < active.size(); ++c)
          jac->block<3, 1>(3 * i, static_cast<Eigen::Index>(c)) =
              active[c] < param::kCount ? Eigen::Vector3d(j.col(active[c])) : Eigen::Vector3d::Zero();
      }
      continue;
    }
    // Flange point k: the model with its tool translation at the point gives the same lever for
    // every link parameter; the tool's own parameters belong to point 0 and move nothing here.
    const int e = 3 * (d.flange_point - 1);
    const Eigen::Vector3d at = s.extra.segment<3>(e);
    Eigen::Isometry3d tool = Eigen::Isometry3d::Identity();
    tool.translation() = at;
    const MdhModel mk = m.with_tool(tool);
    const Eigen::Isometry3d flange = forward_kinematics(m, d.q_deg, EndFrame::flange);
    r.segment<3>(3 * i) = d.measured_mm - flange * at;
    if (jac) {
      const IdentificationJacobian j = identification_jacobian(mk, d.q_deg);
      for (std::size_t c = 0; c < active.size(); ++c) {
        const int a = active[c];
        Eigen::Vector3d col = Eigen::Vector3d::Zero();
        if (a < param::kToolTranslation) col = j.col(a);
        else if (a >= kFlangePointCandidateBase && extra_index(a) / 3 == e / 3)
          col = flange.linear().col(extra_index(a) % 3);
        jac->block<3, 1>(3 * i, static_cast<Eigen::Index>(c)) = col;
      }
    }
  }
}

Eigen::MatrixXd PositionProblem::generic_jacobian(const CalibrationState& s, const std::vector<int>& candidates,
                                                  const std::vector<JointVector>& q) const {
  std::vector<PositionMeasurement> d;
  const int points = flange_point_count();
  for (const auto& qk : q)
    for (int k = 0; k <= points; ++k) d.push_back({qk, Eigen::Vector3d::Zero(), k});
  Eigen::VectorXd r;
  Eigen::MatrixXd jac;
  PositionProblem(d).evaluate(s, candidates, r, &jac);
  return jac;
}

// ---- distances -----------------------------------------------------------------------------------

std::size_t DistanceProblem::distinct() const {
  std::vector<Eigen::Matrix<double, 2 * kJointCount, 1>> pairs;
  for (const auto& d : data_) {
    pairs.emplace_back();
    if (d.fixed_base >= 0) {  // (pose, point k): the point as a joint vector no robot reaches
      pairs.back() << d.q_a_deg, JointVector::Constant(1e9 + d.fixed_base);
      continue;
    }
    const bool swap = lexicographic_less(d.q_b_deg, d.q_a_deg);
    pairs.back() << (swap ? d.q_b_deg : d.q_a_deg), (swap ? d.q_a_deg : d.q_b_deg);
  }
  return count_distinct(std::move(pairs));
}

void DistanceProblem::evaluate(const CalibrationState& s, const std::vector<int>& active, Eigen::VectorXd& r,
                               Eigen::MatrixXd* jac) const {
  const MdhModel& m = s.model;
  const auto n = static_cast<Eigen::Index>(data_.size());
  r.resize(n);
  if (jac) jac->resize(n, static_cast<Eigen::Index>(active.size()));
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto& d = data_[static_cast<std::size_t>(i)];
    const bool fixed = d.fixed_base >= 0;
    const Eigen::Vector3d pa = forward_position(m, d.q_a_deg);
    const Eigen::Vector3d pb =
        fixed ? Eigen::Vector3d(s.extra.segment<3>(3 * d.fixed_base)) : forward_position(m, d.q_b_deg);
    const Eigen::Vector3d diff = pa - pb;
    const double len = diff.norm();
    r[i] = d.distance_mm - len;
    if (!jac) continue;
    // d|Pa − Pb| = u · (dPa − dPb); a fixed point's own coordinates: dPb = dB, column −uᵀ.
    const Eigen::Vector3d u = len > 0 ? Eigen::Vector3d(diff / len) : Eigen::Vector3d::Zero();
    const IdentificationJacobian ja = identification_jacobian(m, d.q_a_deg);
    const IdentificationJacobian jb =
        fixed ? IdentificationJacobian::Zero().eval() : identification_jacobian(m, d.q_b_deg);
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

Eigen::MatrixXd DistanceProblem::generic_jacobian(const CalibrationState& s, const std::vector<int>& candidates,
                                                  const std::vector<JointVector>& q) const {
  const bool pairs =
      std::any_of(data_.begin(), data_.end(), [](const DistanceMeasurement& d) { return d.fixed_base < 0; });
  std::vector<DistanceMeasurement> d;
  for (std::size_t k = 0; k + 1 < q.size(); ++k) {
    if (pairs)
      d.push_back({q[k], q[k + 1], (forward_position(s.model, q[k]) - forward_position(s.model, q[k + 1])).norm()});
    for (int b = 0; b < fixed_count_; ++b)
      d.push_back({q[k], JointVector::Zero(), (forward_position(s.model, q[k]) - s.extra.segment<3>(3 * b)).norm(), b});
  }
  Eigen::VectorXd r;
  Eigen::MatrixXd jac;
  DistanceProblem(d, fixed_count_).evaluate(s, candidates, r, &jac);
  return jac;
}

}  // namespace errfield::robot::detail
