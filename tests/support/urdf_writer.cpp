#include "support/urdf_writer.hpp"

#include <cmath>
#include <cstdio>
#include <numbers>
#include <set>
#include <stdexcept>

namespace errfield::testing {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

std::string vec(const Eigen::Vector3d& v) { return num(v.x()) + " " + num(v.y()) + " " + num(v.z()); }

Eigen::Matrix4d rot_x(double a) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m(1, 1) = std::cos(a), m(1, 2) = -std::sin(a), m(2, 1) = std::sin(a), m(2, 2) = std::cos(a);
  return m;
}
Eigen::Matrix4d rot_y(double a) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m(0, 0) = std::cos(a), m(0, 2) = std::sin(a), m(2, 0) = -std::sin(a), m(2, 2) = std::cos(a);
  return m;
}
Eigen::Matrix4d rot_z(double a) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m(0, 0) = std::cos(a), m(0, 1) = -std::sin(a), m(1, 0) = std::sin(a), m(1, 1) = std::cos(a);
  return m;
}
Eigen::Matrix4d trans(const Eigen::Vector3d& p) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.block<3, 1>(0, 3) = p;
  return m;
}
// Rodrigues: R = I + sin(q) K + (1 - cos(q)) K^2 for the unit axis u.
Eigen::Matrix4d rot_axis(const Eigen::Vector3d& axis, double q) {
  const Eigen::Vector3d u = axis.normalized();
  Eigen::Matrix3d k;
  k << 0, -u.z(), u.y(), u.z(), 0, -u.x(), -u.y(), u.x(), 0;
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.block<3, 3>(0, 0) = Eigen::Matrix3d::Identity() + std::sin(q) * k + (1 - std::cos(q)) * k * k;
  return m;
}

Eigen::Matrix4d origin(const TestUrdfJoint& j) {
  return trans(1000.0 * j.xyz_m) * rot_z(j.rpy_rad.z()) * rot_y(j.rpy_rad.y()) * rot_x(j.rpy_rad.x());
}

// rpy (URDF: R = Rz(y) Ry(p) Rx(r)) and xyz of a 4x4 transform in mm.
void to_origin(const Eigen::Matrix4d& m, TestUrdfJoint& j) {
  const double p = std::atan2(-m(2, 0), std::hypot(m(0, 0), m(1, 0)));
  double r = 0, y = 0;
  if (std::abs(std::cos(p)) > 1e-9) {
    r = std::atan2(m(2, 1), m(2, 2));
    y = std::atan2(m(1, 0), m(0, 0));
  } else {
    y = std::atan2(-m(0, 1), m(1, 1));
  }
  j.rpy_rad = {r, p, y};
  j.xyz_m = m.block<3, 1>(0, 3) / 1000.0;
}

}  // namespace

std::string urdf_xml(const std::string& robot_name, const std::vector<TestUrdfJoint>& joints) {
  std::string s = "<?xml version=\"1.0\"?>\n<robot name=\"" + robot_name + "\">\n";
  std::set<std::string> links;
  for (const auto& j : joints)
    for (const auto& l : {j.parent, j.child})
      if (links.insert(l).second) s += "  <link name=\"" + l + "\"/>\n";
  for (const auto& j : joints) {
    s += "  <joint name=\"" + j.name + "\" type=\"" + j.type + "\">\n";
    s += "    <parent link=\"" + j.parent + "\"/>\n    <child link=\"" + j.child + "\"/>\n";
    s += "    <origin xyz=\"" + vec(j.xyz_m) + "\" rpy=\"" + vec(j.rpy_rad) + "\"/>\n";
    if (j.type != "fixed") s += "    <axis xyz=\"" + vec(j.axis) + "\"/>\n";
    if (j.write_limit && (j.type == "revolute" || j.type == "prismatic"))
      s += "    <limit lower=\"" + num(j.lower_rad) + "\" upper=\"" + num(j.upper_rad) +
           "\" effort=\"100\" velocity=\"2\"/>\n";
    s += j.extra;
    s += "  </joint>\n";
  }
  return s + "</robot>\n";
}

Eigen::Matrix4d test_urdf_fk(const std::vector<TestUrdfJoint>& joints, const std::string& base,
                             const std::string& tip, const robot::JointVector& q_deg) {
  // Path from the tip up to the base, then multiplied base first.
  std::vector<const TestUrdfJoint*> path;
  for (std::string link = tip; link != base;) {
    const TestUrdfJoint* parent = nullptr;
    for (const auto& j : joints)
      if (j.child == link) parent = &j;
    if (!parent) throw std::runtime_error("test_urdf_fk: no path from " + base + " to " + tip);
    path.insert(path.begin(), parent);
    link = parent->parent;
  }
  Eigen::Matrix4d t = Eigen::Matrix4d::Identity();
  int k = 0;
  for (const auto* j : path) {
    t = t * origin(*j);
    if (j->type == "revolute") t = t * rot_axis(j->axis, q_deg[k++] * kDeg);
  }
  return t;
}

std::vector<TestUrdfJoint> urdf_joints_of(const robot::MdhModel& model) {
  std::vector<TestUrdfJoint> js;
  TestUrdfJoint base_frame{"base_link-base", "base_link", "base", "fixed"};
  js.push_back(base_frame);
  Eigen::Matrix4d prev = model.base().matrix();
  std::string parent = "base_link";
  for (int i = 0; i < robot::kJointCount; ++i) {
    const robot::MdhLink& l = model.link(i);
    const Eigen::Matrix4d o = prev * rot_x(l.alpha_deg * kDeg) * trans({l.a_mm, 0, 0}) * rot_y(l.beta_deg * kDeg) *
                              rot_z(l.theta0_deg * kDeg) * trans({0, 0, l.d_mm});
    TestUrdfJoint j{"joint_" + std::to_string(i + 1), parent, "link_" + std::to_string(i + 1)};
    to_origin(o, j);
    j.lower_rad = l.q_min_deg * kDeg;
    j.upper_rad = l.q_max_deg * kDeg;
    js.push_back(j);
    parent = j.child;
    prev = Eigen::Matrix4d::Identity();
  }
  js.push_back({"link_6-flange", "link_6", "flange", "fixed"});
  TestUrdfJoint tool{"flange-tool0", "flange", "tool0", "fixed"};
  to_origin(model.tool().matrix(), tool);
  js.push_back(tool);
  return js;
}

// Joints in arbitrary frames: rpy on every origin, axes along -z, x, y and oblique, a fixed joint
// inside the chain, a fixed sibling frame, the tip beyond the last joint.
std::vector<TestUrdfJoint> general_test_arm() {
  std::vector<TestUrdfJoint> js;
  auto rev = [&](std::string name, std::string p, std::string c, Eigen::Vector3d xyz, Eigen::Vector3d rpy,
                 Eigen::Vector3d axis, double lo, double hi) {
    TestUrdfJoint j{name, p, c};
    j.xyz_m = xyz, j.rpy_rad = rpy, j.axis = axis, j.lower_rad = lo, j.upper_rad = hi;
    js.push_back(j);
  };
  auto fixed = [&](std::string name, std::string p, std::string c, Eigen::Vector3d xyz, Eigen::Vector3d rpy) {
    TestUrdfJoint j{name, p, c, "fixed"};
    j.xyz_m = xyz, j.rpy_rad = rpy;
    js.push_back(j);
  };
  fixed("world_mount", "world", "base_link", {0.1, -0.2, 0.05}, {0.02, -0.01, 0.3});
  fixed("base_marker", "base_link", "marker", {0.3, 0, 0}, {0, 0, 0});
  rev("j1", "base_link", "l1", {0.01, 0.02, 0.4}, {0.1, -0.05, 0.7}, {0, 0, -1}, -2.9, 2.9);
  rev("j2", "l1", "l2", {0.15, 0.0, 0.1}, {1.2, 0.3, -0.4}, {0, 1, 0}, -2.0, 1.5);
  fixed("l2_plate", "l2", "l2b", {0.0, 0.05, 0.3}, {0.0, 0.2, 0.1});
  rev("j3", "l2b", "l3", {0.02, 0.6, -0.03}, {-0.3, 0.1, 0.9}, {1, 0, 0}, -1.5, 2.5);
  rev("j4", "l3", "l4", {0.5, 0.1, 0.12}, {0.4, 1.1, 0.0}, Eigen::Vector3d(1, 2, 2) / 3.0, -3.1, 3.1);
  rev("j5", "l4", "l5", {0.0, -0.08, 0.2}, {2.0, -0.7, 0.25}, {0, -1, 0}, -2.2, 2.2);
  rev("j6", "l5", "l6", {0.03, 0.0, 0.09}, {0.0, 0.0, -1.3}, {0, 0, 1}, -6.0, 6.0);
  fixed("l6_tool", "l6", "tool_tip", {0.01, 0.02, 0.15}, {0.3, 0.2, 0.1});
  return js;
}

}  // namespace errfield::testing
