#pragma once
/// A seeded random source whose output is the same on every platform and standard library:
/// std::mt19937_64 (fully specified by the standard) plus distributions written out here, since
/// std::normal_distribution and friends are implementation-defined. Use it for anything that must
/// be reproducible from a seed (the simulator, random test configurations in the pipeline).
/// Not thread-safe; give each thread its own (e.g. seeded with `seed + thread index`).

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>

namespace errfield::robot {

class SimulationRng {
 public:
  explicit SimulationRng(std::uint64_t seed) : engine_(seed) {}

  /// Uniform in [0, 1) with 53 random bits.
  double uniform01() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  /// Uniform in [lo, hi).
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform01(); }
  /// Standard normal by the Box–Muller transform (both values of a pair are used).
  double normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u1 = uniform01();
    while (u1 <= 0.0) u1 = uniform01();
    const double u2 = uniform01();
    const double r = std::sqrt(-2.0 * std::log(u1));
    spare_ = r * std::sin(2.0 * std::numbers::pi * u2);
    has_spare_ = true;
    return r * std::cos(2.0 * std::numbers::pi * u2);
  }
  /// Normal with mean and standard deviation.
  double normal(double mean, double sigma) { return mean + sigma * normal(); }
  /// Integer uniform in [0, n) (n >= 1), by rejection so it is unbiased.
  std::uint64_t below(std::uint64_t n) {
    const std::uint64_t limit = UINT64_MAX - UINT64_MAX % n;
    std::uint64_t v;
    do v = engine_();
    while (v >= limit);
    return v % n;
  }
  std::mt19937_64& engine() { return engine_; }

 private:
  std::mt19937_64 engine_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

}  // namespace errfield::robot
