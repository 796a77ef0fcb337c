// Rotated (gstat `anis`) likelihood fit, 2-D and 3-D. A rotated geometric anisotropy with range R
// and ratios s, t is ARD on rotated coordinates: with the rotation's rows (major, minor 1, minor 2)
// the mapped lag is |diag(1/R, 1/(sR), 1/(tR)) Q (x - y)|. So for fixed angles the fit is the ARD
// fit (analytic gradients, L-BFGS) of the coordinates rotated by Q(angles), and the angles are
// optimized outside it on the profile nll(angles) = min over the rest, derivative-free: a coarse
// grid then golden sections along each angle in turn. The angle's standard error comes from the
// profile's curvature (a central second difference), which is the observed information of the
// profile likelihood. Formulas: docs/kriging.md, "Rotated anisotropy".

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

#include <Eigen/LU>

#include "errfield/anisotropy.hpp"
#include "errfield/error.hpp"
#include "kriging/likelihood_profile.hpp"
#include "kriging/likelihood_rotated.hpp"

namespace errfield::detail {
namespace {

struct RotatedProfile {
  const Eigen::MatrixXd* x;
  const Eigen::MatrixXd* z;
  const Eigen::MatrixXd* f;
  ModelComponent structure;
  LikelihoodFitOptions ard_options;
  int inner_fits = 0;
  int evaluations = 0;

  // 2-D: {angle}; 3-D: {azimuth, dip, rotation}; degrees. The rotation alone: ratios 1.
  static Anisotropy rotation(const std::vector<double>& angles) {
    return angles.size() == 1 ? Anisotropy::rotated({angles[0], 1.0})
                              : Anisotropy::rotated({angles[0], angles[1], angles[2], 1.0, 1.0});
  }

  LikelihoodFitResult fit_at(const std::vector<double>& angles) {
    const Anisotropy q = rotation(angles);
    Eigen::MatrixXd u(x->rows(), x->cols());
    Eigen::VectorXd in(x->cols()), out(x->cols());
    for (Eigen::Index i = 0; i < x->rows(); ++i) {
      in = x->row(i).transpose();
      q.apply(in.data(), out.data(), static_cast<int>(in.size()));
      u.row(i) = out.transpose();
    }
    ++inner_fits;
    LikelihoodFitResult r = fit_profiled_likelihood(u, *z, *f, structure, ard_options);
    evaluations += r.evaluations;
    return r;
  }
  double value(const std::vector<double>& angles) { return fit_at(angles).negative_log_likelihood; }
};

// Minimum of g on [lo, hi] by golden sections, starting knowing g(mid) = g_mid.
template <class G>
double golden(G g, double lo, double hi, double tol) {
  const double r = 0.5 * (std::sqrt(5.0) - 1.0);
  double a = lo, b = hi;
  double c = b - r * (b - a), d = a + r * (b - a);
  double gc = g(c), gd = g(d);
  while (b - a > tol) {
    if (gc < gd) {
      b = d, d = c, gd = gc;
      c = b - r * (b - a);
      gc = g(c);
    } else {
      a = c, c = d, gc = gd;
      d = a + r * (b - a);
      gd = g(d);
    }
  }
  return gc < gd ? c : d;
}

// The rotation's rows (major, minor 1, minor 2) as errfield's Anisotropy::rotated builds them.
Eigen::Matrix3d frame_of(const std::vector<double>& angles) {
  const Anisotropy q = Anisotropy::rotated({angles[0], angles[1], angles[2], 1.0, 1.0});
  Eigen::Matrix3d m;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m(r, c) = q.matrix()[static_cast<std::size_t>(3 * r + c)];
  return m;
}

// gstat's (azimuth, dip, rotation) of a right-handed orthonormal frame, inverting the GSLIB rotation
// of anisotropy.cpp: u = (cb ca, cb sa, -sb), v_z = st cb, w_z = ct cb, with alpha = 90 - azimuth,
// beta = -dip, theta = rotation. Angles in [0, 360), as gstat wants them.
std::vector<double> angles_of(const Eigen::Matrix3d& m) {
  const double deg = 180.0 / std::numbers::pi;
  const double sb = std::clamp(-m(0, 2), -1.0, 1.0);
  const double cb = std::sqrt(std::max(0.0, 1.0 - sb * sb));
  double alpha, theta;
  if (cb > 1e-12) {
    alpha = std::atan2(m(0, 1), m(0, 0));
    theta = std::atan2(m(1, 2), m(2, 2));
  } else {  // major axis vertical: the rotation about it is folded into alpha
    theta = 0.0;
    alpha = std::atan2(-m(1, 0), m(1, 1));
  }
  auto wrap = [](double a) { return std::fmod(std::fmod(a, 360.0) + 360.0, 360.0); };
  return {wrap(90.0 - alpha * deg), wrap(-std::asin(sb) * deg), wrap(theta * deg)};
}

// The frame's rows sorted by decreasing range (an odd permutation flips the last row, keeping it
// right-handed; an axis' sign does not change the lags), as gstat's angles.
std::vector<double> sorted_angles(const std::vector<double>& angles, const std::vector<double>& ranges) {
  const Eigen::Matrix3d m = frame_of(angles);
  std::array<int, 3> order{0, 1, 2};
  std::sort(order.begin(), order.end(), [&](int a, int b) { return ranges[static_cast<std::size_t>(a)] > ranges[static_cast<std::size_t>(b)]; });
  Eigen::Matrix3d s;
  for (int r = 0; r < 3; ++r) s.row(r) = m.row(order[static_cast<std::size_t>(r)]);
  if (s.determinant() < 0.0) s.row(2) *= -1.0;
  return angles_of(s);
}

// The angles with the smallest profile likelihood: the centres of a coarse grid, then golden
// sections along each angle in turn. Angle boxes: a rotation by 90 degrees swaps the roles of the
// axes (ARD's ranges absorb it), so 2-D needs [0, 90); 3-D azimuth [0, 180), dip and rotation [-90, 90).
std::vector<double> best_angles(RotatedProfile& pr, int d) {
  std::vector<double> lo, hi;
  std::vector<int> grid;
  if (d == 2) {
    lo = {0.0};
    hi = {90.0};
    grid = {6};
  } else {
    lo = {0.0, -90.0, -90.0};
    hi = {180.0, 90.0, 90.0};
    grid = {6, 4, 4};
  }
  const std::size_t na = lo.size();
  std::vector<double> best(na), at(na);
  double best_value = std::numeric_limits<double>::infinity();
  std::vector<int> idx(na, 0);
  while (true) {  // the coarse grid, cell centres
    for (std::size_t k = 0; k < na; ++k) at[k] = lo[k] + (idx[k] + 0.5) * (hi[k] - lo[k]) / grid[k];
    const double v = pr.value(at);
    if (v < best_value) best_value = v, best = at;
    std::size_t k = 0;
    while (k < na && ++idx[k] == grid[k]) idx[k++] = 0;
    if (k == na) break;
  }
  // Golden sections along each angle in turn, within one grid cell of the best point, twice.
  const double tol = 0.05;
  for (int sweep = 0; sweep < (na == 1 ? 1 : 2); ++sweep)
    for (std::size_t k = 0; k < na; ++k) {
      const double cell = (hi[k] - lo[k]) / grid[k] / (sweep + 1);
      auto g = [&](double a) {
        std::vector<double> t = best;
        t[k] = a;
        return pr.value(t);
      };
      const double a = golden(g, best[k] - cell, best[k] + cell, tol);
      std::vector<double> t = best;
      t[k] = a;
      const double v = pr.value(t);
      if (v < best_value) best_value = v, best = t;
    }
  // 3-D: rewrite the frame with the longest range first (gstat wants ratios <= 1); the profile is
  // the same function of the frame, so the fit there is the same up to the optimizer's tolerance.
  if (na == 3) {
    const std::vector<double> sorted = sorted_angles(best, pr.fit_at(best).ranges);
    if (pr.value(sorted) <= best_value + 1e-6 * std::fabs(best_value)) best = sorted;
  }
  return best;
}

// Standard errors of the angles from the profile's curvature (step 1 degree; NaN if not convex).
std::vector<double> angle_standard_errors(RotatedProfile& pr, const std::vector<double>& best, double nll) {
  std::vector<double> angle_se(best.size(), std::numeric_limits<double>::quiet_NaN());
  for (std::size_t k = 0; k < best.size(); ++k) {
    const double h = 1.0;
    std::vector<double> p = best, m = best;
    p[k] += h;
    m[k] -= h;
    const double curvature_deg = (pr.value(p) - 2.0 * nll + pr.value(m)) / (h * h);
    const double curvature_rad = curvature_deg * (180.0 / std::numbers::pi) * (180.0 / std::numbers::pi);
    if (curvature_rad > 0.0) angle_se[k] = std::sqrt(1.0 / curvature_rad) * (180.0 / std::numbers::pi);
  }
  return angle_se;
}

// ARD ranges on the rotated axes -> range = the one along the first axis, ratios to it. In 2-D
// the major axis is made the longer one (ratio <= 1, angle + 90 otherwise), as gstat writes it;
// in 3-D the frame was sorted (ratios <= 1 unless the refit there moved).
void as_gstat_anisotropy(const std::vector<double>& best, LikelihoodFitResult& r) {
  const std::size_t na = best.size();
  const std::vector<double> ranges = r.ranges;  // along the rotated axes
  std::vector<double> range_se = r.range_standard_errors;
  double angle0 = best[0];
  std::size_t major = 0;
  if (na == 1 && ranges[1] > ranges[0]) {
    major = 1;
    angle0 += 90.0;
  }
  const double range = ranges[major];
  std::vector<double> gstat_anis;
  if (na == 1) {
    gstat_anis = {std::fmod(angle0 + 180.0, 180.0), ranges[1 - major] / range};
  } else {
    gstat_anis = {best[0], best[1], best[2], ranges[1] / range, ranges[2] / range};
  }
  std::vector<ModelComponent> comps = r.model.components();
  for (auto& c : comps)
    if (c.kind != ModelKind::Nugget) c.range = range;
  r.model = VariogramModel(std::move(comps), Anisotropy::rotated(gstat_anis));
  if (na == 1 && major == 1) {
    std::swap(r.ranges[0], r.ranges[1]);
    std::swap(range_se[0], range_se[1]);
  }
  r.range_standard_errors = range_se;
  r.angles_deg.assign(gstat_anis.begin(), gstat_anis.begin() + static_cast<std::ptrdiff_t>(na));
}

}  // namespace

LikelihoodFitResult fit_rotated_likelihood(const Eigen::MatrixXd& x, const Eigen::MatrixXd& z,
                                           const Eigen::MatrixXd& f, const ModelComponent& structure,
                                           const LikelihoodFitOptions& options) {
  const int d = static_cast<int>(x.cols());
  if (d != 2 && d != 3)
    throw ArgumentError("likelihood: rotated anisotropy (gstat's anis) needs 2 or 3 coordinates, got " +
                        std::to_string(d) + "; use ARD in other dimensions");
  RotatedProfile pr{&x, &z, &f, structure, options};
  pr.ard_options.anisotropy = LikelihoodFitOptions::Anisotropy::Ard;
  pr.ard_options.initial_model.reset();  // its ranges are along the given axes, not the rotated ones
  const std::vector<double> best = best_angles(pr, d);
  LikelihoodFitResult r = pr.fit_at(best);
  std::vector<double> angle_se = angle_standard_errors(pr, best, r.negative_log_likelihood);
  as_gstat_anisotropy(best, r);
  r.angle_standard_errors_deg = angle_se;
  r.parameters += static_cast<int>(best.size());
  r.evaluations = pr.evaluations;
  r.message += "; angles by a profile search over " + std::to_string(pr.inner_fits) + " ARD fits";
  return r;
}

}  // namespace errfield::detail
