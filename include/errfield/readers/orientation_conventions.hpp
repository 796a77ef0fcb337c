#pragma once
/// How a foreign file writes an orientation: Euler angles in some axis sequence, turned about the
/// fixed axes (extrinsic) or the moving ones (intrinsic), or a quaternion with w first or last.
/// Use it when reading measurements exported by tracker software or a robot controller; errfield
/// itself writes orientations as fixed-axis X-Y-Z angles (R = Rz·Ry·Rx, robot/pose.hpp), which is
/// the sequence "xyz-extrinsic" here (and, equally, "ZYX-intrinsic").
///
/// Names follow scipy's `Rotation.from_euler`: a sequence of three axis letters, lower case for
/// extrinsic, upper case for intrinsic ("xyz", "XYZ"); a suffix "-extrinsic" / "-intrinsic" says
/// it in words and then the letters' case does not matter. Proper Euler sequences ("zxz") are
/// accepted as well as Tait–Bryan ones ("zyx").

#include <array>
#include <string>
#include <string_view>

#include <Eigen/Core>

namespace errfield::readers {

struct EulerConvention {
  /// The axes turned about, in the order the angles are given (0 = x, 1 = y, 2 = z).
  std::array<int, 3> axes{0, 1, 2};
  /// True: each turn about the axes as already turned (intrinsic, R = R_a1·R_a2·R_a3); false:
  /// about the fixed axes (extrinsic, R = R_a3·R_a2·R_a1).
  bool intrinsic = false;

  /// Parses "xyz-extrinsic", "XYZ-intrinsic", "zyx", "ZYX", ... Throws ArgumentError naming
  /// `what` (the option) and the text for anything else.
  static EulerConvention parse(std::string_view text, std::string_view what = "--euler");
  /// "xyz-extrinsic" form.
  std::string name() const;
  /// Every axis turned about once (x, y and z in some order): the angles can be named by axis.
  bool tait_bryan() const noexcept;
  /// The rotation of three angles (radians, in the sequence's order).
  Eigen::Matrix3d rotation(const Eigen::Vector3d& angles_rad) const;
};

enum class QuaternionOrder { wxyz, xyzw };

/// Parses "wxyz" or "xyzw"; throws ArgumentError naming `what` otherwise.
QuaternionOrder parse_quaternion_order(std::string_view text, std::string_view what = "--quaternion");

}  // namespace errfield::readers
