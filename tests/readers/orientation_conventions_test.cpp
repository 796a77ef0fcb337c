// Euler conventions against independent ground truth: errfield's own fixed-axis XYZ
// (robot/pose.hpp), the textbook matrix of intrinsic X-Y-Z angles written out element by element,
// and the identity "intrinsic abc = extrinsic cba with the angles reversed".

#include "errfield/readers/orientation_conventions.hpp"

#include <numbers>
#include <random>

#include <gtest/gtest.h>

#include "errfield/error.hpp"
#include "errfield/robot/pose.hpp"

namespace errfield::readers {
namespace orientation_conventions_test {

constexpr double kRad = std::numbers::pi / 180.0;

Eigen::Vector3d random_angles_deg(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-179.0, 179.0), v(-89.0, 89.0);
  return {u(rng), v(rng), u(rng)};
}

TEST(EulerConvention, ExtrinsicXyzIsErrfieldsFixedAxisXyz) {
  const EulerConvention c = EulerConvention::parse("xyz-extrinsic");
  std::mt19937_64 rng(1);
  for (int k = 0; k < 100; ++k) {
    const Eigen::Vector3d a = random_angles_deg(rng);
    const Eigen::Matrix3d want = robot::rotation_from_rpy_deg(a.x(), a.y(), a.z());
    EXPECT_LT((c.rotation(a * kRad) - want).cwiseAbs().maxCoeff(), 1e-14) << a.transpose();
  }
}

// R = Rx(a) Ry(b) Rz(c) multiplied out by hand (e.g. Craig, appendix B, X-Y-Z Euler angles).
Eigen::Matrix3d intrinsic_xyz_by_hand(double a, double b, double c) {
  const double ca = std::cos(a), sa = std::sin(a), cb = std::cos(b), sb = std::sin(b), cc = std::cos(c), sc = std::sin(c);
  Eigen::Matrix3d r;
  r << cb * cc, -cb * sc, sb,                                 //
      sa * sb * cc + ca * sc, -sa * sb * sc + ca * cc, -sa * cb,  //
      -ca * sb * cc + sa * sc, ca * sb * sc + sa * cc, ca * cb;
  return r;
}

TEST(EulerConvention, IntrinsicXyzMatchesTheMatrixWrittenOut) {
  for (const char* name : {"XYZ-intrinsic", "XYZ", "xyz-intrinsic"}) {
    const EulerConvention c = EulerConvention::parse(name);
    EXPECT_TRUE(c.intrinsic) << name;
    std::mt19937_64 rng(2);
    for (int k = 0; k < 100; ++k) {
      const Eigen::Vector3d a = random_angles_deg(rng) * kRad;
      EXPECT_LT((c.rotation(a) - intrinsic_xyz_by_hand(a.x(), a.y(), a.z())).cwiseAbs().maxCoeff(), 1e-14) << name;
    }
  }
}

TEST(EulerConvention, IntrinsicIsExtrinsicReversed) {
  std::mt19937_64 rng(3);
  for (const auto& [intrinsic, extrinsic] :
       std::vector<std::pair<const char*, const char*>>{{"ZYX", "xyz"}, {"ZXZ", "zxz"}, {"YZX", "xzy"}}) {
    const EulerConvention i = EulerConvention::parse(intrinsic), e = EulerConvention::parse(extrinsic);
    for (int k = 0; k < 50; ++k) {
      const Eigen::Vector3d a = random_angles_deg(rng) * kRad;
      EXPECT_LT((i.rotation(a) - e.rotation(a.reverse())).cwiseAbs().maxCoeff(), 1e-14) << intrinsic;
    }
  }
}

TEST(EulerConvention, NamesAndRefusals) {
  EXPECT_EQ(EulerConvention::parse("zyx").name(), "zyx-extrinsic");
  EXPECT_EQ(EulerConvention::parse("zyx-INTRINSIC").name(), "ZYX-intrinsic");
  EXPECT_TRUE(EulerConvention::parse("xyz").tait_bryan());
  EXPECT_FALSE(EulerConvention::parse("zxz").tait_bryan());
  for (const char* bad : {"xy", "xyw", "xxz", "XyZ", "xyz-sideways", ""})
    EXPECT_THROW(EulerConvention::parse(bad), ArgumentError) << bad;
  EXPECT_EQ(parse_quaternion_order("xyzw"), QuaternionOrder::xyzw);
  EXPECT_THROW(parse_quaternion_order("wzyx"), ArgumentError);
}

}  // namespace orientation_conventions_test
}  // namespace errfield::readers
