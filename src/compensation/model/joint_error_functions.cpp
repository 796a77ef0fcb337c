#include "errfield/compensation/model/joint_error_functions.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <nlohmann/json.hpp>

#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"
#include "errfield/json_file.hpp"
#include "errfield/robot/kinematics.hpp"
#include "errfield/variogram_model.hpp"

namespace errfield::compensation {

namespace {

constexpr int kJoints = robot::kJointCount;
// A joint whose Jacobian column (RMS over the poses) is below this fraction of the largest one's
// gets no function: 1 % is a 10 mm lever beside a 1 m arm.
constexpr double kMinRelativeLever = 0.01;

/// P_1(u) .. P_degree(u) by Bonnet's recursion.
void legendre(double u, int degree, double* out) {
  double previous = 1.0, current = u;
  for (int n = 1; n <= degree; ++n) {
    out[n - 1] = current;
    const double next = ((2.0 * n + 1.0) * u * current - n * previous) / (n + 1.0);
    previous = current;
    current = next;
  }
}

double scaled(double q, double lo, double hi) {
  if (!(hi > lo)) return 0.0;
  return std::clamp(2.0 * (q - lo) / (hi - lo) - 1.0, -1.0, 1.0);
}

/// R M R for symmetric R and M, made exactly symmetric. R (a ridge inverse) can be ill-conditioned,
/// and rounding in the two products then leaves mirror entries apart: by 4e-6 of the entry on a
/// 52 x 52 covariance in CI's ASan build, which the model file's reader refused as not symmetric.
Eigen::MatrixXd symmetric_sandwich(const Eigen::MatrixXd& r, const Eigen::MatrixXd& m) {
  const Eigen::MatrixXd s = r * m * r;
  return 0.5 * (s + s.transpose());
}

[[noreturn]] void bad_functions_member(const std::string& source, const std::string& what) {
  throw InputError(source + ": member \"joint_error_functions" + what, source);
}

/// ", got V" for a member that is there (the value as written), "" otherwise.
std::string got(const nlohmann::json& object, const char* key) {
  return object.contains(key) ? ", got " + object[key].dump() : std::string();
}

/// A coefficient covariance read from a file must be one: symmetric (to rounding), positive
/// semi-definite (an indefinite one gave a tool point variance of -823,050 mm² with status ok) and
/// no variance beyond kMaxCoefficientVarianceMrad2 (1e300 made plan's updates overflow).
void check_coefficient_covariance(const Eigen::MatrixXd& c, const std::string& source) {
  const std::string member = ".coefficient_covariance_mrad2\"";
  const double largest = c.cwiseAbs().maxCoeff();
  constexpr double kLargestVariance = kMaxCoefficientVarianceMrad2;
  for (Eigen::Index r = 0; r < c.rows(); ++r) {
    if (c(r, r) < 0.0)
      bad_functions_member(source, member + "[" + std::to_string(r) + "][" + std::to_string(r) + "]: a variance below 0 (" +
                                       format_number(c(r, r)) + ")");
    if (c(r, r) > kLargestVariance)
      bad_functions_member(source, member + "[" + std::to_string(r) + "][" + std::to_string(r) + "]: variance " +
                                       format_number(c(r, r)) + " mrad², beyond " + format_number(kLargestVariance) +
                                       " (no fit leaves a coefficient that uncertain); refit the model with 'errfield fit'");
    for (Eigen::Index k = 0; k < r; ++k)
      if (std::abs(c(r, k) - c(k, r)) > 1e-6 * largest)
        bad_functions_member(source, member + ": not symmetric: [" + std::to_string(r) + "][" + std::to_string(k) + "] = " +
                                         format_number(c(r, k)) + " but [" + std::to_string(k) + "][" + std::to_string(r) +
                                         "] = " + format_number(c(k, r)));
  }
  if (c.rows() == 0 || largest == 0.0) return;
  // Eigenvalues below -1e-9 of the largest are no rounding of a covariance fit computed.
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(0.5 * (c + c.transpose()), Eigen::EigenvaluesOnly);
  const double lowest = eigen.eigenvalues().minCoeff(), highest = eigen.eigenvalues().maxCoeff();
  if (lowest < -1e-9 * std::max(highest, 0.0))
    bad_functions_member(source, member + ": not positive semi-definite (eigenvalue " + format_number(lowest) +
                                     " mrad² beside " + format_number(highest) +
                                     "): some combination of the coefficients would have a negative variance; refit the "
                                     "model with 'errfield fit'");
}

/// Ridge least squares of y on the design's columns with the penalty that minimizes generalized
/// cross-validation, from none (lambda -> infinity: no functions) down to 1e-12 of the largest
/// eigenvalue of the Gram matrix: GCV(lambda) = rows * RSS / (rows - df)^2. All penalties come from
/// one eigendecomposition of the p x p Gram matrix F'F = V diag(s^2) V' (p <= 120: cheap, where a
/// thin SVD of the rows x p design cost ~30 s of compile time): beta = V diag(1 / (s^2 + lambda))
/// V'F'y. With z = V'F'y, the design's own coordinates of y are z_k / s_k, and the part of y outside
/// its columns is |y|^2 - sum (z_k/s_k)^2.
struct RidgeFit {
  Eigen::VectorXd beta;           ///< zero when no penalty beat "no functions"
  Eigen::MatrixXd ridge_inverse;  ///< (F'F + lambda I)^-1; empty then
  double lambda = std::numeric_limits<double>::infinity();
  double largest_s2 = 0.0;
  double effective_parameters = 0.0;
  /// ridge_with_prior: the residual variance of the uniform ridge's fit and the prior's penalty
  /// per column (noise_variance / sd^2); empty without a prior.
  double noise_variance = 0.0;
  Eigen::VectorXd prior_penalty;
};

RidgeFit ridge_by_gcv(const Eigen::MatrixXd& design, const Eigen::VectorXd& y) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> gram(design.transpose() * design);
  const Eigen::VectorXd s2 = gram.eigenvalues().cwiseMax(0.0);
  const Eigen::MatrixXd& v = gram.eigenvectors();
  const Eigen::VectorXd z = v.transpose() * (design.transpose() * y);
  RidgeFit out;
  out.largest_s2 = s2.size() > 0 ? s2.maxCoeff() : 0.0;
  Eigen::VectorXd uy = Eigen::VectorXd::Zero(s2.size());
  for (Eigen::Index k = 0; k < s2.size(); ++k)
    if (s2[k] > 1e-14 * out.largest_s2) uy[k] = z[k] / std::sqrt(s2[k]);
  const double yy = y.squaredNorm(), outside = std::max(yy - uy.squaredNorm(), 0.0);
  const auto rows = static_cast<double>(design.rows());
  double best_gcv = rows * yy / (rows * rows);
  if (out.largest_s2 > 0.0)
    for (double t = 0.0; t <= 12.0; t += 0.25) {
      const double lambda = out.largest_s2 * std::pow(10.0, -t);
      double rss = outside, df = 0.0;
      for (Eigen::Index k = 0; k < s2.size(); ++k) {
        const double shrink = lambda / (s2[k] + lambda);
        rss += shrink * shrink * uy[k] * uy[k];
        df += s2[k] / (s2[k] + lambda);
      }
      if (df >= rows - 1.0) continue;
      const double gcv = rows * rss / ((rows - df) * (rows - df));
      if (gcv < best_gcv) {
        best_gcv = gcv;
        out.lambda = lambda;
        out.effective_parameters = df;
      }
    }
  out.beta = Eigen::VectorXd::Zero(design.cols());
  if (std::isfinite(out.lambda)) {
    Eigen::VectorXd inv(s2.size());
    for (Eigen::Index k = 0; k < s2.size(); ++k) inv[k] = 1.0 / (s2[k] + out.lambda);
    out.ridge_inverse = v * inv.asDiagonal() * v.transpose();
    out.beta = v * inv.cwiseProduct(z);
  }
  return out;
}

/// The ridge with the physical prior: penalty lambda I + diag(sigma^2 / sd_k^2), sigma^2 the noise
/// variance the uniform ridge's GCV fit leaves (RSS / (rows - df)), lambda again by GCV over the same
/// grid (or no functions). The uniform ridge alone lets GCV pick penalties down to 1e-12 of the
/// largest eigenvalue, so a direction the measured point barely sees (angle errors that turn the
/// flange about it) takes whatever coefficient fits the residuals' noise: 49 mrad on real data, and
/// -446 / +441 mrad gravity terms on 40 tool-down poses (issue 34). p <= ~140 columns: one
/// Cholesky factorization of p x p per penalty.
RidgeFit ridge_with_prior(const Eigen::MatrixXd& design, const Eigen::VectorXd& y, const Eigen::VectorXd& prior_sd) {
  RidgeFit out = ridge_by_gcv(design, y);
  // No finite sd (the prior off, or only gravity sds without gravity terms): the plain ridge is the fit.
  if (!std::isfinite(out.lambda) || prior_sd.size() != design.cols() || !prior_sd.array().isFinite().any()) return out;
  const Eigen::MatrixXd gram = design.transpose() * design;
  const Eigen::VectorXd fy = design.transpose() * y;
  const double yy = y.squaredNorm();
  const auto rows = static_cast<double>(design.rows());
  const double rss_uniform = std::max(yy - 2.0 * out.beta.dot(fy) + out.beta.dot(gram * out.beta), 0.0);
  out.noise_variance = rss_uniform / std::max(rows - out.effective_parameters, 1.0);
  out.prior_penalty = out.noise_variance * prior_sd.cwiseInverse().cwiseAbs2();
  const Eigen::Index p = design.cols();
  double best_gcv = rows * yy / (rows * rows);
  double best_lambda = std::numeric_limits<double>::infinity();
  for (double t = 0.0; t <= 12.0; t += 0.25) {
    const double lambda = out.largest_s2 * std::pow(10.0, -t);
    Eigen::MatrixXd a = gram;
    a.diagonal().array() += lambda;
    a.diagonal() += out.prior_penalty;
    const Eigen::LLT<Eigen::MatrixXd> llt(a);
    if (llt.info() != Eigen::Success) continue;
    const Eigen::MatrixXd inverse = llt.solve(Eigen::MatrixXd::Identity(p, p));
    const Eigen::VectorXd beta = inverse * fy;
    const double rss = std::max(yy - 2.0 * beta.dot(fy) + beta.dot(gram * beta), 0.0);
    const double df = inverse.cwiseProduct(gram).sum();
    if (df >= rows - 1.0) continue;
    const double gcv = rows * rss / ((rows - df) * (rows - df));
    if (gcv < best_gcv) {
      best_gcv = gcv;
      best_lambda = lambda;
      out.effective_parameters = df;
      out.ridge_inverse = inverse;
      out.beta = beta;
    }
  }
  out.lambda = best_lambda;
  if (!std::isfinite(best_lambda)) {  // no functions beat the prior's
    out.beta = Eigen::VectorXd::Zero(p);
    out.ridge_inverse.resize(0, 0);
    out.effective_parameters = 0.0;
    out.prior_penalty.resize(0);
  }
  return out;
}

/// Covariance of two readings of one component at the model-mapped joints a and b (field and
/// nugget on a reading itself, the field only between two readings at one location).
double reading_covariance(const VariogramModel& m, const Eigen::VectorXd& a, const Eigen::VectorXd& b, bool same) {
  if (same) return m.sill();
  const double h = (a - b).norm();
  return h > 0.0 ? m.sill() - m.gamma(h) : m.sill() - m.nugget();
}

}  // namespace

double gravity_lever_m(const robot::KinematicFrames& frames, int joint, int frame) {
  const Eigen::Isometry3d& axis = frames.frames[static_cast<std::size_t>(joint + 1)];
  const Eigen::Vector3d arm = frames.frames[static_cast<std::size_t>(frame)].translation() - axis.translation();
  // ĝ = -z of the world frame: ĝ · (z × arm) = -(z × arm)_z.
  return -1e-3 * axis.linear().col(2).cross(arm).z();
}

namespace {

/// The coefficients as one vector in the design's column order.
Eigen::VectorXd coefficient_vector(const JointErrorFunctions& f) {
  Eigen::VectorXd beta(f.parameter_count());
  for (int j = 0; j < kJoints; ++j)
    for (int k = 0; k < f.degree; ++k) beta[j * f.degree + k] = f.coefficients_mrad(j, k);
  for (std::size_t t = 0; t < f.gravity_terms.size(); ++t)
    beta[kJoints * f.degree + static_cast<Eigen::Index>(t)] = f.gravity_terms[t].coefficient_mrad;
  return beta;
}

void set_coefficients(JointErrorFunctions& f, const Eigen::VectorXd& beta) {
  f.coefficients_mrad = Eigen::Map<const Eigen::MatrixXd>(beta.data(), f.degree, kJoints).transpose();
  for (std::size_t t = 0; t < f.gravity_terms.size(); ++t)
    f.gravity_terms[t].coefficient_mrad = beta[kJoints * f.degree + static_cast<Eigen::Index>(t)];
}

/// The prior sd of each coefficient in the design's column order.
Eigen::VectorXd prior_sd_of(const JointErrorFunctions& f, const JointFunctionPrior& prior) {
  Eigen::VectorXd sd(f.parameter_count());
  sd.head(kJoints * f.degree).setConstant(prior.polynomial_sd_mrad);
  sd.tail(static_cast<Eigen::Index>(f.gravity_terms.size())).setConstant(prior.gravity_sd_mrad);
  return sd;
}

/// The gravity terms whose design column lies (to within `min_fraction` of its norm) in the span of
/// the joint-offset columns J_j(q_i) of the joints that move the point: over a batch where the lever
/// barely varies (one tool orientation, a small cube) the term is a joint offset, which the
/// calibration already holds, and the pair of them is free to cancel.
std::vector<std::size_t> undetermined_gravity_terms(const JointErrorFunctions& f, const std::vector<robot::KinematicFrames>& frames,
                                                    const std::array<bool, kJoints>& moves_the_point, double min_fraction) {
  std::vector<std::size_t> out;
  if (f.gravity_terms.empty() || !(min_fraction > 0.0)) return out;
  const auto n = static_cast<Eigen::Index>(frames.size());
  int moving = 0;
  for (bool m : moves_the_point) moving += m ? 1 : 0;
  Eigen::MatrixXd offsets(3 * n, moving);
  Eigen::MatrixXd gravity(3 * n, static_cast<Eigen::Index>(f.gravity_terms.size()));
  for (Eigen::Index i = 0; i < n; ++i) {
    const robot::KinematicFrames& at = frames[static_cast<std::size_t>(i)];
    const Eigen::Matrix<double, 6, 6> jacobian = robot::geometric_jacobian(at, robot::EndFrame::tool);
    for (int j = 0, c = 0; j < kJoints; ++j)
      if (moves_the_point[static_cast<std::size_t>(j)]) offsets.block<3, 1>(3 * i, c++) = jacobian.block<3, 1>(0, j);
    for (std::size_t t = 0; t < f.gravity_terms.size(); ++t) {
      const GravityLoadTerm& g = f.gravity_terms[t];
      gravity.block<3, 1>(3 * i, static_cast<Eigen::Index>(t)) = gravity_lever_m(at, g.joint, g.frame) * jacobian.block<3, 1>(0, g.joint);
    }
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(offsets);
  for (Eigen::Index t = 0; t < gravity.cols(); ++t) {
    const Eigen::VectorXd column = gravity.col(t);
    const double norm = column.norm();
    if (!(norm > 0.0)) continue;
    const Eigen::VectorXd outside = column - offsets * qr.solve(column);
    if (outside.norm() < min_fraction * norm) out.push_back(static_cast<std::size_t>(t));
  }
  return out;
}

// A gravity term whose lever's RMS over the poses is below this fraction of the largest term's
// carries no load worth a coefficient: the lever about a vertical axis is zero up to the base's
// tilt (a milliradian: 0.1 % of an arm's lever).
constexpr double kMinRelativeGravityLever = 0.02;

/// The gravity-load terms of the joints that move the point: every frame origin beyond the joint
/// and the tool point, unless its lever is negligible or (to 1e-6 of its RMS at every pose) the
/// lever of an earlier point of the same joint (coincident origins, as at a spherical wrist).
std::vector<GravityLoadTerm> gravity_terms_over(const std::vector<robot::KinematicFrames>& frames,
                                                const std::array<bool, kJoints>& moves_the_point) {
  struct Candidate {
    GravityLoadTerm term;
    Eigen::VectorXd lever;
  };
  std::vector<Candidate> candidates;
  double largest_rms = 0.0;
  const auto n = static_cast<Eigen::Index>(frames.size());
  for (int j = 0; j < kJoints; ++j) {
    if (!moves_the_point[static_cast<std::size_t>(j)]) continue;
    for (int frame = j + 2; frame <= kJoints + 1; ++frame) {
      Candidate c;
      c.term.joint = j;
      c.term.frame = frame;
      c.lever.resize(n);
      for (Eigen::Index i = 0; i < n; ++i) c.lever[i] = gravity_lever_m(frames[static_cast<std::size_t>(i)], j, frame);
      c.term.scale_m = std::sqrt(c.lever.squaredNorm() / static_cast<double>(std::max<Eigen::Index>(n, 1)));
      largest_rms = std::max(largest_rms, c.term.scale_m);
      candidates.push_back(std::move(c));
    }
  }
  std::vector<GravityLoadTerm> terms;
  std::vector<const Candidate*> kept;
  for (const Candidate& c : candidates) {
    if (!(c.term.scale_m > kMinRelativeGravityLever * largest_rms)) continue;
    const bool copy = std::any_of(kept.begin(), kept.end(), [&](const Candidate* k) {
      return k->term.joint == c.term.joint && (k->lever - c.lever).cwiseAbs().maxCoeff() <= 1e-6 * c.term.scale_m;
    });
    if (copy) continue;
    kept.push_back(&c);
    terms.push_back(c.term);
  }
  return terms;
}

/// The gravity terms' angle error of each joint (mrad) at the pose `frames` describe.
Eigen::Matrix<double, 6, 1> gravity_deflection_mrad(const JointErrorFunctions& f, const robot::KinematicFrames& frames) {
  Eigen::Matrix<double, 6, 1> dq = Eigen::Matrix<double, 6, 1>::Zero();
  for (const GravityLoadTerm& t : f.gravity_terms) dq[t.joint] += t.coefficient_mrad * gravity_lever_m(frames, t.joint, t.frame) / t.scale_m;
  return dq;
}

double largest_gravity_deflection(const JointErrorFunctions& f, const std::vector<robot::KinematicFrames>& frames) {
  double largest = 0.0;
  for (const robot::KinematicFrames& at : frames) largest = std::max(largest, gravity_deflection_mrad(f, at).cwiseAbs().maxCoeff());
  return largest;
}

}  // namespace

Eigen::Matrix<double, 6, 1> JointErrorFunctions::angle_error_mrad(const robot::JointVector& q_deg, const robot::MdhModel* model) const {
  Eigen::Matrix<double, 6, 1> dq = Eigen::Matrix<double, 6, 1>::Zero();
  std::vector<double> p(static_cast<std::size_t>(std::max(degree, 1)));
  for (int j = 0; j < kJoints; ++j) {
    if (!(hi_deg[j] > lo_deg[j])) continue;
    legendre(scaled(q_deg[j], lo_deg[j], hi_deg[j]), degree, p.data());
    for (int k = 0; k < degree; ++k) dq[j] += coefficients_mrad(j, k) * p[static_cast<std::size_t>(k)];
  }
  if (model && !gravity_terms.empty()) {
    robot::KinematicFrames frames;
    robot::forward_kinematics_all(*model, q_deg, frames);
    dq += gravity_deflection_mrad(*this, frames);
  }
  return dq;
}

Eigen::MatrixXd JointErrorFunctions::design_rows(const robot::KinematicFrames& frames, const robot::JointVector& q_deg) const {
  const Eigen::Matrix<double, 6, 6> jacobian = robot::geometric_jacobian(frames, robot::EndFrame::tool);
  Eigen::MatrixXd d = Eigen::MatrixXd::Zero(3, parameter_count());
  std::vector<double> p(static_cast<std::size_t>(std::max(degree, 1)));
  for (int j = 0; j < kJoints; ++j) {
    if (!(hi_deg[static_cast<std::size_t>(j)] > lo_deg[static_cast<std::size_t>(j)])) continue;
    legendre(scaled(q_deg[j], lo_deg[static_cast<std::size_t>(j)], hi_deg[static_cast<std::size_t>(j)]), degree, p.data());
    for (int k = 0; k < degree; ++k) d.col(j * degree + k) = 1e-3 * p[static_cast<std::size_t>(k)] * jacobian.block<3, 1>(0, j);
  }
  for (std::size_t t = 0; t < gravity_terms.size(); ++t) {
    const GravityLoadTerm& g = gravity_terms[t];
    d.col(kJoints * degree + static_cast<Eigen::Index>(t)) =
        1e-3 * gravity_lever_m(frames, g.joint, g.frame) / g.scale_m * jacobian.block<3, 1>(0, g.joint);
  }
  return d;
}

Eigen::MatrixXd JointErrorFunctions::design_rows(const robot::MdhModel& model, const robot::JointVector& q_deg) const {
  robot::KinematicFrames frames;
  robot::forward_kinematics_all(model, q_deg, frames);
  return design_rows(frames, q_deg);
}

Eigen::MatrixXd JointErrorFunctions::design_rows_at_point(const robot::MdhModel& reflector, const robot::MdhModel& at,
                                                          const robot::JointVector& q_deg) const {
  Eigen::MatrixXd d = design_rows(reflector, q_deg);
  const Eigen::Matrix<double, 3, kJoints> ja =
      robot::geometric_jacobian(reflector, q_deg, robot::EndFrame::tool).topRows<3>();
  const Eigen::Matrix<double, 3, kJoints> jb = robot::geometric_jacobian(at, q_deg, robot::EndFrame::tool).topRows<3>();
  const Eigen::Index polynomial = kJoints * static_cast<Eigen::Index>(degree);
  for (Eigen::Index c = 0; c < d.cols(); ++c) {
    const int j = c < polynomial ? static_cast<int>(c / degree) : gravity_terms[static_cast<std::size_t>(c - polynomial)].joint;
    const double n2 = ja.col(j).squaredNorm();
    d.col(c) = n2 > 0.0 ? Eigen::Vector3d(jb.col(j) * (ja.col(j).dot(d.col(c)) / n2)) : Eigen::Vector3d::Zero();
  }
  return d;
}

JointFunctionPrediction JointErrorFunctions::predict(const robot::MdhModel& model, const robot::JointVector& q_deg,
                                                    const Eigen::MatrixXd* taken_back) const {
  JointFunctionPrediction out;
  if (parameter_count() == 0) return out;
  // One design block for both: the same mapping the fit used.
  Eigen::MatrixXd d = design_rows(model, q_deg);
  out.position_error_mm = d * coefficient_vector(*this);
  if (coefficient_covariance_mrad2.size() > 0) {
    if (taken_back) {
      if (taken_back->rows() != 3 || taken_back->cols() != d.cols())
        throw ArgumentError("JointErrorFunctions::predict: taken_back is " + std::to_string(taken_back->rows()) + " x " +
                            std::to_string(taken_back->cols()) + "; expected 3 x " + std::to_string(d.cols()));
      d -= *taken_back;
    }
    out.axis_variance_mm2 = (d * coefficient_covariance_mrad2 * d.transpose()).diagonal();
  }
  return out;
}

Eigen::Vector3d JointErrorFunctions::axis_variance_mm2(const robot::MdhModel& model, const robot::JointVector& q_deg) const {
  return predict(model, q_deg).axis_variance_mm2;
}

Eigen::Vector3d JointErrorFunctions::position_error_mm(const robot::MdhModel& model, const robot::JointVector& q_deg) const {
  return predict(model, q_deg).position_error_mm;
}

double JointErrorFunctions::largest_angle_error_mrad() const {
  double largest = 0.0;
  std::vector<double> p(static_cast<std::size_t>(std::max(degree, 1)));
  for (int j = 0; j < kJoints; ++j)
    for (int s = 0; s <= 200; ++s) {
      legendre(-1.0 + s / 100.0, degree, p.data());
      double dq = 0.0;
      for (int k = 0; k < degree; ++k) dq += coefficients_mrad(j, k) * p[static_cast<std::size_t>(k)];
      largest = std::max(largest, std::abs(dq));
    }
  return largest;
}

JointErrorFunctions::Size JointErrorFunctions::size_over(const robot::MdhModel& model,
                                                         const std::vector<robot::JointVector>& poses_deg) const {
  Size out;
  for (const robot::JointVector& q : poses_deg) {
    const Eigen::Matrix<double, 6, 1> polynomial = angle_error_mrad(q);
    const Eigen::Matrix<double, 6, 1> total = angle_error_mrad(q, &model);
    for (int j = 0; j < kJoints; ++j) {
      if (out.largest_joint < 0 || std::abs(total[j]) > out.largest_mrad) {
        out.largest_mrad = std::abs(total[j]);
        out.largest_joint = j;
      }
      const double gravity = total[j] - polynomial[j];
      const double smaller = std::min(std::abs(polynomial[j]), std::abs(gravity));
      if (polynomial[j] * gravity < 0.0 && smaller > out.cancelling_mrad) {
        out.cancelling_mrad = smaller;
        out.cancelling_polynomial_mrad = polynomial[j];
        out.cancelling_gravity_mrad = gravity;
        out.cancelling_joint = j;
      }
    }
  }
  return out;
}

nlohmann::json JointErrorFunctions::to_json() const {
  nlohmann::json c = nlohmann::json::array();
  for (int j = 0; j < kJoints; ++j) {
    nlohmann::json row = nlohmann::json::array();
    for (int k = 0; k < degree; ++k) row.push_back(coefficients_mrad(j, k));
    c.push_back(row);
  }
  nlohmann::json j = {{"degree", degree}, {"lo_deg", lo_deg}, {"hi_deg", hi_deg}, {"coefficients_mrad", c}};
  if (!gravity_terms.empty()) {
    nlohmann::json g = nlohmann::json::array();
    for (const GravityLoadTerm& t : gravity_terms)
      g.push_back({{"joint", t.joint + 1}, {"frame", t.frame}, {"scale_m", t.scale_m}, {"coefficient_mrad", t.coefficient_mrad}});
    j["gravity_terms"] = g;
  }
  if (coefficient_covariance_mrad2.size() > 0) {
    nlohmann::json cov = nlohmann::json::array();
    for (Eigen::Index r = 0; r < coefficient_covariance_mrad2.rows(); ++r) {
      nlohmann::json row = nlohmann::json::array();
      for (Eigen::Index k = 0; k < coefficient_covariance_mrad2.cols(); ++k) row.push_back(coefficient_covariance_mrad2(r, k));
      cov.push_back(row);
    }
    j["coefficient_covariance_mrad2"] = cov;
  }
  return j;
}

JointErrorFunctions JointErrorFunctions::from_json(const nlohmann::json& j, const std::string& source) {
  if (!j.is_object()) bad_functions_member(source, "\": expected an object {degree, lo_deg, hi_deg, coefficients_mrad}");
  JointErrorFunctions f;
  const auto degree = j.contains("degree") ? json_integer_in(j["degree"], 1, 20) : std::nullopt;
  if (!degree) bad_functions_member(source, ".degree\": expected an integer 1..20" + got(j, "degree"));
  f.degree = static_cast<int>(*degree);
  auto six = [&](const char* key, std::array<double, 6>& into) {
    if (!j.contains(key) || !j[key].is_array() || j[key].size() != 6) bad_functions_member(source, std::string(".") + key + "\": expected 6 numbers (deg)");
    for (std::size_t k = 0; k < 6; ++k) {
      if (!j[key][k].is_number() || !std::isfinite(j[key][k].get<double>()))
        bad_functions_member(source, std::string(".") + key + "\"[" + std::to_string(k) + "]: expected a finite number (deg)");
      into[k] = j[key][k].get<double>();
    }
  };
  six("lo_deg", f.lo_deg);
  six("hi_deg", f.hi_deg);
  for (int k = 0; k < kJoints; ++k)
    if (f.hi_deg[static_cast<std::size_t>(k)] < f.lo_deg[static_cast<std::size_t>(k)])
      bad_functions_member(source, ".hi_deg\"[" + std::to_string(k) + "]: below lo_deg");
  const auto& c = j.contains("coefficients_mrad") ? j["coefficients_mrad"] : nlohmann::json();
  if (!c.is_array() || c.size() != 6) bad_functions_member(source, ".coefficients_mrad\": expected 6 arrays of " + std::to_string(f.degree) + " numbers");
  f.coefficients_mrad.resize(kJoints, f.degree);
  for (std::size_t r = 0; r < 6; ++r) {
    if (!c[r].is_array() || c[r].size() != static_cast<std::size_t>(f.degree))
      bad_functions_member(source, ".coefficients_mrad\"[" + std::to_string(r) + "]: expected " + std::to_string(f.degree) + " numbers");
    for (std::size_t k = 0; k < c[r].size(); ++k) {
      if (!c[r][k].is_number() || !std::isfinite(c[r][k].get<double>()))
        bad_functions_member(source, ".coefficients_mrad\"[" + std::to_string(r) + "][" + std::to_string(k) + "]: expected a finite number");
      f.coefficients_mrad(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(k)) = c[r][k].get<double>();
    }
    // The joint's largest angle error over its fitted range (sampled as largest_angle_error_mrad).
    double largest = 0.0;
    std::vector<double> basis(static_cast<std::size_t>(f.degree));
    for (int s = 0; s <= 200; ++s) {
      legendre(-1.0 + s / 100.0, f.degree, basis.data());
      double dq = 0.0;
      for (int k = 0; k < f.degree; ++k) dq += f.coefficients_mrad(static_cast<Eigen::Index>(r), k) * basis[static_cast<std::size_t>(k)];
      largest = std::max(largest, std::abs(dq));
    }
    if (!(largest <= kMaxCredibleAngleErrorMrad))
      bad_functions_member(source, ".coefficients_mrad\"[" + std::to_string(r) + "]: angle errors up to " +
                                       format_number(largest) + " mrad; a joint error function beyond " +
                                       format_number(kMaxCredibleAngleErrorMrad) +
                                       " mrad (about 57 degrees) is no calibration residual: refit the model with 'errfield fit'");
  }
  if (j.contains("gravity_terms")) {
    const auto& g = j["gravity_terms"];
    if (!g.is_array()) bad_functions_member(source, ".gravity_terms\": expected an array of {joint, frame, scale_m, coefficient_mrad}");
    for (std::size_t t = 0; t < g.size(); ++t) {
      const std::string at = ".gravity_terms\"[" + std::to_string(t) + "]";
      const auto& e = g[t];
      if (!e.is_object()) bad_functions_member(source, at + ": expected {joint, frame, scale_m, coefficient_mrad}");
      GravityLoadTerm term;
      const auto joint = e.contains("joint") ? json_integer_in(e["joint"], 1, 6) : std::nullopt;
      if (!joint) bad_functions_member(source, at + ".joint: expected an integer 1..6" + got(e, "joint"));
      term.joint = static_cast<int>(*joint) - 1;
      // The loaded point lies beyond the joint: frames joint+1 .. 7 (1-based joint; 7 = the tool point).
      const auto frame = e.contains("frame") ? json_integer_in(e["frame"], term.joint + 2, 7) : std::nullopt;
      if (!frame)
        bad_functions_member(source, at + ".frame: expected an integer " + std::to_string(term.joint + 2) + "..7 (a frame beyond joint " +
                                         std::to_string(term.joint + 1) + "; 7 = the tool point)" + got(e, "frame"));
      term.frame = static_cast<int>(*frame);
      // fit sets scale_m to the lever's RMS over the fitted poses: millimetres to metres on any arm.
      // The design divides by it, so 1e-300 made every design row overflow (plan crashed on it).
      if (!e.contains("scale_m") || !e["scale_m"].is_number() || !(e["scale_m"].get<double>() >= kMinGravityScaleM) ||
          !(e["scale_m"].get<double>() <= kMaxGravityScaleM))
        bad_functions_member(source, at + ".scale_m: expected a lever scale from " + format_number(kMinGravityScaleM) + " to " +
                                         format_number(kMaxGravityScaleM) + " m" + got(e, "scale_m"));
      term.scale_m = e["scale_m"].get<double>();
      if (!e.contains("coefficient_mrad") || !e["coefficient_mrad"].is_number() ||
          !(std::abs(e["coefficient_mrad"].get<double>()) <= kMaxCredibleAngleErrorMrad))
        bad_functions_member(source, at + ".coefficient_mrad: expected a deflection within +-" +
                                         format_number(kMaxCredibleAngleErrorMrad) + " mrad (about 57 degrees at the "
                                         "fitted poses' RMS lever; beyond it is no calibration residual)" +
                                         got(e, "coefficient_mrad"));
      term.coefficient_mrad = e["coefficient_mrad"].get<double>();
      f.gravity_terms.push_back(term);
    }
  }
  if (j.contains("coefficient_covariance_mrad2")) {
    const auto& v = j["coefficient_covariance_mrad2"];
    const auto p = static_cast<std::size_t>(f.parameter_count());
    if (!v.is_array() || v.size() != p)
      bad_functions_member(source, ".coefficient_covariance_mrad2\": expected " + std::to_string(p) + " rows of " + std::to_string(p) + " numbers");
    f.coefficient_covariance_mrad2.resize(static_cast<Eigen::Index>(p), static_cast<Eigen::Index>(p));
    for (std::size_t r = 0; r < p; ++r) {
      if (!v[r].is_array() || v[r].size() != p)
        bad_functions_member(source, ".coefficient_covariance_mrad2\"[" + std::to_string(r) + "]: expected " + std::to_string(p) + " numbers");
      for (std::size_t k = 0; k < p; ++k) {
        if (!v[r][k].is_number() || !std::isfinite(v[r][k].get<double>()))
          bad_functions_member(source, ".coefficient_covariance_mrad2\"[" + std::to_string(r) + "][" + std::to_string(k) + "]: expected a finite number");
        f.coefficient_covariance_mrad2(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(k)) = v[r][k].get<double>();
      }
    }
    check_coefficient_covariance(f.coefficient_covariance_mrad2, source);
  }
  return f;
}

void JointFunctionPrior::validate() const {
  if (!(polynomial_sd_mrad > 0.0) || !(gravity_sd_mrad > 0.0))
    throw ArgumentError("JointFunctionPrior: prior sd " + std::to_string(polynomial_sd_mrad) + " / " +
                        std::to_string(gravity_sd_mrad) + " mrad; expected values > 0 (infinity: no prior)");
  if (!(min_identifiable_fraction >= 0.0 && min_identifiable_fraction < 1.0))
    throw ArgumentError("JointFunctionPrior: min_identifiable_fraction " + std::to_string(min_identifiable_fraction) +
                        "; expected 0 <= value < 1");
}

JointErrorFunctionFit fit_joint_error_functions(const robot::MdhModel& model, const std::vector<robot::JointVector>& q_deg,
                                                const std::vector<Eigen::Vector3d>& residual_mm, int degree,
                                                bool gravity_load, const JointFunctionPrior& prior) {
  if (degree < 1 || degree > 20)
    throw ArgumentError("fit_joint_error_functions: degree " + std::to_string(degree) + "; expected 1..20");
  if (q_deg.size() != residual_mm.size() || q_deg.empty())
    throw ArgumentError("fit_joint_error_functions: " + std::to_string(q_deg.size()) + " poses for " +
                        std::to_string(residual_mm.size()) + " residuals");
  const auto n = static_cast<Eigen::Index>(q_deg.size());
  JointErrorFunctionFit out;
  JointErrorFunctions& f = out.functions;
  f.degree = degree;
  f.lo_deg.fill(std::numeric_limits<double>::infinity());
  f.hi_deg.fill(-std::numeric_limits<double>::infinity());
  for (const auto& q : q_deg)
    for (int j = 0; j < kJoints; ++j) {
      f.lo_deg[static_cast<std::size_t>(j)] = std::min(f.lo_deg[static_cast<std::size_t>(j)], q[j]);
      f.hi_deg[static_cast<std::size_t>(j)] = std::max(f.hi_deg[static_cast<std::size_t>(j)], q[j]);
    }
  // A joint that barely moved carries no function: its polynomial in u would be fitted to noise.
  for (std::size_t j = 0; j < 6; ++j)
    if (f.hi_deg[j] - f.lo_deg[j] < 1.0) f.hi_deg[j] = f.lo_deg[j];
  // Nor does a joint that barely moves the measured point (a wrist joint turning a reflector that
  // sits near its axis): its coefficients would be free to absorb anything at huge angles.
  std::vector<robot::KinematicFrames> frames(q_deg.size());
  Eigen::Matrix<double, 6, 1> lever = Eigen::Matrix<double, 6, 1>::Zero();  // mean |J_j|^2, (mm/rad)^2
  for (std::size_t i = 0; i < q_deg.size(); ++i) {
    robot::forward_kinematics_all(model, q_deg[i], frames[i]);
    lever += robot::geometric_jacobian(frames[i], robot::EndFrame::tool).topRows<3>().colwise().squaredNorm().transpose();
  }
  std::array<bool, kJoints> moves_the_point{};
  for (int j = 0; j < kJoints; ++j) {
    moves_the_point[static_cast<std::size_t>(j)] = lever[j] >= kMinRelativeLever * kMinRelativeLever * lever.maxCoeff();
    if (!moves_the_point[static_cast<std::size_t>(j)]) f.hi_deg[static_cast<std::size_t>(j)] = f.lo_deg[static_cast<std::size_t>(j)];
  }
  prior.validate();
  if (gravity_load) {
    f.gravity_terms = gravity_terms_over(frames, moves_the_point);
    const std::vector<std::size_t> undetermined =
        undetermined_gravity_terms(f, frames, moves_the_point, prior.min_identifiable_fraction);
    for (auto it = undetermined.rbegin(); it != undetermined.rend(); ++it) {
      const GravityLoadTerm& g = f.gravity_terms[*it];
      out.undetermined_gravity_terms.insert(out.undetermined_gravity_terms.begin(),
                                            "joint " + std::to_string(g.joint + 1) + " frame " + std::to_string(g.frame));
      f.gravity_terms.erase(f.gravity_terms.begin() + static_cast<std::ptrdiff_t>(*it));
    }
  }
  const Eigen::Index p = f.parameter_count();
  // Design: row 3i+a, column j*degree+k-1 = J_j(q_i)[a] * P_k(u_ij) * 1e-3 (mm per mrad), then the
  // gravity terms' columns J_j(q_i)[a] * lever(q_i) / scale * 1e-3.
  Eigen::MatrixXd design = Eigen::MatrixXd::Zero(3 * n, p);
  Eigen::VectorXd y(3 * n);
  for (Eigen::Index i = 0; i < n; ++i) {
    y.segment<3>(3 * i) = residual_mm[static_cast<std::size_t>(i)];
    design.middleRows<3>(3 * i) = f.design_rows(frames[static_cast<std::size_t>(i)], q_deg[static_cast<std::size_t>(i)]);
  }
  const RidgeFit ridge = ridge_with_prior(design, y, prior_sd_of(f, prior));
  out.ridge_inverse = ridge.ridge_inverse;
  if (ridge.prior_penalty.size() > 0) out.prior_middle_diagonal = ridge.noise_variance * ridge.prior_penalty;
  const Eigen::VectorXd& beta = ridge.beta;
  const double best_lambda = ridge.lambda, best_df = ridge.effective_parameters, s2max = ridge.largest_s2;
  set_coefficients(f, beta);
  out.largest_gravity_deflection_mrad = largest_gravity_deflection(f, frames);
  const Eigen::VectorXd fitted = design * beta;
  out.remaining_mm.resize(static_cast<std::size_t>(n));
  double before = 0.0, after = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) {
    out.remaining_mm[static_cast<std::size_t>(i)] = y.segment<3>(3 * i) - fitted.segment<3>(3 * i);
    before += y.segment<3>(3 * i).squaredNorm();
    after += out.remaining_mm[static_cast<std::size_t>(i)].squaredNorm();
  }
  // Leave-one-pose-out residuals of the regression, (I - H_ii)^-1 r_i with H_ii = F_i R F_i' the
  // pose's 3 x 3 block of the ridge hat matrix: the in-sample residuals understate a new pose's by
  // their ratio, which the field's variance calibration has to know.
  if (std::isfinite(best_lambda) && after > 0.0) {
    double held_out = 0.0;
    out.held_out_coefficient_change_mrad.resize(static_cast<std::size_t>(n));
    for (Eigen::Index i = 0; i < n; ++i) {
      const auto fi = design.middleRows<3>(3 * i);
      const Eigen::Matrix3d h = fi * out.ridge_inverse * fi.transpose();
      const Eigen::Vector3d loo = (Eigen::Matrix3d::Identity() - h).inverse() * out.remaining_mm[static_cast<std::size_t>(i)];
      held_out += loo.squaredNorm();
      out.held_out_coefficient_change_mrad[static_cast<std::size_t>(i)] = -(out.ridge_inverse * (fi.transpose() * loo));
    }
    out.leave_one_out_inflation = held_out / after;
  }
  out.design = std::move(design);
  out.rms_before_mm = std::sqrt(before / static_cast<double>(n));
  out.rms_after_mm = std::sqrt(after / static_cast<double>(n));
  out.effective_parameters = best_df;
  out.ridge = std::isfinite(best_lambda) && s2max > 0.0 ? best_lambda / s2max : best_lambda;
  return out;
}

void set_coefficient_covariance(JointErrorFunctionFit& fit, const std::vector<robot::JointVector>& q_deg,
                                const VariogramModel& field_model) {
  JointErrorFunctions& f = fit.functions;
  f.coefficient_covariance_mrad2.resize(0, 0);
  if (fit.ridge_inverse.size() == 0) return;
  const auto n = static_cast<Eigen::Index>(q_deg.size());
  if (fit.design.rows() != 3 * n)
    throw ArgumentError("set_coefficient_covariance: " + std::to_string(q_deg.size()) + " poses for a design of " +
                        std::to_string(fit.design.rows() / 3));
  // The residuals' covariance per component, between the poses' joints in the model's metric.
  Eigen::MatrixXd x(kJoints, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const robot::JointVector& q = q_deg[static_cast<std::size_t>(i)];
    field_model.anisotropy().apply(q.data(), x.col(i).data(), kJoints);
  }
  // Without the covariance of a constant: ordinary kriging estimates each component's mean from the
  // remaining residuals, so a shift of the functions common to all poses does not reach a
  // prediction. (With nearly linear fitted variograms, whose sill is arbitrary and large, that
  // constant part made the variance ~5x too large on SIMULATED ER20 data.) P K P with P = I - 11'/n,
  // applied as F_a' P K P F_a = G_a' K G_a with the centred design columns G_a = P F_a.
  const Eigen::Index p = fit.design.cols();
  std::array<Eigen::MatrixXd, 3> g;
  for (int a = 0; a < 3; ++a) {
    g[static_cast<std::size_t>(a)].resize(n, p);
    for (Eigen::Index i = 0; i < n; ++i) g[static_cast<std::size_t>(a)].row(i) = fit.design.row(3 * i + a);
    g[static_cast<std::size_t>(a)].rowwise() -= g[static_cast<std::size_t>(a)].colwise().mean();
  }
  // F' S F = sum over the three (independent) components of G_a' K G_a, with K assembled a block of
  // columns at a time (never n x n: 5,000 poses would need 200 MB).
  constexpr Eigen::Index kBlock = 256;
  Eigen::MatrixXd middle = Eigen::MatrixXd::Zero(p, p);
  Eigen::MatrixXd k(n, std::min(kBlock, n));
  for (Eigen::Index j0 = 0; j0 < n; j0 += kBlock) {
    const Eigen::Index b = std::min(kBlock, n - j0);
    for (Eigen::Index jj = 0; jj < b; ++jj)
      for (Eigen::Index i = 0; i < n; ++i) k(i, jj) = reading_covariance(field_model, x.col(i), x.col(j0 + jj), i == j0 + jj);
    for (const Eigen::MatrixXd& ga : g) middle.noalias() += (ga.transpose() * k.leftCols(b)) * ga.middleRows(j0, b);
  }
  // Where the prior decided a direction, its bias is as uncertain as the prior: R diag(sigma^2 P) R.
  if (fit.prior_middle_diagonal.size() == p) middle.diagonal() += fit.prior_middle_diagonal;
  f.coefficient_covariance_mrad2 = symmetric_sandwich(fit.ridge_inverse, middle);
}

bool refit_by_generalized_least_squares(JointErrorFunctionFit& fit, const std::vector<robot::JointVector>& q_deg,
                                        const std::vector<Eigen::Vector3d>& residual_mm, const VariogramModel& field_model,
                                        const JointFunctionPrior& prior) {
  const auto n = static_cast<Eigen::Index>(q_deg.size());
  if (fit.design.rows() != 3 * n || residual_mm.size() != q_deg.size())
    throw ArgumentError("refit_by_generalized_least_squares: " + std::to_string(q_deg.size()) + " poses and " +
                        std::to_string(residual_mm.size()) + " residuals for a design of " +
                        std::to_string(fit.design.rows() / 3));
  if (fit.ridge_inverse.size() == 0) return false;  // no function to refit
  Eigen::MatrixXd x(kJoints, n);
  for (Eigen::Index i = 0; i < n; ++i) field_model.anisotropy().apply(q_deg[static_cast<std::size_t>(i)].data(), x.col(i).data(), kJoints);
  Eigen::MatrixXd k(n, n);
  for (Eigen::Index j = 0; j < n; ++j)
    for (Eigen::Index i = j; i < n; ++i) k(i, j) = reading_covariance(field_model, x.col(i), x.col(j), i == j);
  // In place (N^2 once, not twice: fit's dense budget counts such matrices).
  const Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>, Eigen::Lower> llt(k);
  if (llt.info() != Eigen::Success) return false;
  // Whitened by L^-1 (K = L L') and with each component's constant profiled out (ordinary kriging
  // takes it), the GLS problem is an ordinary one: the ridge by GCV as before, on F~ and y~.
  const Eigen::VectorXd w = llt.matrixL().solve(Eigen::VectorXd::Ones(n));
  const double ww = w.squaredNorm();
  const Eigen::Index p = fit.design.cols();
  Eigen::MatrixXd fw(3 * n, p);
  Eigen::VectorXd yw(3 * n);
  for (int a = 0; a < 3; ++a) {
    Eigen::MatrixXd fa(n, p);
    Eigen::VectorXd ya(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      fa.row(i) = fit.design.row(3 * i + a);
      ya[i] = residual_mm[static_cast<std::size_t>(i)][a];
    }
    llt.matrixL().solveInPlace(fa);
    llt.matrixL().solveInPlace(ya);
    fa -= w * ((w.transpose() * fa) / ww);
    ya -= w * (w.dot(ya) / ww);
    fw.middleRows(a * n, n) = fa;
    yw.segment(a * n, n) = ya;
  }
  JointErrorFunctions& f = fit.functions;
  const RidgeFit ridge = ridge_with_prior(fw, yw, prior_sd_of(f, prior));
  set_coefficients(f, ridge.beta);
  // The whitened readings have covariance P (the projection that removed the constants), and
  // F~ lies in its range: cov(beta) = R F~'F~ R, plus the prior's share where it decided.
  f.coefficient_covariance_mrad2.resize(0, 0);
  fit.prior_middle_diagonal.resize(0);
  if (ridge.ridge_inverse.size() > 0) {
    Eigen::MatrixXd middle = fw.transpose() * fw;
    if (ridge.prior_penalty.size() == p) {
      fit.prior_middle_diagonal = ridge.noise_variance * ridge.prior_penalty;
      middle.diagonal() += fit.prior_middle_diagonal;
    }
    f.coefficient_covariance_mrad2 = symmetric_sandwich(ridge.ridge_inverse, middle);
  }
  fit.ridge_inverse = ridge.ridge_inverse;
  fit.effective_parameters = ridge.effective_parameters;
  fit.ridge = std::isfinite(ridge.lambda) && ridge.largest_s2 > 0.0 ? ridge.lambda / ridge.largest_s2 : ridge.lambda;
  const Eigen::VectorXd fitted = fit.design * ridge.beta;
  double after = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) {
    fit.remaining_mm[static_cast<std::size_t>(i)] = residual_mm[static_cast<std::size_t>(i)] - fitted.segment<3>(3 * i);
    after += fit.remaining_mm[static_cast<std::size_t>(i)].squaredNorm();
  }
  fit.rms_after_mm = std::sqrt(after / static_cast<double>(n));
  fit.generalized = true;
  return true;
}

}  // namespace errfield::compensation
