#include "robot/json_fields.hpp"

#include <cmath>

#include "errfield/error.hpp"
#include "errfield/robot/pose.hpp"

namespace errfield::robot::detail {

void json_fail(const std::string& source, const std::string& field, const std::string& what) {
  throw InputError(source + ": " + field + ": " + what, source, 0, field);
}

double json_number(const nlohmann::json& obj, const std::string& key, const std::string& path,
                   const std::string& source, const double* fallback) {
  const auto it = obj.find(key);
  if (it == obj.end()) {
    if (fallback) return *fallback;
    json_fail(source, path + key, "missing (expected a number)");
  }
  if (!it->is_number()) json_fail(source, path + key, "expected a number, got " + it->dump());
  const double v = it->get<double>();
  if (!std::isfinite(v)) json_fail(source, path + key, "expected a finite number, got " + it->dump());
  return v;
}

void json_check_keys(const nlohmann::json& obj, std::initializer_list<const char*> allowed, const std::string& path,
                     const std::string& source) {
  if (!obj.is_object()) {
    const std::string where = path.empty() ? "(top level)" : path.substr(0, path.size() - (path.back() == '.' ? 1 : 0));
    json_fail(source, where, "expected an object, got " + obj.dump());
  }
  for (auto it = obj.begin(); it != obj.end(); ++it) {
    bool ok = false;
    for (const char* a : allowed) ok = ok || it.key() == a;
    if (!ok) {
      std::string list;
      for (const char* a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
      json_fail(source, path + it.key(), "unknown field (expected one of: " + list + ")");
    }
  }
}

Eigen::Isometry3d json_pose(const nlohmann::json& j, const std::string& path, const std::string& source) {
  if (!j.is_object())
    json_fail(source, path, "expected an object {x_mm, y_mm, z_mm, rx_deg, ry_deg, rz_deg}, got " + j.dump());
  json_check_keys(j, {"x_mm", "y_mm", "z_mm", "rx_deg", "ry_deg", "rz_deg"}, path + ".", source);
  const double zero = 0.0;
  PoseXyzRpy p;
  p.x_mm = json_number(j, "x_mm", path + ".", source, &zero);
  p.y_mm = json_number(j, "y_mm", path + ".", source, &zero);
  p.z_mm = json_number(j, "z_mm", path + ".", source, &zero);
  p.rx_deg = json_number(j, "rx_deg", path + ".", source, &zero);
  p.ry_deg = json_number(j, "ry_deg", path + ".", source, &zero);
  p.rz_deg = json_number(j, "rz_deg", path + ".", source, &zero);
  return to_isometry(p);
}

nlohmann::json pose_json(const Eigen::Isometry3d& t) {
  const PoseXyzRpy p = to_xyz_rpy(t);
  return {{"x_mm", p.x_mm}, {"y_mm", p.y_mm}, {"z_mm", p.z_mm},
          {"rx_deg", p.rx_deg}, {"ry_deg", p.ry_deg}, {"rz_deg", p.rz_deg}};
}

MdhModel json_nested_model(const nlohmann::json& parent, const std::string& member, const std::string& source) {
  try {
    return MdhModel::from_json(parent[member], source);
  } catch (const InputError& e) {
    std::string what = e.what();
    const std::string prefix = source + ": ";
    if (what.rfind(prefix, 0) == 0) what.erase(0, prefix.size());
    throw InputError(prefix + member + (e.column().empty() ? ": " : ".") + what, source, e.row(),
                     e.column().empty() ? member : member + "." + e.column());
  }
}

}  // namespace errfield::robot::detail
