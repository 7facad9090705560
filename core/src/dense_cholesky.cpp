#include "dense_cholesky.hpp"

#include "block_cholesky.hpp"
#include "weakest_pivot.hpp"

#include <cmath>
#include <string>

#include <Eigen/Cholesky>

namespace fgcal::detail {

void DenseCholesky::scatter(const CscMatrix& upper) {
  U_.resize(upper.rows, upper.cols);
  for (CscMatrix::Index c = 0; c < upper.cols; ++c) {
    double* col = U_.col(c).data();
    for (CscMatrix::Index p = upper.colptr[c]; p < upper.colptr[c + 1]; ++p) col[upper.rowind[p]] = upper.values[p];
  }
}

SolverStatus DenseCholesky::factorize(const CscMatrix& upper) {
  SolverStatus st;
  const CscMatrix::Index n = upper.cols;
  if (upper.rows != n || upper.colptr.size() != static_cast<std::size_t>(n) + 1) {
    st.code = SolverStatus::Code::Failed;
    st.message = "matrix to factorize is not square or its column pointers are malformed";
    return st;
  }
  factorized_ = false;
  for (CscMatrix::Index j = 0; j < n; ++j)
    for (CscMatrix::Index p = upper.colptr[j]; p < upper.colptr[j + 1]; ++p)
      if (!std::isfinite(upper.values[p])) {
        st.code = SolverStatus::Code::Failed;
        st.failed_column = j;
        st.message = "matrix holds NaN or inf (column " + std::to_string(j) + ")";
        return st;
      }
  // Every entry of the upper triangle is written: a sparse pattern leaves the rest zero.
  U_.setZero(n, n);
  scatter(upper);
  Eigen::LLT<Eigen::Ref<MatX>, Eigen::Upper> llt(U_);  // in place
  if (llt.info() != Eigen::Success) {
    // Which pivot fails: the library's kernel, column by column from a fresh
    // copy, on U = L^T (row j of L is column j of U, contiguous: Eigen's
    // vectorised dot). At a pivot that is zero up to rounding (a gauge
    // freedom) it and Eigen's blocked LLT may disagree on the sign; where the
    // kernel accepts every pivot, its factor stands.
    U_.setZero(n, n);
    scatter(upper);
    VecX inv_diag(n);
    const auto minus_dot = [this](double x, auto&, int i, int j, int k_end) {
      return x - U_.col(i).head(k_end).dot(U_.col(j).head(k_end));
    };
    const int failed = choleskyInPlace<0>(
        static_cast<int>(n), [this](int i, int j) -> double& { return U_(j, i); }, inv_diag.data(), minus_dot);
    if (failed >= 0) {
      st.code = SolverStatus::Code::NotPositiveDefinite;
      st.failed_column = failed;
      st.message = "matrix is not positive definite or numerically singular (column " + std::to_string(failed) +
                   ": a pivot not positive, or below kSingularPivotRatio of its diagonal entry)";
      return st;
    }
  }
  WeakestPivot check(upper);  // as after CHOLMOD: a rounding-level positive pivot is singular
  for (CscMatrix::Index j = 0; j < n; ++j) check.visit(j, U_(j, j));
  st = check.status();
  factorized_ = st.ok();
  return st;
}

SolverStatus DenseCholesky::solve(const VecX& b, VecX& x) const {
  SolverStatus st;
  if (!factorized_ || b.size() != U_.rows()) {
    st.code = SolverStatus::Code::Failed;
    st.message = !factorized_ ? "solve called before a successful factorization"
                              : "right-hand side has the wrong number of rows";
    return st;
  }
  x = U_.triangularView<Eigen::Upper>().transpose().solve(b);
  U_.triangularView<Eigen::Upper>().solveInPlace(x);
  return st;
}

}  // namespace fgcal::detail
