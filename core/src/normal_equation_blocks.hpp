// The writers of normal-equation blocks into H's cached positions, shared by
// the factors' linearization (factor_blocks.cpp) and the normal equations
// formed from a stored J (stored_jacobian.cpp).
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

// f(std::integral_constant<int, dof>) for the tangent sizes that get a
// fixed-size kernel (4, 6, 8), f(integral_constant<int, Eigen::Dynamic>)
// for any other.
template <class F>
inline void withSmallDof(int dof, F&& f) {
  switch (dof) {
    case 4: f(std::integral_constant<int, 4>{}); return;
    case 6: f(std::integral_constant<int, 6>{}); return;
    case 8: f(std::integral_constant<int, 8>{}); return;
    default: f(std::integral_constant<int, Eigen::Dynamic>{}); return;
  }
}

// H(p, q) += Jp^T Jq (= when Assign) for a block in the columns of q;
// `upper_only` for a diagonal block, whose lower triangle CHOLMOD does not read.
// With every size fixed (R, CP, CQ) the product is formed in registers; with
// any of them Eigen::Dynamic, entry by entry from the columns of Jp and Jq
// (no temporary: a dynamic-size product would allocate one per block, and
// factors of small residuals, e.g. 2-D reprojection errors, are linearized
// some 10^5 times per iteration). R may stay fixed with dynamic CP, CQ.
template <bool Assign, int R, int CP, int CQ>
void accumulateBlock(const double* jp, Index sp, const double* jq, Index sq, int rows, int cp, int cq,
                     double* H, const Index* colptr_q, Index offset, bool upper_only) {
  if constexpr (R != Eigen::Dynamic && CP != Eigen::Dynamic && CQ != Eigen::Dynamic) {
    const StridedMap<R, CP> Jp(jp, rows, cp, Eigen::OuterStride<>(sp));
    const StridedMap<R, CQ> Jq(jq, rows, cq, Eigen::OuterStride<>(sq));
    const Eigen::Matrix<double, CP, CQ> M = Jp.transpose() * Jq;
    for (int c = 0; c < cq; ++c) {
      double* col = H + colptr_q[c] + offset;
      const int rmax = upper_only ? c + 1 : cp;
      for (int r = 0; r < rmax; ++r) put<Assign>(col[r], M(r, c));
    }
  } else {
    const int n = R != Eigen::Dynamic ? R : rows;
    for (int c = 0; c < cq; ++c) {
      double* col = H + colptr_q[c] + offset;
      const double* q = jq + static_cast<std::ptrdiff_t>(c) * sq;
      const int rmax = upper_only ? c + 1 : cp;
      for (int r = 0; r < rmax; ++r) {
        const double* p = jp + static_cast<std::ptrdiff_t>(r) * sp;
        double sum = 0.0;
        for (int k = 0; k < n; ++k) sum += p[k] * q[k];
        put<Assign>(col[r], sum);
      }
    }
  }
}

// g += J^T r for one key's d x dof block J (column-major) of a factor with d
// residual rows; R fixed (or Eigen::Dynamic for d at run time), dof at run time.
template <int R>
inline void addTransposeTimes(const double* J, int d, int dof, const double* r, double* g) {
  const int n = R != Eigen::Dynamic ? R : d;
  for (int c = 0; c < dof; ++c) {
    const double* col = J + static_cast<std::ptrdiff_t>(c) * n;
    double sum = 0.0;
    for (int k = 0; k < n; ++k) sum += col[k] * r[k];
    g[c] += sum;
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
