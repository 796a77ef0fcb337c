#include "kriging/cholmod_factor.hpp"

#include <cstring>

#include <cholmod.h>

#include "errfield/error.hpp"

namespace errfield::detail {
namespace {

std::string status_message(int status) {
  switch (status) {
    case CHOLMOD_OK: return "ok";
    case CHOLMOD_NOT_INSTALLED: return "CHOLMOD: a required method is not installed";
    case CHOLMOD_OUT_OF_MEMORY: return "CHOLMOD: out of memory";
    case CHOLMOD_TOO_LARGE: return "CHOLMOD: problem too large (integer overflow)";
    case CHOLMOD_INVALID: return "CHOLMOD: invalid input";
    case CHOLMOD_GPU_PROBLEM: return "CHOLMOD: GPU failure";
    case CHOLMOD_NOT_POSDEF: return "CHOLMOD: matrix not positive definite";
    case CHOLMOD_DSMALL: return "CHOLMOD: tiny diagonal entry in the factor";
    default: return "CHOLMOD: unknown status " + std::to_string(status);
  }
}

}  // namespace

struct CholmodFactor::State {
  cholmod_common common;
  cholmod_sparse* a = nullptr;
  cholmod_factor* l = nullptr;
  State() {
    cholmod_start(&common);
    common.print = 0;          // statuses are reported through message(), not stderr
    common.final_ll = 1;       // keep an L L' factor so that solve_forward gives |L^-1 P c|^2
    common.error_handler = nullptr;
  }
  ~State() {
    if (l) cholmod_free_factor(&l, &common);
    if (a) cholmod_free_sparse(&a, &common);
    cholmod_finish(&common);
  }
};

CholmodFactor::CholmodFactor() : state_(std::make_unique<State>()) {}
CholmodFactor::~CholmodFactor() = default;

bool CholmodFactor::analyze(int n, const std::vector<int>& col_ptr, const std::vector<int>& row_index,
                            const std::vector<double>& values) {
  auto& s = *state_;
  auto& c = s.common;
  if (s.a) return true;
  const auto nnz = static_cast<std::size_t>(col_ptr.back());
  s.a = cholmod_allocate_sparse(static_cast<std::size_t>(n), static_cast<std::size_t>(n), nnz, 1, 1, -1,
                                CHOLMOD_REAL, &c);
  if (!s.a) {
    message_ = status_message(c.status) + " while allocating the " + std::to_string(n) + " x " +
               std::to_string(n) + " matrix with " + std::to_string(nnz) + " non-zeros";
    return false;
  }
  std::memcpy(s.a->p, col_ptr.data(), col_ptr.size() * sizeof(int));
  std::memcpy(s.a->i, row_index.data(), row_index.size() * sizeof(int));
  std::memcpy(s.a->x, values.data(), values.size() * sizeof(double));
  s.l = cholmod_analyze(s.a, &c);
  if (!s.l || c.status < CHOLMOD_OK) {
    message_ = status_message(c.status) + " in the symbolic analysis";
    return false;
  }
  return true;
}

double CholmodFactor::predicted_factor_bytes() const {
  const auto* l = state_->l;
  if (!l) return 0.0;
  // Supernodal: xsize values (dense supernodes, more than lnz); simplicial: lnz values + indices.
  const double values = l->is_super ? static_cast<double>(l->xsize) : state_->common.lnz;
  return values * sizeof(double) + state_->common.lnz * sizeof(int);
}

bool CholmodFactor::factorize(int n, const std::vector<int>& col_ptr, const std::vector<int>& row_index,
                              const std::vector<double>& values, double beta) {
  auto& s = *state_;
  auto& c = s.common;
  if (!s.a && !analyze(n, col_ptr, row_index, values)) return false;
  double b[2] = {beta, 0.0};
  const int ok = cholmod_factorize_p(s.a, b, nullptr, 0, s.l, &c);
  if (!ok || c.status < CHOLMOD_OK) {
    message_ = status_message(c.status) + " in the numeric factorization";
    return false;
  }
  if (c.status == CHOLMOD_NOT_POSDEF || s.l->minor < s.l->n) {
    message_ = "CHOLMOD: covariance matrix not positive definite (leading minor of order " +
               std::to_string(s.l->minor + 1) + " fails)";
    return false;
  }
  message_.clear();
  return true;
}

namespace {
cholmod_dense view(Eigen::MatrixXd& b) {
  cholmod_dense d{};
  d.nrow = static_cast<std::size_t>(b.rows());
  d.ncol = static_cast<std::size_t>(b.cols());
  d.nzmax = d.nrow * d.ncol;
  d.d = d.nrow;
  d.x = b.data();
  d.z = nullptr;
  d.xtype = CHOLMOD_REAL;
  d.dtype = CHOLMOD_DOUBLE;
  return d;
}
}  // namespace

void CholmodFactor::solve(Eigen::MatrixXd& b) const {
  auto& s = *state_;
  cholmod_dense in = view(b);
  cholmod_dense* x = cholmod_solve(CHOLMOD_A, s.l, &in, &s.common);
  if (!x) throw Error(status_message(s.common.status) + " in a sparse solve");
  std::memcpy(b.data(), x->x, static_cast<std::size_t>(b.size()) * sizeof(double));
  cholmod_free_dense(&x, &s.common);
}

void CholmodFactor::solve_forward(Eigen::MatrixXd& b) const {
  auto& s = *state_;
  cholmod_dense in = view(b);
  cholmod_dense* pb = cholmod_solve(CHOLMOD_P, s.l, &in, &s.common);
  if (!pb) throw Error(status_message(s.common.status) + " in a sparse permutation");
  cholmod_dense* x = cholmod_solve(CHOLMOD_L, s.l, pb, &s.common);
  cholmod_free_dense(&pb, &s.common);
  if (!x) throw Error(status_message(s.common.status) + " in a sparse triangular solve");
  std::memcpy(b.data(), x->x, static_cast<std::size_t>(b.size()) * sizeof(double));
  cholmod_free_dense(&x, &s.common);
}

double CholmodFactor::rcond() const { return cholmod_rcond(state_->l, &state_->common); }

std::size_t CholmodFactor::factor_nonzeros() const {
  const auto* l = state_->l;
  if (!l) return 0;
  if (l->is_super) return static_cast<std::size_t>(l->xsize);
  return static_cast<std::size_t>(static_cast<const int*>(l->p)[l->n]);
}

}  // namespace errfield::detail
