#include "errfield/scattered_idw.hpp"

#include "errfield/thread_count.hpp"

namespace errfield {

namespace detail {
void validate_scattered_idw_options(double power, double radius, double exact_distance, int threads) {
  if (!(power >= 0.0) || !std::isfinite(power))
    throw ArgumentError("ScatteredIdwOptions::power is " + format_number(power) + "; expected a finite value >= 0");
  if (!(radius > 0.0))
    throw ArgumentError("ScatteredIdwOptions::radius is " + format_number(radius) +
                        "; expected a value > 0 (infinity for no limit)");
  if (!(exact_distance >= 0.0) || !std::isfinite(exact_distance))
    throw ArgumentError("ScatteredIdwOptions::exact_distance is " + format_number(exact_distance) +
                        "; expected a finite value >= 0");
  check_thread_count("ScatteredIdwOptions::threads", threads);
}
}  // namespace detail

template class ScatteredIdw<Eigen::Vector3d, double>;
template class ScatteredIdw<Eigen::Vector3d, Eigen::Vector3d>;
template class ScatteredIdw<Eigen::VectorXd, double>;

}  // namespace errfield
