#pragma once
// Between the CLI's table form (one row per sample, one column per component) and the estimators'
// vectors of values or points. Shared by the IDW and kriging method runners.

#include <cstddef>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "errfield/concepts.hpp"

namespace errfield::cli {

template <class V>
std::vector<V> rows_as_values(const Eigen::MatrixXd& m) {
  std::vector<V> v(static_cast<std::size_t>(m.rows()));
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    if constexpr (std::is_same_v<V, double>) v[static_cast<std::size_t>(i)] = m(i, 0);
    else v[static_cast<std::size_t>(i)] = m.row(i).transpose();
  }
  return v;
}

template <class V>
Eigen::MatrixXd values_as_rows(const std::vector<V>& v) {
  constexpr int C = ValueTraits<V>::kComponents;
  Eigen::MatrixXd m(static_cast<Eigen::Index>(v.size()), C);
  for (std::size_t i = 0; i < v.size(); ++i)
    for (int c = 0; c < C; ++c) m(static_cast<Eigen::Index>(i), c) = ValueTraits<V>::component(std::as_const(v[i]), c);
  return m;
}

inline std::vector<Eigen::VectorXd> rows_as_points(const Eigen::MatrixXd& m) {
  std::vector<Eigen::VectorXd> p(static_cast<std::size_t>(m.rows()));
  for (Eigen::Index i = 0; i < m.rows(); ++i) p[static_cast<std::size_t>(i)] = m.row(i).transpose();
  return p;
}

}  // namespace errfield::cli
