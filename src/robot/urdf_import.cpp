// URDF parsing (urdfdom) and extraction of the base -> tip chain; see urdf_import.hpp.
#include "robot/degrees.hpp"

#include "errfield/robot/urdf_import.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
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

std::size_t line_of(const std::string& text, std::size_t offset) {
  return 1 + static_cast<std::size_t>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(offset), '\n'));
}

// The angles of an <origin rpy="R P Y"> start tag, as written: urdfdom turns them into a quaternion
// at once, where 1e20 rad (or an angle in degrees) is some rotation and no longer visible.
// `xml` from `begin` is the start tag, which ends at `last` ('>'). `line_of` is computed only for
// a refusal (it counts from the file's start).
void check_origin_angles(const std::string& xml, std::size_t begin, std::size_t last, const std::string& source) {
  if (xml.compare(begin, 7, "<origin") != 0 || !std::isspace(static_cast<unsigned char>(xml[begin + 7]))) return;
  const std::string tag = xml.substr(begin, last - begin + 1);
  std::size_t at = 0;
  while ((at = tag.find("rpy", at)) != std::string::npos) {
    const bool word_start = std::isspace(static_cast<unsigned char>(tag[at - 1])) != 0;
    at += 3;
    std::size_t k = tag.find_first_not_of(" \t\r\n", at);
    if (!word_start || k == std::string::npos || tag[k] != '=') continue;
    k = tag.find_first_not_of(" \t\r\n", k + 1);
    if (k == std::string::npos || (tag[k] != '"' && tag[k] != '\'')) continue;
    const std::size_t end = tag.find(tag[k], k + 1);
    if (end == std::string::npos) return;  // malformed: the parser reports it
    std::istringstream values(tag.substr(k + 1, end - k - 1));
    std::string item;
    for (int component = 1; values >> item; ++component) {
      char* stop = nullptr;
      const double v = std::strtod(item.c_str(), &stop);
      if (stop == item.c_str() || *stop != '\0') continue;  // not a number: the parser reports it
      if (!(std::abs(v) <= kMaxUrdfOriginAngle_rad))
        throw InputError(source + ":" + std::to_string(line_of(xml, begin)) + ": <origin rpy=\"" + tag.substr(k + 1, end - k - 1) +
                             "\">: component " + std::to_string(component) + " = " + item +
                             (std::isfinite(v) ? " rad is beyond " + std::to_string(static_cast<int>(kMaxUrdfOriginAngle_rad)) +
                                                     " rad (about 16 turns); URDF angles are in radians, within one turn"
                                               : " is not a finite angle"),
                         source, line_of(xml, begin));
    }
    return;
  }
}

// One linear pass over the markup before the recursive parser sees it: refuses a nesting deeper
// than kMaxUrdfDepth (the parser would recurse once per level, in quadratic time, and overflow the
// stack at ~100,000 levels) and a <!DOCTYPE> (urdfdom then finds no <robot> element and says only
// that). Comments, CDATA and processing instructions are skipped; malformed markup is left to the parser.
void check_markup(const std::string& xml, const std::string& source) {
  int depth = 0;
  std::size_t i = 0;
  const auto skip_past = [&](const char* end) {
    const std::size_t e = xml.find(end, i);
    i = e == std::string::npos ? xml.size() : e + std::char_traits<char>::length(end);
  };
  while ((i = xml.find('<', i)) != std::string::npos) {
    const std::size_t start = i;
    if (xml.compare(i, 4, "<!--") == 0) {
      skip_past("-->");
    } else if (xml.compare(i, 9, "<![CDATA[") == 0) {
      skip_past("]]>");
    } else if (xml.compare(i, 2, "<?") == 0) {
      skip_past("?>");
    } else if (xml.compare(i, 2, "<!") == 0) {
      std::string word = xml.substr(i + 2, 7);
      std::transform(word.begin(), word.end(), word.begin(), [](unsigned char c) { return std::toupper(c); });
      if (word == "DOCTYPE")
        throw InputError(source + ":" + std::to_string(line_of(xml, start)) +
                             ": a <!DOCTYPE> declaration is not supported in a URDF (urdfdom reads no DTD and would "
                             "then find no <robot> element); remove it",
                         source, line_of(xml, start));
      skip_past(">");
    } else if (xml.compare(i, 2, "</") == 0) {
      --depth;
      skip_past(">");
    } else {
      // A start tag: find its '>' outside quoted attribute values; "/>" closes it at once.
      char quote = 0;
      std::size_t j = i + 1;
      for (; j < xml.size(); ++j) {
        const char c = xml[j];
        if (quote) {
          if (c == quote) quote = 0;
        } else if (c == '"' || c == '\'') {
          quote = c;
        } else if (c == '>') {
          break;
        }
      }
      if (j >= xml.size()) return;  // unterminated: the parser reports it
      check_origin_angles(xml, i, j, source);
      if (xml[j - 1] != '/' && ++depth > kMaxUrdfDepth)
        throw InputError(source + ":" + std::to_string(line_of(xml, start)) + ": elements nested more than " +
                             std::to_string(kMaxUrdfDepth) +
                             " levels deep; a URDF nests ~5 (the limit is in docs/reliability.md, \"Input limits\")",
                         source, line_of(xml, start));
      i = j + 1;
    }
  }
}

urdf::ModelInterfaceSharedPtr parse_model(const std::string& xml, const std::string& source) {
  if (xml.size() > kMaxUrdfBytes)
    throw InputError(source + ": " + std::to_string(xml.size()) + " bytes; a URDF errfield reads is at most " +
                         std::to_string(kMaxUrdfBytes >> 20) + " MiB (docs/reliability.md, \"Input limits\")",
                     source);
  check_markup(xml, source);
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
  {
    double rpy[3];
    o.rotation.getRPY(rpy[0], rpy[1], rpy[2]);
    const double xyz[3] = {o.position.x, o.position.y, o.position.z};
    for (int k = 0; k < 6; ++k) {
      const double v = k < 3 ? xyz[k] : rpy[k - 3];
      const std::string what = std::string(k < 3 ? "xyz" : "rpy") + " component " + std::to_string(k % 3 + 1) +
                               " = " + fmt(v) + (k < 3 ? " m" : " rad");
      if (!std::isfinite(v)) throw InputError(where + ": <origin> " + what + " is not finite", source);
      if (v != 0.0 && std::abs(v) < kMinUrdfNonzeroOrigin)
        throw InputError(where + ": <origin> " + what + " is neither 0 nor a physical size (|value| < " +
                             fmt(kMinUrdfNonzeroOrigin) + "); write 0 if the offset is zero",
                         source);
      if (k < 3 && std::abs(v) > kMaxUrdfOriginOffset_m)
        throw InputError(where + ": <origin> " + what + " is beyond " + fmt(kMaxUrdfOriginOffset_m) +
                             " m; URDF lengths are in metres (a value in mm?)",
                         source);
    }
  }
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
  if (!(std::abs(j.limits->lower) <= kMaxUrdfJointLimit_rad && std::abs(j.limits->upper) <= kMaxUrdfJointLimit_rad))
    throw InputError(where + ": <limit lower=\"" + fmt(j.limits->lower) + "\" upper=\"" + fmt(j.limits->upper) +
                         "\"> is beyond +-" + fmt(kMaxUrdfJointLimit_rad) +
                         " rad (about 16 turns); URDF limits are in radians: give the joint's real travel",
                     source);
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
  // urdfdom keeps only one parent joint per link and drops the other silently: refuse a link that
  // is the child of two joints (the file is then a graph, not a kinematic tree).
  {
    std::map<std::string, std::string> parent_joint_of;  // child link -> joint
    for (const auto& [name, joint] : model->joints_) {
      const auto [it, fresh] = parent_joint_of.emplace(joint->child_link_name, name);
      if (!fresh)
        throw InputError(source + ": link '" + joint->child_link_name + "' is the child of two joints, '" + it->second +
                             "' and '" + name + "'; a URDF is a tree (each link has at most one parent joint)",
                         source);
    }
  }
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
  const std::string name = path.string();
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw InputError(name + ": is a directory, not a URDF file", name);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError("cannot open URDF file '" + name + "'", name);
  // Bounded read: the limit is checked before the file (or a device such as /dev/zero) is in memory.
  std::string text;
  char chunk[65536];
  while (in.read(chunk, sizeof chunk) || in.gcount() > 0) {
    text.append(chunk, static_cast<std::size_t>(in.gcount()));
    if (text.size() > kMaxUrdfBytes)
      throw InputError(name + ": larger than " + std::to_string(kMaxUrdfBytes >> 20) +
                           " MiB; a URDF errfield reads is at most that (docs/reliability.md, \"Input limits\")",
                       name);
  }
  if (in.bad()) throw InputError(name + ": read error", name);
  return parse_urdf_chain(text, base_link, tip_link, name);
}

}  // namespace errfield::robot
