#include "errfield/robot/kinematics.hpp"
#include "robot/degrees.hpp"

#include <cmath>
#include <numbers>

#include "errfield/error.hpp"

namespace errfield::robot {

namespace {


// One link step: (R, p) <- (R, p) · [Rc · Rz(theta0 + q), (a, 0, 0) + d · Rc e_z].
// cos/sin(theta0 + q) come from the precomputed cos/sin(theta0) by the addition formulas, so the
// only trig per link is one sincos of q.
inline void step(const MdhLinkConstants& c, double q_rad, Eigen::Matrix3d& r, Eigen::Vector3d& p) {
  const double sq = std::sin(q_rad), cq = std::cos(q_rad);
  const double ct = cq * c.cos_theta0 - sq * c.sin_theta0;
  const double st = sq * c.cos_theta0 + cq * c.sin_theta0;
  const Eigen::Matrix3d rc = r * c.r_const;  // world axes of the frame after Rx(alpha) Ry(beta)
  p += c.a_mm * r.col(0) + c.d_mm * rc.col(2);
  r.col(0) = ct * rc.col(0) + st * rc.col(1);
  r.col(1) = -st * rc.col(0) + ct * rc.col(1);
  r.col(2) = rc.col(2);
}

}  // namespace

EndFrame parse_end_frame(const std::string& text, const std::string& what) {
  if (text == "flange") return EndFrame::flange;
  if (text == "tool") return EndFrame::tool;
  throw ArgumentError(what + ": expected 'flange' or 'tool', got '" + text + "'");
}

Eigen::Isometry3d forward_kinematics(const MdhModel& model, const JointVector& q_deg, EndFrame frame) {
  Eigen::Matrix3d r = model.base().linear();
  Eigen::Vector3d p = model.base().translation();
  for (int i = 0; i < kJointCount; ++i) step(model.constants(i), q_deg[i] * kDeg, r, p);
  Eigen::Isometry3d t;
  t.matrix().row(3) << 0, 0, 0, 1;
  if (frame == EndFrame::tool) {
    t.translation() = p + r * model.tool().translation();
    t.linear() = r * model.tool().linear();
  } else {
    t.translation() = p;
    t.linear() = r;
  }
  return t;
}

Eigen::Vector3d forward_position(const MdhModel& model, const JointVector& q_deg, EndFrame frame) {
  Eigen::Matrix3d r = model.base().linear();
  Eigen::Vector3d p = model.base().translation();
  for (int i = 0; i < kJointCount; ++i) step(model.constants(i), q_deg[i] * kDeg, r, p);
  return frame == EndFrame::tool ? Eigen::Vector3d(p + r * model.tool().translation()) : p;
}

void forward_kinematics_all(const MdhModel& model, const JointVector& q_deg, KinematicFrames& out) {
  Eigen::Matrix3d r = model.base().linear();
  Eigen::Vector3d p = model.base().translation();
  out.frames[0] = model.base();
  for (int i = 0; i < kJointCount; ++i) {
    step(model.constants(i), q_deg[i] * kDeg, r, p);
    Eigen::Isometry3d& f = out.frames[static_cast<std::size_t>(i + 1)];
    f.matrix().row(3) << 0, 0, 0, 1;
    f.linear() = r;
    f.translation() = p;
  }
  Eigen::Isometry3d& t = out.frames[kJointCount + 1];
  t.matrix().row(3) << 0, 0, 0, 1;
  t.linear() = r * model.tool().linear();
  t.translation() = p + r * model.tool().translation();
}

Eigen::Matrix<double, 6, kJointCount> geometric_jacobian(const KinematicFrames& frames, EndFrame frame) {
  const Eigen::Vector3d pe =
      frame == EndFrame::tool ? frames.tool().translation() : frames.flange().translation();
  Eigen::Matrix<double, 6, kJointCount> j;
  for (int i = 0; i < kJointCount; ++i) {
    // Joint i+1 turns about z of link frame i+1 through that frame's origin.
    const Eigen::Isometry3d& f = frames.frames[static_cast<std::size_t>(i + 1)];
    const Eigen::Vector3d z = f.linear().col(2);
    j.template block<3, 1>(0, i) = z.cross(pe - f.translation());
    j.template block<3, 1>(3, i) = z;
  }
  return j;
}

Eigen::Matrix<double, 6, kJointCount> geometric_jacobian(const MdhModel& model, const JointVector& q_deg,
                                                         EndFrame frame) {
  KinematicFrames frames;
  forward_kinematics_all(model, q_deg, frames);
  return geometric_jacobian(frames, frame);
}

// ---- identification ----------------------------------------------------------------------------

std::string parameter_name(int index) {
  static const char* const link_names[] = {"alpha", "a", "theta0", "d", "beta"};
  static const char* const frame_names[] = {"x", "y", "z", "rx", "ry", "rz"};
  if (index < 0 || index >= param::kCount)
    throw ArgumentError("parameter index " + std::to_string(index) + " outside [0, " +
                        std::to_string(param::kCount) + ")");
  if (index < param::kBaseTranslation)
    return "link" + std::to_string(index / param::kPerLink + 1) + "." + link_names[index % param::kPerLink];
  if (index < param::kToolTranslation) return std::string("base.") + frame_names[index - param::kBaseTranslation];
  return std::string("tool.") + frame_names[index - param::kToolTranslation];
}

bool parameter_is_angle(int index) {
  if (index < param::kBaseTranslation) {
    const int k = index % param::kPerLink;
    return k == param::kAlpha || k == param::kTheta0 || k == param::kBeta;
  }
  return index >= param::kBaseRotation && index < param::kToolTranslation;
}

const char* parameter_unit(int index) { return parameter_is_angle(index) ? "rad" : "mm"; }

IdentificationJacobian identification_jacobian(const MdhModel& model, const JointVector& q_deg) {
  KinematicFrames f;
  forward_kinematics_all(model, q_deg, f);
  const Eigen::Vector3d pt = f.tool().translation();
  IdentificationJacobian j;
  for (int i = 0; i < kJointCount; ++i) {
    const Eigen::Isometry3d& prev = f.frames[static_cast<std::size_t>(i)];
    const Eigen::Isometry3d& cur = f.frames[static_cast<std::size_t>(i + 1)];
    const MdhLink& l = model.link(i);
    const Eigen::Vector3d x_prev = prev.linear().col(0);
    // Frame after Rx(alpha) Dx(a): its y axis carries beta, its origin is o_{i-1} + a x_{i-1}.
    const Eigen::Vector3d y_mid =
        prev.linear() * Eigen::AngleAxisd(l.alpha_deg * kDeg, Eigen::Vector3d::UnitX()).toRotationMatrix().col(1);
    const Eigen::Vector3d o_mid = prev.translation() + l.a_mm * x_prev;
    const Eigen::Vector3d z_cur = cur.linear().col(2);
    const int base = param::kPerLink * i;
    j.col(base + param::kAlpha) = x_prev.cross(pt - prev.translation());
    j.col(base + param::kA) = x_prev;
    j.col(base + param::kTheta0) = z_cur.cross(pt - cur.translation());
    j.col(base + param::kD) = z_cur;
    j.col(base + param::kBeta) = y_mid.cross(pt - o_mid);
  }
  const Eigen::Vector3d ob = f.frames[0].translation();
  for (int k = 0; k < 3; ++k) {
    j.col(param::kBaseTranslation + k) = Eigen::Vector3d::Unit(k);
    j.col(param::kBaseRotation + k) = Eigen::Vector3d::Unit(k).cross(pt - ob);
    j.col(param::kToolTranslation + k) = f.flange().linear().col(k);
  }
  return j;
}

MdhModel apply_parameter_increment(const MdhModel& model, const ParameterVector& delta) {
  std::array<MdhLink, kJointCount> links = model.links();
  for (int i = 0; i < kJointCount; ++i) {
    MdhLink& l = links[static_cast<std::size_t>(i)];
    const int b = param::kPerLink * i;
    l.alpha_deg += delta[b + param::kAlpha] / kDeg;
    l.a_mm += delta[b + param::kA];
    l.theta0_deg += delta[b + param::kTheta0] / kDeg;
    l.d_mm += delta[b + param::kD];
    l.beta_deg += delta[b + param::kBeta] / kDeg;
  }
  Eigen::Isometry3d base = model.base();
  const Eigen::Vector3d w = delta.segment<3>(param::kBaseRotation);
  const Eigen::Matrix3d rw = w.norm() > 0 ? Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix()
                                          : Eigen::Matrix3d::Identity();
  // Rotation about the base origin, then translation: world point P = R_B p + o_B becomes
  // Rw R_B p + o_B + dt, whose derivative is w x (P - o_B) + dt (the Jacobian's columns).
  base.linear() = rw * base.linear();
  base.translation() += delta.segment<3>(param::kBaseTranslation);
  Eigen::Isometry3d tool = model.tool();
  tool.translation() += delta.segment<3>(param::kToolTranslation);
  return MdhModel(model.name(), links, base, tool);
}

}  // namespace errfield::robot
