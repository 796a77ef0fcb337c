// kernels/dense_cholesky.hpp's functions compiled for AVX2 + FMA (this file alone has -mavx2 -mfma,
// set in CMakeLists.txt, and is kept out of the unity batches). Eigen is included here under
// another namespace name: its templates are instantiated in every object that uses them and the
// linker keeps one copy of each name, so AVX2 instances under Eigen's own names could replace the
// plain ones everywhere (and fault on a CPU without AVX2). Include nothing here that brings Eigen
// in under its own name; tests/kernels checks that this object defines no shared symbol outside
// that namespace and errfield::kernels::detail::avx2.
#if defined(ERRFIELD_DENSE_AVX2)

#define Eigen errfield_eigen_avx2
#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "dense_cholesky.hpp"

namespace errfield::kernels::detail::avx2 {
#include "dense_cholesky_eigen.inc"
}  // namespace errfield::kernels::detail::avx2

#endif
