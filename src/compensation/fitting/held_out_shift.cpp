#include "errfield/compensation/fitting/held_out_shift.hpp"

#include <array>
#include <map>
#include <utility>

#include "errfield/compensation/model/kriging_fields.hpp"

namespace errfield::compensation {

using robot::JointVector;
using robot::kJointCount;

HeldOutShift joint_function_held_out_shift(std::shared_ptr<const JointErrorFunctionFit> fit,
                                           const std::vector<JointVector>& poses, const robot::MdhModel& reflector,
                                           const robot::MdhModel& at) {
  if (!fit || fit->held_out_coefficient_change_mrad.size() != poses.size()) return nullptr;
  using Key = std::array<double, kJointCount>;
  auto key_of = [](const JointVector& q) {
    Key k;
    for (int j = 0; j < kJointCount; ++j) k[static_cast<std::size_t>(j)] = q[j];
    return k;
  };
  std::map<Key, std::size_t> pose_index;
  for (std::size_t i = 0; i < poses.size(); ++i) pose_index.emplace(key_of(poses[i]), i);
  return [fit, pose_index = std::move(pose_index), key_of, reflector, at](const ErrorField& field) {
    const std::vector<JointVector> q = field.sample_joints();
    const JointErrorFunctions& f = fit->functions;
    const Eigen::Index p = f.parameter_count(), n = static_cast<Eigen::Index>(q.size());
    if (p == 0) return std::vector<Eigen::Vector3d>(q.size(), Eigen::Vector3d::Zero());
    const bool own_point = at.tool().isApprox(reflector.tool(), 1e-12);
    // Row s: sample s's 3 x P design block, axis by axis: each column is one quantity over the
    // samples, for the field's leave-one-out operator.
    Eigen::MatrixXd design(n, 3 * p);
    for (Eigen::Index s = 0; s < n; ++s) {
      const JointVector& qs = q[static_cast<std::size_t>(s)];
      const Eigen::MatrixXd block = own_point ? f.design_rows(reflector, qs) : f.design_rows_at_point(reflector, at, qs);
      for (int a = 0; a < 3; ++a) design.block(s, a * p, 1, p) = block.row(a);
    }
    const Eigen::MatrixXd left = leave_one_out_residuals_of(field, design);
    if (left.rows() != n) return std::vector<Eigen::Vector3d>{};
    std::vector<Eigen::Vector3d> shift(q.size(), Eigen::Vector3d::Zero());
    for (Eigen::Index s = 0; s < n; ++s) {
      const auto found = pose_index.find(key_of(q[static_cast<std::size_t>(s)]));
      if (found == pose_index.end()) continue;
      const Eigen::VectorXd& change = fit->held_out_coefficient_change_mrad[found->second];
      for (int a = 0; a < 3; ++a) shift[static_cast<std::size_t>(s)][a] = -left.row(s).segment(a * p, p).dot(change);
    }
    return shift;
  };
}

}  // namespace errfield::compensation
