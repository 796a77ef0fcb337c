// URDF chain -> modified D-H model, and the FK check between the two; see urdf_import.hpp and
#include "robot/degrees.hpp"
// docs/robot.md ("Importing a URDF").

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

#include "errfield/error.hpp"
#include "errfield/robot/kinematics.hpp"
#include "errfield/robot/pose.hpp"
#include "errfield/robot/random.hpp"
#include "errfield/robot/urdf_import.hpp"

namespace errfield::robot {

namespace {

// Consecutive axes closer to parallel than this (sine of the angle) get the parallel treatment
// (alpha 0 or 180 plus Hayati beta, exact for any tilt): their common normal would lie ~ offset /
// angle away along the axes, and FK through such a distant point loses the 1e-9 mm the import
// promises. URDFs with rounded angles (rpy="1.5708 0 0") tilt nominally parallel axes by ~4e-6 rad.
constexpr double kParallelSine = 1e-3;
// Parallel axes closer than this (mm) are the same line: no common-normal direction exists.
constexpr double kCoincident_mm = 1e-9;

struct AxisLine {
  Eigen::Vector3d p;  ///< a point on the axis (the joint frame origin), mm
  Eigen::Vector3d u;  ///< unit direction (the URDF axis, so q turns right-handed about it)
};

// Unit vector perpendicular to z closest to `x_pref`; when x_pref is (nearly) along z, the x axis
// of the frame whose y axis is the closest to `y_pref` instead.
Eigen::Vector3d in_plane_x(const Eigen::Vector3d& z, const Eigen::Vector3d& x_pref, const Eigen::Vector3d& y_pref) {
  const Eigen::Vector3d x = x_pref - x_pref.dot(z) * z;
  if (x.norm() > 1e-6) return x.normalized();
  const Eigen::Vector3d y = (y_pref - y_pref.dot(z) * z).normalized();
  return y.cross(z).normalized();
}

// The sign of a common-normal direction is free; pick the one that keeps theta0 (the angle from
// the previous x to this one about z) within (-90, 90], so tables like SPEC Table 1 come out with
// theta0 = 0; when the two are perpendicular, theta0 = +90.
Eigen::Vector3d orient(const Eigen::Vector3d& x, const Eigen::Vector3d& x_prev, const Eigen::Vector3d& z) {
  const double c = x.dot(x_prev);
  if (c > 1e-12) return x;
  if (c < -1e-12) return -x;
  return x_prev.cross(x).dot(z) >= 0 ? x : Eigen::Vector3d(-x);
}

Eigen::Matrix3d frame_rotation(const Eigen::Vector3d& x, const Eigen::Vector3d& z) {
  Eigen::Matrix3d r;
  r.col(0) = x;
  r.col(1) = z.cross(x);
  r.col(2) = z;
  return r;
}

// Rounding noise of the construction (1e-17 instead of 0, 90.00000000000001) is removed so the
// JSON reads like a table; the changes are far below the 1e-9 mm the verification allows.
// `per_unit` (1e6, 1e9) is exact in binary, so r is the double nearest to the rounded decimal.
double snap(double v, double per_unit, double tolerance) {
  const double r = std::round(v * per_unit) / per_unit;
  return (std::abs(r - v) <= tolerance ? r : v) + 0.0;
}

double snap_deg(double v) { return snap(v, 1e9, 1e-12); }
double snap_mm(double v) { return snap(v, 1e6, 1e-11); }

// Base and tool are stored as xyz + rpy; snapping that form keeps an identity exactly the identity.
Eigen::Isometry3d snap_pose(const Eigen::Isometry3d& t) {
  PoseXyzRpy p = to_xyz_rpy(t);
  for (double* v : {&p.x_mm, &p.y_mm, &p.z_mm}) *v = snap_mm(*v);
  for (double* v : {&p.rx_deg, &p.ry_deg, &p.rz_deg}) *v = snap_deg(*v);
  return to_isometry(p);
}

}  // namespace

MdhModel mdh_from_urdf_chain(const UrdfChain& chain, const Eigen::Isometry3d& tool) {
  const auto rev = chain.revolute();
  if (static_cast<int>(rev.size()) != kJointCount)
    throw ArgumentError("mdh_from_urdf_chain: the chain has " + std::to_string(rev.size()) + " revolute joints, " +
                        "expected " + std::to_string(kJointCount));
  // Joint axes at q = 0 in the base link frame, and the tip pose there.
  std::array<AxisLine, kJointCount> axis;
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  int k = 0;
  for (const UrdfJoint& j : chain.joints) {
    t = t * j.origin;
    if (j.revolute) axis[static_cast<std::size_t>(k++)] = {t.translation(), (t.linear() * j.axis).normalized()};
  }
  const Eigen::Isometry3d tip = t;

  // Frames 0..6 at q = 0 (origin o, axes x and z) and foot[i], where the line x_{i-1} meets axis i.
  std::array<Eigen::Vector3d, kJointCount + 1> o, x, z, foot;
  std::array<bool, kJointCount + 1> hayati{};
  const auto& a0 = axis[0];
  z[0] = a0.u;
  o[0] = a0.p - a0.p.dot(a0.u) * a0.u;  // the base link origin projected on axis 1
  x[0] = in_plane_x(z[0], Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY());
  foot[1] = o[0];
  for (std::size_t i = 1; i < kJointCount; ++i) {
    const AxisLine& a = axis[i - 1];
    const AxisLine& b = axis[i];
    z[i] = a.u;
    const Eigen::Vector3d c = a.u.cross(b.u);
    const double s = c.norm();
    if (s > kParallelSine) {
      // Skew or intersecting: the unique common normal, between the closest points of the lines.
      const Eigen::Vector3d w = a.p - b.p;
      const double cb = a.u.dot(b.u), d = a.u.dot(w), e = b.u.dot(w), den = c.squaredNorm();
      o[i] = a.p + ((cb * e - d) / den) * a.u;
      foot[i + 1] = b.p + ((e - cb * d) / den) * b.u;
      x[i] = orient(c / s, x[i - 1], z[i]);
    } else {
      // (Nearly) parallel: Craig's choice d_i = 0 (the normal starts where x_{i-1} meets axis i);
      // it ends where axis i+1 crosses the plane normal to axis i there, and Hayati's beta takes
      // any residual tilt of axis i+1 (0 for exactly parallel axes).
      hayati[i + 1] = true;
      o[i] = foot[i];
      foot[i + 1] = b.p + ((o[i] - b.p).dot(a.u) / b.u.dot(a.u)) * b.u;
      Eigen::Vector3d n = foot[i + 1] - o[i];
      n -= n.dot(a.u) * a.u;
      x[i] = n.norm() > kCoincident_mm ? orient(n.normalized(), x[i - 1], z[i])
                                       : Eigen::Vector3d((x[i - 1] - x[i - 1].dot(z[i]) * z[i]).normalized());
    }
  }
  // Flange frame 6: on axis 6 level with the tip origin, x towards the tip's x where possible, so
  // the tool is the identity when the tip link's z is the last axis.
  z[kJointCount] = axis[kJointCount - 1].u;
  o[kJointCount] = foot[kJointCount] + (tip.translation() - foot[kJointCount]).dot(z[kJointCount]) * z[kJointCount];
  x[kJointCount] = in_plane_x(z[kJointCount], tip.linear().col(0), tip.linear().col(1));

  std::array<MdhLink, kJointCount> links;
  for (std::size_t i = 1; i <= kJointCount; ++i) {
    MdhLink& l = links[i - 1];
    const Eigen::Matrix3d r_prev = frame_rotation(x[i - 1], z[i - 1]);
    const Eigen::Vector3d w = r_prev.transpose() * z[i];  // = Rx(alpha) Ry(beta) e_z
    const double alpha = std::atan2(-w.y(), w.z());
    const double beta = hayati[i] ? std::asin(std::clamp(w.x(), -1.0, 1.0)) : 0.0;
    const Eigen::Matrix3d r_mid = r_prev * Eigen::AngleAxisd(alpha, Eigen::Vector3d::UnitX()).toRotationMatrix() *
                                  Eigen::AngleAxisd(beta, Eigen::Vector3d::UnitY()).toRotationMatrix();
    const double theta0 = std::atan2(x[i].dot(r_mid.col(1)), x[i].dot(r_mid.col(0)));
    l.alpha_deg = snap_deg(alpha / kDeg);
    l.beta_deg = snap_deg(beta / kDeg);
    l.theta0_deg = snap_deg(theta0 / kDeg);
    l.a_mm = snap_mm((foot[i] - o[i - 1]).dot(x[i - 1]));
    l.d_mm = snap_mm((o[i] - foot[i]).dot(z[i]));
    l.q_min_deg = rev[i - 1]->lower_deg;
    l.q_max_deg = rev[i - 1]->upper_deg;
  }
  Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
  base.linear() = frame_rotation(x[0], z[0]);
  base.translation() = o[0];
  Eigen::Isometry3d flange = Eigen::Isometry3d::Identity();
  flange.linear() = frame_rotation(x[kJointCount], z[kJointCount]);
  flange.translation() = o[kJointCount];
  return MdhModel(chain.robot_name.empty() ? "robot" : chain.robot_name, links, snap_pose(base),
                  snap_pose(flange.inverse() * tip * tool));
}

UrdfVerification verify_urdf_import(const MdhModel& model, const UrdfChain& chain, const Eigen::Isometry3d& tool,
                                    int samples, std::uint64_t seed) {
  if (samples < 1) throw ArgumentError("verify_urdf_import: samples = " + std::to_string(samples) + ", expected >= 1");
  const auto rev = chain.revolute();
  if (static_cast<int>(rev.size()) != kJointCount)
    throw ArgumentError("verify_urdf_import: the chain has " + std::to_string(rev.size()) + " revolute joints");
  SimulationRng rng(seed);
  UrdfVerification v;
  v.samples = samples;
  for (int s = 0; s < samples; ++s) {
    JointVector q = JointVector::Zero();
    if (s > 0)
      for (int i = 0; i < kJointCount; ++i)
        q[i] = rng.uniform(rev[static_cast<std::size_t>(i)]->lower_deg, rev[static_cast<std::size_t>(i)]->upper_deg);
    const Eigen::Isometry3d tm = forward_kinematics(model, q, EndFrame::tool);
    const Eigen::Isometry3d tu = urdf_chain_pose(chain, q) * tool;
    const double dp = (tm.translation() - tu.translation()).norm();
    // |R1 - R2|_F = 2 sqrt(2) sin(angle / 2): accurate for tiny angles, unlike acos of the trace.
    const double f = (tm.linear() - tu.linear()).norm() / (2.0 * std::numbers::sqrt2);
    const double dr = 2.0 * std::asin(std::min(1.0, f));
    const double inf = std::numeric_limits<double>::infinity();  // NaN must fail, not vanish in max
    v.max_position_mm = std::max(v.max_position_mm, std::isfinite(dp) ? dp : inf);
    v.max_rotation_rad = std::max(v.max_rotation_rad, std::isfinite(dr) ? dr : inf);
  }
  v.passed = v.max_position_mm <= kUrdfPositionTolerance_mm && v.max_rotation_rad <= kUrdfRotationTolerance_rad;
  return v;
}

}  // namespace errfield::robot
