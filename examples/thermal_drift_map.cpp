// The estimators know nothing about robots: here they map a thermal drift field. Displacement
// sensors on a machine bed (x, y in mm) report the bed's vertical drift (µm) after warm-up; we
// estimate how it varies (variogram), fit a model, krige a map with its uncertainty, and compare
// with IDW by cross-validation. The readings are synthetic (a smooth warm spot plus sensor noise).
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "errfield/cross_validation.hpp"
#include "errfield/empirical_variogram.hpp"
#include "errfield/kriging.hpp"
#include "errfield/scattered_idw.hpp"
#include "errfield/variogram_fit.hpp"

int main() {
  using namespace errfield;
  using Point = Eigen::Vector2d;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> ux(0, 2000), uy(0, 1000);
  std::normal_distribution<double> noise(0, 0.4);
  // The warm spot: a motor near (1500, 300) mm lifts the bed by up to 12 µm.
  auto drift = [](const Point& p) { return 12.0 * std::exp(-((p - Point(1500, 300)).squaredNorm()) / (2 * 450.0 * 450.0)); };
  std::vector<Point> sensors;
  std::vector<double> reading;
  for (int i = 0; i < 80; ++i) {
    sensors.emplace_back(ux(rng), uy(rng));
    reading.push_back(drift(sensors.back()) + noise(rng));
  }

  const EmpiricalVariogram ev = empirical_variogram<Point, EuclideanMetric, double>(
      sensors, reading, EuclideanMetric{}, LagBins::uniform(0, 1400, 100));
  ModelComponent gau;
  gau.kind = ModelKind::Gaussian;
  const VariogramFitResult fit = fit_variogram(ev, {gau});
  std::printf("fitted variogram (µm², mm): %s\n", fit.model.to_string().c_str());

  KrigingOptions ko;
  ko.nugget = NuggetTreatment::MeasurementError;  // the nugget is sensor noise: map the true drift
  const Kriging<Point, double> kriging(sensors, reading, fit.model, ko);
  const std::vector<Point> probes{{1500, 300}, {200, 800}, {1000, 500}};
  const auto map = kriging.predict(probes);
  for (std::size_t i = 0; i < probes.size(); ++i)
    std::printf("at (%4.0f, %4.0f) mm: drift %.2f ± %.2f µm (true %.2f)\n", probes[i].x(), probes[i].y(), map.mean[i],
                std::sqrt(map.variance[i]), drift(probes[i]));

  ScatteredIdwEstimator<Point, double> idw;
  idw.options.power = 2;
  idw.options.neighbors = 8;
  const auto cv_idw = cross_validate<Point, double>(idw, sensors, reading);
  std::printf("leave-one-out RMS: kriging %.2f µm, IDW %.2f µm\n", kriging.leave_one_out().rms_error,
              cv_idw.summary.rms_error);
  return 0;
}
