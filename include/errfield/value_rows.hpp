#pragma once
// Between a table of samples (an Eigen matrix, one row per sample, one column per coordinate or
// component) and the estimators' vectors of points and values (errfield/concepts.hpp Value).

#include <cstddef>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "errfield/concepts.hpp"

namespace errfield {

/// One value per row (V = double reads column 0; a vector type reads the whole row).
template <class V>
std::vector<V> rows_as_values(const Eigen::MatrixXd& m) {
  std::vector<V> v(static_cast<std::size_t>(m.rows()));
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    if constexpr (std::is_same_v<V, double>) v[static_cast<std::size_t>(i)] = m(i, 0);
    else v[static_cast<std::size_t>(i)] = m.row(i).transpose();
  }
  return v;
}

/// One row per value, one column per component.
template <class V>
Eigen::MatrixXd values_as_rows(const std::vector<V>& v) {
  constexpr int C = ValueTraits<V>::kComponents;
  Eigen::MatrixXd m(static_cast<Eigen::Index>(v.size()), C);
  for (std::size_t i = 0; i < v.size(); ++i)
    for (int c = 0; c < C; ++c) m(static_cast<Eigen::Index>(i), c) = ValueTraits<V>::component(std::as_const(v[i]), c);
  return m;
}

/// One point per row, for matrices of any storage order.
template <class M>
std::vector<Eigen::VectorXd> rows_as_points(const M& m) {
  std::vector<Eigen::VectorXd> p(static_cast<std::size_t>(m.rows()));
  for (Eigen::Index i = 0; i < m.rows(); ++i) p[static_cast<std::size_t>(i)] = m.row(i).transpose();
  return p;
}

}  // namespace errfield
