#include "errfield/robot/inverse_kinematics.hpp"
#include "robot/degrees.hpp"

#include <array>
#include <cmath>
#include <limits>
#include <numbers>

#include <Eigen/Cholesky>

#include "errfield/error.hpp"

namespace errfield::robot {

namespace {


using Vector6 = Eigen::Matrix<double, 6, 1>;
using Matrix6 = Eigen::Matrix<double, 6, 6>;

struct Residual {
  Vector6 weighted;  // [dp (mm); w * dr (mm)]
  double position_mm;
  double orientation_rad;
  double cost;  // |weighted|^2
};

Residual residual(const KinematicFrames& f, const Eigen::Isometry3d& target, const IkOptions& o) {
  const Eigen::Isometry3d& cur = o.frame == EndFrame::tool ? f.tool() : f.flange();
  Residual r;
  const Eigen::Vector3d dp = target.translation() - cur.translation();
  r.weighted.head<3>() = dp;
  r.position_mm = dp.norm();
  if (o.position_only) {
    r.weighted.tail<3>().setZero();
    r.orientation_rad = 0.0;
  } else {
    const Eigen::Vector3d dr = rotation_log(target.linear() * cur.linear().transpose());
    r.weighted.tail<3>() = o.orientation_weight_mm * dr;
    r.orientation_rad = dr.norm();
  }
  r.cost = r.weighted.squaredNorm();
  return r;
}

// Joint ranges the solver works in: the model's limits, or none (to tell a target that needs a
// joint beyond its limit from one no joint values reach).
struct Limits {
  JointVector lo, hi;
  static Limits of(const MdhModel& m) { return {m.q_min_deg(), m.q_max_deg()}; }
  static Limits none() {
    return {JointVector::Constant(-std::numeric_limits<double>::infinity()),
            JointVector::Constant(std::numeric_limits<double>::infinity())};
  }
};

JointVector clamp(const Limits& l, const JointVector& q) { return q.cwiseMax(l.lo).cwiseMin(l.hi); }

// An upper bound on the distance from the base origin to the end frame over all joint values:
// each link moves the origin by a along one axis and d along a perpendicular one (sqrt(a^2 + d^2));
// with a Hayati beta the axes need not be perpendicular, so |a| + |d| there.
double reach_bound_mm(const MdhModel& m, EndFrame frame) {
  double s = 0.0;
  for (const auto& l : m.links())
    s += l.beta_deg == 0.0 ? std::hypot(l.a_mm, l.d_mm) : std::abs(l.a_mm) + std::abs(l.d_mm);
  if (frame == EndFrame::tool) s += m.tool().translation().norm();
  return s;
}

bool converged(const Residual& r, const IkOptions& o) {
  return r.position_mm <= o.position_tolerance_mm && r.orientation_rad <= o.orientation_tolerance_rad;
}

}  // namespace

void IkOptions::validate() const {
  auto positive = [](double v, const char* name) {
    if (!(v > 0) || !std::isfinite(v))
      throw ArgumentError(std::string("IkOptions::") + name + " = " + std::to_string(v) + ", expected > 0");
  };
  positive(position_tolerance_mm, "position_tolerance_mm");
  positive(orientation_tolerance_rad, "orientation_tolerance_rad");
  positive(orientation_weight_mm, "orientation_weight_mm");
  positive(initial_damping, "initial_damping");
  if (max_iterations < 1)
    throw ArgumentError("IkOptions::max_iterations = " + std::to_string(max_iterations) + ", expected >= 1");
}

const char* to_string(IkStatus s) {
  switch (s) {
    case IkStatus::converged: return "converged";
    case IkStatus::joint_limits: return "joint_limits";
    case IkStatus::unreachable: return "unreachable";
    case IkStatus::max_iterations: return "max_iterations";
  }
  return "?";
}

namespace {

struct Solve {
  JointVector q;
  Residual r;
  int iterations = 0;
  bool stalled = false;
};

// Damped least squares within `lim` (see the header).
Solve solve(const MdhModel& model, const Eigen::Isometry3d& target, const JointVector& seed_deg, const IkOptions& o,
            const Limits& lim) {
  JointVector q = clamp(lim, seed_deg);
  KinematicFrames f;
  forward_kinematics_all(model, q, f);
  Residual r = residual(f, target, o);
  double lambda = -1.0;
  int it = 0;
  bool stalled = false;
  for (; it < o.max_iterations && !converged(r, o); ++it) {
    Eigen::Matrix<double, 6, kJointCount> j = geometric_jacobian(f, o.frame);
    if (o.position_only) j.bottomRows<3>().setZero();
    else j.bottomRows<3>() *= o.orientation_weight_mm;
    const Matrix6 a = j.transpose() * j;
    const Vector6 g = j.transpose() * r.weighted;  // joint-space step direction, per rad
    const double scale = std::max(a.diagonal().mean(), 1e-300);
    if (lambda < 0) lambda = o.initial_damping;
    bool accepted = false;
    for (int tries = 0; tries < 30; ++tries) {
      // Active set: a joint at a limit whose step points outwards is frozen and the step re-solved
      // without it, so the solver converges to the best pose within the limits instead of crawling.
      std::array<bool, kJointCount> frozen{};
      Vector6 dq_rad = Vector6::Zero();
      for (int pass = 0; pass < kJointCount; ++pass) {
        Matrix6 damped = a;
        Vector6 rhs = g;
        for (int i = 0; i < kJointCount; ++i)
          if (frozen[static_cast<std::size_t>(i)]) {
            damped.row(i).setZero();
            damped.col(i).setZero();
            damped(i, i) = 1.0;
            rhs[i] = 0.0;
          } else {
            damped(i, i) += lambda * scale;
          }
        dq_rad = damped.ldlt().solve(rhs);
        bool changed = false;
        for (int i = 0; i < kJointCount; ++i) {
          if (!frozen[static_cast<std::size_t>(i)] && ((q[i] <= lim.lo[i] && dq_rad[i] < 0) ||
                                                       (q[i] >= lim.hi[i] && dq_rad[i] > 0))) {
            frozen[static_cast<std::size_t>(i)] = true;
            changed = true;
          }
        }
        if (!changed) break;
      }
      const JointVector q_new = clamp(lim, q + dq_rad / kDeg);
      if ((q_new - q).cwiseAbs().maxCoeff() < 1e-13) break;  // the limits or the step size stop us
      KinematicFrames f_new;
      forward_kinematics_all(model, q_new, f_new);
      const Residual r_new = residual(f_new, target, o);
      if (r_new.cost < r.cost) {
        q = q_new;
        f = f_new;
        r = r_new;
        lambda = std::max(lambda / 5.0, 1e-15);
        accepted = true;
        break;
      }
      lambda *= 8.0;
    }
    if (!accepted) {
      stalled = true;
      break;
    }
  }
  return {q, r, it, stalled};
}

}  // namespace

namespace {

// Farther from the base than every link (and the tool) laid end to end: no joint values reach it,
// so there is nothing to iterate (a plan of an out-of-reach cube used to run the full solver from
// 24 seeds per point; found by fuzzing).
bool beyond_reach(const MdhModel& model, const Eigen::Isometry3d& target, const IkOptions& o) {
  const double distance = (target.translation() - model.base().translation()).norm();
  return distance > reach_bound_mm(model, o.frame) + o.position_tolerance_mm;
}

IkResult unreachable_at_seed(const MdhModel& model, const Eigen::Isometry3d& target, const JointVector& seed_deg,
                             const IkOptions& o) {
  IkResult out;
  out.q_deg = clamp(Limits::of(model), seed_deg);
  KinematicFrames f;
  forward_kinematics_all(model, out.q_deg, f);
  const Residual r = residual(f, target, o);
  out.position_residual_mm = r.position_mm;
  out.orientation_residual_rad = r.orientation_rad;
  out.iterations = 0;
  out.status = IkStatus::unreachable;
  return out;
}

}  // namespace

IkResult inverse_kinematics(const MdhModel& model, const Eigen::Isometry3d& target, const JointVector& seed_deg,
                            const IkOptions& o) {
  if (beyond_reach(model, target, o)) return unreachable_at_seed(model, target, seed_deg, o);
  const Solve s = solve(model, target, seed_deg, o, Limits::of(model));
  IkResult out;
  out.q_deg = s.q;
  out.position_residual_mm = s.r.position_mm;
  out.orientation_residual_rad = s.r.orientation_rad;
  out.iterations = s.iterations;
  if (converged(s.r, o)) {
    out.status = IkStatus::converged;
  } else if (s.stalled) {
    // Outside the sphere no joint values reach: unreachable. Inside, stalled at a limit: the
    // target is a joint-limit failure only if the same solver without limits, continued from
    // here, reaches it; otherwise it is out of the workspace (or at a singularity) all the same.
    const double distance = (target.translation() - model.base().translation()).norm();
    bool at_limit = false;
    for (int i = 0; i < kJointCount; ++i)
      at_limit = at_limit || s.q[i] <= model.link(i).q_min_deg + 1e-9 || s.q[i] >= model.link(i).q_max_deg - 1e-9;
    out.status = IkStatus::unreachable;
    if (at_limit && distance <= reach_bound_mm(model, o.frame) &&
        converged(solve(model, target, s.q, o, Limits::none()).r, o))
      out.status = IkStatus::joint_limits;
  } else {
    out.status = IkStatus::max_iterations;
  }
  return out;
}

IkResult inverse_kinematics_multistart(const MdhModel& model, const Eigen::Isometry3d& target, const IkOptions& o) {
  // Seeds: the waist turned towards the target, the shoulder/elbow/wrist in a few postures.
  const Eigen::Vector3d p_base = model.base().inverse() * target.translation();
  const double q1 = std::atan2(p_base.y(), p_base.x()) / kDeg;
  if (beyond_reach(model, target, o)) {
    JointVector seed;
    seed << q1, 0.0, 0.0, 0.0, 0.0, 0.0;
    return unreachable_at_seed(model, target, seed, o);
  }
  const double q2s[] = {-90.0, -45.0, 0.0, 30.0};
  const double q3s[] = {0.0, 45.0, -45.0};
  const double q5s[] = {-45.0, 45.0};
  IkResult best;
  best.position_residual_mm = std::numeric_limits<double>::infinity();
  for (double q2 : q2s)
    for (double q3 : q3s)
      for (double q5 : q5s) {
        JointVector seed;
        seed << q1, q2, q3, 0.0, q5, 0.0;
        IkResult r = inverse_kinematics(model, target, seed, o);
        if (r.ok()) return r;
        const double score = r.position_residual_mm + o.orientation_weight_mm * r.orientation_residual_rad;
        const double best_score =
            best.position_residual_mm + o.orientation_weight_mm * best.orientation_residual_rad;
        if (score < best_score) best = r;
      }
  return best;
}

}  // namespace errfield::robot
