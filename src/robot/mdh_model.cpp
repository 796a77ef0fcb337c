#include "errfield/robot/mdh_model.hpp"
#include "robot/degrees.hpp"

#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

#include <nlohmann/json.hpp>

#include "errfield/atomic_file.hpp"
#include "errfield/error.hpp"
#include "errfield/json_file.hpp"
#include "robot/json_fields.hpp"

namespace errfield::robot {

namespace {


std::string fmt(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

void check_rigid(const Eigen::Isometry3d& t, const std::string& what) {
  if (!t.matrix().allFinite()) throw ArgumentError("MdhModel: " + what + " transform has a non-finite entry");
  const double orth = (t.linear().transpose() * t.linear() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (orth > 1e-9 || t.linear().determinant() < 0)
    throw ArgumentError("MdhModel: " + what + " rotation is not a proper rotation matrix (|R^T R - I| = " +
                        fmt(orth) + ", expected <= 1e-9)");
}

MdhLinkConstants make_constants(const MdhLink& l) {
  MdhLinkConstants c;
  c.r_const = (Eigen::AngleAxisd(l.alpha_deg * kDeg, Eigen::Vector3d::UnitX()) *
               Eigen::AngleAxisd(l.beta_deg * kDeg, Eigen::Vector3d::UnitY()))
                  .toRotationMatrix();
  c.a_mm = l.a_mm;
  c.d_mm = l.d_mm;
  c.cos_theta0 = std::cos(l.theta0_deg * kDeg);
  c.sin_theta0 = std::sin(l.theta0_deg * kDeg);
  return c;
}

using detail::json_check_keys;
using detail::json_number;
using detail::json_pose;
using detail::pose_json;

[[noreturn]] void fail(const std::string& source, const std::string& field, const std::string& what) {
  detail::json_fail(source, field, what);
}

}  // namespace

MdhModel::MdhModel(std::string name, const std::array<MdhLink, kJointCount>& links, const Eigen::Isometry3d& base,
                   const Eigen::Isometry3d& tool)
    : name_(std::move(name)), links_(links), base_(base), tool_(tool) {
  for (int i = 0; i < kJointCount; ++i) {
    const MdhLink& l = links_[static_cast<std::size_t>(i)];
    const std::string where = "MdhModel: link " + std::to_string(i + 1) + " ";
    const std::pair<const char*, double> fields[] = {{"alpha_deg", l.alpha_deg}, {"a_mm", l.a_mm},
                                                     {"theta0_deg", l.theta0_deg}, {"d_mm", l.d_mm},
                                                     {"beta_deg", l.beta_deg}, {"q_min_deg", l.q_min_deg},
                                                     {"q_max_deg", l.q_max_deg}};
    for (const auto& [field, v] : fields)
      if (!std::isfinite(v)) throw ArgumentError(where + field + " = " + fmt(v) + ", expected a finite number");
    if (!(l.q_min_deg < l.q_max_deg))
      throw ArgumentError(where + "joint limits: q_min_deg = " + fmt(l.q_min_deg) + " must be < q_max_deg = " +
                          fmt(l.q_max_deg));
    constants_[static_cast<std::size_t>(i)] = make_constants(l);
  }
  check_rigid(base_, "base");
  check_rigid(tool_, "tool");
}

MdhModel MdhModel::er20_c10() {
  // SPEC Table 1 (alpha_{i-1}, a_{i-1}, theta0_i, d_i); limits: see header comment.
  const std::array<MdhLink, kJointCount> links{{
      {0.0, 0.0, 0.0, 504.0, 0.0, -170.0, 170.0},
      {90.0, 166.605, 0.0, 0.0, 0.0, -150.0, 90.0},
      {0.0, -782.27, 0.0, 0.0, 0.0, -80.0, 180.0},
      {-90.0, -138.826, 0.0, 761.35, 0.0, -180.0, 180.0},
      {90.0, 0.0, 0.0, 0.0, 0.0, -135.0, 135.0},
      {-90.0, 0.0, 0.0, 125.0, 0.0, -360.0, 360.0},
  }};
  return MdhModel("ER20-C10", links);
}

MdhModel MdhModel::from_json(const nlohmann::json& j, const std::string& source) {
  if (!j.is_object()) fail(source, "(top level)", "expected a JSON object, got " + j.dump().substr(0, 60));
  // "registration": the tracker registration calibrate stores beside the robot (compensation/model/registration.hpp).
  json_check_keys(j, {"name", "units", "links", "base", "tool", "comment", "registration"}, "", source);
  std::string name = "robot";
  if (const auto it = j.find("name"); it != j.end()) {
    if (!it->is_string()) fail(source, "name", "expected a string, got " + it->dump());
    name = it->get<std::string>();
  }
  if (const auto it = j.find("units"); it != j.end()) {
    // Optional and informative; if present it must agree with what the field names say.
    if (!it->is_object()) fail(source, "units", "expected {\"length\": \"mm\", \"angle\": \"deg\"}, got " + it->dump());
    if (it->contains("length") && (*it)["length"] != "mm")
      fail(source, "units.length", "only \"mm\" is supported, got " + (*it)["length"].dump());
    if (it->contains("angle") && (*it)["angle"] != "deg")
      fail(source, "units.angle", "only \"deg\" is supported, got " + (*it)["angle"].dump());
  }
  const auto links_it = j.find("links");
  if (links_it == j.end()) fail(source, "links", "missing (expected an array of 6 link objects)");
  if (!links_it->is_array() || links_it->size() != kJointCount)
    fail(source, "links", "expected an array of 6 link objects, got " +
                              (links_it->is_array() ? std::to_string(links_it->size()) + " entries" : links_it->dump()));
  std::array<MdhLink, kJointCount> links;
  const double zero = 0.0, lo = -180.0, hi = 180.0;
  for (int i = 0; i < kJointCount; ++i) {
    const auto& l = (*links_it)[static_cast<std::size_t>(i)];
    const std::string path = "links[" + std::to_string(i) + "].";
    if (!l.is_object()) fail(source, path.substr(0, path.size() - 1), "expected an object, got " + l.dump());
    json_check_keys(l, {"alpha_deg", "a_mm", "theta0_deg", "d_mm", "beta_deg", "q_min_deg", "q_max_deg"}, path, source);
    MdhLink& m = links[static_cast<std::size_t>(i)];
    m.alpha_deg = json_number(l, "alpha_deg", path, source, nullptr);
    m.a_mm = json_number(l, "a_mm", path, source, nullptr);
    m.theta0_deg = json_number(l, "theta0_deg", path, source, nullptr);
    m.d_mm = json_number(l, "d_mm", path, source, nullptr);
    m.beta_deg = json_number(l, "beta_deg", path, source, &zero);
    m.q_min_deg = json_number(l, "q_min_deg", path, source, &lo);
    m.q_max_deg = json_number(l, "q_max_deg", path, source, &hi);
    if (!(m.q_min_deg < m.q_max_deg))
      fail(source, path + "q_min_deg", "must be < q_max_deg (" + fmt(m.q_min_deg) + " >= " + fmt(m.q_max_deg) + ")");
  }
  Eigen::Isometry3d base = Eigen::Isometry3d::Identity(), tool = Eigen::Isometry3d::Identity();
  if (const auto it = j.find("base"); it != j.end()) base = json_pose(*it, "base", source);
  if (const auto it = j.find("tool"); it != j.end()) tool = json_pose(*it, "tool", source);
  return MdhModel(std::move(name), links, base, tool);
}

MdhModel MdhModel::load(const std::filesystem::path& path) {
  return with_json_source(path.string(), [&] { return from_json(read_json_file(path, "robot description"), path.string()); });
}

nlohmann::json MdhModel::to_json() const {
  nlohmann::json links = nlohmann::json::array();
  for (const MdhLink& l : links_)
    links.push_back({{"alpha_deg", l.alpha_deg}, {"a_mm", l.a_mm}, {"theta0_deg", l.theta0_deg}, {"d_mm", l.d_mm},
                     {"beta_deg", l.beta_deg}, {"q_min_deg", l.q_min_deg}, {"q_max_deg", l.q_max_deg}});
  return {{"name", name_},
          {"units", {{"length", "mm"}, {"angle", "deg"}}},
          {"links", links},
          {"base", pose_json(base_)},
          {"tool", pose_json(tool_)}};
}

void MdhModel::save(const std::filesystem::path& path) const { write_file_atomically(path, to_json().dump(2) + "\n"); }

JointVector MdhModel::q_min_deg() const {
  JointVector q;
  for (int i = 0; i < kJointCount; ++i) q[i] = links_[static_cast<std::size_t>(i)].q_min_deg;
  return q;
}

JointVector MdhModel::q_max_deg() const {
  JointVector q;
  for (int i = 0; i < kJointCount; ++i) q[i] = links_[static_cast<std::size_t>(i)].q_max_deg;
  return q;
}

bool MdhModel::within_limits(const JointVector& q_deg, double slack_deg) const {
  for (int i = 0; i < kJointCount; ++i) {
    const MdhLink& l = links_[static_cast<std::size_t>(i)];
    if (!(q_deg[i] >= l.q_min_deg - slack_deg && q_deg[i] <= l.q_max_deg + slack_deg)) return false;
  }
  return true;
}

MdhModel MdhModel::with_base(const Eigen::Isometry3d& base) const { return MdhModel(name_, links_, base, tool_); }
MdhModel MdhModel::with_tool(const Eigen::Isometry3d& tool) const { return MdhModel(name_, links_, base_, tool); }
MdhModel MdhModel::with_tool_point(const Eigen::Vector3d& point_mm) const {
  Eigen::Isometry3d tool = tool_;
  tool.translation() = point_mm;
  return with_tool(tool);
}
MdhModel MdhModel::with_links(const std::array<MdhLink, kJointCount>& links) const {
  return MdhModel(name_, links, base_, tool_);
}
MdhModel MdhModel::with_name(std::string name) const { return MdhModel(std::move(name), links_, base_, tool_); }

}  // namespace errfield::robot
