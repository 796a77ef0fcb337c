// URDF parsing (urdfdom) and extraction of the base -> tip chain; see urdf_import.hpp.
#include "robot/degrees.hpp"

#include "errfield/robot/urdf_import.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

#include "errfield/error.hpp"

#ifdef ERRFIELD_HAVE_URDFDOM
#include <mutex>

#include <console_bridge/console.h>
#include <urdf_parser/urdf_parser.h>
#endif

namespace errfield::robot {

namespace {

// URDF files print axes with a few digits ("0.7071 0.7071 0" has length 0.99999...); anything
// further from 1 is a mistake, not rounding. Accepted axes are normalized, as KDL and ROS do.
constexpr double kAxisLengthTolerance = 1e-6;

std::string fmt(double v) {
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

}  // namespace

std::vector<const UrdfJoint*> UrdfChain::revolute() const {
  std::vector<const UrdfJoint*> r;
  for (const UrdfJoint& j : joints)
    if (j.revolute) r.push_back(&j);
  return r;
}

Eigen::Isometry3d urdf_chain_pose(const UrdfChain& chain, const JointVector& q_deg) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  int k = 0;
  for (const UrdfJoint& j : chain.joints) {
    t = t * j.origin;
    if (j.revolute) {
      if (k >= kJointCount)
        throw ArgumentError("urdf_chain_pose: the chain has more than " + std::to_string(kJointCount) +
                            " revolute joints");
      t = t * Eigen::AngleAxisd(q_deg[k++] * kDeg, j.axis);
    }
  }
  return t;
}

#ifndef ERRFIELD_HAVE_URDFDOM

bool urdf_support_available() noexcept { return false; }

UrdfChain parse_urdf_chain(const std::string&, const std::string&, const std::string&, const std::string& source) {
  throw Error(source + ": this errfield was built without URDF support (urdfdom, Debian liburdfdom-dev, was not "
                       "found at configure time); install it (scripts/setup.sh) and rebuild");
}

#else

bool urdf_support_available() noexcept { return true; }

namespace {

// urdfdom reports why it rejects a file through console_bridge, on stderr; collect the messages so
// the exception carries them. console_bridge's handler is process-global, hence the mutex.
class CollectingHandler : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_WARN) messages.push_back(text);
  }
  std::vector<std::string> messages;
};

std::mutex& console_mutex() {
  static std::mutex m;
  return m;
}

urdf::ModelInterfaceSharedPtr parse_model(const std::string& xml, const std::string& source) {
  CollectingHandler handler;
  urdf::ModelInterfaceSharedPtr model;
  {
    std::lock_guard<std::mutex> lock(console_mutex());
    console_bridge::useOutputHandler(&handler);
    try {
      model = urdf::parseURDF(xml);
    } catch (const std::exception& e) {
      handler.messages.push_back(e.what());
    }
    console_bridge::restorePreviousOutputHandler();
  }
  if (!model) {
    std::string why;
    for (const auto& m : handler.messages) why += (why.empty() ? "" : "; ") + m;
    throw InputError(source + ": not a valid URDF" + (why.empty() ? std::string() : ": " + why), source);
  }
  return model;
}

std::string joint_kind(int type) {
  switch (type) {
    case urdf::Joint::REVOLUTE: return "revolute";
    case urdf::Joint::CONTINUOUS: return "continuous";
    case urdf::Joint::PRISMATIC: return "prismatic";
    case urdf::Joint::FLOATING: return "floating";
    case urdf::Joint::PLANAR: return "planar";
    case urdf::Joint::FIXED: return "fixed";
    default: return "of unknown type";
  }
}

std::string link_list(const urdf::ModelInterface& model) {
  std::vector<urdf::LinkSharedPtr> links;
  model.getLinks(links);
  std::string s;
  for (std::size_t i = 0; i < links.size() && i < 30; ++i) s += (i ? ", " : "") + links[i]->name;
  if (links.size() > 30) s += ", ... (" + std::to_string(links.size()) + " links)";
  return s;
}

// The first non-fixed joint in the subtree below `joint` (itself included), or null.
urdf::JointConstSharedPtr moving_joint_in(const urdf::ModelInterface& model, const urdf::JointConstSharedPtr& joint) {
  if (joint->type != urdf::Joint::FIXED) return joint;
  const auto child = model.getLink(joint->child_link_name);
  if (!child) return nullptr;
  for (const auto& c : child->child_joints)
    if (auto m = moving_joint_in(model, c)) return m;
  return nullptr;
}

UrdfJoint convert_joint(const urdf::Joint& j, const std::string& source) {
  const std::string where = source + ": joint '" + j.name + "' (link '" + j.parent_link_name + "' -> '" +
                            j.child_link_name + "')";
  UrdfJoint out;
  out.name = j.name;
  out.parent_link = j.parent_link_name;
  out.child_link = j.child_link_name;
  const urdf::Pose& o = j.parent_to_joint_origin_transform;
  out.origin.linear() = Eigen::Quaterniond(o.rotation.w, o.rotation.x, o.rotation.y, o.rotation.z)
                            .normalized()
                            .toRotationMatrix();
  out.origin.translation() = 1000.0 * Eigen::Vector3d(o.position.x, o.position.y, o.position.z);
  if (!out.origin.matrix().allFinite()) throw InputError(where + ": <origin> has a non-finite value", source);
  switch (j.type) {
    case urdf::Joint::FIXED:
      return out;
    case urdf::Joint::REVOLUTE:
      break;
    case urdf::Joint::CONTINUOUS:
      throw InputError(where + " is continuous (no joint limits); errfield's robot JSON needs limits: declare it "
                               "type=\"revolute\" with <limit lower=\"...\" upper=\"...\"> (radians)",
                       source);
    case urdf::Joint::PRISMATIC:
      throw InputError(where + " is prismatic; an MD-H 6R model holds revolute joints only", source);
    default:
      throw InputError(where + " is " + joint_kind(j.type) + "; the chain may hold only revolute and fixed joints",
                       source);
  }
  if (j.mimic)
    throw InputError(where + " mimics joint '" + j.mimic->joint_name +
                         "'; coupled joints are not supported (each MD-H joint moves on its own)",
                     source);
  const Eigen::Vector3d axis(j.axis.x, j.axis.y, j.axis.z);
  const double len = axis.norm();
  if (!std::isfinite(len) || std::abs(len - 1.0) > kAxisLengthTolerance)
    throw InputError(where + ": <axis xyz=\"" + fmt(axis.x()) + " " + fmt(axis.y()) + " " + fmt(axis.z()) +
                         "\"> has length " + fmt(len) + "; a joint axis must be a unit vector (length 1 within " +
                         fmt(kAxisLengthTolerance) + ")",
                     source);
  out.axis = axis / len;
  out.revolute = true;
  if (!j.limits) throw InputError(where + " has no <limit>; revolute joints need lower and upper limits", source);
  out.lower_deg = j.limits->lower / kDeg;
  out.upper_deg = j.limits->upper / kDeg;
  if (!std::isfinite(out.lower_deg) || !std::isfinite(out.upper_deg) || !(out.lower_deg < out.upper_deg))
    throw InputError(where + ": <limit lower=\"" + fmt(j.limits->lower) + "\" upper=\"" + fmt(j.limits->upper) +
                         "\"> must satisfy lower < upper (radians)",
                     source);
  return out;
}

}  // namespace

UrdfChain parse_urdf_chain(const std::string& urdf_xml, const std::string& base_link, const std::string& tip_link,
                           const std::string& source) {
  const urdf::ModelInterfaceSharedPtr model = parse_model(urdf_xml, source);
  const auto base = model->getLink(base_link);
  if (!base)
    throw InputError(source + ": --base: no link named '" + base_link + "' (links: " + link_list(*model) + ")", source);
  const auto tip = model->getLink(tip_link);
  if (!tip)
    throw InputError(source + ": --tip: no link named '" + tip_link + "' (links: " + link_list(*model) + ")", source);
  if (base_link == tip_link)
    throw InputError(source + ": --base and --tip are the same link '" + base_link + "'", source);

  // Walk up from the tip; the path must reach the base (a chain runs from parent to child links).
  std::vector<urdf::JointConstSharedPtr> path;
  for (auto link = urdf::LinkConstSharedPtr(tip); link->name != base_link;) {
    if (!link->parent_joint)
      throw InputError(source + ": tip link '" + tip_link + "' is not below base link '" + base_link +
                           "': going from '" + tip_link + "' towards the root the path ends at '" + link->name +
                           "' without passing '" + base_link + "'",
                       source);
    path.push_back(link->parent_joint);
    link = model->getLink(link->parent_joint->parent_link_name);
    if (!link) throw InputError(source + ": joint '" + path.back()->name + "' has no parent link", source);
  }
  std::reverse(path.begin(), path.end());

  UrdfChain chain;
  chain.robot_name = model->getName();
  chain.base_link = base_link;
  chain.tip_link = tip_link;
  chain.source = source;
  for (std::size_t i = 0; i < path.size(); ++i) {
    chain.joints.push_back(convert_joint(*path[i], source));
    if (i + 1 == path.size()) break;
    // A link between base and tip whose other children move is not a serial arm: refuse rather
    // than silently drop the moving branch. Fixed children (flange, sensor frames) are harmless.
    const auto link = model->getLink(path[i]->child_link_name);
    for (const auto& c : link->child_joints) {
      if (c->name == path[i + 1]->name) continue;
      if (const auto m = moving_joint_in(*model, c))
        throw InputError(source + ": link '" + link->name + "' on the chain '" + base_link + "' -> '" + tip_link +
                             "' branches: besides joint '" + path[i + 1]->name + "' on the chain it carries the " +
                             joint_kind(m->type) + " joint '" + m->name + "' (towards link '" + m->child_link_name +
                             "'); an MD-H model is one serial chain without branches",
                         source);
    }
  }
  const auto rev = chain.revolute();
  if (static_cast<int>(rev.size()) != kJointCount) {
    std::string names;
    for (const auto* j : rev) names += (names.empty() ? "" : ", ") + j->name;
    throw InputError(source + ": the chain '" + base_link + "' -> '" + tip_link + "' has " +
                         std::to_string(rev.size()) + " revolute joint" + (rev.size() == 1 ? "" : "s") +
                         (names.empty() ? std::string() : " (" + names + ")") + "; errfield supports 6R arms: exactly " +
                         std::to_string(kJointCount) + " revolute joints between --base and --tip",
                     source);
  }
  return chain;
}

#endif

UrdfChain read_urdf_chain(const std::filesystem::path& path, const std::string& base_link,
                          const std::string& tip_link) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError("cannot open URDF file '" + path.string() + "'", path.string());
  std::ostringstream s;
  s << in.rdbuf();
  return parse_urdf_chain(s.str(), base_link, tip_link, path.string());
}

}  // namespace errfield::robot
