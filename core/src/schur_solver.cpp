#include "fgcal/core/internal/schur_solver.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "block_cholesky.hpp"
#include "dense_cholesky.hpp"
#include "parallel.hpp"
#include "schur_six_avx2.hpp"

namespace fgcal {

namespace {
using Index = CscMatrix::Index;

// v.segment(start, n), with a compile-time size when D is fixed: a
// dynamic-size segment sends the small products below through Eigen's
// general matrix-vector path.
template <int D, class V>
auto seg(V& v, Eigen::Index start, int n) {
  if constexpr (D == Eigen::Dynamic)
    return v.segment(start, n);
  else
    return v.template segment<D>(start);
}

// L^-1 of the Cholesky factor of a symmetric positive definite n x n A
// (column-major, only its lower triangle read, then overwritten by L), n <=
// 9; N > 0 fixes n at compile time. False when A (any lane, T as in
// block_cholesky.hpp) is not positive definite by the library's pivot rule.
// Plain loops that the compiler unrolls at 6x6: Eigen's LLT and triangular
// solves take their general blocked paths even for fixed-size matrices.
// L^-1 goes by rows, so that a row's entries depend only on earlier rows,
// not on each other.
template <int N, class T>
bool inverseCholeskyFactor(int n_dyn, T* A, T* Linv) {
  constexpr int kMax = N > 0 ? N : 9;
  const int n = N > 0 ? N : n_dyn;
  T inv_diag[kMax];
  const T* L = A;
  if (detail::choleskyInPlace<N>(n, [A, n](int i, int j) -> T& { return A[i + n * j]; }, inv_diag) >= 0)
    return false;
  for (int i = 0; i < n; ++i) {  // row i of L^-1: -(1 / L(i, i)) sum_k L(i, k) L^-1(k, j)
    for (int j = 0; j < i; ++j) {
      T v = L[i + n * j] * Linv[j + n * j];
      for (int k = j + 1; k < i; ++k) v += L[i + n * k] * Linv[k + n * j];
      Linv[i + n * j] = -v * inv_diag[i];
    }
    Linv[i + n * i] = inv_diag[i];
    for (int j = i + 1; j < n; ++j) Linv[i + n * j] = T(0.0);
  }
  return true;
}
// A 6x6 lower-triangular L^-1 kept packed by rows: entry (i, k <= i) at
// i (i + 1) / 2 + k, 21 doubles instead of 36 (it is the solver's largest
// array after H: one per board pose).
constexpr int packed(int i, int k) { return i * (i + 1) / 2 + k; }
// out <- the lower triangle of a column-major 6x6, entry (i, k) read as full(i + 6 k).
template <class Full>
void packLower6(Full&& full, double* out) {
  for (int i = 0; i < 6; ++i)
    for (int k = 0; k <= i; ++k) out[packed(i, k)] = full(i + 6 * k);
}
inline Vec6 lowerTimes6(const double* L, const double* v) {
  Vec6 out;
  for (int i = 0; i < 6; ++i) {
    double s = 0.0;
    for (int k = 0; k <= i; ++k) s += L[packed(i, k)] * v[k];
    out[i] = s;
  }
  return out;
}
inline Vec6 lowerTransposeTimes6(const double* L, const Vec6& v) {
  Vec6 out = Vec6::Zero();
  for (int i = 0; i < 6; ++i)
    for (int k = 0; k <= i; ++k) out[k] += L[packed(i, k)] * v[i];
  return out;
}
}  // namespace

SchurSolver::~SchurSolver() = default;

// The upper triangle of S by block columns: column j's partners i <= j
// (sorted), and where block (i, j) starts within each of j's columns.
struct SchurSolver::ReducedPattern {
  std::vector<std::vector<std::size_t>> upper;
  std::vector<std::vector<Index>> offset_in_col;  // parallel to upper[j]
  Index offset(std::size_t i, std::size_t j) const {
    const auto it = std::lower_bound(upper[j].begin(), upper[j].end(), i);
    return offset_in_col[j][static_cast<std::size_t>(it - upper[j].begin())];
  }
};

SchurSolver::SchurSolver(const LinearSystem& system, int threads, ReducedSolve reduced, Kernel kernel)
    : sys_(system), ne_(system.numEliminatedBlocks()), offset_(system.numEliminatedColumns()),
      threads_(threads) {
  if (threads < 1) throw std::invalid_argument("SchurSolver: threads must be >= 1, got " + std::to_string(threads));
  const auto& blocks = sys_.blocks();
  const std::size_t nr = blocks.size() - ne_;
  all_blocks_six_ = std::all_of(blocks.begin(), blocks.end(), [](const auto& b) { return b.dof == 6; });
  use_avx2_ = all_blocks_six_ && kernel == Kernel::Auto && detail::cpuHasAvx2Fma();
  reduced_col0_.resize(nr);
  for (std::size_t j = 0; j < nr; ++j) reduced_col0_[j] = blocks[ne_ + j].col0;

  linkEliminatedBlocks();
  const ReducedPattern pattern = reducedPattern();
  layOutReducedSystem(pattern);
  pairOffsets(pattern);
  copiesOfC(pattern);

  // A small, nearly full S (every camera pair shares a board pose) is
  // factored densely: no symbolic analysis, no supernodal bookkeeping.
  const double n = static_cast<double>(S_.cols), full = n * (n + 1.0) / 2.0;
  const bool dense = reduced == ReducedSolve::Dense ||
                     (reduced == ReducedSolve::Auto &&
                      (S_.cols <= 32 ||
                       (S_.cols <= kDenseMaxColumns && 2.0 * static_cast<double>(S_.colptr[S_.cols]) >= full)));
  if (dense)
    dense_ = std::make_unique<detail::DenseCholesky>();
  else
    cholesky_ = std::make_unique<SparseCholesky>();
}

// Links from each eliminated block to the reduced blocks whose columns hold
// it, grouped by e (counted, then filled; ascending j within a group since
// the reduced blocks are visited in order).
void SchurSolver::linkEliminatedBlocks() {
  const auto& blocks = sys_.blocks();
  const auto& nbrs = sys_.blockNeighbours();
  const std::size_t nr = blocks.size() - ne_;
  link_begin_.assign(ne_ + 1, 0);
  for (std::size_t j = 0; j < nr; ++j) {
    const auto& bj = blocks[ne_ + j];
    for (std::size_t k = bj.neighbour_begin; k < bj.neighbour_end; ++k)
      if (nbrs[k].block < ne_) ++link_begin_[nbrs[k].block + 1];
  }
  for (std::size_t e = 0; e < ne_; ++e) link_begin_[e + 1] += link_begin_[e];
  links_.resize(link_begin_[ne_]);
  std::vector<std::size_t> fill(link_begin_.begin(), link_begin_.end() - 1);
  for (std::size_t j = 0; j < nr; ++j) {
    const auto& bj = blocks[ne_ + j];
    for (std::size_t k = bj.neighbour_begin; k < bj.neighbour_end; ++k)
      if (nbrs[k].block < ne_) links_[fill[nbrs[k].block]++] = {j, nbrs[k].offset};
  }
  for (std::size_t e = 0; e < ne_; ++e) max_links_ = std::max(max_links_, link_begin_[e + 1] - link_begin_[e]);
}

// Pattern of S (upper): direct reduced neighbours, and pairs sharing an
// eliminated block. Column j's partners i <= j through an eliminated block
// come from the links of the blocks in j's columns; mark[i] == j once i is
// listed.
SchurSolver::ReducedPattern SchurSolver::reducedPattern() const {
  const auto& blocks = sys_.blocks();
  const auto& nbrs = sys_.blockNeighbours();
  const std::size_t nr = blocks.size() - ne_;
  ReducedPattern pattern;
  pattern.upper.resize(nr);
  std::vector<std::size_t> mark(nr, nr);
  for (std::size_t j = 0; j < nr; ++j) {
    auto& u = pattern.upper[j];
    auto add = [&](std::size_t i) {
      if (mark[i] != j) {
        mark[i] = j;
        u.push_back(i);
      }
    };
    add(j);
    const auto& bj = blocks[ne_ + j];
    for (std::size_t k = bj.neighbour_begin; k < bj.neighbour_end; ++k) {
      const std::size_t e = nbrs[k].block;
      if (e >= ne_) {
        add(e - ne_);
        continue;
      }
      for (std::size_t p = link_begin_[e]; p < link_begin_[e + 1] && links_[p].j <= j; ++p) add(links_[p].j);
    }
    std::sort(u.begin(), u.end());
  }
  pattern.offset_in_col.resize(nr);
  for (std::size_t j = 0; j < nr; ++j) {
    Index off = 0;
    for (std::size_t i : pattern.upper[j]) {
      pattern.offset_in_col[j].push_back(off);
      if (i != j) off += blocks[ne_ + i].dof;
    }
  }
  return pattern;
}

// S's compressed columns: block (i, j) full for i < j, the upper triangle of (j, j).
void SchurSolver::layOutReducedSystem(const ReducedPattern& pattern) {
  const auto& blocks = sys_.blocks();
  const std::size_t nr = pattern.upper.size();
  S_.rows = S_.cols = sys_.numColumns() - offset_;
  S_.colptr.assign(S_.cols + 1, 0);
  for (std::size_t j = 0; j < nr; ++j) {
    const auto& bj = blocks[ne_ + j];
    const Index off = pattern.upper[j].empty() ? 0 : pattern.offset_in_col[j].back();
    for (int c = 0; c < bj.dof; ++c) S_.colptr[bj.col0 - offset_ + c + 1] = off + c + 1;
  }
  for (Index c = 0; c < S_.cols; ++c) S_.colptr[c + 1] += S_.colptr[c];
  S_.rowind.resize(S_.colptr[S_.cols]);
  S_.values.assign(S_.colptr[S_.cols], 0.0);
  for (std::size_t j = 0; j < nr; ++j) {
    const auto& bj = blocks[ne_ + j];
    for (int c = 0; c < bj.dof; ++c) {
      Index pos = S_.colptr[bj.col0 - offset_ + c];
      for (std::size_t i : pattern.upper[j]) {
        const auto& bi = blocks[ne_ + i];
        const int rows = i == j ? c + 1 : bi.dof;
        for (int r = 0; r < rows; ++r) S_.rowind[pos++] = bi.col0 - offset_ + r;
      }
    }
  }
}

// Per eliminated block, per pair of its links p <= q: where block (j_p, j_q) starts in S's columns.
void SchurSolver::pairOffsets(const ReducedPattern& pattern) {
  std::size_t num_pairs = 0;
  for (std::size_t e = 0; e < ne_; ++e) {
    const std::size_t l = link_begin_[e + 1] - link_begin_[e];
    num_pairs += l * (l + 1) / 2;
  }
  pair_begin_.assign(ne_ + 1, 0);
  pair_offset_.reserve(num_pairs);
  for (std::size_t e = 0; e < ne_; ++e) {
    pair_begin_[e] = pair_offset_.size();
    for (std::size_t p = link_begin_[e]; p < link_begin_[e + 1]; ++p)
      for (std::size_t q = p; q < link_begin_[e + 1]; ++q)
        pair_offset_.push_back(pattern.offset(links_[p].j, links_[q].j));
  }
  pair_begin_[ne_] = pair_offset_.size();
}

// C: where each of its entries sits in H and in S.
void SchurSolver::copiesOfC(const ReducedPattern& pattern) {
  const auto& blocks = sys_.blocks();
  const auto& nbrs = sys_.blockNeighbours();
  const std::size_t nr = pattern.upper.size();
  for (std::size_t j = 0; j < nr; ++j) {
    const auto& bj = blocks[ne_ + j];
    for (int c = 0; c < bj.dof; ++c) {
      const Index hcol = bj.col0 + c, scol = hcol - offset_;
      for (std::size_t k = bj.neighbour_begin; k < bj.neighbour_end; ++k)
        if (nbrs[k].block >= ne_)
          copies_.push_back({sys_.hessianColumnPointers()[hcol] + nbrs[k].offset,
                             S_.colptr[scol] + pattern.offset(nbrs[k].block - ne_, j), blocks[nbrs[k].block].dof});
      copies_.push_back(
          {sys_.hessianColumnPointers()[hcol] + bj.neighbour_rows, S_.colptr[scol] + pattern.offset(j, j), c + 1});
    }
  }
}

// One eliminated 6x6 block with 6-dof neighbours, on two-lane packets. Y_p
// is kept transposed: column i of Y_p^T = B_p^T L^-T is the sum over k <= i
// of L^-1(i, k) times row k of B_p (L^-1 is lower triangular), so that
// rhs_p -= Y_p^T z and S_pq -= Y_p^T Y_q are sums of those columns, the
// latter over the upper triangle only when p = q. Eigen's fixed-size
// products take neither the triangle nor the transposed operand's layout.
void SchurSolver::eliminateSix(std::size_t e, const double* Linv, const double* z,
                               std::vector<Eigen::Matrix<double, 6, 6>>& Y, double* sv, double* rhs) const {
  using A2 = Eigen::Array2d;
  using Index = CscMatrix::Index;
  const auto& blocks = sys_.blocks();
  const Index* hp = sys_.hessianColumnPointers().data();
  const double* hv = sys_.hessianValues().data();
  const Index* sp = S_.colptr.data();
  const std::size_t l0 = link_begin_[e], l1 = link_begin_[e + 1];
  for (std::size_t p = l0; p < l1; ++p) {
    const auto& bj = blocks[ne_ + links_[p].j];
    double Bt[36];  // B_p^T: row k of B_p at Bt + 6 k
    for (int c = 0; c < 6; ++c) {
      const double* col = hv + hp[bj.col0 + c] + links_[p].h_offset;
      for (int r = 0; r < 6; ++r) Bt[c + 6 * r] = col[r];
    }
    double* Yt = Y[p - l0].data();
    A2 g0(0.0, 0.0), g1(0.0, 0.0), g2(0.0, 0.0);
#pragma GCC unroll 6
    for (int i = 0; i < 6; ++i) {
      A2 y0(0.0, 0.0), y1(0.0, 0.0), y2(0.0, 0.0);
#pragma GCC unroll 6
      for (int k = 0; k <= i; ++k) {
        const A2 l(Linv[packed(i, k)], Linv[packed(i, k)]);
        y0 += l * Eigen::Map<const A2>(Bt + 6 * k);
        y1 += l * Eigen::Map<const A2>(Bt + 6 * k + 2);
        y2 += l * Eigen::Map<const A2>(Bt + 6 * k + 4);
      }
      Eigen::Map<A2>(Yt + 6 * i) = y0;
      Eigen::Map<A2>(Yt + 6 * i + 2) = y1;
      Eigen::Map<A2>(Yt + 6 * i + 4) = y2;
      const A2 zi(z[i], z[i]);
      g0 += y0 * zi, g1 += y1 * zi, g2 += y2 * zi;
    }
    double* rj = rhs + (bj.col0 - offset_);
    Eigen::Map<A2>(rj) -= g0;
    Eigen::Map<A2>(rj + 2) -= g1;
    Eigen::Map<A2>(rj + 4) -= g2;
  }
  std::size_t pair = pair_begin_[e];
  for (std::size_t p = l0; p < l1; ++p) {
    const double* Yp = Y[p - l0].data();
    for (std::size_t q = p; q < l1; ++q, ++pair) {
      const double* Yq = Y[q - l0].data();
      const auto& bj = blocks[ne_ + links_[q].j];
      const Index so = pair_offset_[pair];
#pragma GCC unroll 6
      for (int c = 0; c < 6; ++c) {
        // Column c of Y_p^T Y_q: the sum over i of column i of Y_p^T times Y_q^T(c, i).
        A2 m0(0.0, 0.0), m1(0.0, 0.0), m2(0.0, 0.0);
#pragma GCC unroll 6
        for (int i = 0; i < 6; ++i) {
          const A2 y(Yq[c + 6 * i], Yq[c + 6 * i]);
          m0 += Eigen::Map<const A2>(Yp + 6 * i) * y;
          if (p != q || c >= 2) m1 += Eigen::Map<const A2>(Yp + 6 * i + 2) * y;
          if (p != q || c >= 4) m2 += Eigen::Map<const A2>(Yp + 6 * i + 4) * y;
        }
        double* col = sv + sp[bj.col0 - offset_ + c] + so;
        const int rows = p == q ? c + 1 : 6;
        const double m[6] = {m0[0], m0[1], m1[0], m1[1], m2[0], m2[1]};
        for (int r = 0; r < rows; ++r) col[r] -= m[r];
      }
    }
  }
}

SolverStatus SchurSolver::solve(const VecX& b, VecX& x) { return solve(b, x, Damping{}, nullptr); }

SolverStatus SchurSolver::solve(const VecX& b, VecX& x, const Damping& damping, double* xDx) {
  if (!(damping.lambda >= 0.0) || !std::isfinite(damping.lambda) || !(damping.min_diagonal >= 0.0) ||
      !(damping.min_diagonal <= damping.max_diagonal))
    throw std::invalid_argument("SchurSolver: damping needs a finite lambda >= 0 and 0 <= min_diagonal <= "
                                "max_diagonal, got lambda " + std::to_string(damping.lambda) + ", min_diagonal " +
                                std::to_string(damping.min_diagonal) + ", max_diagonal " +
                                std::to_string(damping.max_diagonal));
  return all_blocks_six_ ? solveImpl<6, 6>(b, x, damping, xDx)
                         : solveImpl<Eigen::Dynamic, Eigen::Dynamic>(b, x, damping, xDx);
}

// With A_e = L L^T: Y_i = L^-1 B_i and z = L^-1 b_e, so that
//   S_ij -= Y_i^T Y_j,  rhs_i -= Y_i^T z,  x_e = L^-T L^-1 (b_e - sum_i B_i x_i).
// L^-1 is formed once per block (small: at most 9x9) and kept for the back
// substitution, which reads B_i from H again: the Y_i live only while their
// block is eliminated, so no per-link storage goes through memory. One
// solve's state and its steps, by the block sizes DE (eliminated) and DR
// (reduced): 6 and 6 when every block is 6x6, else dynamic.
template <int DE, int DR>
struct SchurSolver::Pass {
  using MatEE = Eigen::Matrix<double, DE, DE>;
  using MatER = Eigen::Matrix<double, DE, DR>;
  using MatRR = Eigen::Matrix<double, DR, DR>;
  using VecE = Eigen::Matrix<double, DE, 1>;

  SchurSolver& solver;
  const VecX& b;
  const Damping& damping;
  const int T;  // threads of this solve
  const std::vector<LinearSystem::BlockColumn>& blocks = solver.sys_.blocks();
  const Index* hp = solver.sys_.hessianColumnPointers().data();
  const double* hv = solver.sys_.hessianValues().data();
  const Index* sp = solver.S_.colptr.data();
  const bool damped = damping.lambda != 0.0;
  Workspace<DE, DR>& ws = solver.workspace<DE, DR>();
  std::vector<SolverStatus> status = std::vector<SolverStatus>(static_cast<std::size_t>(T));

  // Damping: H_jj + lambda clamp(H_jj), added where H_jj is read (an
  // eliminated block's gather, the reduced system's copy of C).
  double clampDiagonal(double h) const { return std::clamp(h, damping.min_diagonal, damping.max_diagonal); }
  double damp(double h) const { return h + damping.lambda * clampDiagonal(h); }
  double* packedFactor(std::size_t e) const { return ws.packed.data() + 21 * e; }

  // B_p: the coupling block of eliminated block e with its p-th reduced neighbour, in H.
  MatER couplingBlock(std::size_t e, std::size_t p) const {
    const auto& be = blocks[e];
    const auto& bj = blocks[solver.ne_ + solver.links_[p].j];
    MatER B(be.dof, bj.dof);
    if constexpr (DE == 6 && DR == 6) {
      for (int c = 0; c < 6; ++c)
        B.col(c) = Eigen::Map<const VecE>(hv + hp[bj.col0 + c] + solver.links_[p].h_offset);
      return B;
    }
    for (int c = 0; c < bj.dof; ++c)
      for (int r = 0; r < be.dof; ++r) B(r, c) = hv[hp[bj.col0 + c] + solver.links_[p].h_offset + r];
    return B;
  }

  // A_e's lower triangle, from the upper one H holds, into lane k of A.
  template <class Lane, class Entry>
  void gatherBlock(std::size_t e, Entry* A, Lane&& lane) const {
    const auto& be = blocks[e];
    for (int c = 0; c < be.dof; ++c) {
      const double* col = hv + hp[be.col0 + c] + be.neighbour_rows;
      for (int r = 0; r < c; ++r) lane(A[c + be.dof * r]) = col[r];
      lane(A[c + be.dof * c]) = damped ? damp(col[c]) : col[c];
    }
  }

  // Block e's L^-1 alone; false, the thread's status set, when it is not positive definite.
  bool inverseFactor(std::size_t e, int t) {
    const auto& be = blocks[e];
    MatEE A(be.dof, be.dof);
    gatherBlock(e, A.data(), [](double& x) -> double& { return x; });
    if constexpr (DE == 6) {
      double full[36];
      if (inverseCholeskyFactor<6>(6, A.data(), full)) {
        packLower6([&](int idx) { return full[idx]; }, packedFactor(e));
        return true;
      }
    } else {
      ws.Linv[e].resize(be.dof, be.dof);
      if (inverseCholeskyFactor<0>(be.dof, A.data(), ws.Linv[e].data())) return true;
    }
    SolverStatus& st = status[static_cast<std::size_t>(t)];
    st.code = SolverStatus::Code::NotPositiveDefinite;
    st.failed_column = be.col0;
    st.message = "an eliminated block is not positive definite";
    return false;
  }

  // Every L^-1 of blocks e0..e1. Four 6x6 blocks at a time: the square
  // roots and divisions of one column are a serial chain per block, and the
  // lanes of the four (two SSE2 packets, or one AVX2 register) keep the
  // pipelines busy with independent ones.
  bool factorBlocks(int t, std::size_t e0, std::size_t e1) {
    std::size_t e = e0;
    if constexpr (DE == 6) {
      constexpr int kLanes = 4;
      using Lanes = Eigen::Array<double, kLanes, 1>;
      Lanes A4[36], Linv4[36];
      for (; e + kLanes <= e1; e += kLanes) {
        for (int k = 0; k < kLanes; ++k)
          gatherBlock(e + static_cast<std::size_t>(k), A4, [k](Lanes& x) -> double& { return x[k]; });
        static_assert(sizeof(Lanes) == kLanes * sizeof(double), "lanes of A4 and Linv4 are contiguous");
        const bool ok = solver.use_avx2_ ? detail::inverseCholeskySixAvx2(A4[0].data(), Linv4[0].data())
                                         : inverseCholeskyFactor<6>(6, A4, Linv4);
        if (ok) {
          for (int k = 0; k < kLanes; ++k)
            packLower6([&](int idx) { return Linv4[idx][k]; }, packedFactor(e + static_cast<std::size_t>(k)));
        } else {
          for (int k = 0; k < kLanes; ++k)  // which one is not positive definite, from the single-block path
            if (!inverseFactor(e + static_cast<std::size_t>(k), t)) return false;
        }
      }
    }
    for (; e < e1; ++e)
      if (!inverseFactor(e, t)) return false;
    return true;
  }

  // Blocks of other sizes: Eigen's products on Y_p = L^-1 B_p.
  void eliminateGeneral(std::size_t e, std::vector<MatER>& Y, double* sv, VecX& rh) {
    const auto& be = blocks[e];
    const std::size_t l0 = solver.link_begin_[e], l1 = solver.link_begin_[e + 1];
    const MatEE& Linv = ws.Linv[e];
    const VecE z = Linv * seg<DE>(b, be.col0, be.dof);
    for (std::size_t p = l0; p < l1; ++p) {
      const auto& bj = blocks[solver.ne_ + solver.links_[p].j];
      MatER& Yp = Y[p - l0];
      Yp.noalias() = Linv * couplingBlock(e, p);
      seg<DR>(rh, bj.col0 - solver.offset_, bj.dof).noalias() -= Yp.transpose() * z;
    }
    std::size_t pair = solver.pair_begin_[e];
    for (std::size_t p = l0; p < l1; ++p) {
      const auto& bi = blocks[solver.ne_ + solver.links_[p].j];
      for (std::size_t q = p; q < l1; ++q, ++pair) {
        const auto& bj = blocks[solver.ne_ + solver.links_[q].j];
        const MatRR M = Y[p - l0].transpose() * Y[q - l0];
        const Index so = solver.pair_offset_[pair];
        for (int c = 0; c < bj.dof; ++c) {
          double* col = sv + sp[bj.col0 - solver.offset_ + c] + so;
          const int rows = p == q ? c + 1 : bi.dof;
          for (int r = 0; r < rows; ++r) col[r] -= M(r, c);
        }
      }
    }
  }

  // Thread t's S values and rhs: the solver's own for thread 0 (C copied in,
  // damped; pairs coupled only through eliminated blocks start at zero), a
  // zeroed part for the others.
  std::pair<double*, VecX*> startPart(int t, VecX& rhs) {
    if (t > 0) {
      auto& part = solver.S_parts_[static_cast<std::size_t>(t - 1)];
      part.assign(solver.S_.values.size(), 0.0);
      VecX& rh = solver.rhs_parts_[static_cast<std::size_t>(t - 1)];
      rh.setZero(solver.S_.cols);
      return {part.data(), &rh};
    }
    double* sv = solver.S_.values.data();
    std::fill(solver.S_.values.begin(), solver.S_.values.end(), 0.0);
    for (const Copy& cp : solver.copies_) std::copy_n(hv + cp.h_pos, cp.count, sv + cp.s_pos);
    if (damped)  // S(j, j) ends column j, as H(j, j) does
      for (Index j = 0; j < solver.S_.cols; ++j) sv[sp[j + 1] - 1] = damp(sv[sp[j + 1] - 1]);
    return {sv, &rhs};
  }

  // Thread t's range of blocks: first every block's L^-1, then the products that use them.
  void eliminate(int t, VecX& rhs) {
    const auto [sv, rh] = startPart(t, rhs);
    auto& Y = ws.Y[static_cast<std::size_t>(t)];
    Y.resize(solver.max_links_);
    double* const y_rows = Y.empty() ? nullptr : Y.front().data();  // the AVX2 kernel's view (none without links)
    const detail::SixElimination six_at{hv, hp, sp, sv, rh->data(), solver.offset_, solver.reduced_col0_.data()};
    const auto [e0, e1] = detail::chunkRange(solver.ne_, T, t);
    if (!factorBlocks(t, e0, e1)) return;
    for (std::size_t e = e0; e < e1; ++e) {
      if constexpr (DE == 6 && DR == 6) {
        const std::size_t l0 = solver.link_begin_[e], l1 = solver.link_begin_[e + 1];
        const Vec6 z = lowerTimes6(packedFactor(e), b.data() + blocks[e].col0);
        static_assert(sizeof(MatER) == 36 * sizeof(double), "Y's 6x6 blocks are contiguous");
        if (solver.use_avx2_)  // Y_p by rows in the same workspace
          detail::eliminateSixAvx2(six_at, solver.links_.data() + l0, l1 - l0, packedFactor(e), z.data(),
                                   solver.pair_offset_.data() + solver.pair_begin_[e], y_rows);
        else
          solver.eliminateSix(e, packedFactor(e), z.data(), Y, sv, rh->data());
      } else {
        eliminateGeneral(e, Y, sv, *rh);
      }
    }
  }

  // x_e = L^-T L^-1 (b_e - sum_p B_p x_p) for every eliminated block.
  void backSubstitute(const VecX& xr, VecX& x) {
    detail::parallelRun(T, [&](int t) {
      const auto [e0, e1] = detail::chunkRange(solver.ne_, T, t);
      for (std::size_t e = e0; e < e1; ++e) {
        const auto& be = blocks[e];
        VecE u = seg<DE>(b, be.col0, be.dof);
        for (std::size_t p = solver.link_begin_[e]; p < solver.link_begin_[e + 1]; ++p) {
          const auto& bj = blocks[solver.ne_ + solver.links_[p].j];
          u.noalias() -= couplingBlock(e, p) * seg<DR>(xr, bj.col0 - solver.offset_, bj.dof);
        }
        if constexpr (DE == 6) {
          seg<6>(x, be.col0, 6) = lowerTransposeTimes6(packedFactor(e), lowerTimes6(packedFactor(e), u.data()));
        } else {
          const VecE v = ws.Linv[e] * u;
          seg<DE>(x, be.col0, be.dof).noalias() = ws.Linv[e].transpose() * v;
        }
      }
    });
  }
};

template <int DE, int DR>
SolverStatus SchurSolver::solveImpl(const VecX& b, VecX& x, const Damping& damping, double* xDx) {
  static_assert(DE != 6 || DR == 6, "6x6 eliminated blocks keep packed factors, which the general path does not read");
  // Each thread eliminates a range of blocks into its own S and rhs (S is
  // small: the reduced system); they are summed afterwards. The parts and the
  // per-block workspace are kept between solves: no allocation per iteration.
  Pass<DE, DR> pass{*this, b, damping, detail::threadsFor(threads_, ne_, 2048)};
  const int T = pass.T;
  S_parts_.resize(static_cast<std::size_t>(T - 1));
  rhs_parts_.resize(static_cast<std::size_t>(T - 1));
  if constexpr (DE == 6)
    pass.ws.packed.resize(21 * ne_);
  else
    pass.ws.Linv.resize(ne_);
  pass.ws.Y.resize(static_cast<std::size_t>(T));
  VecX rhs = b.tail(S_.cols);
  detail::parallelRun(T, [&](int t) { pass.eliminate(t, rhs); });
  for (const SolverStatus& st : pass.status)
    if (!st.ok()) return st;
  for (int u = 1; u < T; ++u) {
    const std::vector<double>& part = S_parts_[static_cast<std::size_t>(u - 1)];
    for (std::size_t i = 0; i < part.size(); ++i) S_.values[i] += part[i];
    rhs += rhs_parts_[static_cast<std::size_t>(u - 1)];
  }

  VecX xr(S_.cols);
  const SolverStatus st = solveReduced(rhs, xr);
  if (!st.ok()) return st;
  x.resize(sys_.numColumns());
  x.tail(S_.cols) = xr;
  pass.backSubstitute(xr, x);
  if (xDx) {  // H is untouched: D from its diagonal again
    double sum = 0.0;
    for (Index j = 0; j < x.size(); ++j)
      sum += pass.clampDiagonal(pass.hv[sys_.hessianDiagonalPosition(j)]) * x[j] * x[j];
    *xDx = sum;
  }
  return st;
}

// S xr = rhs, densely or by CHOLMOD (its symbolic analysis once); a failed
// column is named in H's numbering.
SolverStatus SchurSolver::solveReduced(const VecX& rhs, VecX& xr) {
  SolverStatus st;
  if (S_.cols == 0) return st;
  if (dense_) {
    st = dense_->factorize(S_);
  } else {
    if (!cholesky_->analyzed()) {
      st = cholesky_->analyze(S_);
      if (!st.ok()) return st;
    }
    st = cholesky_->factorize(S_);
  }
  if (!st.ok()) {
    if (st.failed_column >= 0) st.failed_column += offset_;
    return st;
  }
  return dense_ ? dense_->solve(rhs, xr) : cholesky_->solve(rhs, xr);
}

}  // namespace fgcal
