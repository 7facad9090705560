// The writers of normal-equation blocks into H's cached positions, shared by
// the factors' linearization (factor_blocks.cpp) and the normal equations
// formed from a stored J (jacobian_pattern.cpp).
#pragma once

#include <type_traits>

#include <Eigen/Core>

#include "fgcal/core/internal/sparse_matrix.hpp"
#include "fgcal/core/types.hpp"

namespace fgcal::detail {

using Index = CscMatrix::Index;
// |r|^2 of a whitened residual, summed in one order wherever a cost is formed
// (linearize() and cost() must agree to the bit on one thread).
inline double squaredNorm(const double* r, int d) {
  double sq = 0.0;
  for (int i = 0; i < d; ++i) sq += r[i] * r[i];
  return sq;
}
template <int R, int C>
using StridedMap = Eigen::Map<const Eigen::Matrix<double, R, C>, 0, Eigen::OuterStride<>>;

// x += y, or x = y for a block's first contribution (H then needs no
// clearing before a linearization).
template <bool Assign, class X, class Y>
inline void put(X&& x, const Y& y) {
  if constexpr (Assign)
    x = y;
  else
    x += y;
}
// f(std::true_type) when `assign`, else f(std::false_type): one runtime
// choice for the compile-time Assign of the block writers below.
template <class F>
inline void withAssign(bool assign, F&& f) {
  if (assign)
    f(std::true_type{});
  else
    f(std::false_type{});
}

// H(p, q) += Jp^T Jq (= when Assign) for a block in the columns of q;
// `upper_only` for a diagonal block, whose lower triangle CHOLMOD does not read.
template <bool Assign, int R, int CP, int CQ>
void accumulateBlock(const double* jp, Index sp, const double* jq, Index sq, int rows, int cp, int cq,
                     double* H, const Index* colptr_q, Index offset, bool upper_only) {
  const StridedMap<R, CP> Jp(jp, rows, cp, Eigen::OuterStride<>(sp));
  const StridedMap<R, CQ> Jq(jq, rows, cq, Eigen::OuterStride<>(sq));
  const Eigen::Matrix<double, CP, CQ> M = Jp.transpose() * Jq;
  for (int c = 0; c < cq; ++c) {
    double* col = H + colptr_q[c] + offset;
    const int rmax = upper_only ? c + 1 : cp;
    for (int r = 0; r < rmax; ++r) put<Assign>(col[r], M(r, c));
  }
}

// H(p, q) += w B (= when Assign) for the factor's dp x dq block B
// (column-major), or w B^T when `transposed` (B then dq x dp); only the upper
// triangle when `diagonal`. The 6x6 case (SE(3) with SE(3)) goes by whole
// columns of two-lane packets: a transposed block is transposed once in
// registers, a diagonal block's column c adds its c + 1 upper entries.
template <bool Assign>
void addScaledBlock(const double* B, int dp, int dq, bool transposed, bool diagonal, double w, double* H,
                    const Index* colptr_q, Index offset) {
  if (dp == 6 && dq == 6) {
    const Eigen::Map<const Mat6> Bm(B);
    if (diagonal) {
      for (int c = 0; c < 6; ++c) {
        double* col = H + colptr_q[c] + offset;
        int r = 0;
        for (; r < c; r += 2) put<Assign>(Eigen::Map<Eigen::Vector2d>(col + r), w * Bm.col(c).segment<2>(r));
        if (r == c) put<Assign>(col[r], w * Bm(r, c));
      }
    } else if (transposed) {
      const Mat6 Bt = w * Bm.transpose();
      for (int c = 0; c < 6; ++c) put<Assign>(Eigen::Map<Vec6>(H + colptr_q[c] + offset), Bt.col(c));
    } else {
      for (int c = 0; c < 6; ++c) put<Assign>(Eigen::Map<Vec6>(H + colptr_q[c] + offset), w * Bm.col(c));
    }
    return;
  }
  for (int c = 0; c < dq; ++c) {
    double* col = H + colptr_q[c] + offset;
    const int rmax = diagonal ? c + 1 : dp;
    for (int r = 0; r < rmax; ++r) {
      const std::ptrdiff_t rr = r, cc = c;
      put<Assign>(col[r], w * B[transposed ? cc + rr * dq : rr + cc * dp]);
    }
  }
}


}  // namespace fgcal::detail
