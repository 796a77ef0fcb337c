#include "robot/calibration_identifiability.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include <Eigen/Dense>

namespace errfield::robot::detail {

double arm_reach_mm(const MdhModel& model) {
  double reach = model.tool().translation().norm();
  for (const MdhLink& l : model.links()) reach += std::abs(l.a_mm) + std::abs(l.d_mm);
  return std::max(reach, 1.0);  // a degenerate model still gets a finite scale
}

Eigen::VectorXd physical_units(const std::vector<int>& candidates, double reach_mm) {
  Eigen::VectorXd u(static_cast<Eigen::Index>(candidates.size()));
  for (std::size_t c = 0; c < candidates.size(); ++c)
    u[static_cast<Eigen::Index>(c)] = candidate_is_angle(candidates[c]) ? 1.0 / reach_mm : 1.0;
  return u;
}

double condition_number(const Eigen::MatrixXd& m) {
  if (m.cols() == 0) return 1.0;
  const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(m).singularValues();
  return sv[sv.size() - 1] > 0 ? sv[0] / sv[sv.size() - 1] : std::numeric_limits<double>::infinity();
}

ParameterSelection select_parameters(const Eigen::MatrixXd& jac, const std::vector<int>& candidates, double reach_mm,
                                     double tolerance, double max_condition) {
  ParameterSelection s;
  const Eigen::MatrixXd phys = jac * physical_units(candidates, reach_mm).asDiagonal();
  const Eigen::Index rows = phys.rows();
  double largest = 0;
  for (Eigen::Index c = 0; c < phys.cols(); ++c) largest = std::max(largest, phys.col(c).norm());
  Eigen::MatrixXd basis(rows, 0);      // orthonormal basis of the kept columns
  Eigen::MatrixXd kept_cols(rows, 0);  // the kept physical columns
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    const Eigen::VectorXd col = phys.col(static_cast<Eigen::Index>(c));
    const double norm = col.norm();
    if (!(norm > tolerance * largest)) {
      std::ostringstream why;
      why << "no effect on the measured quantity at these configurations (" << norm / std::max(largest, 1e-300)
          << " of the largest column, in physical units)";
      s.removed.push_back({candidates[c], candidate_name(candidates[c]), why.str()});
      continue;
    }
    Eigen::VectorXd w = col / norm;
    if (basis.cols() > 0) {
      w -= basis * (basis.transpose() * w);
      w -= basis * (basis.transpose() * w);  // second pass: re-orthogonalization
    }
    const double left = w.norm();
    if (left < tolerance) {
      std::ostringstream why;
      why << "redundant: its column is a combination of ";
      const Eigen::VectorXd coef = kept_cols.colPivHouseholderQr().solve(col);
      std::vector<std::pair<double, int>> order;
      for (Eigen::Index k = 0; k < coef.size(); ++k)
        order.emplace_back(-std::abs(coef[k]) * kept_cols.col(k).norm(), static_cast<int>(k));
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
    kept_cols.col(kept_cols.cols() - 1) = col;
    s.kept.push_back(candidates[c]);
  }
  // Weakly identifiable directions: noise would move such a parameter far with no benefit inside
  // the measured region and wild values outside it.
  while (true) {
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(kept_cols, Eigen::ComputeThinV);
    const Eigen::VectorXd sv = svd.singularValues();
    s.condition_number = sv.size() == 0 ? 1.0
                         : sv[sv.size() - 1] > 0 ? sv[0] / sv[sv.size() - 1]
                                                 : std::numeric_limits<double>::infinity();
    if (s.kept.size() <= 1 || s.condition_number <= max_condition) break;
    Eigen::Index worst = 0;
    svd.matrixV().col(sv.size() - 1).cwiseAbs().maxCoeff(&worst);
    std::ostringstream why;
    why << "weakly identifiable: dominates the weakest direction of the physically scaled Jacobian (condition "
           "number "
        << s.condition_number << " > " << max_condition << ")";
    const int index = s.kept[static_cast<std::size_t>(worst)];
    s.removed.push_back({index, candidate_name(index), why.str()});
    s.kept.erase(s.kept.begin() + worst);
    const Eigen::Index cols = kept_cols.cols();
    if (worst + 1 < cols) kept_cols.middleCols(worst, cols - worst - 1) = kept_cols.rightCols(cols - worst - 1).eval();
    kept_cols.conservativeResize(Eigen::NoChange, cols - 1);
  }
  return s;
}

// The Tikhonov weight as a share of (largest singular value / max_condition)²: a direction at the
// cap is fitted to 1 / (1 + 0.1) = 91 % of its least-squares size, one at sqrt(10) × the cap to
// half. Chosen on the study in tests/robot/calibration_distance_geometry_test.cpp (docs/robot.md):
// a share of 1 biased well-determined directions (held-out error +8-15 % on low-noise data), 0.01
// and 0.1 were alike.
constexpr double kRegularizationShare = 0.1;

ParameterSelection select_parameters_regularized(const Eigen::MatrixXd& jac, const std::vector<int>& candidates,
                                                double reach_mm, double tolerance, double max_condition,
                                                double min_participation) {
  ParameterSelection s =
      select_parameters(jac, candidates, reach_mm, tolerance, std::numeric_limits<double>::infinity());
  if (s.kept.empty()) return s;
  std::vector<Eigen::Index> where;  // column of each kept candidate in `jac`
  for (int k : s.kept)
    where.push_back(static_cast<Eigen::Index>(std::find(candidates.begin(), candidates.end(), k) - candidates.begin()));
  const Eigen::MatrixXd phys_all = jac * physical_units(candidates, reach_mm).asDiagonal();
  auto columns = [&] {
    Eigen::MatrixXd m(phys_all.rows(), static_cast<Eigen::Index>(where.size()));
    for (std::size_t c = 0; c < where.size(); ++c) m.col(static_cast<Eigen::Index>(c)) = phys_all.col(where[c]);
    return m;
  };
  const Eigen::VectorXd sv0 = Eigen::JacobiSVD<Eigen::MatrixXd>(columns()).singularValues();
  s.regularization = kRegularizationShare * std::pow(sv0[0] / max_condition, 2);
  while (true) {
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(columns(), Eigen::ComputeThinV);
    const Eigen::VectorXd sv = svd.singularValues();
    const Eigen::ArrayXd filter = sv.array().square() / (sv.array().square() + s.regularization);
    const Eigen::VectorXd participation = (svd.matrixV().array().square().rowwise() * filter.transpose()).rowwise().sum();
    s.condition_number = sv[sv.size() - 1] > 0 ? sv[0] / sv[sv.size() - 1] : std::numeric_limits<double>::infinity();
    Eigen::Index worst = 0;
    const double least = participation.minCoeff(&worst);
    if (least >= min_participation || s.kept.size() <= 1) break;
    std::ostringstream why;
    why << "weakly identifiable: the data determine " << 100 * least
        << " % of it (the rest lies along directions of the physically scaled Jacobian weaker than 1/"
        << max_condition << " of the strongest)";
    const int index = s.kept[static_cast<std::size_t>(worst)];
    s.removed.push_back({index, candidate_name(index), why.str()});
    s.weak.push_back(index);
    s.kept.erase(s.kept.begin() + worst);
    where.erase(where.begin() + worst);
  }
  return s;
}

std::size_t generically_identifiable(const CalibrationProblem& problem, const CalibrationState& s,
                                     const std::vector<int>& candidates, double reach_mm, double tolerance) {
  // Joints on a Kronecker sequence over the limits: positions, or distances between consecutive
  // poses and to every fixed point.
  constexpr int kPoses = 64;
  const MdhModel& m = s.model;
  const JointVector lo = m.q_min_deg(), hi = m.q_max_deg();
  const double step[kJointCount] = {0.6180339887, 0.4142135624, 0.7320508076,
                                    0.2360679775, 0.6457513111, 0.1622776602};
  std::vector<JointVector> q(kPoses + 1);
  for (int k = 0; k <= kPoses; ++k)
    for (int j = 0; j < kJointCount; ++j) {
      const double u = std::fmod(0.5 + (k + 1) * step[j], 1.0);
      q[static_cast<std::size_t>(k)][j] = lo[j] + (0.05 + 0.9 * u) * (hi[j] - lo[j]);
    }
  if (problem.dim() == 3) q.pop_back();  // 64 positions, as 64 distances between 65 poses
  const double no_weak_removal = std::numeric_limits<double>::infinity();
  return select_parameters(problem.generic_jacobian(s, candidates, q), candidates, reach_mm, tolerance,
                           no_weak_removal)
      .kept.size();
}

}  // namespace errfield::robot::detail
