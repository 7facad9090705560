// Solves the normal equations H x = b by eliminating an independent set of
// small variables first (the Schur complement): with H = [[A B] [B^T C]] and A
// block diagonal (LinearSystem with order_for_schur), the reduced system
// S = C - B^T A^-1 B is assembled block by block into a compressed-column
// upper triangle whose pattern is computed once, factorized densely when it
// is small and nearly full (a calibration's camera block) or else by CHOLMOD
// (symbolic analysis once), and the eliminated variables are recovered by
// back-substitution. On a calibration graph (N board poses, a few cameras)
// each iteration is then linear in N with a tiny factorization.
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Core>

#include "fgcal/core/internal/linear_system.hpp"
#include "fgcal/core/internal/sparse_cholesky.hpp"

namespace fgcal {

namespace detail {
class DenseCholesky;
struct SchurLink;  // eliminated block e -- reduced block j (schur_six_avx2.hpp)
}

class SchurSolver {
 public:
  /// How the reduced system is factored. Auto: densely when it has at most
  /// kDenseMaxColumns columns and its upper triangle is at least half full
  /// (or it has at most 32 columns), else sparse (CHOLMOD).
  enum class ReducedSolve { Auto, Dense, Sparse };
  static constexpr int kDenseMaxColumns = 512;
  /// The elimination of 6x6 blocks: Auto runs a kernel for AVX2 and FMA when
  /// the CPU has them (x86-64), Baseline the one for the instruction set the
  /// library was built for. They differ in rounding only.
  enum class Kernel { Auto, Baseline };

  /// Keeps a reference to `system` (its structure must not change). `threads`
  /// eliminate blocks in parallel on large systems.
  explicit SchurSolver(const LinearSystem& system, int threads = 1, ReducedSolve reduced = ReducedSolve::Auto,
                       Kernel kernel = Kernel::Auto);
  ~SchurSolver();
  SchurSolver(const SchurSolver&) = delete;
  SchurSolver& operator=(const SchurSolver&) = delete;

  /// x = H^-1 b for the H currently in the system (undamped; see the
  /// overload below for Levenberg-Marquardt's damping).
  /// NotPositiveDefinite names a column of H when an eliminated block or the
  /// reduced system is not positive definite.
  SolverStatus solve(const VecX& b, VecX& x);
  /// Levenberg-Marquardt damping added while the blocks are read, H itself
  /// untouched: (H + lambda D) x = b with D = diag(clamp(H_jj, min_diagonal,
  /// max_diagonal)). The defaults are OptimizerOptions' (lambda 0: none).
  struct Damping {
    double lambda = 0.0;
    double min_diagonal = 1e-6;
    double max_diagonal = 1e32;
  };
  /// x = (H + lambda D)^-1 b; when `xDx` is not null, also sum_j D_jj x_j^2
  /// (one more pass over H's diagonal). Throws std::invalid_argument unless
  /// lambda is finite and >= 0 and 0 <= min_diagonal <= max_diagonal.
  SolverStatus solve(const VecX& b, VecX& x, const Damping& damping, double* xDx = nullptr);

  /// Columns of the reduced system, whether it is factored densely, and how
  /// many sparse symbolic analyses ran (0 on the dense path).
  CscMatrix::Index reducedSize() const { return S_.cols; }
  bool reducedIsDense() const { return dense_ != nullptr; }
  int analysisCount() const { return cholesky_ ? cholesky_->analysisCount() : 0; }
  /// Whether 6x6 blocks are eliminated with AVX2 and FMA.
  bool usesAvx2() const { return use_avx2_; }

 private:
  // The structure, computed once by the constructor in these steps.
  struct ReducedPattern;
  void linkEliminatedBlocks();
  ReducedPattern reducedPattern() const;
  void layOutReducedSystem(const ReducedPattern& pattern);
  void pairOffsets(const ReducedPattern& pattern);
  void copiesOfC(const ReducedPattern& pattern);

  template <int DE, int DR>
  struct Pass;  // one solve's state and steps
  template <int DE, int DR>
  SolverStatus solveImpl(const VecX& b, VecX& x, const Damping& damping, double* xDx);
  SolverStatus solveReduced(const VecX& rhs, VecX& xr);
  // Eliminates block e when it and its neighbours are all 6x6: rhs and S
  // (of the calling thread) updated from L^-1 (Linv, packed by rows) and z = L^-1 b_e, with
  // Y as the per-link workspace.
  void eliminateSix(std::size_t e, const double* Linv, const double* z, std::vector<Eigen::Matrix<double, 6, 6>>& Y,
                    double* sv, double* rhs) const;
  template <int DE, int DR>
  struct Workspace {
    std::vector<Eigen::Matrix<double, DE, DE>> Linv;  // inverse Cholesky factor per eliminated block (general path)
    std::vector<double> packed;                        // 6x6 path: L^-1 per block, lower triangle packed by rows (21)
    std::vector<std::vector<Eigen::Matrix<double, DE, DR>>> Y;  // per thread: L^-1 B of the block at hand (transposed in eliminateSix)
  };
  template <int DE, int DR>
  Workspace<DE, DR>& workspace() {
    if constexpr (DE == 6) return ws6_;
    else return wsx_;
  }
  Workspace<6, 6> ws6_;
  Workspace<Eigen::Dynamic, Eigen::Dynamic> wsx_;

  const LinearSystem& sys_;
  std::size_t ne_;           // eliminated blocks: 0 .. ne_-1
  CscMatrix::Index offset_;  // columns of H before the reduced system
  CscMatrix S_;
  std::vector<detail::SchurLink> links_;      // grouped by e, ascending j
  std::vector<CscMatrix::Index> reduced_col0_; // per reduced block j: its first column of H
  std::vector<std::size_t> link_begin_;       // per e, ne_ + 1 entries
  std::size_t max_links_ = 0;                 // the most links of one eliminated block
  std::vector<CscMatrix::Index> pair_offset_; // per e, per link pair p <= q: offset of block (j_p, j_q) in S
  std::vector<std::size_t> pair_begin_;       // per e
  struct Copy {                // one entry run of C copied from H into S
    CscMatrix::Index h_pos, s_pos;
    int count;
  };
  std::vector<Copy> copies_;
  bool all_blocks_six_ = false;
  bool use_avx2_ = false;
  std::unique_ptr<SparseCholesky> cholesky_;        // the sparse reduced path, or
  std::unique_ptr<detail::DenseCholesky> dense_;  // the dense one
  std::vector<std::vector<double>> S_parts_;  // per extra thread: its S values
  std::vector<VecX> rhs_parts_;               // and its reduced right-hand side
  int threads_ = 1;
};

}  // namespace fgcal
