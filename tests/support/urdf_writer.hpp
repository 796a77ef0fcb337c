#pragma once
// A small URDF writer for the URDF import tests (tests/robot/urdf_import_test.cpp and the KDL peer)
// and their own forward kinematics of what they wrote: 4x4 matrices multiplied out from the
// URDF's definitions (rpy = Rz(y) Ry(p) Rx(r), Rodrigues' rotation about the axis), independent of
// urdfdom and of errfield's import code.

#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "errfield/robot/mdh_model.hpp"

namespace errfield::testing {

struct TestUrdfJoint {
  TestUrdfJoint(std::string name_, std::string parent_, std::string child_, std::string type_ = "revolute")
      : name(std::move(name_)), parent(std::move(parent_)), child(std::move(child_)), type(std::move(type_)) {}
  std::string name, parent, child;
  std::string type = "revolute";    ///< revolute, fixed, prismatic, continuous, ...
  Eigen::Vector3d xyz_m = Eigen::Vector3d::Zero();    ///< <origin xyz>, metres
  Eigen::Vector3d rpy_rad = Eigen::Vector3d::Zero();  ///< <origin rpy>, radians
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();    ///< <axis xyz> as written
  double lower_rad = -3.0, upper_rad = 3.0;           ///< <limit> (revolute and prismatic)
  bool write_limit = true;
  std::string extra;  ///< raw XML inside <joint> (e.g. a <mimic>)
};

/// URDF text: a <link> for every name the joints mention, then the joints; numbers in full precision.
std::string urdf_xml(const std::string& robot_name, const std::vector<TestUrdfJoint>& joints);

/// Pose (4x4, mm) of link `tip` in link `base` for the revolute joints' positions `q_deg` in the
/// order they appear on the path; joints must be listed parent before child.
Eigen::Matrix4d test_urdf_fk(const std::vector<TestUrdfJoint>& joints, const std::string& base,
                             const std::string& tip, const robot::JointVector& q_deg);

/// A URDF of an MdhModel: link i's frame is MD-H frame i, joint i's origin is
/// Rx(alpha) Dx(a) Ry(beta) Rz(theta0) Dz(d) (Dz commutes with the joint's Rz), ROS-Industrial's
/// extra frames (base_link -> base, link_6 -> flange -> tool0 with tool0 = flange · tool), limits
/// from the model. The base transform goes between base_link and link_0's joint.
std::vector<TestUrdfJoint> urdf_joints_of(const robot::MdhModel& model);

/// A 6R arm in awkward frames (world -> base_link -> ... -> tool_tip): rpy on every origin, axes
/// along -z, y, x, oblique (1,2,2)/3, -y, z, a fixed joint inside the chain (l2 -> l2b), a fixed
/// sibling frame on base_link, the tip 150 mm beyond joint j6. Revolute joints j1..j6.
std::vector<TestUrdfJoint> general_test_arm();

}  // namespace errfield::testing
