#include "robot/rigid_fit.hpp"
#include "robot/degrees.hpp"
#include "errfield/robot/simulator.hpp"

#include <cmath>
#include <fstream>
#include <numbers>

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "errfield/error.hpp"
#include "errfield/json_file.hpp"
#include "errfield/robot/cube_budget.hpp"
#include "errfield/robot/paper_reference.hpp"
#include "robot/json_fields.hpp"

namespace errfield::robot {

namespace {


Eigen::Isometry3d from_six(const std::array<double, 6>& v) { return to_isometry({v[0], v[1], v[2], v[3], v[4], v[5]}); }


MdhModel apply_deviation(const MdhModel& nominal, const GeometricDeviation& g) {
  auto links = nominal.links();
  for (int i = 0; i < kJointCount; ++i) {
    auto& l = links[static_cast<std::size_t>(i)];
    const auto& d = g.link[static_cast<std::size_t>(i)];
    l.alpha_deg += d[0];
    l.a_mm += d[1];
    l.theta0_deg += d[2];
    l.d_mm += d[3];
    l.beta_deg += d[4];
    // The true robot is not bound by the controller's limits; keep the nominal ones, widened so
    // a deflected joint near a limit is still a valid configuration.
    l.q_min_deg -= 5.0;
    l.q_max_deg += 5.0;
  }
  Eigen::Isometry3d tool = nominal.tool() * to_isometry(g.tool);
  return MdhModel(nominal.name() + " (simulated true geometry)", links, nominal.base(), tool);
}

}  // namespace

// ---- configuration -----------------------------------------------------------------------------

SimulatorConfig SimulatorConfig::paper_default() {
  SimulatorConfig c;
  c.seed = 1;
  c.nominal = MdhModel::er20_c10().with_tool(paper_ball()).with_name("ER20-C10 + Table 7 ball");
  // Geometric deviations (docs/robot.md "Simulator"): a few tenths of a mm and hundredths of a
  // degree per parameter, the size an uncalibrated arm of this class shows after assembly.
  c.geometry.link = {{
      {0.073, 1.452, 0.109, 1.814, 0.000},
      {-0.109, -1.814, 0.146, 1.089, 0.000},
      {0.090, 2.903, -0.127, -1.452, 0.073},
      {-0.146, -1.089, 0.109, 2.540, 0.000},
      {0.127, 0.906, -0.163, -0.726, 0.000},
      {-0.109, 0.726, 0.146, 1.089, 0.000},
  }};
  c.geometry.tool = {0.096, -0.077, 0.154, 0.0, 0.0, 0.0};
  c.absorb_rigid_part = true;
  c.compliance.stiffness_nm_per_rad = {3.0e6, 3.0e6, 2.4e6, 6.0e5, 5.0e5, 3.0e5};
  c.compliance.link_mass_kg = {60.0, 45.0, 35.0, 18.0, 6.0, 2.0};
  c.compliance.payload_kg = 10.0;
  c.transmission.amplitude_deg = {0.0084, 0.0105, 0.0105, 0.0126, 0.0126, 0.0126};
  c.transmission.harmonic = {8.0, 12.0, 10.0, 6.0, 7.0, 5.0};
  c.transmission.phase_deg = {10.0, 70.0, 140.0, 200.0, 260.0, 320.0};
  c.repeatability_sigma_mm = 0.02;
  // Tracker 2.5 m in front of the robot, turned to face it (a typical set-up).
  c.tracker.tracker_from_world = to_isometry({0, 0, 0, 0, 0, 180}) * to_isometry({-2500, 300, -200, 0, 0, 0});
  c.tracker.sigma_constant_mm = 0.005;
  c.tracker.sigma_per_m_mm = 0.0025;
  return c;
}

void SimulatorConfig::validate() const {
  auto nonneg = [](double v, const std::string& name) {
    if (!(v >= 0) || !std::isfinite(v))
      throw ArgumentError("SimulatorConfig: " + name + " = " + std::to_string(v) + ", expected a finite value >= 0");
  };
  for (int i = 0; i < kJointCount; ++i) {
    const auto k = static_cast<std::size_t>(i);
    nonneg(compliance.stiffness_nm_per_rad[k], "compliance.stiffness_nm_per_rad[" + std::to_string(i) + "]");
    nonneg(compliance.link_mass_kg[k], "compliance.link_mass_kg[" + std::to_string(i) + "]");
    for (double v : compliance.mass_offset_mm[k])
      if (!std::isfinite(v)) throw ArgumentError("SimulatorConfig: compliance.mass_offset_mm[" + std::to_string(i) + "] is not finite");
    nonneg(transmission.amplitude_deg[k], "transmission.amplitude_deg[" + std::to_string(i) + "]");
    nonneg(end_range.onset_deg[k], "end_range.onset_deg[" + std::to_string(i) + "]");
    if (!std::isfinite(end_range.error_at_limit_deg[k]))
      throw ArgumentError("SimulatorConfig: end_range.error_at_limit_deg[" + std::to_string(i) + "] is not finite");
  }
  nonneg(compliance.payload_kg, "compliance.payload_kg");
  if (!tool_offset_mm.allFinite()) throw ArgumentError("SimulatorConfig: tool_offset_mm has a non-finite entry");
  nonneg(repeatability_sigma_mm, "repeatability_sigma_mm");
  nonneg(tracker.sigma_constant_mm, "tracker.sigma_constant_mm");
  nonneg(tracker.sigma_per_m_mm, "tracker.sigma_per_m_mm");
}

SimulatorConfig SimulatorConfig::from_json(const nlohmann::json& j, const std::string& source) {
  using namespace detail;
  SimulatorConfig c = paper_default();
  if (!j.is_object()) json_fail(source, "(top level)", "expected a JSON object");
  json_check_keys(j, {"comment", "seed", "robot", "geometry", "tool_offset_mm", "compliance", "transmission",
                      "end_range", "repeatability_sigma_mm", "tracker"},
                  "", source);
  if (j.contains("seed")) {
    if (!j["seed"].is_number_unsigned()) json_fail(source, "seed", "expected a non-negative integer, got " + j["seed"].dump());
    c.seed = j["seed"].get<std::uint64_t>();
  }
  if (j.contains("robot")) c.nominal = detail::json_nested_model(j, "robot", source);
  if (j.contains("geometry")) {
    const auto& g = j["geometry"];
    if (!g.is_object()) json_fail(source, "geometry", "expected an object");
    json_check_keys(g, {"links", "tool", "absorb_rigid_part"}, "geometry.", source);
    if (g.contains("links")) {
      const auto& links = g["links"];
      if (!links.is_array() || links.size() != kJointCount)
        json_fail(source, "geometry.links", "expected an array of 6 deviation objects");
      for (std::size_t i = 0; i < kJointCount; ++i) {
        const std::string path = "geometry.links[" + std::to_string(i) + "].";
        json_check_keys(links[i], {"alpha_deg", "a_mm", "theta0_deg", "d_mm", "beta_deg"}, path, source);
        const double zero = 0.0;
        auto& d = c.geometry.link[i];
        d[0] = json_number(links[i], "alpha_deg", path, source, &zero);
        d[1] = json_number(links[i], "a_mm", path, source, &zero);
        d[2] = json_number(links[i], "theta0_deg", path, source, &zero);
        d[3] = json_number(links[i], "d_mm", path, source, &zero);
        d[4] = json_number(links[i], "beta_deg", path, source, &zero);
      }
    }
    if (g.contains("tool")) c.geometry.tool = to_xyz_rpy(json_pose(g["tool"], "geometry.tool", source));
    if (g.contains("absorb_rigid_part")) {
      if (!g["absorb_rigid_part"].is_boolean()) json_fail(source, "geometry.absorb_rigid_part", "expected true or false");
      c.absorb_rigid_part = g["absorb_rigid_part"].get<bool>();
    }
  }
  if (j.contains("tool_offset_mm")) {
    const auto a = json_array<3>(j["tool_offset_mm"], "tool_offset_mm", source);
    c.tool_offset_mm = Eigen::Vector3d(a[0], a[1], a[2]);
  }
  if (j.contains("compliance")) {
    const auto& g = j["compliance"];
    json_check_keys(g, {"stiffness_nm_per_rad", "link_mass_kg", "mass_offset_mm", "payload_kg", "gravity_world"}, "compliance.", source);
    if (g.contains("mass_offset_mm")) {
      if (!g["mass_offset_mm"].is_array() || g["mass_offset_mm"].size() != kJointCount)
        throw InputError(source + ": member \"compliance.mass_offset_mm\": expected 6 arrays of 3 numbers (mm)", source);
      for (std::size_t k = 0; k < kJointCount; ++k)
        c.compliance.mass_offset_mm[k] = json_array<3>(g["mass_offset_mm"][k], "compliance.mass_offset_mm[" + std::to_string(k) + "]", source);
    }
    if (g.contains("stiffness_nm_per_rad"))
      c.compliance.stiffness_nm_per_rad = json_array<6>(g["stiffness_nm_per_rad"], "compliance.stiffness_nm_per_rad", source);
    if (g.contains("link_mass_kg"))
      c.compliance.link_mass_kg = json_array<6>(g["link_mass_kg"], "compliance.link_mass_kg", source);
    if (g.contains("payload_kg")) c.compliance.payload_kg = json_number(g, "payload_kg", "compliance.", source, nullptr);
    if (g.contains("gravity_world")) {
      const auto a = json_array<3>(g["gravity_world"], "compliance.gravity_world", source);
      c.compliance.gravity_world = Eigen::Vector3d(a[0], a[1], a[2]);
    }
  }
  if (j.contains("transmission")) {
    const auto& g = j["transmission"];
    json_check_keys(g, {"amplitude_deg", "harmonic", "phase_deg"}, "transmission.", source);
    if (g.contains("amplitude_deg"))
      c.transmission.amplitude_deg = json_array<6>(g["amplitude_deg"], "transmission.amplitude_deg", source);
    if (g.contains("harmonic")) c.transmission.harmonic = json_array<6>(g["harmonic"], "transmission.harmonic", source);
    if (g.contains("phase_deg")) c.transmission.phase_deg = json_array<6>(g["phase_deg"], "transmission.phase_deg", source);
  }
  if (j.contains("end_range")) {
    const auto& g = j["end_range"];
    json_check_keys(g, {"onset_deg", "error_at_limit_deg"}, "end_range.", source);
    if (g.contains("onset_deg")) c.end_range.onset_deg = json_array<6>(g["onset_deg"], "end_range.onset_deg", source);
    if (g.contains("error_at_limit_deg"))
      c.end_range.error_at_limit_deg = json_array<6>(g["error_at_limit_deg"], "end_range.error_at_limit_deg", source);
  }
  if (j.contains("repeatability_sigma_mm"))
    c.repeatability_sigma_mm = json_number(j, "repeatability_sigma_mm", "", source, nullptr);
  if (j.contains("tracker")) {
    const auto& g = j["tracker"];
    json_check_keys(g, {"tracker_from_world", "sigma_constant_mm", "sigma_per_m_mm"}, "tracker.", source);
    if (g.contains("tracker_from_world"))
      c.tracker.tracker_from_world = json_pose(g["tracker_from_world"], "tracker.tracker_from_world", source);
    if (g.contains("sigma_constant_mm"))
      c.tracker.sigma_constant_mm = json_number(g, "sigma_constant_mm", "tracker.", source, nullptr);
    if (g.contains("sigma_per_m_mm")) c.tracker.sigma_per_m_mm = json_number(g, "sigma_per_m_mm", "tracker.", source, nullptr);
  }
  try {
    c.validate();
  } catch (const ArgumentError& e) {
    throw InputError(source + ": " + e.what(), source);
  }
  return c;
}

SimulatorConfig SimulatorConfig::load(const std::string& path) {
  return with_json_source(path, [&] { return from_json(read_json_file(path, "simulation JSON"), path); });
}

nlohmann::json SimulatorConfig::to_json() const {
  nlohmann::json links = nlohmann::json::array();
  for (const auto& d : geometry.link)
    links.push_back({{"alpha_deg", d[0]}, {"a_mm", d[1]}, {"theta0_deg", d[2]}, {"d_mm", d[3]}, {"beta_deg", d[4]}});
  return {
      {"comment", "errfield simulation configuration (SIMULATED robot and tracker); docs/robot.md"},
      {"seed", seed},
      {"robot", nominal.to_json()},
      {"geometry", {{"links", links}, {"tool", detail::pose_json(to_isometry(geometry.tool))},
                    {"absorb_rigid_part", absorb_rigid_part}}},
      {"tool_offset_mm", {tool_offset_mm.x(), tool_offset_mm.y(), tool_offset_mm.z()}},
      {"compliance",
       {{"stiffness_nm_per_rad", compliance.stiffness_nm_per_rad},
        {"link_mass_kg", compliance.link_mass_kg},
        {"mass_offset_mm", compliance.mass_offset_mm},
        {"payload_kg", compliance.payload_kg},
        {"gravity_world", {compliance.gravity_world.x(), compliance.gravity_world.y(), compliance.gravity_world.z()}}}},
      {"transmission",
       {{"amplitude_deg", transmission.amplitude_deg},
        {"harmonic", transmission.harmonic},
        {"phase_deg", transmission.phase_deg}}},
      {"end_range", {{"onset_deg", end_range.onset_deg}, {"error_at_limit_deg", end_range.error_at_limit_deg}}},
      {"repeatability_sigma_mm", repeatability_sigma_mm},
      {"tracker",
       {{"tracker_from_world", detail::pose_json(tracker.tracker_from_world)},
        {"sigma_constant_mm", tracker.sigma_constant_mm},
        {"sigma_per_m_mm", tracker.sigma_per_m_mm}}},
  };
}

// ---- the simulated robot -----------------------------------------------------------------------

SimulatedRobot::SimulatedRobot(const SimulatorConfig& config)
    : config_(config), true_geometry_(apply_deviation(config.nominal, config.geometry)) {
  config_.validate();
  if (config_.absorb_rigid_part) {
    // Sample configurations over the joint ranges (clipped to ±120° so folded poses do not
    // dominate), with a fixed internal seed: the absorbed motion is a property of the robot, not of
    // the measurement stream.
    SimulationRng rng(0x5eed'ba5eULL);
    std::vector<Eigen::Vector3d> truth, nominal;
    for (int k = 0; k < 400; ++k) {
      JointVector q;
      for (int i = 0; i < kJointCount; ++i) {
        const MdhLink& l = config_.nominal.link(i);
        q[i] = rng.uniform(std::max(l.q_min_deg, -120.0), std::min(l.q_max_deg, 120.0));
      }
      truth.push_back(forward_position(true_geometry_, q));
      nominal.push_back(forward_position(config_.nominal, q));
    }
    const Eigen::Isometry3d fix = fit_rigid(truth, nominal);
    true_geometry_ = true_geometry_.with_base(fix * true_geometry_.base());
  }
  if (!config_.tool_offset_mm.isZero())
    true_geometry_ = true_geometry_.with_tool(true_geometry_.tool() * Eigen::Translation3d(config_.tool_offset_mm));
}

JointVector SimulatedRobot::joint_deflection_deg(const JointVector& q_cmd_deg) const {
  JointVector dq = JointVector::Zero();
  const ComplianceModel& c = config_.compliance;
  KinematicFrames f;
  forward_kinematics_all(true_geometry_, q_cmd_deg, f);
  // Point masses: link i halfway between frame i and frame i+1 origins (link 6: 50 mm past the
  // flange), payload at the tool point. Forces in N, lever arms in m.
  std::array<Eigen::Vector3d, kJointCount + 1> point;
  std::array<double, kJointCount + 1> mass;
  for (int i = 0; i < kJointCount; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const Eigen::Vector3d o = f.frames[k + 1].translation();
    point[k] = i + 1 < kJointCount ? Eigen::Vector3d(0.5 * (o + f.frames[k + 2].translation()))
                                   : Eigen::Vector3d(o + 50.0 * f.frames[k + 1].linear().col(2));
    point[k] += f.frames[k + 1].linear() * Eigen::Vector3d(c.mass_offset_mm[k][0], c.mass_offset_mm[k][1], c.mass_offset_mm[k][2]);
    mass[k] = c.link_mass_kg[k];
  }
  point[kJointCount] = f.tool().translation();
  mass[kJointCount] = c.payload_kg;
  for (int j = 0; j < kJointCount; ++j) {
    const auto k = static_cast<std::size_t>(j);
    if (c.stiffness_nm_per_rad[k] <= 0) continue;
    const Eigen::Vector3d z = f.frames[k + 1].linear().col(2);
    const Eigen::Vector3d o = f.frames[k + 1].translation();
    double torque = 0.0;  // N·m about +z_j
    for (std::size_t b = k; b < point.size(); ++b)
      torque += z.dot(((point[b] - o) * 1e-3).cross(mass[b] * c.gravity_world));
    dq[j] += torque / c.stiffness_nm_per_rad[k] / kDeg;
  }
  const TransmissionErrorModel& t = config_.transmission;
  for (int j = 0; j < kJointCount; ++j) {
    const auto k = static_cast<std::size_t>(j);
    dq[j] += t.amplitude_deg[k] * std::sin(t.harmonic[k] * q_cmd_deg[j] * kDeg + t.phase_deg[k] * kDeg);
  }
  const EndRangeErrorModel& e = config_.end_range;
  for (int j = 0; j < kJointCount; ++j) {
    const auto k = static_cast<std::size_t>(j);
    const double q = q_cmd_deg[j], onset = e.onset_deg[k];
    const double limit = q >= 0 ? config_.nominal.link(j).q_max_deg : -config_.nominal.link(j).q_min_deg;
    if (e.error_at_limit_deg[k] == 0.0 || std::abs(q) <= onset || limit <= onset) continue;
    const double t = (std::abs(q) - onset) / (limit - onset);
    dq[j] += (q >= 0 ? 1.0 : -1.0) * e.error_at_limit_deg[k] * t * t;
  }
  return dq;
}

Eigen::Isometry3d SimulatedRobot::true_pose(const JointVector& q_cmd_deg, EndFrame frame) const {
  return forward_kinematics(true_geometry_, q_cmd_deg + joint_deflection_deg(q_cmd_deg), frame);
}

Eigen::Vector3d SimulatedRobot::move(const JointVector& q_cmd_deg, SimulationRng& rng) const {
  const double s = config_.repeatability_sigma_mm;
  return true_position(q_cmd_deg) + Eigen::Vector3d(rng.normal(0, s), rng.normal(0, s), rng.normal(0, s));
}

Eigen::Vector3d SimulatedRobot::measure(const Eigen::Vector3d& world_mm, SimulationRng& rng) const {
  const Eigen::Vector3d p = config_.tracker.tracker_from_world * world_mm;
  const double s = config_.tracker.sigma_constant_mm + config_.tracker.sigma_per_m_mm * p.norm() * 1e-3;
  return p + Eigen::Vector3d(rng.normal(0, s), rng.normal(0, s), rng.normal(0, s));
}

double SimulatedRobot::measure_distance(const Eigen::Vector3d& a_world_mm, const Eigen::Vector3d& b_world_mm,
                                        SimulationRng& rng) const {
  return (measure(a_world_mm, rng) - measure(b_world_mm, rng)).norm();
}

// ---- the paper's set-up ------------------------------------------------------------------------

Eigen::Isometry3d paper_tool() { return from_six(paper::kToolOffset); }
Eigen::Isometry3d paper_ball() { return from_six(paper::kBallOffset); }

std::vector<Eigen::Vector3d> MeasurementCube::grid(double step_mm) const {
  const double cells = size_mm / step_mm;
  const int n = static_cast<int>(std::lround(cells));
  if (!(step_mm > 0) || n < 1 || std::abs(cells - n) > 1e-9)
    throw ArgumentError("MeasurementCube::grid: step " + std::to_string(step_mm) + " mm does not divide the cube size " +
                        std::to_string(size_mm) + " mm");
  check_cube_budget(size_mm, step_mm, false, "MeasurementCube::grid: step");
  std::vector<Eigen::Vector3d> out;
  out.reserve(static_cast<std::size_t>(n + 1) * static_cast<std::size_t>(n + 1) * static_cast<std::size_t>(n + 1));
  for (int k = 0; k <= n; ++k)
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) out.push_back(min_corner_mm + step_mm * Eigen::Vector3d(i, j, k));
  return out;
}

std::vector<Eigen::Vector3d> MeasurementCube::random_per_cell(double step_mm, SimulationRng& rng) const {
  const int n = static_cast<int>(std::lround(size_mm / step_mm));
  if (!(step_mm > 0) || n < 1 || std::abs(size_mm / step_mm - n) > 1e-9)
    throw ArgumentError("MeasurementCube::random_per_cell: step " + std::to_string(step_mm) +
                        " mm does not divide the cube size " + std::to_string(size_mm) + " mm");
  check_cube_budget(size_mm, step_mm, false, "MeasurementCube::random_per_cell: step");
  std::vector<Eigen::Vector3d> out;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const double x = rng.uniform01(), y = rng.uniform01(), z = rng.uniform01();
        out.push_back(min_corner_mm + step_mm * Eigen::Vector3d(i + x, j + y, k + z));
      }
  return out;
}

MeasurementCube paper_cube() {
  MeasurementCube c;
  c.min_corner_mm = Eigen::Vector3d(750.0, -250.0, 350.0);
  c.size_mm = paper::kCubeSideMm;
  c.orientation = rotation_from_rpy_deg(180.0, 0.0, 0.0);
  return c;
}

Eigen::Vector3d paper_base_point_nominal() { return paper_cube().min_corner_mm; }

IkResult cube_seed(const MdhModel& model, const MeasurementCube& cube) {
  return inverse_kinematics_multistart(model, cube.pose(cube.center()));
}

IkResult solve_cube_pose(const MdhModel& model, const MeasurementCube& cube, const Eigen::Vector3d& p,
                         const JointVector& seed_deg) {
  return inverse_kinematics(model, cube.pose(p), seed_deg);
}

}  // namespace errfield::robot
