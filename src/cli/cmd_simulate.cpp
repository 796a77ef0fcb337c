// `errfield simulate`: measurement files from the simulated robot and laser tracker, in the
// columns `errfield calibrate` (and the pipeline's `fit`) read. Every file says it is SIMULATED.

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <tuple>

#include <nlohmann/json.hpp>

#include "cli/cli_support.hpp"
#include "cli/command_registry.hpp"
#include "cli/pipeline_cli.hpp"
#include "cli/robot_cli.hpp"
#include "errfield/error.hpp"
#include "errfield/robot/builtin_robots.hpp"
#include "errfield/robot/cube_budget.hpp"
#include "errfield/robot/pose.hpp"
#include "errfield/robot/simulated_data.hpp"
#include "errfield/robot/simulator.hpp"

namespace errfield::cli {
namespace {

struct SimulateArgs {
  std::string config, robot, joints, cube, orientation, sample = "grid", out, truth_out, config_out, robot_out,
      joint_box, tool_offset, outliers, reflectors, probe;
  double probe_noise_mdeg = 10.0;
  double orientation_spread = 0.0;
  int joint_decimals = -1;
  std::vector<std::string> bases, fixed_bases;
  double step = 125.0;
  long long seed = -1;
  std::string measure = "both";
  bool truth_columns = false;
  std::string systematic = "config";
  double compliance_mrad_per_knm = -1.0;  // < 0: as --systematic left it
  std::string mass_offset;                // "X,Y,Z" mm; empty: as the config left it
  std::vector<std::string> end_range_errors;
};

double parse_number(const std::string& text, const std::string& what) {
  try {
    std::size_t used = 0;
    const double v = std::stod(text, &used);
    if (used != text.size() || !std::isfinite(v)) throw std::invalid_argument("trailing");
    return v;
  } catch (const std::exception&) {
    throw ArgumentError(what + ": '" + text + "' is not a number");
  }
}

Eigen::Vector3d parse_vec3(const std::string& text, const std::string& what) {
  const auto items = split_list(text, what);
  if (items.size() != 3) throw ArgumentError(what + ": expected X,Y,Z, got '" + text + "'");
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) {
    try {
      std::size_t used = 0;
      v[i] = std::stod(items[static_cast<std::size_t>(i)], &used);
      if (used != items[static_cast<std::size_t>(i)].size()) throw std::invalid_argument("trailing");
    } catch (const std::exception&) {
      throw ArgumentError(what + ": '" + items[static_cast<std::size_t>(i)] + "' is not a number");
    }
  }
  return v;
}

// "A:B" -> (A, B) as numbers, for --outliers FRACTION:MM.
std::pair<double, double> parse_pair(const std::string& text, const std::string& what) {
  const auto colon = text.find(':');
  if (colon == std::string::npos) throw ArgumentError(what + ": expected FRACTION:MM, got '" + text + "'");
  return {parse_number(text.substr(0, colon), what + " FRACTION"), parse_number(text.substr(colon + 1), what + " MM")};
}

// --reflectors "X1,Y1,Z1;X2,Y2,Z2;...": points on the flange (flange frame, mm), labelled r1, r2, ...
std::vector<Eigen::Vector3d> parse_reflectors(const std::string& text) {
  std::vector<Eigen::Vector3d> out;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find(';', start), text.size());
    const std::string item = text.substr(start, end - start);
    const std::string what = "--reflectors (reflector " + std::to_string(out.size() + 1) + ")";
    const Eigen::Vector3d v = parse_vec3(item, what);
    // As --tool-offset: a point on the flange, not 10 m away.
    if (!(v.norm() <= 1e4)) throw ArgumentError(what + ": '" + item + "' is " + format_number(v.norm()) + " mm from the flange; expected at most 10000 mm");
    out.push_back(v);
    start = end + 1;
  }
  if (out.size() < 2)
    throw ArgumentError("--reflectors: expected at least two points X1,Y1,Z1;X2,Y2,Z2 (flange frame, mm), got '" + text + "'");
  return out;
}

// Streams of their own for the offset and the outliers, so that switching them on leaves every
// other number of the file as it was (tests compare with and without).
constexpr std::uint64_t kToolOffsetStream = 0x7001'0FF5'E7ULL, kOutlierStream = 0x0071'1E55ULL;

// --systematic realistic: effects a kinematic model cannot express, of the size seen on real arms
// and concentrated at the workspace extremes (docs/robot.md, "Systematic effects"): a softer
// shoulder and elbow (1 mrad per kN·m: ~0.7 mrad at full reach of a 20 kg arm), end-of-travel
// errors on q1 (dress-pack drag beyond 110 deg, 0.3 deg at the limit) and q5 (wrist hose beyond
// 95 deg, 1.5 deg at the limit), and half the config's cyclic transmission error. Why these: with
// them a fit of 280 scattered KR 16 poses reproduces what real tracker data of a 6-axis arm showed
// (issue 19): a smooth field the kriging learns (leave-one-out ~0.1 mm, real data 0.07-0.09 mm),
// and rows at |q1| > 110 deg or |q5| > 95 deg whose residual after calibration is beyond 5 robust
// sigma though they are no outliers. The config's full cyclic error alone leaves 0.13 mm that no
// method learns at such densities (0.43 mm at twice it), more than real data leave.
constexpr double kRealisticComplianceMradPerKnm = 1.0;
constexpr double kRealisticCyclicScale = 0.5;
constexpr double kRealisticQ1OnsetDeg = 110.0, kRealisticQ1ErrorDeg = 0.3;
constexpr double kRealisticQ5OnsetDeg = 95.0, kRealisticQ5ErrorDeg = 1.5;

// Joints 2 and 3 (shoulder, elbow) carry the arm's weight: their compliance is what --compliance sets.
void set_shoulder_elbow_compliance(robot::SimulatorConfig& config, double mrad_per_knm) {
  // mrad/(kN·m) = 1e-6 rad/(N·m); stiffness is its inverse; 0 = rigid.
  const double stiffness = mrad_per_knm > 0 ? 1e6 / mrad_per_knm : 0.0;
  config.compliance.stiffness_nm_per_rad[1] = stiffness;
  config.compliance.stiffness_nm_per_rad[2] = stiffness;
}

// --systematic and its refinements --compliance and --end-range-error, applied to the config.
// Returns a description for the file's SIMULATED header (empty: the config's effects untouched).
std::string apply_systematic_effects(robot::SimulatorConfig& config, const std::string& preset,
                                     double compliance_mrad_per_knm, const std::vector<std::string>& end_range,
                                     const std::string& mass_offset) {
  std::string said;
  if (preset == "none") {
    config.compliance.stiffness_nm_per_rad.fill(0.0);
    config.transmission.amplitude_deg.fill(0.0);
    config.end_range = {};
    said = " no systematic joint effects (rigid joints, no transmission error: geometry only);";
  } else if (preset == "realistic") {
    set_shoulder_elbow_compliance(config, kRealisticComplianceMradPerKnm);
    for (double& amplitude : config.transmission.amplitude_deg) amplitude *= kRealisticCyclicScale;
    config.end_range.onset_deg[0] = kRealisticQ1OnsetDeg;
    config.end_range.error_at_limit_deg[0] = kRealisticQ1ErrorDeg;
    config.end_range.onset_deg[4] = kRealisticQ5OnsetDeg;
    config.end_range.error_at_limit_deg[4] = kRealisticQ5ErrorDeg;
    said = " realistic systematic effects (joints 2-3 compliance " + format_number(kRealisticComplianceMradPerKnm) +
           " mrad/kNm under gravity, " + format_number(kRealisticCyclicScale) +
           " x the config's cyclic transmission error, end-of-travel errors on q1 beyond " +
           format_number(kRealisticQ1OnsetDeg) + " deg and q5 beyond " + format_number(kRealisticQ5OnsetDeg) + " deg);";
  } else if (preset != "config") {
    throw ArgumentError("--systematic: expected config, none or realistic, got '" + preset + "'");
  }
  if (compliance_mrad_per_knm >= 0) {
    if (!std::isfinite(compliance_mrad_per_knm))
      throw ArgumentError("--compliance: expected a finite value >= 0 (mrad/kNm), got " +
                          format_number(compliance_mrad_per_knm));
    set_shoulder_elbow_compliance(config, compliance_mrad_per_knm);
    said += " joints 2-3 compliance " + format_number(compliance_mrad_per_knm) + " mrad/kNm under gravity;";
  }
  if (!mass_offset.empty()) {
    const std::vector<double> v = parse_numbers(mass_offset, 3, "--mass-offset");
    for (auto& offset : config.compliance.mass_offset_mm) offset = {v[0], v[1], v[2]};
    said += " link masses " + mass_offset + " mm off the frame origins' lines (link frames);";
  }
  for (const std::string& item : end_range) {
    // qJ:ONSET_DEG:ERROR_DEG
    const auto first = item.find(':'), second = item.find(':', first == std::string::npos ? first : first + 1);
    if (first == std::string::npos || second == std::string::npos || item.size() < 3 || item[0] != 'q' ||
        first != 2 || item[1] < '1' || item[1] > '6')
      throw ArgumentError("--end-range-error: expected qJ:ONSET_DEG:ERROR_DEG with J in 1..6 (e.g. q1:90:0.1), got '" +
                          item + "'");
    const auto k = static_cast<std::size_t>(item[1] - '1');
    const double onset = parse_number(item.substr(first + 1, second - first - 1), "--end-range-error ONSET_DEG");
    const double error = parse_number(item.substr(second + 1), "--end-range-error ERROR_DEG");
    const robot::MdhLink& l = config.nominal.link(static_cast<int>(k));
    if (!(onset >= 0) || !(onset < std::max(l.q_max_deg, -l.q_min_deg)))
      throw ArgumentError("--end-range-error " + item + ": ONSET_DEG must be >= 0 and below the joint's limit (" +
                          format_number(std::max(l.q_max_deg, -l.q_min_deg)) + " deg for " + item.substr(0, 2) +
                          " of robot '" + config.nominal.name() + "')");
    config.end_range.onset_deg[k] = onset;
    config.end_range.error_at_limit_deg[k] = error;
    said += " " + item.substr(0, 2) + " error growing beyond |" + item.substr(0, 2) + "| = " + format_number(onset) +
            " deg to " + format_number(error) + " deg at the limit;";
  }
  return said;
}

// The simulation the options describe: --config (or the paper's) with --robot and --seed over it.
struct SimulationBase {
  robot::SimulatorConfig config;
  const robot::BuiltinRobot* builtin = nullptr;  // --robot NAME: its cube is the default region
};

SimulationBase load_simulation(const SimulateArgs& a) {
  using namespace robot;
  SimulationBase s{a.config.empty() ? SimulatorConfig::paper_default() : SimulatorConfig::load(a.config)};
  if (!a.robot.empty()) {
    s.config.nominal = load_robot_or_default(a.robot);
    s.builtin = builtin_robot_unless_file(a.robot);
  }
  if (a.seed >= 0) s.config.seed = static_cast<std::uint64_t>(a.seed);
  return s;
}

// What the tracker reads at each visit: --measure, --outliers, --reflectors, --probe.
struct ReadingOptions {
  bool want_positions = true, want_distances = true;
  double outlier_fraction = 0.0, outlier_mm = 0.0;
  std::vector<Eigen::Vector3d> reflectors;
  std::optional<Eigen::Isometry3d> probe;
};

// --measure, --joint-decimals and --orientation-spread, refused before any file is read.
ReadingOptions check_recording_options(const SimulateArgs& a) {
  if (a.measure != "positions" && a.measure != "distances" && a.measure != "both")
    throw ArgumentError("--measure: expected positions, distances or both, got '" + a.measure + "'");
  ReadingOptions r;
  r.want_positions = a.measure != "distances";
  r.want_distances = a.measure != "positions";
  if (a.joint_decimals != -1 && (a.joint_decimals < 0 || a.joint_decimals > 12))
    throw ArgumentError("--joint-decimals: expected 0..12, got " + std::to_string(a.joint_decimals));
  if (!(a.orientation_spread >= 0.0 && a.orientation_spread <= 90.0))
    throw ArgumentError("--orientation-spread: expected 0..90 deg, got " + format_number(a.orientation_spread));
  return r;
}

// The unknown tool offset: the true tool point is the nominal one moved by this (nominal tool frame, mm).
void apply_tool_offset(const SimulateArgs& a, robot::SimulatorConfig& config) {
  using namespace robot;
  if (a.tool_offset.empty()) return;
  Eigen::Vector3d tool_offset = Eigen::Vector3d::Zero();
  if (a.tool_offset.rfind("random:", 0) == 0) {
    const double mm = parse_number(a.tool_offset.substr(7), "--tool-offset random:MM");
    if (!(mm >= 0)) throw ArgumentError("--tool-offset random:MM needs MM >= 0, got '" + a.tool_offset + "'");
    SimulationRng offset_rng(config.seed ^ kToolOffsetStream);
    tool_offset = mm * random_unit_vector(offset_rng);
  } else {
    tool_offset = parse_vec3(a.tool_offset, "--tool-offset");
  }
  // Beyond a 10 m tool the simulated positions are no robot's, and at ~1e150 mm squared distances
  // overflow into "computed value is -inf" half-way through the job: refuse the option instead.
  constexpr double kMaxToolOffset_mm = 1e4;
  if (!(tool_offset.norm() <= kMaxToolOffset_mm))
    throw ArgumentError("--tool-offset: '" + a.tool_offset + "' moves the tool point " +
                        format_number(tool_offset.norm()) + " mm; expected at most " +
                        format_number(kMaxToolOffset_mm) + " mm (a tool of at most 10 m)");
  config.tool_offset_mm += tool_offset;
}

void read_outliers(const SimulateArgs& a, ReadingOptions& r) {
  if (a.outliers.empty()) return;
  std::tie(r.outlier_fraction, r.outlier_mm) = parse_pair(a.outliers, "--outliers");
  // A gross outlier is a reading off by up to a reflector's knock or a beam break: metres at
  // most. 10 m (the --tool-offset ceiling) bounds it far above that and keeps every derived
  // number (distances, squared errors) finite: 1e300 overflowed later, exit 1 with no option named.
  constexpr double kMaxOutlier_mm = 1e4;
  if (!(r.outlier_fraction >= 0 && r.outlier_fraction <= 1) || !(r.outlier_mm > 0) || !(r.outlier_mm <= kMaxOutlier_mm))
    throw ArgumentError("--outliers: expected FRACTION in [0, 1] and MM in (0, " + format_number(kMaxOutlier_mm) +
                        "] (a gross outlier of at most 10 m), got '" + a.outliers + "'");
}

// --reflectors and --probe: the points on the flange the tracker reads instead of the tool point.
void read_flange_points(const SimulateArgs& a, ReadingOptions& r) {
  if (!a.reflectors.empty()) {
    r.reflectors = parse_reflectors(a.reflectors);
    if (r.want_distances)
      throw ArgumentError("--reflectors: only with --measure positions (distances to base points from several "
                          "reflectors are not simulated)");
  }
  // --probe X,Y,Z,RX,RY,RZ: a 6-DoF probe on the flange (flange frame, mm and deg).
  if (!a.probe.empty()) {
    const std::vector<double> v = parse_numbers(a.probe, 6, "--probe");
    r.probe = robot::to_isometry({v[0], v[1], v[2], v[3], v[4], v[5]});
    if (!r.reflectors.empty()) throw ArgumentError("--probe and --reflectors: give one (a probe is read as one point with an orientation)");
    if (r.want_distances)
      throw ArgumentError("--probe: only with --measure positions (a probe's orientation has no distance to a base point)");
    if (r.probe->translation().norm() > 2000.0)
      throw ArgumentError("--probe: the probe point " + a.probe + " is over 2 m from the flange (mm expected)");
  }
  if (!(a.probe_noise_mdeg >= 0.0 && a.probe_noise_mdeg <= 1e4))
    throw ArgumentError("--probe-noise: expected 0 to 10000 mdeg, got " + format_number(a.probe_noise_mdeg));
}

// The region: --cube, else the built-in robot's own cube, else the paper's.
robot::MeasurementCube simulation_cube(const SimulateArgs& a, const robot::BuiltinRobot* builtin) {
  using namespace robot;
  MeasurementCube cube = paper_cube();
  if (builtin) {
    cube.min_corner_mm = builtin->cube_min_mm;
    cube.size_mm = builtin->cube_size_mm;
    cube.orientation = rotation_from_rpy_deg(builtin->cube_rpy_deg.x(), builtin->cube_rpy_deg.y(), builtin->cube_rpy_deg.z());
  }
  if (!a.cube.empty()) {
    const auto items = split_list(a.cube, "--cube");
    if (items.size() != 4) throw ArgumentError("--cube: expected X0,Y0,Z0,SIZE (mm), got '" + a.cube + "'");
    cube.min_corner_mm = parse_vec3(items[0] + "," + items[1] + "," + items[2], "--cube");
    cube.size_mm = parse_number(items[3], "--cube SIZE");
    if (!(cube.size_mm > 0)) throw ArgumentError("--cube: SIZE must be > 0, got '" + items[3] + "'");
  }
  if (!a.orientation.empty()) {
    const Eigen::Vector3d rpy = parse_vec3(a.orientation, "--orientation");
    cube.orientation = rotation_from_rpy_deg(rpy.x(), rpy.y(), rpy.z());
  }
  return cube;
}

struct PoseRow {
  std::string id, kind;
  robot::JointVector q;
};

// The poses to visit: bases first (the paper's reference is measured before the targets), then targets.
struct SimulatedPoses {
  std::vector<PoseRow> rows;
  std::vector<Eigen::Vector3d> base_nominal;  // --base: robot positions, one base row each
  // --fixed-base: points in the cell (e.g. tracker nests), not carried by the robot; the tracker
  // measures each once (one reading shared by all its distances), no base rows.
  std::vector<Eigen::Vector3d> fixed;
  bool scattered = false;
};

// IK of cube points on one branch, the one of the cube centre's solution (the seed), so that the
// poses of a file do not flip elbow or wrist between neighbours.
class BranchSolver {
 public:
  BranchSolver(const robot::MdhModel& nominal, const robot::MeasurementCube& cube)
      : nominal_(nominal), cube_(cube), seed_(cube_seed(nominal, cube)) {}

  void check_seed() const {
    if (!seed_.ok())
      throw ArgumentError("the cube centre " + std::to_string(cube_.center().x()) + "," +
                          std::to_string(cube_.center().y()) + "," + std::to_string(cube_.center().z()) +
                          " is not reachable at the requested orientation (" + to_string(seed_.status) +
                          "); give a --cube (and --orientation) inside the reach of robot '" + nominal_.name() +
                          "'");
  }
  // Nothing when unreachable or when IK left the branch (a joint moved by more than 120 deg from
  // the seed: an elbow or wrist flip).
  std::optional<robot::JointVector> try_solve(const Eigen::Isometry3d& pose) const {
    const robot::IkResult r = inverse_kinematics(nominal_, pose, seed_.q_deg);
    if (!r.ok() || (r.q_deg - seed_.q_deg).cwiseAbs().maxCoeff() > 120.0) return std::nullopt;
    return r.q_deg;
  }
  robot::JointVector solve(const Eigen::Vector3d& p, const std::string& id) const {
    check_seed();
    const robot::IkResult r = solve_cube_pose(nominal_, cube_, p, seed_.q_deg);
    if (!r.ok()) {
      std::ostringstream s;
      s << "point " << id << " (" << p.transpose() << ") is not reachable at the requested orientation: "
        << to_string(r.status) << ", residual " << r.position_residual_mm << " mm";
      throw ArgumentError(s.str());
    }
    return r.q_deg;
  }

 private:
  const robot::MdhModel& nominal_;
  const robot::MeasurementCube& cube_;
  robot::IkResult seed_;
};

// Targets from --joints: the commanded joints as they are, within the robot's limits.
void add_joint_file_rows(const SimulateArgs& a, const robot::MdhModel& nominal, std::vector<PoseRow>& rows) {
  const CsvTable table = CsvTable::read(a.joints);
  const auto q = read_joint_columns(table);
  for (std::size_t i = 0; i < q.size(); ++i) {
    if (!nominal.within_limits(q[i]))
      throw InputError(a.joints + ":" + std::to_string(table.line_of_row(i)) + ": joints outside the robot's limits",
                       a.joints, table.line_of_row(i), "q1");
    rows.push_back({"p" + std::to_string(i), "target", q[i]});
  }
}

// --sample random:N or scattered:N: N >= 1, checked against the point budget before the cast (1e12 must not wrap).
int sample_count(const SimulateArgs& a, std::size_t prefix) {
  const std::string what = "--sample " + a.sample.substr(0, prefix) + "N";
  const double nd = parse_number(a.sample.substr(prefix), what);
  robot::check_point_budget(nd, "--sample " + a.sample);
  const int n = static_cast<int>(nd);
  if (n < 1 || n != nd) throw ArgumentError(what + " needs N >= 1, got '" + a.sample + "'");
  return n;
}

// Joints uniform in a box: poses wherever those joints put the tool, any orientation.
void add_joint_box_rows(const SimulateArgs& a, const robot::MdhModel& nominal, int n, robot::SimulationRng& rng,
                        std::vector<PoseRow>& rows) {
  using namespace robot;
  const auto v = parse_numbers(a.joint_box, 12, "--joint-box");
  JointVector lo, hi;
  for (int j = 0; j < kJointCount; ++j) {
    lo[j] = v[static_cast<std::size_t>(2 * j)];
    hi[j] = v[static_cast<std::size_t>(2 * j + 1)];
    if (!(lo[j] <= hi[j]) || lo[j] < nominal.link(j).q_min_deg || hi[j] > nominal.link(j).q_max_deg)
      throw ArgumentError("--joint-box: q" + std::to_string(j + 1) + " [" + format_number(lo[j]) + ", " +
                          format_number(hi[j]) + "] must be ordered and within the joint limits [" +
                          format_number(nominal.link(j).q_min_deg) + ", " +
                          format_number(nominal.link(j).q_max_deg) + "] of robot '" + nominal.name() + "'");
  }
  for (int i = 0; i < n; ++i) rows.push_back({"p" + std::to_string(i), "target", random_joints_in_box(lo, hi, rng)});
}

// Positions uniform in the cube, orientations within the cone; poses that are unreachable (or
// reachable only on another branch) are drawn again.
void add_scattered_cube_rows(const SimulateArgs& a, const BranchSolver& solver, const robot::MeasurementCube& cube,
                             int n, robot::SimulationRng& rng, std::vector<PoseRow>& rows) {
  solver.check_seed();
  long attempts = 0;
  for (int i = 0; i < n;) {
    if (++attempts > 20L * n + 100)
      throw ArgumentError("--sample " + a.sample + ": too many poses in the cube are unreachable at orientation "
                          "spread " + format_number(a.orientation_spread) + " deg (" + std::to_string(i) +
                          " of " + std::to_string(n) + " found); use a smaller --cube or --orientation-spread");
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() =
        cube.min_corner_mm + cube.size_mm * Eigen::Vector3d(rng.uniform01(), rng.uniform01(), rng.uniform01());
    pose.linear() = robot::random_orientation_in_cone(cube.orientation, a.orientation_spread, rng);
    if (const auto q = solver.try_solve(pose)) {
      rows.push_back({"p" + std::to_string(i), "target", *q});
      ++i;
    }
  }
}

// --sample grid, cells or random:N: the target points in the cube.
std::vector<Eigen::Vector3d> cube_points(const SimulateArgs& a, const robot::MeasurementCube& cube,
                                         robot::SimulationRng& rng) {
  std::vector<Eigen::Vector3d> pts;
  if (a.sample == "grid" || a.sample == "cells") robot::check_cube_budget(cube.size_mm, a.step, false, "--step");
  if (a.sample == "grid") {
    naming_options([&] { pts = cube.grid(a.step); }, {{"MeasurementCube::grid: step", "--step"}});
  } else if (a.sample == "cells") {
    naming_options([&] { pts = cube.random_per_cell(a.step, rng); },
                   {{"MeasurementCube::random_per_cell: step", "--step"}});
  } else if (a.sample.rfind("random:", 0) == 0) {
    const int n = sample_count(a, 7);
    for (int i = 0; i < n; ++i)
      pts.push_back(cube.min_corner_mm + cube.size_mm * Eigen::Vector3d(rng.uniform01(), rng.uniform01(), rng.uniform01()));
  } else {
    throw ArgumentError("--sample: expected grid, cells, random:N or scattered:N, got '" + a.sample + "'");
  }
  return pts;
}

// Each cube point at the cube's orientation, or at one drawn within --orientation-spread (up to 50 tries).
void add_cube_point_rows(const SimulateArgs& a, const BranchSolver& solver, const robot::MeasurementCube& cube,
                         robot::SimulationRng& rng, std::vector<PoseRow>& rows) {
  const std::vector<Eigen::Vector3d> pts = cube_points(a, cube, rng);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const std::string id = "p" + std::to_string(i);
    if (a.orientation_spread == 0.0) {
      rows.push_back({id, "target", solver.solve(pts[i], id)});
      continue;
    }
    solver.check_seed();
    Eigen::Isometry3d pose = cube.pose(pts[i]);
    std::optional<robot::JointVector> q;
    for (int tries = 0; tries < 50 && !q; ++tries) {
      pose.linear() = robot::random_orientation_in_cone(cube.orientation, a.orientation_spread, rng);
      q = solver.try_solve(pose);
    }
    if (!q)
      throw ArgumentError("point " + id + " is not reachable within orientation spread " +
                          format_number(a.orientation_spread) + " deg; use a smaller --orientation-spread");
    rows.push_back({id, "target", *q});
  }
}

// Targets: joints from a file, or cube points solved by IK on the nominal model.
SimulatedPoses choose_poses(const SimulateArgs& a, const robot::MdhModel& nominal, const robot::MeasurementCube& cube,
                            robot::SimulationRng& rng) {
  const BranchSolver solver(nominal, cube);
  if (!a.fixed_bases.empty() && !a.bases.empty())
    throw ArgumentError("--base and --fixed-base: give base points either as robot positions (--base) or as fixed "
                        "points (--fixed-base), not both");
  SimulatedPoses p;
  p.scattered = a.sample.rfind("scattered:", 0) == 0;
  if (!a.joint_box.empty() && !p.scattered) throw ArgumentError("--joint-box: only with --sample scattered:N");
  if (a.orientation_spread > 0 && !a.joints.empty())
    throw ArgumentError("--orientation-spread: not with --joints (the joints fix the orientation)");
  for (const auto& b : a.fixed_bases) p.fixed.push_back(parse_vec3(b, "--fixed-base"));
  if (a.bases.empty() && p.fixed.empty()) p.base_nominal.push_back(cube.min_corner_mm);
  for (const auto& b : a.bases) p.base_nominal.push_back(parse_vec3(b, "--base"));
  for (std::size_t k = 0; k < p.base_nominal.size(); ++k)
    p.rows.push_back({"b" + std::to_string(k), "base", solver.solve(p.base_nominal[k], "b" + std::to_string(k))});
  if (!a.joints.empty()) {
    add_joint_file_rows(a, nominal, p.rows);
  } else if (p.scattered) {
    const int n = sample_count(a, 10);
    if (!a.joint_box.empty()) add_joint_box_rows(a, nominal, n, rng, p.rows);
    else add_scattered_cube_rows(a, solver, cube, n, rng, p.rows);
  } else {
    add_cube_point_rows(a, solver, cube, rng, p.rows);
  }
  return p;
}

// One row per tracker reading: what the file records and what the simulation knows.
struct Readings {
  std::size_t per_pose = 1;  // readings per visit: one per reflector
  std::vector<Eigen::Vector3d> nominal, truth, measured;
  std::vector<robot::JointVector> recorded;
  std::vector<std::size_t> pose_of;
  std::vector<Eigen::Vector3d> probe_angles;  // --probe: the orientation read (deg)
  std::vector<Eigen::Vector3d> fixed_measured;
  std::vector<int> is_outlier;
  std::size_t outlier_count = 0;
};

// The visits of one run, each read as the options ask, in one random stream.
class Visits {
 public:
  Visits(const SimulateArgs& a, const robot::SimulatorConfig& config, const robot::SimulatedRobot& robot,
         const ReadingOptions& reading, robot::SimulationRng& rng)
      : a_(a), config_(config), robot_(robot), reading_(reading), rng_(rng) {}

  // Visit every row once (bases first, as the paper's reference is measured before the targets):
  // fresh repeatability noise per move, one tracker reading per visit. The robot moves at the
  // commanded joints; the file records them to --joint-decimals.
  Readings visit(const std::vector<PoseRow>& rows) const {
    Readings out;
    out.per_pose = reading_.reflectors.empty() ? 1 : reading_.reflectors.size();
    const std::size_t n = rows.size() * out.per_pose;
    out.nominal.resize(n);
    out.truth.resize(n);
    out.measured.resize(n);
    out.recorded.resize(n);
    out.pose_of.resize(n);
    out.probe_angles.resize(reading_.probe ? n : 0);
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const robot::JointVector q = a_.joint_decimals >= 0 ? robot::round_joints(rows[i].q, a_.joint_decimals) : rows[i].q;
      if (reading_.probe) read_probe(i, rows[i].q, q, out);
      else if (reading_.reflectors.empty()) read_tool_point(i, rows[i].q, q, out);
      else read_reflectors(i, rows[i].q, q, out);
    }
    return out;
  }

 private:
  // The probe: its point read as a reflector's, its orientation in the tracker frame with the
  // probe's own angular noise (per axis, a small rotation applied on the probe side).
  void read_probe(std::size_t i, const robot::JointVector& commanded, const robot::JointVector& q, Readings& out) const {
    using namespace robot;
    const Eigen::Isometry3d& probe = *reading_.probe;
    auto& rng = rng_;
    out.recorded[i] = q;
    out.pose_of[i] = i;
    const Eigen::Isometry3d true_flange = robot_.true_pose(commanded, EndFrame::flange);
    out.nominal[i] = forward_kinematics(config_.nominal, q, EndFrame::flange) * probe.translation();
    const double s = config_.repeatability_sigma_mm;
    out.truth[i] = true_flange * probe.translation() + Eigen::Vector3d(rng.normal(0, s), rng.normal(0, s), rng.normal(0, s));
    out.measured[i] = robot_.measure(out.truth[i], rng);
    const double sd = a_.probe_noise_mdeg * 1e-3 * std::acos(-1.0) / 180.0;
    const Eigen::Vector3d noise(rng.normal(0, sd), rng.normal(0, sd), rng.normal(0, sd));
    const Eigen::Matrix3d read = config_.tracker.tracker_from_world.linear() * true_flange.linear() * probe.linear() *
                                 Eigen::AngleAxisd(noise.norm(), noise.norm() > 0 ? Eigen::Vector3d(noise.normalized())
                                                                                    : Eigen::Vector3d::UnitX())
                                     .toRotationMatrix();
    out.probe_angles[i] = rpy_deg_from_rotation(read);
  }

  void read_tool_point(std::size_t i, const robot::JointVector& commanded, const robot::JointVector& q,
                       Readings& out) const {
    out.recorded[i] = q;
    out.pose_of[i] = i;
    out.nominal[i] = forward_position(config_.nominal, q);
    const Eigen::Vector3d reached = robot_.move(commanded, rng_);
    out.truth[i] = reached;
    out.measured[i] = robot_.measure(reached, rng_);
  }

  // With --reflectors every visit is read at each reflector on the flange: K rows per pose that
  // share the joints, the move (one repeatability draw, a translation of the flange) and the robot's
  // errors, each with its own tracker reading. The pose's joint deflections turn the flange, so each
  // point sees its own error: what a model of one point cannot tell.
  void read_reflectors(std::size_t i, const robot::JointVector& commanded, const robot::JointVector& q,
                       Readings& out) const {
    using namespace robot;
    auto& rng = rng_;
    const Eigen::Isometry3d nominal_flange = forward_kinematics(config_.nominal, q, EndFrame::flange);
    const Eigen::Isometry3d true_flange = robot_.true_pose(commanded, EndFrame::flange);
    const double s = config_.repeatability_sigma_mm;
    const Eigen::Vector3d repeat(rng.normal(0, s), rng.normal(0, s), rng.normal(0, s));
    for (std::size_t k = 0; k < out.per_pose; ++k) {
      const std::size_t r = i * out.per_pose + k;
      out.recorded[r] = q;
      out.pose_of[r] = i;
      out.nominal[r] = nominal_flange * reading_.reflectors[k];
      out.truth[r] = true_flange * reading_.reflectors[k] + repeat;
      out.measured[r] = robot_.measure(out.truth[r], rng);
    }
  }

  const SimulateArgs& a_;
  const robot::SimulatorConfig& config_;
  const robot::SimulatedRobot& robot_;
  const ReadingOptions& reading_;
  robot::SimulationRng& rng_;
};

// Gross outliers: a tracker reading off by outlier_mm in a random direction (a reflector
// knocked, a beam break read as a valid point) on target rows only, in a stream of their own.
void add_outliers(const ReadingOptions& reading, std::uint64_t seed, std::size_t base_rows, Readings& out) {
  const std::size_t n = out.measured.size();
  out.is_outlier.assign(n, 0);
  if (!(reading.outlier_fraction > 0)) return;
  robot::SimulationRng orng(seed ^ kOutlierStream);
  const std::size_t first_target = base_rows * out.per_pose;
  for (std::size_t k : robot::choose_outliers(n - first_target, reading.outlier_fraction, orng)) {
    out.measured[first_target + k] += reading.outlier_mm * robot::random_unit_vector(orng);
    out.is_outlier[first_target + k] = 1;
    ++out.outlier_count;
  }
}

// The file's columns: point (and reflector), kind, the recorded joints, nominal and measured
// positions, distances to the base points, and with --truth-columns what only a simulation knows.
OutputTable measurement_table(const SimulateArgs& a, const ReadingOptions& reading, const SimulatedPoses& poses,
                              const Readings& r) {
  const std::vector<PoseRow>& rows = poses.rows;
  const std::size_t n = r.measured.size();
  OutputTable out;
  std::vector<std::string> ids(n), kinds(n), labels(n);
  for (std::size_t i = 0; i < n; ++i) {
    ids[i] = rows[r.pose_of[i]].id;
    kinds[i] = rows[r.pose_of[i]].kind;
    labels[i] = "r" + std::to_string(i % r.per_pose + 1);
  }
  out.add_column("point", ids);
  if (!reading.reflectors.empty()) out.add_column("reflector", labels);
  out.add_column("kind", kinds);
  const auto qn = joint_column_names();
  for (int k = 0; k < robot::kJointCount; ++k) {
    std::vector<double> v(n);
    for (std::size_t i = 0; i < n; ++i) v[i] = r.recorded[i][k];
    out.add_numeric_column(qn[static_cast<std::size_t>(k)], v);
  }
  auto add_xyz = [&](const std::vector<Eigen::Vector3d>& p, const char* x, const char* y, const char* z) {
    std::vector<double> vx(n), vy(n), vz(n);
    for (std::size_t i = 0; i < n; ++i) {
      vx[i] = p[i].x();
      vy[i] = p[i].y();
      vz[i] = p[i].z();
    }
    out.add_numeric_column(x, vx);
    out.add_numeric_column(y, vy);
    out.add_numeric_column(z, vz);
  };
  add_xyz(r.nominal, "x", "y", "z");
  if (reading.want_positions) add_xyz(r.measured, "mx", "my", "mz");
  if (reading.probe) add_xyz(r.probe_angles, "mrx", "mry", "mrz");
  if (reading.want_distances)
    for (std::size_t k = 0; k < poses.base_nominal.size(); ++k) {
      std::vector<double> d(n);
      for (std::size_t i = 0; i < n; ++i) d[i] = (r.measured[i] - r.measured[k]).norm();
      out.add_numeric_column("dist_b" + std::to_string(k), d);
    }
  if (reading.want_distances)
    for (std::size_t k = 0; k < poses.fixed.size(); ++k) {
      std::vector<double> d(n);
      for (std::size_t i = 0; i < n; ++i) d[i] = (r.measured[i] - r.fixed_measured[k]).norm();
      out.add_numeric_column("dist_b" + std::to_string(k), d);
    }
  if (a.truth_columns) {
    add_xyz(r.truth, "true_x", "true_y", "true_z");
    std::vector<double> flag(r.is_outlier.begin(), r.is_outlier.end());
    out.add_numeric_column("outlier", flag);
  }
  return out;
}

// The comment lines above the columns: SIMULATED, with everything that makes the data look real said.
std::string file_header(const SimulateArgs& a, const robot::SimulatorConfig& config, const ReadingOptions& reading,
                        const SimulatedPoses& poses, const Readings& r, const std::string& systematic) {
  std::ostringstream text;
  // A name or path with a line break would end the comment line and start a data line.
  const auto one_line = [](std::string s) {
    std::replace_if(s.begin(), s.end(), [](char c) { return c == '\n' || c == '\r'; }, ' ');
    return s;
  };
  text << "# SIMULATED data (errfield simulate; not a real robot): seed " << config.seed << ", robot '"
       << one_line(config.nominal.name()) << "'" << (a.config.empty() ? ", default simulation" : ", config " + one_line(a.config))
       << "\n";
  if (poses.scattered || a.orientation_spread > 0 || a.joint_decimals >= 0 || !a.tool_offset.empty() ||
      r.outlier_count > 0 || !systematic.empty()) {
    text << "# SIMULATED like real data:";
    if (poses.scattered) text << " " << a.sample << (a.joint_box.empty() ? " poses in the cube" : " poses in a joint box") << ";";
    if (a.orientation_spread > 0) text << " tool orientation within " << format_number(a.orientation_spread) << " deg;";
    if (a.joint_decimals >= 0)
      text << " q1..q6 recorded to " << a.joint_decimals << " decimals (the robot moved at the unrounded joints);";
    if (!a.tool_offset.empty()) text << " the true tool differs from the nominal robot's by an offset (--truth-out);";
    if (r.outlier_count > 0)
      text << " " << r.outlier_count << " gross outlier(s) of " << format_number(reading.outlier_mm)
           << " mm in the tracker readings;";
    text << systematic << "\n";
  }
  const auto& reflectors = reading.reflectors;
  if (!reflectors.empty()) {
    text << "# SIMULATED reflectors on the flange, each pose read at every one (flange frame, mm):";
    for (std::size_t k = 0; k < reflectors.size(); ++k)
      text << (k ? ";" : "") << " r" << k + 1 << " = " << format_number(reflectors[k].x()) << ","
           << format_number(reflectors[k].y()) << "," << format_number(reflectors[k].z());
    text << "; rows of one pose share point and q1..q6; x,y,z are the nominal position of the row's reflector (FK of "
            "the flange times its offset), not of the robot's tool\n";
  }
  if (reading.probe)
    text << "# SIMULATED 6-DoF probe on the flange at " << a.probe << " (X,Y,Z mm, RX,RY,RZ deg, flange frame), "
         << "orientation noise " << format_number(a.probe_noise_mdeg) << " mdeg per axis: mx,my,mz its point, "
         << "mrx,mry,mrz its orientation in the tracker frame (deg, fixed-axis XYZ: R = Rz Ry Rx); x,y,z the probe "
            "point's nominal position\n";
  text << "# q1..q6 commanded joints (deg); x,y,z nominal tool position (FK of q1..q6, robot base frame, mm)";
  if (reading.want_positions) text << "; mx,my,mz measured position (tracker frame, mm)";
  if (reading.want_distances) text << "; dist_bK measured distance to base point bK (mm)";
  const auto& fixed = poses.fixed;
  for (std::size_t k = 0; k < fixed.size(); ++k)
    text << "; b" << k << " is a fixed point at " << format_number(fixed[k].x()) << "," << format_number(fixed[k].y())
         << "," << format_number(fixed[k].z()) << " (true, robot base frame, mm; no base row)";
  if (a.truth_columns)
    text << "; true_x.. true position (robot base frame, mm; simulation only); outlier 1 on gross outliers";
  text << "\n";
  return text.str();
}

// All outputs or none (a bad --config-out must not leave a new --out next to an old --truth-out).
void write_outputs(const SimulateArgs& a, const robot::SimulatorConfig& config, const robot::SimulatedRobot& robot,
                   const std::string& csv_text) {
  AtomicFileSet outputs;
  outputs.add(a.out, csv_text);
  if (!a.truth_out.empty())
    outputs.add(a.truth_out, robot.true_geometry().with_name("SIMULATED true geometry").to_json().dump(2) + "\n");
  if (!a.config_out.empty()) outputs.add(a.config_out, config.to_json().dump(2) + "\n");
  // The nominal robot (with the tool that is measured) is what plan/fit/compensate take as --robot.
  if (!a.robot_out.empty()) outputs.add(a.robot_out, config.nominal.to_json().dump(2) + "\n");
  outputs.commit();
}

void run_simulate(const SimulateArgs& a) {
  refuse_same_output({{"--out", &a.out}, {"--truth-out", &a.truth_out}, {"--config-out", &a.config_out},
                      {"--robot-out", &a.robot_out}});
  SimulationBase base = load_simulation(a);
  robot::SimulatorConfig& config = base.config;
  ReadingOptions reading = check_recording_options(a);
  apply_tool_offset(a, config);
  read_outliers(a, reading);
  read_flange_points(a, reading);
  const std::string systematic =
      apply_systematic_effects(config, a.systematic, a.compliance_mrad_per_knm, a.end_range_errors, a.mass_offset);
  const robot::SimulatedRobot robot(config);
  robot::SimulationRng rng(config.seed);
  const robot::MeasurementCube cube = simulation_cube(a, base.builtin);
  const SimulatedPoses poses = choose_poses(a, config.nominal, cube, rng);

  Readings readings = Visits(a, config, robot, reading, rng).visit(poses.rows);
  for (const auto& f : poses.fixed) readings.fixed_measured.push_back(robot.measure(f, rng));
  add_outliers(reading, config.seed, poses.base_nominal.size(), readings);
  const OutputTable table = measurement_table(a, reading, poses, readings);
  write_outputs(a, config, robot, file_header(a, config, reading, poses, readings, systematic) + table.to_csv());
  std::cerr << "simulate: " << readings.measured.size() << " SIMULATED measurements ("
            << poses.base_nominal.size() + poses.fixed.size() << " base point(s)) written to " << a.out << "\n";
}

// The simulation and the region: what is simulated before any pose is chosen.
void add_setup_options(CLI::App* cmd, const std::shared_ptr<SimulateArgs>& args) {
  cmd->add_option("--config", args->config, "simulation JSON (docs/robot.md); default: the paper's set-up");
  cmd->add_option("--robot", args->robot,
                  "nominal robot: a built-in name (er20-c10, kr16, ur5e, ur5, ur10; errfield robots) or a robot JSON; overrides "
                  "the config's robot. A built-in name also sets the default --cube to one that robot reaches");
  cmd->add_option("--seed", args->seed, "random seed (overrides the config's)")->check(kUnsignedInteger);
  cmd->add_option("--joints", args->joints, "CSV with commanded joints q1..q6 (deg) instead of cube points");
  cmd->add_option("--cube", args->cube,
                  "X0,Y0,Z0,SIZE: cube min corner and side (mm); default the paper cube (or the --robot NAME's cube)");
  cmd->add_option("--orientation", args->orientation, "RX,RY,RZ tool orientation in the cube (deg; default 180,0,0)");
}

// How the poses are drawn and recorded.
void add_sampling_options(CLI::App* cmd, const std::shared_ptr<SimulateArgs>& args) {
  cmd->add_option("--sample", args->sample,
                  "grid (default), cells (one random point per cell), random:N, or scattered:N (N poses uniform in the "
                  "cube at orientations within --orientation-spread, drawn again where unreachable; with --joint-box: "
                  "joints uniform in the box)");
  cmd->add_option("--orientation-spread", args->orientation_spread,
                  "DEG: each target's tool orientation varies: its z axis uniform in a cone of this half-angle around "
                  "--orientation, turned about itself by up to +-DEG (0..90; default 0 = constant orientation)");
  cmd->add_option("--joint-box", args->joint_box,
                  "LO1,HI1,...,LO6,HI6 (deg): with --sample scattered:N, joints uniform in this box instead of poses "
                  "in the cube");
  cmd->add_option("--joint-decimals", args->joint_decimals,
                  "N: write q1..q6 rounded to N decimals (0..12), as a controller records them; the robot moved at the "
                  "unrounded joints and x,y,z are the FK of the rounded ones")
      ->check(CLI::Range(0, 12));
  cmd->add_option("--tool-offset", args->tool_offset,
                  "X,Y,Z (mm, nominal tool frame) or random:MM (random direction, length MM): the true tool/reflector "
                  "differs from the nominal robot's by this offset, unknown to --robot-out (written to --truth-out "
                  "and --config-out)");
}

// What the tracker reads at each pose.
void add_reading_options(CLI::App* cmd, const std::shared_ptr<SimulateArgs>& args) {
  cmd->add_option("--reflectors", args->reflectors,
                  "X1,Y1,Z1;X2,Y2,Z2;... (flange frame, mm; at least two): every pose is read at each of these "
                  "points on the flange (nests on one plate), one row each with column 'reflector' = r1, r2, ... "
                  "beside 'point'; the rows of a pose share the joints, the move and the robot's errors. "
                  "x,y,z are the nominal FK of each point. Only with --measure positions. fit (kinematic methods) "
                  "and calibrate take the labels together (--tool-reflector picks the model's own point); other "
                  "methods one reflector's rows (docs/robot.md, 'Several points on the flange')");
  cmd->add_option("--probe", args->probe,
                  "X,Y,Z,RX,RY,RZ (flange frame, mm and deg): a 6-DoF probe (a tracker's T-probe): each pose is read "
                  "as the probe point (mx,my,mz) and the probe's orientation in the tracker frame (mrx,mry,mrz, deg, "
                  "fixed-axis XYZ); fit, calibrate and validate take the orientation as three points on the flange "
                  "(docs/data-formats.md, '6-DoF probe readings'). Only with --measure positions; not with --reflectors");
  cmd->add_option("--probe-noise", args->probe_noise_mdeg,
                  "the probe's orientation noise per axis (mdeg, 1 sd; default 10, a T-probe's 0.01 deg)");
  cmd->add_option("--outliers", args->outliers,
                  "FRACTION:MM: that fraction of the target rows gets a gross tracker error of MM (at most 10,000) in a random "
                  "direction (mx,my,mz and the distances); --truth-columns marks them in column 'outlier'");
}

// Effects a kinematic model cannot express.
void add_systematic_options(CLI::App* cmd, const std::shared_ptr<SimulateArgs>& args) {
  cmd->add_option("--systematic", args->systematic,
                  "config (default: the config's joint compliance and cyclic transmission error; the paper's by "
                  "default), none (rigid joints, no transmission error: only geometric deviations, which calibration "
                  "can express), or realistic (joints 2-3 compliance 1 mrad/kNm under gravity, half the config's "
                  "cyclic error, q1 error growing beyond 110 deg to 0.3 deg at its limit, q5 beyond 95 deg to 1.5 "
                  "deg; docs/robot.md)");
  cmd->add_option("--compliance", args->compliance_mrad_per_knm,
                  "MRAD_PER_KNM: compliance of joints 2 and 3 (shoulder, elbow) under the gravity torque of the arm "
                  "and payload, mrad per kN·m (0 = rigid; the paper default is ~0.33-0.42); applied after "
                  "--systematic")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--mass-offset", args->mass_offset,
                  "X,Y,Z: every link's mass moved by this offset (mm, in the link's own frame) from halfway between "
                  "its frame origins, where motors and counterweights put it on a real arm; a gravity model on the frame "
                  "origins (fit's --gravity-load) cannot express it; applied after --systematic");
  cmd->add_option("--end-range-error", args->end_range_errors,
                  "qJ:ONSET_DEG:ERROR_DEG, repeatable: joint J's angle error grows quadratically from 0 at |qJ| = "
                  "ONSET_DEG to ERROR_DEG at the joint's limit, signed like qJ (dress-pack drag, a hose, a "
                  "counterbalance spring); applied after --systematic");
}

void add_base_point_options(CLI::App* cmd, const std::shared_ptr<SimulateArgs>& args) {
  cmd->add_option("--step", args->step, "grid step (mm, must divide the cube side; default 125)");
  cmd->add_option("--base", args->bases, "nominal base point X,Y,Z (mm), repeatable; default the cube's min corner");
  cmd->add_option("--fixed-base", args->fixed_bases,
                  "fixed base point X,Y,Z (mm, true position in the robot base frame), repeatable: a point in the cell "
                  "not carried by the robot (e.g. a tracker nest); dist_b0.. are distances to these, no base rows "
                  "(calibrate: --base-point); not with --base");
  cmd->add_option("--measure", args->measure, "positions, distances or both (default)");
}

void add_output_options(CLI::App* cmd, const std::shared_ptr<SimulateArgs>& args) {
  cmd->add_flag("--truth-columns", args->truth_columns,
                "add true_x,true_y,true_z (the simulator's truth) and outlier (1 on gross outliers)");
  cmd->add_option("--truth-out", args->truth_out, "write the simulated true geometry as a robot JSON");
  cmd->add_option("--config-out", args->config_out, "write the full simulation configuration used as JSON");
  cmd->add_option("--robot-out", args->robot_out,
                  "write the nominal robot (with its measured tool point) as a robot JSON, the --robot of "
                  "plan/fit/compensate");
  cmd->add_option("--out", args->out, "output CSV (written atomically)")->required();
}

void add_simulate_command(CLI::App& app) {
  auto args = std::make_shared<SimulateArgs>();
  auto* cmd = app.add_subcommand(
      "simulate",
      "Simulated robot + laser tracker measurements (SIMULATED data, labelled as such), in the columns\n"
      "'errfield calibrate' and 'errfield fit' read: point, kind (base|target), q1..q6 (deg), x,y,z\n"
      "(nominal, mm), mx,my,mz (tracker frame, mm), dist_b0.. (mm). Base points are robot positions\n"
      "visited first (--base), or fixed points in the cell (--fixed-base; no base rows). Default: the\n"
      "paper's set-up (ER20-C10 with the Table 7 ball, 500 mm cube at\n"
      "tool-down orientation, 125 mm grid, base point at the cube corner).\n"
      "Data that look like real measurements (docs/robot.md): --sample scattered:N (poses anywhere in the\n"
      "cube, or in a --joint-box), --orientation-spread DEG, --joint-decimals N, --tool-offset (a tool the\n"
      "nominal robot does not know), --outliers FRACTION:MM, --robot NAME|R.json (e.g. kr16, ur5e), and\n"
      "systematic effects a kinematic model cannot express, largest at the workspace extremes:\n"
      "--systematic realistic (gravity compliance of joints 2-3, errors growing near the ends of q1's\n"
      "and q5's travel, cyclic joint errors), refined by --compliance and --end-range-error.\n"
      "Example: errfield simulate --sample grid --step 125 --out grid.csv --truth-out true_robot.json\n"
      "Example: errfield simulate --robot ur5e --sample scattered:80 --orientation-spread 30 --joint-decimals 2 \\\n"
      "           --tool-offset random:20 --outliers 0.03:5 --robot-out ur5e.json --out real_like.csv\n"
      "Example: errfield simulate --robot kr16 --sample scattered:300 --joint-box \\\n"
      "           -150,150,-130,-30,70,150,-90,90,-110,110,-180,180 --systematic realistic --outliers 0.02:3 \\\n"
      "           --truth-columns --robot-out kr16.json --out extremes.csv");
  add_setup_options(cmd, args);
  add_sampling_options(cmd, args);
  add_reading_options(cmd, args);
  add_systematic_options(cmd, args);
  add_base_point_options(cmd, args);
  add_output_options(cmd, args);
  cmd->callback([args] { run_simulate(*args); });
}

Registration register_simulate{"simulate", 62, &add_simulate_command};

}  // namespace
}  // namespace errfield::cli
