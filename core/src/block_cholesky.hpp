// The library's one dense Cholesky kernel, A = L L^T column by column, with
// the one pivot rule (pivot_rule.hpp). The Schur solver factors its
// eliminated blocks with it (one block, or four in the lanes of an Eigen
// array), the streamed Schur complement its eliminated variables' blocks,
// and DenseCholesky finds with it the column where Eigen's LLT of the
// reduced system fails: a change to how a pivot is judged or a column is
// computed lands in all of them at once.
#pragma once

#include <cmath>

#include <Eigen/Core>

#include "fgcal/core/internal/pivot_rule.hpp"

namespace fgcal::detail {

// Lanes: T = double factors one matrix, T = Eigen::Array<double, N, 1> N of
// them at once, matrix k in lane k (their serial chains of square roots and
// divisions interleave).
inline bool allLanes(bool b) { return b; }
template <class Expr>
bool allLanes(const Expr& e) {
  return e.all();
}
inline double squareRoot(double x) { return std::sqrt(x); }
template <int N>
Eigen::Array<double, N, 1> squareRoot(const Eigen::Array<double, N, 1>& x) {
  return x.sqrt();
}
inline double reciprocal(double x) { return 1.0 / x; }
template <int N>
Eigen::Array<double, N, 1> reciprocal(const Eigen::Array<double, N, 1>& x) {
  return x.inverse();
}

// x minus the inner product of rows i and j of L over columns 0..k_end-1,
// one subtraction at a time in column order: the kernel's default, which
// the small blocks' unrolled loops keep in registers.
struct SequentialRowDot {
  template <class T, class Lower>
  T operator()(T x, Lower& L, int i, int j, int k_end) const {
    for (int k = 0; k < k_end; ++k) x -= L(i, k) * L(j, k);
    return x;
  }
};

/// How the entries below a pivot are scaled by 1 / L(j, j): multiplied by
/// its reciprocal (one division per column: the Schur solver's blocks), or
/// each divided by L(j, j) (the streamed Schur complement's blocks, as that
/// solver always did, so that a calibration's estimates keep their bits).
enum class ColumnScaling { kReciprocal, kDivide };

/// Factors in place the symmetric positive definite n x n matrix whose lower
/// triangle L(i, j), i >= j, holds (L: a callable returning T&; the upper
/// triangle is never touched): on return L(i, j) holds the factor and
/// inv_diag[j] = 1 / L(j, j). The entries below the pivot are scaled as S
/// says. N > 0 fixes n at compile time (the loops then unroll).
/// `minus_dot(x, L, i, j, k)` gives x - sum_{c < k} L(i, c) L(j, c): a large
/// dense matrix whose rows of L are contiguous passes a vectorised one.
/// Returns -1, or the first column whose pivot pivotAccepted refuses (in any
/// lane), the columns before it factored.
template <int N, ColumnScaling S = ColumnScaling::kReciprocal, class T, class Lower,
          class MinusDot = SequentialRowDot>
int choleskyInPlace(int n_dyn, Lower&& L, T* inv_diag, MinusDot minus_dot = {}) {
  const int n = N > 0 ? N : n_dyn;
  for (int j = 0; j < n; ++j) {
    const T a = L(j, j);
    const T d = minus_dot(a, L, j, j, j);
    if (!allLanes(pivotAccepted(d, a))) return j;
    const T l = squareRoot(d);
    L(j, j) = l;
    inv_diag[j] = reciprocal(l);
    for (int i = j + 1; i < n; ++i) {
      if constexpr (S == ColumnScaling::kDivide)
        L(i, j) = minus_dot(T(L(i, j)), L, i, j, j) / l;
      else
        L(i, j) = minus_dot(T(L(i, j)), L, i, j, j) * inv_diag[j];
    }
  }
  return -1;
}

/// An Eigen matrix's lower triangle factored in place (A = L L^T) by
/// choleskyInPlace, the upper triangle untouched: -1, or the first column
/// whose pivot the rule refuses.
template <ColumnScaling S = ColumnScaling::kReciprocal, class Matrix>
int choleskyLowerInPlace(Matrix& A) {
  Eigen::Matrix<double, Eigen::Dynamic, 1, 0, Matrix::MaxRowsAtCompileTime, 1> inv_diag(A.rows());
  return choleskyInPlace<0, S>(static_cast<int>(A.rows()), [&A](int i, int j) -> double& { return A(i, j); },
                               inv_diag.data());
}

}  // namespace fgcal::detail
