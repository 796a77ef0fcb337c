#pragma once
// Reading JSON fields with messages that name the source and the field path
// ("robot.json: links[2].a_mm: expected a number, got \"x\""). Internal to the robot module.

#include <array>
#include <initializer_list>
#include <string>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "errfield/robot/mdh_model.hpp"

namespace errfield::robot::detail {

[[noreturn]] void json_fail(const std::string& source, const std::string& field, const std::string& what);

/// obj[key] as a finite number; `fallback` null means required.
double json_number(const nlohmann::json& obj, const std::string& key, const std::string& path,
                   const std::string& source, const double* fallback);

/// Rejects keys not in `allowed` (a typo must not become a silent default).
void json_check_keys(const nlohmann::json& obj, std::initializer_list<const char*> allowed, const std::string& path,
                     const std::string& source);

/// {x_mm, y_mm, z_mm, rx_deg, ry_deg, rz_deg} (each optional, default 0) as a transform.
Eigen::Isometry3d json_pose(const nlohmann::json& j, const std::string& path, const std::string& source);
nlohmann::json pose_json(const Eigen::Isometry3d& t);

/// The robot nested at parent[member] (a compensation model's command_model, a simulation set-up's
/// robot). Its errors keep InputError::file() the plain path, as every other reader's, and carry the
/// member path in the message and column ("m.json: command_model.links[2].a_mm: expected a number").
MdhModel json_nested_model(const nlohmann::json& parent, const std::string& member, const std::string& source);

/// An array of exactly N finite numbers.
template <std::size_t N>
std::array<double, N> json_array(const nlohmann::json& j, const std::string& path, const std::string& source) {
  if (!j.is_array() || j.size() != N)
    json_fail(source, path, "expected an array of " + std::to_string(N) + " numbers, got " + j.dump());
  std::array<double, N> out{};
  for (std::size_t i = 0; i < N; ++i) {
    if (!j[i].is_number() || !std::isfinite(j[i].get<double>()))
      json_fail(source, path + "[" + std::to_string(i) + "]", "expected a finite number, got " + j[i].dump());
    out[i] = j[i].get<double>();
  }
  return out;
}

}  // namespace errfield::robot::detail
