#include "errfield/robot/pose.hpp"
#include "robot/degrees.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace errfield::robot {

namespace {
}

Eigen::Matrix3d rotation_from_rpy_deg(double rx_deg, double ry_deg, double rz_deg) {
  return (Eigen::AngleAxisd(rz_deg * kDeg, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(ry_deg * kDeg, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(rx_deg * kDeg, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Vector3d rpy_deg_from_rotation(const Eigen::Matrix3d& r) {
  // R = Rz(c) Ry(b) Rx(a): r20 = -sin b, r21 = cos b sin a, r22 = cos b cos a,
  // r10 = sin c cos b, r00 = cos c cos b.
  const double sb = std::clamp(-r(2, 0), -1.0, 1.0);
  const double cb = std::hypot(r(0, 0), r(1, 0));
  double a, b, c;
  if (cb > 1e-12) {
    b = std::atan2(sb, cb);
    a = std::atan2(r(2, 1), r(2, 2));
    c = std::atan2(r(1, 0), r(0, 0));
  } else {
    // Gimbal lock: only a - c (b = +90°) or a + c (b = -90°) is defined; take a = 0.
    b = sb > 0 ? std::numbers::pi / 2 : -std::numbers::pi / 2;
    a = 0.0;
    c = std::atan2(-r(0, 1), r(1, 1));
  }
  return {a / kDeg, b / kDeg, c / kDeg};
}

Eigen::Isometry3d to_isometry(const PoseXyzRpy& p) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = rotation_from_rpy_deg(p.rx_deg, p.ry_deg, p.rz_deg);
  t.translation() = Eigen::Vector3d(p.x_mm, p.y_mm, p.z_mm);
  return t;
}

PoseXyzRpy to_xyz_rpy(const Eigen::Isometry3d& t) {
  const Eigen::Vector3d e = rpy_deg_from_rotation(t.linear());
  return {t.translation().x(), t.translation().y(), t.translation().z(), e.x(), e.y(), e.z()};
}

Eigen::Vector3d rotation_log(const Eigen::Matrix3d& r) {
  const double cos_angle = std::clamp((r.trace() - 1.0) * 0.5, -1.0, 1.0);
  const Eigen::Vector3d v(r(2, 1) - r(1, 2), r(0, 2) - r(2, 0), r(1, 0) - r(0, 1));
  const double sin_angle_2 = v.norm();  // = 2 sin(angle)
  const double angle = std::atan2(0.5 * sin_angle_2, cos_angle);
  if (angle < 1e-6) return 0.5 * v * (1.0 + angle * angle / 6.0);  // series of angle / (2 sin angle)
  if (std::numbers::pi - angle > 1e-6) return v * (angle / sin_angle_2);
  // Near pi the antisymmetric part vanishes; use the symmetric part
  // (R + R^T)/2 = cos(angle) I + (1 - cos(angle)) u u^T.
  const Eigen::Matrix3d s = (0.5 * (r + r.transpose()) - cos_angle * Eigen::Matrix3d::Identity()) / (1.0 - cos_angle);
  int k = 0;
  s.diagonal().maxCoeff(&k);
  Eigen::Vector3d u = s.col(k) / std::sqrt(std::max(s(k, k), 1e-300));
  u.normalize();
  if (u.dot(v) < 0) u = -u;
  return u * angle;
}

Eigen::Matrix3d rotation_exp(const Eigen::Vector3d& w) {
  const double angle = w.norm();
  if (angle < 1e-12) {
    Eigen::Matrix3d m = Eigen::Matrix3d::Identity();
    m(0, 1) = -w.z(); m(0, 2) = w.y(); m(1, 0) = w.z(); m(1, 2) = -w.x(); m(2, 0) = -w.y(); m(2, 1) = w.x();
    return m;
  }
  return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
}

}  // namespace errfield::robot
