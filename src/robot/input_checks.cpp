#include "errfield/robot/input_checks.hpp"

#include <algorithm>
#include <cmath>

#include "errfield/csv_table.hpp"

namespace errfield::robot {

double reach_scale_mm(const MdhModel& model) {
  double s = 0.0;
  for (const auto& l : model.links()) s += std::abs(l.a_mm) + std::abs(l.d_mm);
  return s;
}

std::optional<std::string> metres_instead_of_mm(const Eigen::MatrixXd& positions_mm, const MdhModel& model,
                                                const std::string& what) {
  const double reach = reach_scale_mm(model);
  if (positions_mm.rows() == 0 || positions_mm.cols() != 3 || reach < 100.0) return std::nullopt;
  const double limit = reach / 100.0;
  const Eigen::Vector3d base = model.base().translation();
  double max_world = 0.0, max_base = 0.0;
  for (Eigen::Index i = 0; i < positions_mm.rows(); ++i) {
    const Eigen::Vector3d p = positions_mm.row(i).transpose();
    max_world = std::max(max_world, p.norm());
    max_base = std::max(max_base, (p - base).norm());
  }
  if (max_world >= limit && max_base >= limit) return std::nullopt;
  return what + ": every position is within " + format_number(std::round(limit * 10) / 10) + " mm of the " +
         (max_world < limit ? "origin" : "robot base") + " (largest distance " +
         format_number(std::round(std::min(max_world, max_base) * 1000) / 1000) + ") for a robot of reach ~" + format_number(std::round(reach)) +
         " mm: are these metres? errfield expects millimetres (multiply by 1000)";
}

std::optional<std::string> lengths_in_metres(const MdhModel& model, const std::string& what) {
  const double reach = reach_scale_mm(model);
  if (!(reach > 0.0) || reach >= 100.0) return std::nullopt;
  return what + ": the links' lengths add up to " + format_number(std::round(reach * 1000) / 1000) +
         " mm (sum of |a_mm| + |d_mm|): are they in metres? errfield expects millimetres (multiply by 1000)";
}

std::optional<std::string> distances_in_metres(const std::vector<double>& distances_mm, const MdhModel& model,
                                               const std::string& what) {
  const double reach = reach_scale_mm(model);
  if (distances_mm.empty() || reach < 100.0) return std::nullopt;
  const double limit = reach / 100.0;
  double largest = 0.0;
  for (double d : distances_mm) largest = std::max(largest, std::abs(d));
  if (largest >= limit || largest == 0.0) return std::nullopt;
  return what + ": every distance is below " + format_number(std::round(limit * 10) / 10) + " mm (largest " +
         format_number(std::round(largest * 1000) / 1000) + ") for a robot of reach ~" + format_number(std::round(reach)) +
         " mm: are these metres? errfield expects millimetres (multiply by 1000)";
}

std::optional<std::string> joints_outside_limits(const std::vector<JointVector>& q_deg, const MdhModel& model,
                                                 const RowLabels& labels, double slack_deg) {
  const JointVector lo = model.q_min_deg(), hi = model.q_max_deg();
  std::size_t count = 0, first = 0;
  int first_joint = 0;
  for (std::size_t i = 0; i < q_deg.size(); ++i) {
    for (int j = 0; j < kJointCount; ++j) {
      if (q_deg[i][j] < lo[j] - slack_deg || q_deg[i][j] > hi[j] + slack_deg) {
        if (count == 0) {
          first = i;
          first_joint = j;
        }
        ++count;
        break;
      }
    }
  }
  if (count == 0) return std::nullopt;
  const double v = q_deg[first][first_joint];
  return labels(first) + ": q" + std::to_string(first_joint + 1) + " = " + format_number(v) +
         " deg is outside the joint limits [" + format_number(lo[first_joint]) + ", " + format_number(hi[first_joint]) +
         "] of " + model.name() + (count > 1 ? " (" + std::to_string(count) + " rows are outside in all)" : "") +
         "; check units (degrees) and joint order";
}

std::optional<std::string> implausible_distance(double measured_mm, double nominal_mm, const MdhModel& model,
                                                bool near_nominal) {
  if (!(measured_mm > 0.0))
    return format_number(measured_mm) + " mm; expected a distance > 0 (the nominal distance is " +
           format_number(std::round(nominal_mm * 1000) / 1000) + " mm)";
  const double limit = reach_scale_mm(model) / 10.0;
  if (!near_nominal || std::abs(measured_mm - nominal_mm) <= limit) return std::nullopt;
  return format_number(measured_mm) + " mm, but the nominal distance is " +
         format_number(std::round(nominal_mm * 1000) / 1000) + " mm: an error of " +
         format_number(std::round((measured_mm - nominal_mm) * 1000) / 1000) + " mm, more than a tenth of " +
         model.name() + "'s size (" + format_number(std::round(limit)) +
         " mm); check the column, its units (mm) and the base point";
}

std::optional<std::string> tracker_frozen(const Eigen::MatrixXd& measured_mm, const Eigen::MatrixXd& nominal_mm) {
  if (measured_mm.rows() < 2 || measured_mm.rows() != nominal_mm.rows() || measured_mm.cols() != 3 ||
      nominal_mm.cols() != 3)
    return std::nullopt;
  const auto spread = [](const Eigen::MatrixXd& p) {
    const Eigen::RowVector3d c = p.colwise().mean();
    return (p.rowwise() - c).rowwise().norm().maxCoeff();
  };
  const double nominal = spread(nominal_mm), measured = spread(measured_mm);
  if (!(nominal > 1.0) || measured > nominal * 1e-6) return std::nullopt;
  return "the " + std::to_string(measured_mm.rows()) + " measured positions (mx,my,mz) lie within " +
         format_number(measured) + " mm of their mean while the nominal positions spread over " +
         format_number(std::round(nominal)) +
         " mm: the tracker did not follow the reflector (a frozen reading?); nothing can be fitted to them";
}

}  // namespace errfield::robot
