#pragma once
// The one place errfield talks to CHOLMOD (SuiteSparse): a sparse symmetric positive definite
// factorization K + beta I = P' L L' P with every CHOLMOD status turned into a message.
// cholmod.h stays inside cholmod_factor.cpp. Not thread-safe: CHOLMOD's workspace lives in its
// "common" object, so callers serialize (KrigingEngine holds a mutex around solves).

#include <cstddef>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace errfield::detail {

class CholmodFactor {
 public:
  CholmodFactor();
  ~CholmodFactor();
  CholmodFactor(const CholmodFactor&) = delete;
  CholmodFactor& operator=(const CholmodFactor&) = delete;

  /// Factors the symmetric matrix given by its lower triangle in compressed columns (n x n,
  /// col_ptr n+1 entries, row indices sorted within a column, diagonal present), plus beta on the
  /// diagonal. Returns false with message() set when CHOLMOD fails (not positive definite: the
  /// failing column is named; out of memory; ...). May be called again with another beta.
  /// The symbolic analysis alone (the fill-reducing ordering): after it, predicted_factor_bytes()
  /// says what the numeric factor will take, before any of it is allocated. factorize() calls it
  /// when it was not called. Returns false with message() set when CHOLMOD fails.
  bool analyze(int n, const std::vector<int>& col_ptr, const std::vector<int>& row_index,
               const std::vector<double>& values);
  /// Bytes of the numeric factor L (values and row indices) as the analysis predicts them.
  double predicted_factor_bytes() const;

  bool factorize(int n, const std::vector<int>& col_ptr, const std::vector<int>& row_index,
                 const std::vector<double>& values, double beta);

  /// b := K^-1 b (b is n x m).
  void solve(Eigen::MatrixXd& b) const;
  /// b := L^-1 P b, so that |L^-1 P c|^2 = c' K^-1 c.
  void solve_forward(Eigen::MatrixXd& b) const;
  /// CHOLMOD's cheap reciprocal condition estimate (from the diagonal of L).
  double rcond() const;
  /// Non-zeros in the factor L.
  std::size_t factor_nonzeros() const;
  const std::string& message() const { return message_; }

  std::mutex& mutex() const { return mutex_; }

 private:
  struct State;
  std::unique_ptr<State> state_;
  std::string message_;
  mutable std::mutex mutex_;
};

}  // namespace errfield::detail
