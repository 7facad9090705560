// The test both Cholesky paths (SparseCholesky over CHOLMOD, the Schur
// solver's dense one) apply after a factorization that succeeded: a
// rank-deficient matrix (gauge freedom) can factor with a rounding-level
// positive pivot instead of failing, so a pivot L(j,j)^2 that the library's
// rule (pivot_rule.hpp) refuses marks it singular, at the column of the
// smallest ratio L(j,j)^2 / A(j,j).
#pragma once

#include <limits>
#include <string>

#include "fgcal/core/internal/pivot_rule.hpp"
#include "fgcal/core/internal/sparse_cholesky.hpp"

namespace fgcal::detail {

class WeakestPivot {
 public:
  /// `upper`: the factorized matrix's upper triangle, rows sorted (A(j, j) last in column j).
  explicit WeakestPivot(const CscMatrix& upper) : A_(upper) {}

  /// The pivot L(col, col) of column `col` (the input's numbering).
  void visit(CscMatrix::Index col, double l) {
    const CscMatrix::Index last = A_.colptr[col + 1] - 1;
    const double a = (last >= A_.colptr[col] && A_.rowind[last] == col) ? A_.values[last] : 0.0;
    const double ratio = a > 0.0 ? l * l / a : 0.0;
    if (!(a > 0.0 && pivotAccepted(l * l, a))) refused_ = true;
    if (ratio < worst_) {
      worst_ = ratio;
      col_ = col;
    }
  }

  /// Success, or NotPositiveDefinite naming the weakest pivot's column.
  SolverStatus status() const {
    SolverStatus st;
    if (refused_) {
      st.code = SolverStatus::Code::NotPositiveDefinite;
      st.failed_column = col_;
      st.message = "matrix is numerically singular (pivot ratio " + std::to_string(worst_) + ")";
    }
    return st;
  }

 private:
  const CscMatrix& A_;
  double worst_ = std::numeric_limits<double>::infinity();
  CscMatrix::Index col_ = -1;
  bool refused_ = false;
};

}  // namespace fgcal::detail
