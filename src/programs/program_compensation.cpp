#include "errfield/programs/program_compensation.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>

#include "errfield/compensation/pipeline.hpp"
#include "errfield/error.hpp"
#include "errfield/compensation/validation/rotation_validation.hpp"
#include "errfield/compensation/tools/target_ik.hpp"
#include "errfield/robot/inverse_kinematics.hpp"
#include "errfield/robot/kinematics.hpp"
#include "errfield/robot/pose.hpp"

namespace errfield::programs {
namespace {

using robot::JointVector;

// Two joint solutions closer than this (deg, largest joint) are one.
constexpr double kSameSolutionDeg = 1e-3;

// The wrist flip of a spherical wrist (q4 + 180, -q5, q6 + 180) and the +-360 deg turns of the
// endless-looking axes 1, 4 and 6: other solutions of the same pose, kept when within the limits.
std::vector<JointVector> variants(const robot::MdhModel& nominal, const JointVector& q, const Eigen::Isometry3d& target) {
  std::vector<JointVector> base{q};
  JointVector flip = q;
  flip[3] += flip[3] > 0 ? -180.0 : 180.0;
  flip[4] = -flip[4];
  flip[5] += flip[5] > 0 ? -180.0 : 180.0;
  const Eigen::Isometry3d at = robot::forward_kinematics(nominal, flip);
  if ((at.translation() - target.translation()).norm() < 1e-6 && robot::rotation_log(at.linear() * target.linear().transpose()).norm() < 1e-8)
    base.push_back(flip);
  std::vector<JointVector> out;
  for (const JointVector& b : base)
    for (int t1 = -1; t1 <= 1; ++t1)
      for (int t4 = -1; t4 <= 1; ++t4)
        for (int t6 = -1; t6 <= 1; ++t6) {
          JointVector v = b;
          v[0] += 360.0 * t1;
          v[3] += 360.0 * t4;
          v[5] += 360.0 * t6;
          if (nominal.within_limits(v)) out.push_back(v);
        }
  return out;
}

double joint_distance(const JointVector& a, const JointVector& b) { return (a - b).cwiseAbs().maxCoeff(); }

const compensation::OutputColumn& column(const compensation::StepColumns& step, const std::string& name) {
  for (const auto& c : step.columns)
    if (c.name == name) return c;
  throw std::logic_error("compensate_columns has no column " + name);
}

std::string joined(const std::string& a, const std::string& b) { return a.empty() ? b : b.empty() ? a : a + "; " + b; }

// What a compensate status means, in the report's words.
std::string refusal_reason(const std::string& status) {
  if (status == "outside-region") return "outside-region: outside the region the model was fitted on (never extrapolated)";
  if (status == "not-credible") return "not-credible: the prediction is far beyond the model's range of errors";
  if (status == "orientation-unknown")
    return "orientation-unknown: the tool point is far from the model's measured points and the model does not "
           "predict the flange's orientation (fit several points, a probe or locate-tool)";
  if (status == "correction-too-large") return "correction-too-large: the correction exceeds the ceiling (--max-correction)";
  if (status == "unreachable") return "unreachable: no joint solution reaches the target";
  if (status == "config-change") return "config-change: the compensated joints leave the target's arm configuration";
  if (status == "branch-change") return "branch-change: the joint solution left the branch it started on";
  if (status == "outside-limits") return "outside-limits: joints outside the robot's limits";
  return status;
}

// One model per tool: compensate's --tool (the working tool, in the model's flange frame).
struct ToolGroup {
  compensation::CompensationModel model;
  robot::MdhModel nominal;
  std::vector<std::size_t> rows;
  std::vector<JointVector> seeds;
};

std::string tool_key(const Eigen::Isometry3d& t) {
  std::string k;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 4; ++j) k += std::to_string(t.matrix()(i, j)) + ",";
  return k;
}

// The nominal joints the controller would take: on the requested configuration, or (configuration
// ignored or none asked) the solution nearest the previous target's. Empty when the target is refused
// (the row says why); a kept seed may still leave a note in the row's reason.
std::optional<JointVector> controller_joints(const ToolGroup& g, const Eigen::Isometry3d& target,
                                             const ConfigurationRequest& conf,
                                             const std::optional<JointVector>& previous, ProgramReportRow& row) {
  const robot::MdhModel& nominal = g.nominal;
  std::optional<JointVector> seed;
  if (conf.matches && !conf.ignored) {
    // The quick answers first (the previous target's branch, compensate's own start), the search
    // over every solution only when neither is on the requested configuration.
    if (previous) {
      const robot::IkResult ik = robot::inverse_kinematics(nominal, target, *previous);
      if (ik.ok() && conf.matches(ik.q_deg)) seed = ik.q_deg;
    }
    if (!seed) {
      const compensation::BranchIkResult ik = compensation::solve_on_branch(nominal, target, g.model.data_joints());
      if (ik.ok() && conf.matches(ik.ik.q_deg)) seed = ik.ik.q_deg;
    }
    const auto on = seed ? std::vector<JointVector>{*seed} : solutions_on_configuration(nominal, target, conf.matches, previous);
    if (on.empty()) {
      row.status = kStatusRefused;
      row.reason = "configuration " + conf.text + " matches no joint solution of the target (a placeholder? the "
                   "controller would refuse the move unless the configuration check is off)";
      return std::nullopt;
    }
    return on.front();
  }
  if (previous) {
    const robot::IkResult ik = robot::inverse_kinematics(nominal, target, *previous);
    if (ik.ok()) seed = ik.q_deg;
  }
  if (!seed) {
    const compensation::BranchIkResult ik = compensation::solve_on_branch(nominal, target, g.model.data_joints());
    if (ik.ok()) seed = ik.ik.q_deg;
  }
  if (!seed) {
    row.status = kStatusRefused;
    row.reason = "unreachable: no joint solution reaches the target";
    return std::nullopt;
  }
  std::string how = previous ? "the solution nearest the previous target's joints" : "the solution nearest the model's training joints";
  if (conf.ignored) {
    const bool match = conf.matches && conf.matches(*seed);
    row.reason = conf.off_by + ": configuration " + conf.text + (match ? " kept" : " not matched") + "; " + how + " is used";
  } else {
    row.reason = "no configuration given: " + how + " is used";
  }
  return seed;
}

// Every literal target into its tool's group with its seed joints; what cannot be compensated
// (computed, joints, refused by the reader, a bad tool, no solution) gets its row's status here.
std::map<std::string, ToolGroup> group_by_tool(const compensation::CompensationModel& model,
                                               const robot::MdhModel& nominal_robot,
                                               const std::vector<ProgramTarget>& targets, ProgramCompensation& out) {
  std::map<std::string, ToolGroup> groups;
  std::optional<JointVector> previous;  // the nominal joints of the previous literal target
  for (std::size_t i = 0; i < targets.size(); ++i) {
    const ProgramTarget& t = targets[i];
    ProgramReportRow& row = out.rows[i];
    row.file = t.file;
    row.line = t.line;
    row.target = t.label;
    if (t.kind == TargetKind::computed || t.kind == TargetKind::joints) {
      row.status = t.refusal.empty() ? (t.kind == TargetKind::computed ? kStatusComputed : kStatusUnchanged) : kStatusRefused;
      row.reason = joined(t.refusal, t.note);
      continue;
    }
    if (!t.refusal.empty()) {
      row.status = kStatusRefused;
      row.reason = t.refusal;
      continue;
    }
    const std::string key = tool_key(t.tool);
    auto g = groups.find(key);
    if (g == groups.end()) {
      try {
        compensation::check_tool_point(t.tool, "tool " + t.tool_name);
        compensation::CompensationModel with_tool = model.with_working_tool(model.tool_in_model_frame(t.tool));
        robot::MdhModel nominal = compensation::nominal_at_working_tool(with_tool, nominal_robot);
        g = groups.emplace(key, ToolGroup{std::move(with_tool), std::move(nominal), {}, {}}).first;
      } catch (const Error& e) {
        row.status = kStatusRefused;
        row.reason = e.what();
        continue;
      }
    }
    const std::optional<JointVector> seed = controller_joints(g->second, t.frame * t.pose_in_frame, t.configuration, previous, row);
    if (!seed) continue;
    previous = seed;
    g->second.rows.push_back(i);
    g->second.seeds.push_back(*seed);
  }
  return groups;
}

// compensate's computation, once per tool, on poses in the robot base frame with the joints found
// above as each row's seed (the configuration compensate holds the row to). Returns row -> new pose
// in the target's frame.
std::map<std::size_t, Eigen::Isometry3d> compensate_groups(std::map<std::string, ToolGroup>& groups,
                                                           const std::vector<ProgramTarget>& targets,
                                                           const ProgramCompensationOptions& options,
                                                           ProgramCompensation& out) {
  std::map<std::size_t, Eigen::Isometry3d> new_pose;
  for (auto& [key, g] : groups) {
    compensation::CompensationTargets ct;
    ct.poses.resize(static_cast<Eigen::Index>(g.rows.size()), 6);
    for (std::size_t r = 0; r < g.rows.size(); ++r) {
      const ProgramTarget& t = targets[g.rows[r]];
      const robot::PoseXyzRpy p = robot::to_xyz_rpy(t.frame * t.pose_in_frame);
      ct.poses.row(static_cast<Eigen::Index>(r)) << p.x_mm, p.y_mm, p.z_mm, p.rx_deg, p.ry_deg, p.rz_deg;
    }
    ct.seed_rows_deg = g.seeds;
    const compensation::StepColumns step =
        compensation::compensate_columns(g.model, g.nominal, ct, options.tolerance_mm, options.max_correction_mm);
    out.max_correction_mm = step.max_correction_mm;
    const auto& status = column(step, "status").words;
    std::array<const std::vector<double>*, 6> cq;
    for (int k = 0; k < 6; ++k) cq[static_cast<std::size_t>(k)] = &column(step, "cq" + std::to_string(k + 1)).numbers;
    for (std::size_t r = 0; r < g.rows.size(); ++r) {
      const std::size_t i = g.rows[r];
      const ProgramTarget& t = targets[i];
      ProgramReportRow& row = out.rows[i];
      if (status[r] != "ok") {
        row.status = kStatusRefused;
        row.reason = joined(refusal_reason(status[r]), row.reason);
        continue;
      }
      JointVector q;
      for (int k = 0; k < 6; ++k) q[k] = (*cq[static_cast<std::size_t>(k)])[r];
      if (t.configuration.matches && !t.configuration.ignored && !t.configuration.matches(q)) {
        row.status = kStatusRefused;
        row.reason = joined("configuration " + t.configuration.text + " is not kept by the compensated joints", row.reason);
        continue;
      }
      const Eigen::Isometry3d moved = t.frame.inverse() * robot::forward_kinematics(g.nominal, q);
      row.status = kStatusOk;
      row.q_deg = q;
      row.d_mm = moved.translation() - t.pose_in_frame.translation();
      row.rotation_mdeg = compensation::kMdegPerRad * robot::rotation_log(moved.linear() * t.pose_in_frame.linear().transpose());
      new_pose[i] = moved;
    }
  }
  return new_pose;
}

// Declared targets: one rewrite for all their uses, only when every use asks for the same.
std::vector<bool> rows_to_rewrite(const std::vector<ProgramTarget>& targets,
                                  const std::map<std::size_t, Eigen::Isometry3d>& new_pose, ProgramCompensation& out) {
  std::map<std::string, std::vector<std::size_t>> shared;
  for (std::size_t i = 0; i < targets.size(); ++i)
    if (targets[i].kind == TargetKind::literal && !targets[i].shared_key.empty()) shared[targets[i].shared_key].push_back(i);
  std::vector<bool> write(targets.size(), false);
  for (std::size_t i = 0; i < targets.size(); ++i)
    write[i] = out.rows[i].status == kStatusOk && targets[i].shared_key.empty();
  for (const auto& [key, uses] : shared) {
    bool all_ok = true, same = true;
    for (std::size_t i : uses) all_ok = all_ok && out.rows[i].status == kStatusOk;
    for (std::size_t i : uses)
      if (all_ok) {
        const Eigen::Isometry3d& a = new_pose.at(uses.front());
        const Eigen::Isometry3d& b = new_pose.at(i);
        same = same && (a.translation() - b.translation()).norm() < 1e-6 &&
               robot::rotation_log(a.linear() * b.linear().transpose()).norm() < 1e-9;
      }
    if (all_ok && same) {
      write[uses.front()] = true;
      continue;
    }
    // One declaration cannot hold two corrections, nor a correction some use refuses.
    const std::string why = !all_ok ? "declared once and another use of it is refused, so the declaration is left as written"
                                    : "declared once but used with different tools, work objects or configurations that "
                                      "need different corrections; the declaration is left as written";
    for (std::size_t i : uses)
      if (out.rows[i].status == kStatusOk) {
        out.rows[i].status = kStatusRefused;
        out.rows[i].reason = joined(why, out.rows[i].reason);
        out.rows[i].d_mm.setConstant(std::numeric_limits<double>::quiet_NaN());
        out.rows[i].q_deg.setConstant(std::numeric_limits<double>::quiet_NaN());
        out.rows[i].rotation_mdeg.setConstant(std::numeric_limits<double>::quiet_NaN());
      }
  }
  return write;
}

}  // namespace

std::vector<JointVector> solutions_on_configuration(const robot::MdhModel& nominal, const Eigen::Isometry3d& target,
                                                    const std::function<bool(const JointVector&)>& wanted,
                                                    const std::optional<JointVector>& near_deg) {
  std::vector<JointVector> seeds;
  if (near_deg) seeds.push_back(*near_deg);
  const JointVector lo = nominal.q_min_deg(), hi = nominal.q_max_deg();
  for (double f1 : {0.5, 0.2, 0.8, 0.05, 0.35, 0.65, 0.95})
    for (double f3 : {0.5, 0.15, 0.85})
      for (double f5 : {0.3, 0.7}) {
        JointVector s;
        const double f[6] = {f1, 0.5, f3, 0.5, f5, 0.5};
        for (int k = 0; k < 6; ++k) s[k] = lo[k] + f[k] * (hi[k] - lo[k]);
        seeds.push_back(s);
      }
  std::vector<JointVector> found;
  for (const JointVector& seed : seeds) {
    const robot::IkResult ik = robot::inverse_kinematics(nominal, target, seed);
    if (!ik.ok()) continue;
    for (const JointVector& v : variants(nominal, ik.q_deg, target)) {
      if (wanted && !wanted(v)) continue;
      const bool known = std::any_of(found.begin(), found.end(), [&](const JointVector& f) { return joint_distance(f, v) < kSameSolutionDeg; });
      if (!known) found.push_back(v);
    }
  }
  if (near_deg)
    std::stable_sort(found.begin(), found.end(), [&](const JointVector& a, const JointVector& b) {
      return (a - *near_deg).norm() < (b - *near_deg).norm();
    });
  return found;
}

ProgramCompensation compensate_program_targets(const compensation::CompensationModel& model,
                                               const robot::MdhModel& nominal_robot,
                                               const std::vector<ProgramTarget>& targets,
                                               const ProgramCompensationOptions& options) {
  ProgramCompensation out;
  out.rows.resize(targets.size());
  std::map<std::string, ToolGroup> groups = group_by_tool(model, nominal_robot, targets, out);
  std::map<std::size_t, Eigen::Isometry3d> new_pose = compensate_groups(groups, targets, options, out);
  const std::vector<bool> write = rows_to_rewrite(targets, new_pose, out);
  for (std::size_t i = 0; i < targets.size(); ++i) {
    if (out.rows[i].status == kStatusOk) out.largest_correction_mm = std::max(out.largest_correction_mm, out.rows[i].d_mm.norm());
    if (!write[i]) continue;
    for (Replacement& r : targets[i].rewrite(new_pose.at(i))) out.replacements.push_back(std::move(r));
  }
  return out;
}

}  // namespace errfield::programs
