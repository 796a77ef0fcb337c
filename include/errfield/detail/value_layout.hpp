#pragma once
// How a Value is laid out in memory, so that kernels can read and write values as plain arrays of
// doubles: `double` and fixed-size Eigen vectors of doubles store exactly kComponents contiguous
// doubles (Eigen guarantees this for fixed sizes); other Value types go through a copy.

#include <cstddef>
#include <limits>
#include <span>
#include <type_traits>
#include <vector>

#include "errfield/concepts.hpp"

namespace errfield::detail {

template <class V>
inline constexpr bool kPackedValue =
    std::is_same_v<V, double> ||
    (requires { typename V::Scalar; } && sizeof(V) == sizeof(double) * ValueTraits<V>::kComponents);

/// Flattens values into n * kComponents doubles.
template <Value V>
std::vector<double> flatten_values(std::span<const V> values) {
  constexpr int C = ValueTraits<V>::kComponents;
  std::vector<double> flat(values.size() * C);
  for (std::size_t i = 0; i < values.size(); ++i)
    for (int c = 0; c < C; ++c) flat[i * C + c] = ValueTraits<V>::component(values[i], c);
  return flat;
}

/// Builds a V from C doubles.
template <Value V>
V value_from(const double* components) {
  if constexpr (std::is_same_v<V, double>) {
    return components[0];
  } else {
    V v = ValueTraits<V>::zero();
    for (int c = 0; c < ValueTraits<V>::kComponents; ++c) ValueTraits<V>::component(v, c) = components[c];
    return v;
  }
}

/// True when every component of v is finite.
template <Value V>
bool value_is_finite(const V& v) {
  for (int c = 0; c < ValueTraits<V>::kComponents; ++c) {
    const double x = ValueTraits<V>::component(v, c);
    if (!(x - x == 0.0)) return false;
  }
  return true;
}

/// A V whose components are all quiet NaN: "no prediction".
template <Value V>
V nan_value() {
  if constexpr (std::is_same_v<V, double>) {
    return std::numeric_limits<double>::quiet_NaN();
  } else {
    V v = ValueTraits<V>::zero();
    for (int c = 0; c < ValueTraits<V>::kComponents; ++c)
      ValueTraits<V>::component(v, c) = std::numeric_limits<double>::quiet_NaN();
    return v;
  }
}

}  // namespace errfield::detail
