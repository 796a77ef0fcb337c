// IDW over scattered samples and how to choose its power by cross-validation. The samples are
// simulated: 400 random points in a 500 mm cube with a smooth error field plus noise (mm).
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "errfield/cross_validation.hpp"
#include "errfield/scattered_idw.hpp"

int main() {
  using namespace errfield;
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(0.0, 500.0);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::vector<Eigen::Vector3d> locations(400);
  std::vector<double> dL;
  for (auto& p : locations) {
    p = Eigen::Vector3d(u(rng), u(rng), u(rng));
    dL.push_back(0.3 * std::sin(p.x() / 150.0) + 5e-4 * p.y() + noise(rng));
  }

  // 10-fold cross-validation of IDW with 8 neighbours for a few powers.
  CrossValidationOptions cv;
  cv.folds = 10;
  cv.seed = 42;
  for (double power : {1.0, 2.0, 3.0}) {
    ScatteredIdwEstimator<Eigen::Vector3d, double> estimator;
    estimator.options.power = power;
    estimator.options.neighbors = 8;
    const auto r = cross_validate(estimator, std::span<const Eigen::Vector3d>(locations), std::span<const double>(dL), cv);
    std::printf("p = %.0f: mean error %+.4f mm, mean |e| %.4f mm, max |e| %.4f mm, RMS %.4f mm\n", power,
                r.summary.mean_error[0], r.summary.mean_abs_error, r.summary.max_abs_error, r.summary.rms_error);
  }

  // Predict at a new point with the chosen settings.
  ScatteredIdwOptions options;
  options.neighbors = 8;
  const ScatteredIdw<Eigen::Vector3d, double> idw(locations, dL, options);
  std::printf("dL at (250, 250, 250) mm: %.4f mm\n", idw(Eigen::Vector3d(250, 250, 250)));
  return 0;
}
