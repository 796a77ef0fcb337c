#pragma once
// Internal: the two measurement models kinematic calibration fits (calibration.hpp): tracker
// positions (3 residuals per pose) and distances to a base point (1 residual per pair), with the
// Jacobian of their predictions with respect to the candidate parameters. The solver
// (calibration_solver.hpp) and the identifiability analysis (calibration_identifiability.hpp)
// only see this interface.

#include <string>
#include <vector>

#include <Eigen/Core>

#include "errfield/robot/calibration.hpp"

namespace errfield::robot::detail {

// What is identified: the robot model and extra parameters, 3 per point (mm): the fixed base points'
// coordinates (distances) or the further flange points' (positions of several points); a problem has
// one kind or the other. Candidate indices below param::kCount are model parameters; index
// param::kCount + e is extra[e] for a base point, kFlangePointCandidateBase + e for a flange point
// (extra_index maps both).
struct CalibrationState {
  MdhModel model;
  Eigen::VectorXd extra;
};

// "link2.alpha", "tool.x", ..., "base point K x|y|z" for a fixed point's coordinate, or
// "flange point K x|y|z" for a further point on the flange.
std::string candidate_name(int index);

// The position in CalibrationState::extra of a candidate index >= param::kCount.
inline int extra_index(int index) {
  return index >= kFlangePointCandidateBase ? index - kFlangePointCandidateBase : index - param::kCount;
}

// A candidate's value is an angle (rad in the Jacobian) rather than a length (mm).
bool candidate_is_angle(int index);

// A measurement model: residuals (measured − predicted), `dim()` rows per measurement, and the
// Jacobian of the predictions with respect to the candidate parameters (columns = `active`).
class CalibrationProblem {
 public:
  virtual ~CalibrationProblem() = default;
  virtual int dim() const = 0;
  virtual std::size_t count() const = 0;
  // Measurements at distinct configurations (a repeated pose or pair adds no equation).
  virtual std::size_t distinct() const = 0;
  virtual void evaluate(const CalibrationState& s, const std::vector<int>& active, Eigen::VectorXd& r,
                        Eigen::MatrixXd* jac) const = 0;
  // The Jacobian of measurements of the same kind (same base points) at generic configurations
  // `q` (several hundred equations), for the "too few poses" guard.
  virtual Eigen::MatrixXd generic_jacobian(const CalibrationState& s, const std::vector<int>& candidates,
                                           const std::vector<JointVector>& q) const = 0;
};

class PositionProblem final : public CalibrationProblem {
 public:
  explicit PositionProblem(const std::vector<PositionMeasurement>& d) : data_(d) {}
  int dim() const override { return 3; }
  std::size_t count() const override { return data_.size(); }
  std::size_t distinct() const override;
  void evaluate(const CalibrationState& s, const std::vector<int>& active, Eigen::VectorXd& r,
                Eigen::MatrixXd* jac) const override;
  // At each configuration, a reading of every flange point the data have.
  Eigen::MatrixXd generic_jacobian(const CalibrationState& s, const std::vector<int>& candidates,
                                   const std::vector<JointVector>& q) const override;
  // The largest PositionMeasurement::flange_point (0: the tool point only).
  int flange_point_count() const;

 private:
  const std::vector<PositionMeasurement>& data_;
};

class DistanceProblem final : public CalibrationProblem {
 public:
  // `fixed_count` fixed base points; their coordinates are CalibrationState::extra.
  DistanceProblem(const std::vector<DistanceMeasurement>& d, int fixed_count) : data_(d), fixed_count_(fixed_count) {}
  int dim() const override { return 1; }
  std::size_t count() const override { return data_.size(); }
  std::size_t distinct() const override;
  void evaluate(const CalibrationState& s, const std::vector<int>& active, Eigen::VectorXd& r,
                Eigen::MatrixXd* jac) const override;
  // Pairs of consecutive configurations if the data have robot-position pairs, and every
  // configuration to every fixed point.
  Eigen::MatrixXd generic_jacobian(const CalibrationState& s, const std::vector<int>& candidates,
                                   const std::vector<JointVector>& q) const override;

 private:
  const std::vector<DistanceMeasurement>& data_;
  int fixed_count_ = 0;
};

// The distinct joint vectors among `q` (exact comparison), in first-seen order.
std::vector<JointVector> distinct_configurations(const std::vector<JointVector>& q);

}  // namespace errfield::robot::detail
