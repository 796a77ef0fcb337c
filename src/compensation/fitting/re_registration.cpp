#include "errfield/compensation/fitting/re_registration.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <random>

#include <Eigen/SVD>

#include "errfield/error.hpp"
#include "errfield/number_format.hpp"
#include "errfield/robot/kinematics.hpp"

namespace errfield::compensation {

using robot::JointVector;

namespace {

/// The model's own frame at joints q: its point's FK plus the field where it is defined, plus only the
/// joint error functions (physical, defined everywhere) where it is not.
Eigen::Vector3d model_prediction(const CompensationModel& model, const JointVector& q, bool& with_field) {
  const ErrorPrediction e = model.predict_error(q);
  with_field = e.inside_region && e.credible;
  const Eigen::Vector3d fk = robot::forward_position(model.command_model(), q);
  return with_field ? Eigen::Vector3d(fk + e.position_error_mm)
                    : Eigen::Vector3d(fk + model.joint_function_error_at(q, model.command_model()));
}

// The median of |r| for a 3-D Gaussian residual with sd s per axis is 1.5382 s (chi with 3 degrees
// of freedom).
constexpr double kChi3Median = 1.5382;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// A rigid motion needs readings that span a plane: on one line the rotation about it is free.
void refuse_readings_on_a_line(const std::vector<Eigen::Vector3d>& tracker_mm, const std::string& source) {
  const std::size_t n = tracker_mm.size();
  Eigen::MatrixXd centred(static_cast<Eigen::Index>(n), 3);
  const Eigen::Vector3d mean = [&] {
    Eigen::Vector3d m = Eigen::Vector3d::Zero();
    for (const auto& t : tracker_mm) m += t;
    return Eigen::Vector3d(m / static_cast<double>(n));
  }();
  for (std::size_t i = 0; i < n; ++i) centred.row(static_cast<Eigen::Index>(i)) = (tracker_mm[i] - mean).transpose();
  const Eigen::Vector3d spread = Eigen::JacobiSVD<Eigen::MatrixXd>(centred).singularValues() / std::sqrt(static_cast<double>(n));
  if (spread[1] < 10.0)
    throw InputError(source + ": the readings lie within " + format_significant(spread[1], 3) +
                         " mm (RMS) of one line: a rigid motion is not determined; measure poses spread over the work volume",
                     source);
}

/// The readings (tracker frame) and where the model puts each of them (robot frame).
struct RegistrationData {
  const std::vector<Eigen::Vector3d>& tracker_mm;
  std::vector<Eigen::Vector3d> predicted;

  Registration fit_on(const std::vector<std::size_t>& rows, const std::vector<Eigen::Vector3d>& to) const {
    std::vector<Eigen::Vector3d> a, b;
    for (const std::size_t i : rows) {
      a.push_back(tracker_mm[i]);
      b.push_back(to[i]);
    }
    return fit_registration(a, b);
  }
  std::vector<double> residuals(const Registration& r) const {
    std::vector<double> e(tracker_mm.size());
    for (std::size_t i = 0; i < e.size(); ++i) e[i] = (r.robot_from_tracker * tracker_mm[i] - predicted[i]).norm();
    return e;
  }
};

/// Triple number t of the n (n - 1) (n - 2) / 6 in lexicographic order.
std::array<std::size_t, 3> nth_triple(std::size_t t, std::size_t n) {
  std::array<std::size_t, 3> k{};
  std::size_t r = t;
  for (k[0] = 0;; ++k[0]) {
    const std::size_t c = (n - 1 - k[0]) * (n - 2 - k[0]) / 2;
    if (r < c) break;
    r -= c;
  }
  for (k[1] = k[0] + 1;; ++k[1]) {
    const std::size_t c = n - 1 - k[1];
    if (r < c) break;
    r -= c;
  }
  k[2] = k[1] + 1 + r;
  return k;
}

/// Least median of squares over triples of readings: a least-squares fit is pulled towards a group
/// of readings in another frame (a tracker bumped mid-series) until no single one stands out; the
/// triple whose registration leaves the smallest median residual is not, up to half the readings.
/// Returns that registration and its median residual.
std::pair<Registration, double> least_median_registration(const RegistrationData& data) {
  const std::size_t n = data.tracker_mm.size();
  std::vector<std::size_t> all(n);
  for (std::size_t i = 0; i < n; ++i) all[i] = i;
  Registration start = data.fit_on(all, data.predicted);
  double best_median = median(data.residuals(start));
  std::mt19937 random(1);  // deterministic: the same readings give the same model
  const std::size_t triples = std::min<std::size_t>(n * (n - 1) * (n - 2) / 6, 3000);
  for (std::size_t t = 0; t < triples; ++t) {
    std::array<std::size_t, 3> k{};
    if (triples == n * (n - 1) * (n - 2) / 6) {  // every triple, in order
      k = nth_triple(t, n);
    } else {
      std::uniform_int_distribution<std::size_t> pick(0, n - 1);
      k = {pick(random), pick(random), pick(random)};
      if (k[0] == k[1] || k[1] == k[2] || k[0] == k[2]) continue;
    }
    const Eigen::Vector3d u = data.tracker_mm[k[1]] - data.tracker_mm[k[0]], v = data.tracker_mm[k[2]] - data.tracker_mm[k[0]];
    if (u.cross(v).norm() < 100.0) continue;  // within ~10 mm of one line: no rotation determined
    const Registration r = data.fit_on({k[0], k[1], k[2]}, data.predicted);
    const double m = median(data.residuals(r));
    if (m < best_median) {
      best_median = m;
      start = r;
    }
  }
  return {start, best_median};
}

}  // namespace

ReRegistration reregister(const CompensationModel& model, const robot::MdhModel& nominal,
                          const std::vector<JointVector>& q_deg, const std::vector<Eigen::Vector3d>& tracker_mm,
                          const std::string& source, const ReRegistrationOptions& o) {
  const std::size_t n = q_deg.size();
  if (n != tracker_mm.size()) throw InputError(source + ": joints and readings differ in count", source);
  if (n < o.min_readings)
    throw InputError(source + ": " + std::to_string(n) + " readings with tracker positions mx,my,mz; register needs at least " +
                         std::to_string(o.min_readings) + " (10-30 spread over the work volume determine the frame well)",
                     source);
  refuse_readings_on_a_line(tracker_mm, source);
  ReRegistration out;
  RegistrationData data{tracker_mm, std::vector<Eigen::Vector3d>(n)};
  std::vector<Eigen::Vector3d> fk(n);
  for (std::size_t i = 0; i < n; ++i) {
    bool with_field = true;
    data.predicted[i] = model_prediction(model, q_deg[i], with_field);
    if (!with_field) ++out.without_field;
    fk[i] = robot::forward_position(nominal, q_deg[i]);
  }
  const auto [start, best_median] = least_median_registration(data);
  // Inliers of the best start, then least squares on them, twice (readings may come back in).
  std::vector<std::size_t> kept;
  Registration current = start;
  double sigma = std::max(o.min_sigma_mm, best_median / kChi3Median);
  for (int round = 0; round < 2; ++round) {
    const std::vector<double> e = data.residuals(current);
    kept.clear();
    for (std::size_t i = 0; i < n; ++i)
      if (e[i] <= o.outlier_sigmas * sigma) kept.push_back(i);
    if (kept.size() < 3) {  // no consensus: judged below on every reading
      kept.resize(n);
      for (std::size_t i = 0; i < n; ++i) kept[i] = i;
    }
    current = data.fit_on(kept, data.predicted);
    std::vector<double> kept_residual;
    const std::vector<double> after = data.residuals(current);
    for (const std::size_t i : kept) kept_residual.push_back(after[i]);
    sigma = std::max(o.min_sigma_mm, median(kept_residual) / kChi3Median);
  }
  out.registration = current;
  out.residual_mm = data.residuals(current);
  out.robust_sigma_mm = sigma;
  for (std::size_t i = 0; i < n; ++i)
    if (std::find(kept.begin(), kept.end(), i) == kept.end()) out.excluded.push_back(i);
  std::sort(out.excluded.begin(), out.excluded.end(),
            [&](std::size_t a, std::size_t b) { return out.residual_mm[a] > out.residual_mm[b]; });
  const std::size_t most_excluded = static_cast<std::size_t>(std::floor(o.max_excluded_share * static_cast<double>(n)));
  if (out.excluded.size() > most_excluded || kept.size() < o.min_readings) {
    const std::size_t worst = out.excluded.front();
    throw InputError(source + ": the readings do not fit one rigid motion: " + std::to_string(out.excluded.size()) + " of " +
                         std::to_string(n) + " lie beyond " + format_significant(o.outlier_sigmas, 3) +
                         " robust sd (" + format_significant(sigma, 3) + " mm per axis) of the registration the others agree on, reading " +
                         std::to_string(worst + 1) + " " + format_significant(out.residual_mm[worst], 3) +
                         " mm off (more than a fifth: not a few bad readings); are they of this robot, with joints in "
                         "degrees, and did the tracker stay put during the series?",
                     source);
  }
  out.registration.points = kept.size();
  out.nominal_registration = data.fit_on(kept, fk);
  out.nominal_registration.points = kept.size();
  return out;
}

}  // namespace errfield::compensation
