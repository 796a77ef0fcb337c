#pragma once
/// Rigid poses at the robot adapter's interface: position in mm plus a rotation given as three
/// angles in degrees.
///
/// Euler convention (used everywhere errfield reads or writes `rx,ry,rz`): fixed-axis X-Y-Z
/// roll-pitch-yaw, `R = Rz(rz) · Ry(ry) · Rx(rx)` — rotate about the fixed X axis by rx, then about
/// the fixed Y axis by ry, then about the fixed Z axis by rz (equivalently intrinsic Z, Y', X'').
/// This is KDL's `Rotation::RPY(rx, ry, rz)`, and "tool pointing down" is `rx = 180, ry = rz = 0`.
/// Conversions back pick ry in [-90°, 90°]; at ry = ±90° (gimbal lock) rx is set to 0.

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace errfield::robot {

/// A pose in the user's units: position (mm) and fixed-axis XYZ angles (deg), see file comment.
struct PoseXyzRpy {
  double x_mm = 0.0, y_mm = 0.0, z_mm = 0.0;
  double rx_deg = 0.0, ry_deg = 0.0, rz_deg = 0.0;
};

/// Rotation matrix R = Rz(rz) Ry(ry) Rx(rx), angles in degrees.
Eigen::Matrix3d rotation_from_rpy_deg(double rx_deg, double ry_deg, double rz_deg);

/// Inverse of rotation_from_rpy_deg: (rx, ry, rz) in degrees, ry in [-90, 90].
/// Precondition: `r` is a rotation matrix (orthonormal, det +1) to ~1e-9.
Eigen::Vector3d rpy_deg_from_rotation(const Eigen::Matrix3d& r);

/// Homogeneous transform (mm) of a PoseXyzRpy.
Eigen::Isometry3d to_isometry(const PoseXyzRpy& p);

/// PoseXyzRpy of a homogeneous transform (mm).
PoseXyzRpy to_xyz_rpy(const Eigen::Isometry3d& t);

/// Rotation vector (axis · angle, rad) of a rotation matrix, robust near 0 and pi.
Eigen::Vector3d rotation_log(const Eigen::Matrix3d& r);

/// Rotation matrix of a rotation vector (axis · angle, rad) — Rodrigues' formula.
Eigen::Matrix3d rotation_exp(const Eigen::Vector3d& w);

}  // namespace errfield::robot
