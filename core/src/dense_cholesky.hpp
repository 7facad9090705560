// Dense Cholesky of a small symmetric positive definite matrix given by its
// upper triangle in compressed columns: the Schur complement's reduced system
// when it is small and (nearly) full, as the camera block of a calibration
// is. Same contract as SparseCholesky::factorize / solve (a pivot the
// library's rule refuses, pivot_rule.hpp, is NotPositiveDefinite with a
// column: the first one where the factorization fails, else the weakest
// pivot's), without CHOLMOD's symbolic analysis
// and supernodal machinery, which a 6x6 to 100x100 dense system does not
// need. The factorization is Eigen's blocked LLT (its bits are those of every
// earlier release); where Eigen refuses, the library's kernel
// (block_cholesky.hpp) names the column, and WeakestPivot judges what stands.
#pragma once

#include "fgcal/core/internal/sparse_cholesky.hpp"

namespace fgcal::detail {

class DenseCholesky {
 public:
  /// Factors the matrix whose upper triangle `upper` holds (rows sorted). A
  /// NaN or inf entry is Failed, naming its column.
  SolverStatus factorize(const CscMatrix& upper);
  /// x = A^-1 b; Failed unless the last factorize() succeeded.
  SolverStatus solve(const VecX& b, VecX& x) const;

 private:
  void scatter(const CscMatrix& upper);
  MatX U_;  // A's upper triangle, then its factor U (A = U^T U)
  bool factorized_ = false;
};

}  // namespace fgcal::detail
