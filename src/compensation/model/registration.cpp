#include "errfield/compensation/model/registration.hpp"

#include <cmath>

#include <nlohmann/json.hpp>

#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"
#include "errfield/robot/pose.hpp"
#include "robot/rigid_fit.hpp"

namespace errfield::compensation {

Registration fit_registration(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b) {
  if (a.size() != b.size() || a.size() < 3)
    throw InputError("registration: need at least 3 point pairs, got " + std::to_string(std::min(a.size(), b.size())));
  Registration r;
  r.robot_from_tracker = robot::fit_rigid(a, b);
  double ss = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) ss += (r.robot_from_tracker * a[i] - b[i]).squaredNorm();
  r.residual_rms_mm = std::sqrt(ss / static_cast<double>(a.size()));
  r.points = a.size();
  return r;
}

nlohmann::json registration_to_json(const Registration& r) {
  // The matrix itself, not Euler angles: nlohmann writes doubles in shortest round-trip form, so the
  // transform reads back bit for bit.
  nlohmann::json m = nlohmann::json::array();
  for (int i = 0; i < 3; ++i) {
    nlohmann::json row = nlohmann::json::array();
    for (int k = 0; k < 4; ++k) row.push_back(r.robot_from_tracker.matrix()(i, k));
    m.push_back(row);
  }
  nlohmann::json j = {{"robot_from_tracker", m}, {"residual_rms_mm", r.residual_rms_mm}, {"points", r.points}};
  if (r.reflector_offset_mm)
    j["reflector_offset_mm"] = {r.reflector_offset_mm->x(), r.reflector_offset_mm->y(), r.reflector_offset_mm->z()};
  return j;
}

namespace {

[[noreturn]] void bad(const std::string& source, const std::string& member, const std::string& what) {
  throw InputError(source + ": member \"registration." + member + "\": " + what, source, 0, "registration." + member);
}

double number(const nlohmann::json& v, const std::string& source, const std::string& member) {
  if (!v.is_number() || !std::isfinite(v.get<double>())) bad(source, member, "expected a finite number, got " + v.dump());
  return v.get<double>();
}

}  // namespace

Registration registration_from_json(const nlohmann::json& j, const std::string& source) {
  if (!j.is_object()) bad(source, "", "expected an object");
  for (auto it = j.begin(); it != j.end(); ++it)
    if (it.key() != "robot_from_tracker" && it.key() != "residual_rms_mm" && it.key() != "points" &&
        it.key() != "reflector_offset_mm")
      bad(source, it.key(), "unknown field (expected robot_from_tracker, residual_rms_mm, points, reflector_offset_mm)");
  if (!j.contains("robot_from_tracker")) bad(source, "robot_from_tracker", "missing");
  const auto& m = j["robot_from_tracker"];
  if (!m.is_array() || m.size() != 3) bad(source, "robot_from_tracker", "expected 3 rows of 4 numbers ([R | t])");
  Eigen::Matrix4d t = Eigen::Matrix4d::Identity();
  for (std::size_t i = 0; i < 3; ++i) {
    if (!m[i].is_array() || m[i].size() != 4) bad(source, "robot_from_tracker", "expected 3 rows of 4 numbers ([R | t])");
    for (std::size_t k = 0; k < 4; ++k)
      t(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k)) =
          number(m[i][k], source, "robot_from_tracker[" + std::to_string(i) + "][" + std::to_string(k) + "]");
  }
  const Eigen::Matrix3d r = t.topLeftCorner<3, 3>();
  const double orthogonality = (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (orthogonality > 1e-9 || r.determinant() < 0.0)
    bad(source, "robot_from_tracker", "the 3 x 3 part is not a rotation (|R^T R - I| = " + format_number(orthogonality) +
                                          ", det " + format_number(r.determinant()) + ")");
  Registration out;
  out.robot_from_tracker.matrix() = t;
  if (j.contains("residual_rms_mm")) out.residual_rms_mm = number(j["residual_rms_mm"], source, "residual_rms_mm");
  if (j.contains("points")) {
    if (!j["points"].is_number_unsigned()) bad(source, "points", "expected a count, got " + j["points"].dump());
    out.points = j["points"].get<std::size_t>();
  }
  if (j.contains("reflector_offset_mm")) {
    const auto& o = j["reflector_offset_mm"];
    if (!o.is_array() || o.size() != 3) bad(source, "reflector_offset_mm", "expected 3 numbers");
    out.reflector_offset_mm = Eigen::Vector3d(number(o[0], source, "reflector_offset_mm[0]"),
                                              number(o[1], source, "reflector_offset_mm[1]"),
                                              number(o[2], source, "reflector_offset_mm[2]"));
  }
  return out;
}

std::optional<Registration> find_registration(const nlohmann::json& document, const std::string& source) {
  if (!document.is_object() || !document.contains("registration") || document["registration"].is_null()) return std::nullopt;
  return registration_from_json(document["registration"], source);
}

Eigen::MatrixXd poses_in_robot_frame(const Registration& r, const Eigen::MatrixXd& tracker_poses) {
  if (tracker_poses.cols() != 6)
    throw InputError("poses_in_robot_frame: expected 6 columns x,y,z,rx,ry,rz, got " + std::to_string(tracker_poses.cols()));
  Eigen::MatrixXd out(tracker_poses.rows(), 6);
  for (Eigen::Index i = 0; i < tracker_poses.rows(); ++i) {
    const auto t = tracker_poses.row(i);
    if (!t.allFinite()) {
      out.row(i) = t;
      continue;
    }
    const robot::PoseXyzRpy p = robot::to_xyz_rpy(r.robot_from_tracker * robot::to_isometry({t[0], t[1], t[2], t[3], t[4], t[5]}));
    out.row(i) << p.x_mm, p.y_mm, p.z_mm, p.rx_deg, p.ry_deg, p.rz_deg;
  }
  return out;
}

}  // namespace errfield::compensation
