#pragma once
/// The three contracts the generic estimators are written against.
///
/// - A **Location** is a point of some space with a fixed number of real coordinates: a 3-D
///   nominal position in mm, a 6-D joint vector in degrees, ... Fixed-size and dynamic-size Eigen
///   column vectors of double, `std::array<double, D>` and plain `double` (1-D) qualify. Another
///   type qualifies by specializing `LocationTraits`.
/// - A **Metric** over a Location is a callable `double(const L&, const L&)`: a lag.
/// - A **Value** is the error quantity attached to a location: `double`, or a fixed-size Eigen
///   column vector (e.g. a 3-D position error). It must support `+`, `-` and scaling, and
///   `ValueTraits` says how many components it has and how to read them.
///
/// Estimators check these with `static_assert`-friendly concepts, so a wrong type gives one
/// readable line instead of a page of template errors.

#include <array>
#include <concepts>
#include <cstddef>

#include <Eigen/Core>

namespace errfield {

// ---- Location ----------------------------------------------------------------------------------

/// Customization point: how many coordinates a location has and how to read coordinate i.
template <class L>
struct LocationTraits;

template <int D>
struct LocationTraits<Eigen::Matrix<double, D, 1>> {
  static constexpr int kDimension = D;  ///< Eigen::Dynamic (-1) when known only at run time.
  static int size(const Eigen::Matrix<double, D, 1>& l) { return static_cast<int>(l.size()); }
  static double coordinate(const Eigen::Matrix<double, D, 1>& l, int i) { return l[i]; }
};

template <std::size_t D>
struct LocationTraits<std::array<double, D>> {
  static constexpr int kDimension = static_cast<int>(D);
  static int size(const std::array<double, D>&) { return static_cast<int>(D); }
  static double coordinate(const std::array<double, D>& l, int i) { return l[static_cast<std::size_t>(i)]; }
};

template <>
struct LocationTraits<double> {
  static constexpr int kDimension = 1;
  static int size(double) { return 1; }
  static double coordinate(double l, int) { return l; }
};

template <class L>
concept Location = requires(const L& l, int i) {
  { LocationTraits<L>::kDimension } -> std::convertible_to<int>;
  { LocationTraits<L>::size(l) } -> std::convertible_to<int>;
  { LocationTraits<L>::coordinate(l, i) } -> std::convertible_to<double>;
};

// ---- Metric ------------------------------------------------------------------------------------

/// A lag between two locations: non-negative, zero for equal locations, symmetric.
template <class M, class L>
concept Metric = Location<L> && requires(const M& metric, const L& a, const L& b) {
  { metric(a, b) } -> std::convertible_to<double>;
};

// ---- Value -------------------------------------------------------------------------------------

/// Customization point: number of components of an error quantity and access to them.
template <class V>
struct ValueTraits;

template <>
struct ValueTraits<double> {
  static constexpr int kComponents = 1;
  static double zero() { return 0.0; }
  static double component(const double& v, int) { return v; }
  static double& component(double& v, int) { return v; }
  static double squared_norm(double v) { return v * v; }
};

template <int N>
struct ValueTraits<Eigen::Matrix<double, N, 1>> {
  static_assert(N > 0, "errfield Values must have a size fixed at compile time");
  using Type = Eigen::Matrix<double, N, 1>;
  static constexpr int kComponents = N;
  static Type zero() { return Type::Zero(); }
  static double component(const Type& v, int i) { return v[i]; }
  static double& component(Type& v, int i) { return v[i]; }
  static double squared_norm(const Type& v) { return v.squaredNorm(); }
};

template <class V>
concept Value = std::copyable<V> && requires(const V& a, const V& b, double w, int i) {
  { ValueTraits<V>::kComponents } -> std::convertible_to<int>;
  { ValueTraits<V>::zero() } -> std::convertible_to<V>;
  { ValueTraits<V>::component(a, i) } -> std::convertible_to<double>;
  { ValueTraits<V>::squared_norm(a) } -> std::convertible_to<double>;
  { V(a - b) };
  { V(a + b) };
  { V(w * a) };
};

}  // namespace errfield
