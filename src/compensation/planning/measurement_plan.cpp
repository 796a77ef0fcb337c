#include "errfield/compensation/planning/measurement_plan.hpp"

#include <cmath>
#include <cstdio>

#include "errfield/error.hpp"
#include "errfield/robot/cube_budget.hpp"
#include "errfield/robot/inverse_kinematics.hpp"
#include "errfield/robot/random.hpp"

namespace errfield::compensation {

using namespace errfield::robot;

namespace {
// "g12": built by appending (GCC 12 warns falsely on "g" + std::to_string(n)).
std::string label(char prefix, std::size_t n) {
  std::string s(1, prefix);
  s += std::to_string(n);
  return s;
}
}  // namespace

void PlanOptions::validate() const {
  if (!(size_mm > 0) || !std::isfinite(size_mm))
    throw ArgumentError("plan: cube size " + std::to_string(size_mm) + " mm; expected > 0");
  const double k = size_mm / step_mm;
  if (!(step_mm > 0) || std::abs(k - std::round(k)) > 1e-9)
    throw ArgumentError("plan: step " + std::to_string(step_mm) + " mm must divide the cube side " +
                        std::to_string(size_mm) + " mm");
  if (!min_corner_mm.allFinite()) throw ArgumentError("plan: cube corner is not finite");
  check_cube_budget(size_mm, step_mm, sample_per_cell, "plan: step");
}

std::vector<PlannedPoint> plan_measurements(const MdhModel& robot, const PlanOptions& o) {
  o.validate();
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = o.orientation;
  pose.translation() = o.min_corner_mm + Eigen::Vector3d::Constant(0.5 * o.size_mm);
  const IkResult centre = inverse_kinematics_multistart(robot, pose);
  std::vector<PlannedPoint> points;
  for (std::size_t b = 0; b < o.base_points_mm.size(); ++b)
    points.push_back({label('b', b), "base", o.base_points_mm[b], JointVector::Zero()});
  const int n = static_cast<int>(std::lround(o.size_mm / o.step_mm));
  for (int k = 0; k <= n; ++k)
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i)
        points.push_back({label('g', points.size() - o.base_points_mm.size()), "grid",
                          o.min_corner_mm + o.step_mm * Eigen::Vector3d(i, j, k), JointVector::Zero()});
  if (o.sample_per_cell) {
    SimulationRng rng(o.seed);
    int s = 0;
    for (int k = 0; k < n; ++k)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          const Eigen::Vector3d u(rng.uniform01(), rng.uniform01(), rng.uniform01());
          points.push_back({label('s', static_cast<std::size_t>(s++)), "sample",
                            o.min_corner_mm + o.step_mm * (Eigen::Vector3d(i, j, k) + u), JointVector::Zero()});
        }
  }
  // Stops at the 10th unreachable point: each costs up to 24 full IK solves, and a cube that is
  // mostly out of reach would otherwise take minutes to be refused (found by fuzzing).
  constexpr std::size_t kReported = 10;
  std::string unreachable;
  std::size_t bad = 0, checked = 0;
  for (auto& p : points) {
    if (bad == kReported) break;
    ++checked;
    pose.translation() = p.position_mm;
    const IkResult r = centre.ok() ? inverse_kinematics(robot, pose, centre.q_deg) : inverse_kinematics_multistart(robot, pose);
    p.q_deg = r.q_deg;
    if (!r.ok()) {
      if (++bad <= kReported) {
        char buf[200];
        std::snprintf(buf, sizeof buf, "\n  %s (%.1f, %.1f, %.1f) mm: %s, residual %.3g mm", p.id.c_str(), p.position_mm.x(),
                      p.position_mm.y(), p.position_mm.z(), to_string(r.status), r.position_residual_mm);
        unreachable += buf;
      }
    }
  }
  if (bad)
    throw InputError("plan: " + std::to_string(bad) + " of the first " + std::to_string(checked) + " of " +
                     std::to_string(points.size()) + " points are unreachable at the requested orientation" +
                     (bad == kReported ? " (stopped at " + std::to_string(kReported) + ")" : std::string()) + ":" +
                     unreachable + "\nMove or shrink the cube, or change the orientation.");
  return points;
}

StepRecommendation recommend_grid_step(const VariogramModel& model, double size_mm, double gamma_max, double min_step) {
  if (!(gamma_max > 0)) throw ArgumentError("recommend_grid_step: gamma_max must be > 0");
  StepRecommendation best;
  best.gamma_max_mm2 = gamma_max;
  bool found = false;
  double smallest = 0;
  for (int k = 1; k <= 1000; ++k) {
    const double step = size_mm / k;
    if (step < min_step) break;
    // whole-millimetre steps only (10, 20, 25, ... for a 500 mm cube), as a plan is written down
    if (std::abs(step - std::round(step)) > 1e-9 && std::abs(size_mm - std::round(size_mm)) < 1e-9) continue;
    smallest = step;
    const double diag = step * std::sqrt(3.0);
    if (model.gamma(diag) <= gamma_max) {
      best.step_mm = step;
      best.cell_diagonal_mm = diag;
      best.gamma_at_diagonal_mm2 = model.gamma(diag);
      found = true;
      break;  // k grows: the first step that qualifies is the largest
    }
  }
  char buf[512];
  if (found) {
    std::snprintf(buf, sizeof buf,
                  "step %.4g mm: the largest step dividing the %.4g mm cube whose cell diagonal (%.4g mm) keeps the "
                  "variogram at %.3g mm² <= %.3g mm², so errors at a cell's vertices and inside it stay similar "
                  "(IDW error about sqrt(gamma) = %.3g mm).",
                  best.step_mm, size_mm, best.cell_diagonal_mm, best.gamma_at_diagonal_mm2, gamma_max,
                  std::sqrt(best.gamma_at_diagonal_mm2));
  } else {
    best.step_mm = smallest;
    best.cell_diagonal_mm = smallest * std::sqrt(3.0);
    best.gamma_at_diagonal_mm2 = model.gamma(best.cell_diagonal_mm);
    std::snprintf(buf, sizeof buf,
                  "no step >= %.4g mm meets gamma <= %.3g mm² at the cell diagonal (the model's nugget or short-range "
                  "variation is too large); the smallest allowed step %.4g mm gives %.3g mm². Expect IDW errors of "
                  "about %.3g mm.",
                  min_step, gamma_max, smallest, best.gamma_at_diagonal_mm2, std::sqrt(best.gamma_at_diagonal_mm2));
  }
  best.reason = buf;
  return best;
}

}  // namespace errfield::compensation
