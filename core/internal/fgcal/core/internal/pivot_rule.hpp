// The one rule by which every Cholesky factorization of the library accepts
// a pivot: the dense column kernel (block_cholesky.hpp) of the Schur
// solvers' eliminated blocks and of the dense reduced system, its AVX2 lanes,
// and the test after CHOLMOD's factorization (weakest_pivot.hpp). A fix to
// the rule is made here, once. No Eigen: the AVX2 kernel includes it.
#pragma once

#include <limits>

namespace fgcal::detail {

/// A pivot L(j,j)^2 below this fraction of A(j,j) marks the matrix singular:
/// a rank-deficient matrix (gauge freedom) can factor with a rounding-level
/// positive pivot instead of failing.
inline constexpr double kSingularPivotRatio = 1e-12;

/// Whether the pivot d = A(j,j) - sum_k L(j,k)^2 of a column whose diagonal
/// entry is a may stand: positive, finite and not below kSingularPivotRatio
/// of a (NaN fails every comparison, so it fails too). T is double, or an
/// Eigen array of lanes (one block per lane: the result is then per lane).
template <class T>
auto pivotAccepted(const T& d, const T& a) {
  return (d > 0.0) && (d <= std::numeric_limits<double>::max()) && (d >= kSingularPivotRatio * a);
}

}  // namespace fgcal::detail
