#include "errfield/readers/orientation_conventions.hpp"

#include <cctype>

#include <Eigen/Geometry>

#include "errfield/error.hpp"

namespace errfield::readers {

namespace {

[[noreturn]] void bad_euler(std::string_view text, std::string_view what, const std::string& why) {
  throw ArgumentError(std::string(what) + ": '" + std::string(text) + "' " + why +
                      "; expected three axis letters and the kind, e.g. xyz-extrinsic (errfield's own: R = "
                      "Rz·Ry·Rx), XYZ-intrinsic, zyx-extrinsic, or scipy's short form (xyz: extrinsic, XYZ: "
                      "intrinsic)");
}

}  // namespace

EulerConvention EulerConvention::parse(std::string_view text, std::string_view what) {
  const std::size_t dash = text.find('-');
  const std::string_view letters = text.substr(0, dash);
  if (letters.size() != 3) bad_euler(text, what, "does not start with three axis letters");
  EulerConvention c;
  int upper = 0;
  for (std::size_t k = 0; k < 3; ++k) {
    const char l = letters[k];
    const char lower = static_cast<char>(std::tolower(static_cast<unsigned char>(l)));
    if (lower != 'x' && lower != 'y' && lower != 'z') bad_euler(text, what, "has an axis other than x, y or z");
    upper += l != lower;
    c.axes[k] = lower - 'x';
  }
  if (c.axes[0] == c.axes[1] || c.axes[1] == c.axes[2])
    bad_euler(text, what, "turns twice in a row about one axis (not an Euler sequence)");
  if (dash == std::string_view::npos) {
    if (upper != 0 && upper != 3)
      bad_euler(text, what, "mixes upper and lower case: say the kind (-extrinsic or -intrinsic)");
    c.intrinsic = upper == 3;
    return c;
  }
  std::string kind(text.substr(dash + 1));
  for (char& ch : kind) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  if (kind == "intrinsic") {
    c.intrinsic = true;
  } else if (kind == "extrinsic") {
    c.intrinsic = false;
  } else {
    bad_euler(text, what, "has kind '" + std::string(text.substr(dash + 1)) + "'");
  }
  return c;
}

std::string EulerConvention::name() const {
  std::string s;
  for (int a : axes) s += static_cast<char>((intrinsic ? 'X' : 'x') + a);
  return s + (intrinsic ? "-intrinsic" : "-extrinsic");
}

bool EulerConvention::tait_bryan() const noexcept {
  return axes[0] != axes[2];
}

Eigen::Matrix3d EulerConvention::rotation(const Eigen::Vector3d& angles_rad) const {
  Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
  for (int k = 0; k < 3; ++k) {
    const Eigen::Matrix3d turn =
        Eigen::AngleAxisd(angles_rad[k], Eigen::Vector3d::Unit(axes[static_cast<std::size_t>(k)])).toRotationMatrix();
    // Intrinsic turns act on the moving frame (multiply on the right), extrinsic on the fixed one.
    r = intrinsic ? Eigen::Matrix3d(r * turn) : Eigen::Matrix3d(turn * r);
  }
  return r;
}

QuaternionOrder parse_quaternion_order(std::string_view text, std::string_view what) {
  if (text == "wxyz") return QuaternionOrder::wxyz;
  if (text == "xyzw") return QuaternionOrder::xyzw;
  throw ArgumentError(std::string(what) + ": '" + std::string(text) +
                      "'; expected wxyz (w first, errfield's mqw,mqx,mqy,mqz) or xyzw (w last, as ROS and scipy)");
}

}  // namespace errfield::readers
