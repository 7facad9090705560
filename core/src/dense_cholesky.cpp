#include "dense_cholesky.hpp"

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
    // Which pivot fails, column by column from a fresh copy. At a pivot that
    // is zero up to rounding (a gauge freedom) this loop and Eigen's blocked
    // one may disagree on its sign: when every pivot here is positive, this
    // factor stands and the ratio test below judges it.
    U_.setZero(n, n);
    scatter(upper);
    for (CscMatrix::Index j = 0; j < n; ++j) {
      const double d = U_(j, j) - U_.col(j).head(j).squaredNorm();
      if (!(d > 0.0)) {
        st.code = SolverStatus::Code::NotPositiveDefinite;
        st.failed_column = j;
        st.message = "matrix is not positive definite";
        return st;
      }
      U_(j, j) = std::sqrt(d);
      for (CscMatrix::Index k = j + 1; k < n; ++k)
        U_(j, k) = (U_(j, k) - U_.col(j).head(j).dot(U_.col(k).head(j))) / U_(j, j);
    }
  }
  WeakestPivot check(upper);  // as SparseCholesky: a rounding-level positive pivot is singular
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
