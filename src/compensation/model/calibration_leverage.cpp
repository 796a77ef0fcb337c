#include "errfield/compensation/model/calibration_leverage.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>
#include <Eigen/Cholesky>
#include <nlohmann/json.hpp>

#include "errfield/error.hpp"
#include "errfield/robot/kinematics.hpp"

namespace errfield::compensation {

using namespace errfield::robot;

namespace {

/// The columns `parameters` of the identification Jacobian at the model's tool point.
Eigen::Matrix<double, 3, Eigen::Dynamic> parameter_columns(const MdhModel& model, const JointVector& q_deg,
                                                            const std::vector<int>& parameters) {
  const IdentificationJacobian j = identification_jacobian(model, q_deg);
  Eigen::Matrix<double, 3, Eigen::Dynamic> out(3, static_cast<Eigen::Index>(parameters.size()));
  for (std::size_t c = 0; c < parameters.size(); ++c) out.col(static_cast<Eigen::Index>(c)) = j.col(parameters[c]);
  return out;
}

/// The prior sd of parameter `index` (mm or rad).
double prior_sd(int index) {
  if (index >= param::kBaseTranslation && index < param::kToolTranslation)
    return index < param::kBaseRotation ? kFreeBaseSdMm : kFreeBaseSdRad;
  return parameter_is_angle(index) ? kGeometricErrorSdRad : kGeometricErrorSdMm;
}

}  // namespace

std::optional<CalibrationLeverage> CalibrationLeverage::of(const MdhModel& model, const std::vector<JointVector>& q_deg,
                                                           double noise_variance_mm2,
                                                           const std::vector<Eigen::Vector3d>& point_of_reading_mm,
                                                           const std::vector<double>& weights) {
  if (q_deg.empty() || !(noise_variance_mm2 > 0.0) || !std::isfinite(noise_variance_mm2)) return std::nullopt;
  CalibrationLeverage out;
  for (int p = 0; p < param::kCount; ++p) out.parameters.push_back(p);
  const auto count = static_cast<Eigen::Index>(out.parameters.size());
  std::vector<Eigen::Matrix<double, 3, Eigen::Dynamic>> rows(q_deg.size());
  // The posterior information of the parameters: the readings' (noise variance per component) plus
  // the prior's, which holds the parameters the poses do not move to a robot's usual geometric errors.
  Eigen::MatrixXd information = Eigen::MatrixXd::Zero(count, count);
  for (Eigen::Index k = 0; k < count; ++k) information(k, k) = 1.0 / (prior_sd(static_cast<int>(k)) * prior_sd(static_cast<int>(k)));
  for (std::size_t i = 0; i < q_deg.size(); ++i) {
    const MdhModel at = point_of_reading_mm.empty() ? model : model.with_tool_point(point_of_reading_mm[i]);
    rows[i] = parameter_columns(at, q_deg[i], out.parameters);
    const double w = weights.empty() ? 1.0 : weights[i];
    information.noalias() += (w / noise_variance_mm2) * rows[i].transpose() * rows[i];
  }
  const Eigen::LLT<Eigen::MatrixXd> llt(information);
  if (llt.info() != Eigen::Success) return std::nullopt;
  out.inverse_information = llt.solve(Eigen::MatrixXd::Identity(count, count));
  out.inverse_information = 0.5 * (out.inverse_information + out.inverse_information.transpose()).eval();
  for (std::size_t i = 0; i < q_deg.size(); ++i) {
    if (!weights.empty() && !(weights[i] > 0.0)) continue;  // a rejected reading is no training pose
    out.largest_training = std::max(out.largest_training, (rows[i] * out.inverse_information * rows[i].transpose()).trace());
  }
  if (!(out.largest_training > 0.0)) return std::nullopt;
  return out;
}

double CalibrationLeverage::at(const MdhModel& model, const JointVector& q_deg) const {
  const Eigen::Matrix<double, 3, Eigen::Dynamic> j = parameter_columns(model, q_deg, parameters);
  return (j * inverse_information * j.transpose()).trace();
}

nlohmann::json CalibrationLeverage::to_json() const {
  nlohmann::json names = nlohmann::json::array(), matrix = nlohmann::json::array();
  for (int p : parameters) names.push_back(parameter_name(p));
  for (Eigen::Index r = 0; r < inverse_information.rows(); ++r) {
    nlohmann::json row = nlohmann::json::array();
    for (Eigen::Index c = 0; c < inverse_information.cols(); ++c) row.push_back(inverse_information(r, c));
    matrix.push_back(std::move(row));
  }
  return {{"parameters", names}, {"inverse_information", matrix}, {"largest_training", largest_training}};
}

CalibrationLeverage CalibrationLeverage::from_json(const nlohmann::json& j, const std::string& source) {
  auto fail = [&](const std::string& what) -> void {
    throw InputError(source + ": member \"calibration_leverage\": " + what, source);
  };
  if (!j.is_object() || !j.contains("parameters") || !j["parameters"].is_array() || !j.contains("inverse_information") ||
      !j["inverse_information"].is_array() || !j.contains("largest_training") || !j["largest_training"].is_number())
    fail("expected {\"parameters\": [names], \"inverse_information\": [[numbers]], \"largest_training\": number}");
  CalibrationLeverage out;
  for (const nlohmann::json& name : j["parameters"]) {
    int index = -1;
    for (int p = 0; p < param::kCount && name.is_string(); ++p)
      if (parameter_name(p) == name.get<std::string>()) index = p;
    if (index < 0) fail("unknown parameter " + name.dump());
    if (std::find(out.parameters.begin(), out.parameters.end(), index) != out.parameters.end())
      fail("parameter " + name.dump() + " listed twice");
    out.parameters.push_back(index);
  }
  const auto n = static_cast<Eigen::Index>(out.parameters.size());
  const nlohmann::json& m = j["inverse_information"];
  if (n == 0 || static_cast<Eigen::Index>(m.size()) != n) fail("expected a square matrix of the parameters' count");
  out.inverse_information.resize(n, n);
  for (Eigen::Index r = 0; r < n; ++r) {
    const nlohmann::json& row = m[static_cast<std::size_t>(r)];
    if (!row.is_array() || static_cast<Eigen::Index>(row.size()) != n) fail("expected a square matrix of the parameters' count");
    for (Eigen::Index c = 0; c < n; ++c) {
      const nlohmann::json& v = row[static_cast<std::size_t>(c)];
      if (!v.is_number() || !std::isfinite(v.get<double>())) fail("the matrix holds a value that is not a finite number");
      out.inverse_information(r, c) = v.get<double>();
    }
  }
  // A covariance: symmetric and positive semi-definite (an indefinite one would make leverages
  // negative, and every pose "inside").
  if (!out.inverse_information.isApprox(out.inverse_information.transpose(), 1e-9))
    fail("the matrix is not symmetric");
  const Eigen::VectorXd eigen = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(out.inverse_information).eigenvalues();
  if (eigen.minCoeff() < -1e-9 * std::max(1.0, eigen.cwiseAbs().maxCoeff())) fail("the matrix is not positive semi-definite");
  out.largest_training = j["largest_training"].get<double>();
  if (!(out.largest_training > 0.0) || !std::isfinite(out.largest_training))
    fail("largest_training must be a positive finite number");
  return out;
}

}  // namespace errfield::compensation
