// The elimination of one 6x6 block into the reduced system, on AVX2 and FMA
// when the CPU has them (x86-64 with GCC or Clang: chosen at run time, the
// library itself built for the baseline instruction set). Plain pointers and
// no Eigen, so that nothing but this kernel is compiled for those
// instructions.
#pragma once

#include <cstddef>
#include <cstdint>

namespace fgcal::detail {

// Whether eliminateSixAvx2 may run on this CPU (and operating system).
bool cpuHasAvx2Fma();

// A link of eliminated block e to reduced block j (SchurSolver's): e's rows
// sit at h_offset within each of j's columns of H.
struct SchurLink {
  std::size_t j;
  std::int64_t h_offset;
};

// For e with A_e = L L^T (Linv = L^-1, lower triangle packed by rows), z =
// L^-1 b_e and its k links, each with B_p (6x6, in H's columns of reduced
// block j, which start at H column reduced_col0[j]) and Y_p = L^-1 B_p:
//   rhs_p -= Y_p^T z        (rhs indexed by reduced column: H column - offset)
//   S_pq  -= Y_p^T Y_q      for p <= q (upper triangle of S_pp)
// S in compressed columns (sp, sv), the pair (p, q)'s block at row offset
// pair_offset[n] of its columns, n counting the pairs in the order (0,0),
// (0,1), ..., (1,1), ... Y is a workspace of 36 k doubles (Y_p by rows).
struct SixElimination {
  const double* hv;
  const std::int64_t* hp;
  const std::int64_t* sp;
  double* sv;
  double* rhs;
  std::int64_t offset;
  const std::int64_t* reduced_col0;
};
void eliminateSixAvx2(const SixElimination& at, const SchurLink* links, std::size_t k, const double* Linv,
                      const double* z, const std::int64_t* pair_offset, double* Y);

// L^-1 of the Cholesky factors of four symmetric 6x6 blocks, one per lane:
// entry (i, j) of block k at A[4 (i + 6 j) + k], the lower triangle read;
// L^-1 likewise into Linv (lower triangle written). False, having written
// part of Linv, when a block's pivot fails the library's rule
// (pivot_rule.hpp), decided lane by lane by that rule itself.
bool inverseCholeskySixAvx2(const double* A, double* Linv);

}  // namespace fgcal::detail
