// Sparse Cholesky of a symmetric positive definite matrix given by its upper
// triangle, over CHOLMOD. The symbolic analysis (fill-reducing ordering: AMD,
// or METIS where CHOLMOD finds it better) is done once per sparsity pattern;
// each numeric factorization reuses it. CHOLMOD stays behind this interface.
#pragma once

#include <memory>
#include <string>

#include "fgcal/core/internal/sparse_matrix.hpp"
#include "fgcal/core/types.hpp"

namespace fgcal {

struct SolverStatus {
  enum class Code { Success, NotPositiveDefinite, Failed };
  Code code = Code::Success;
  /// Column of the input matrix where the factorization broke down (NotPositiveDefinite), else -1.
  CscMatrix::Index failed_column = -1;
  std::string message;
  bool ok() const { return code == Code::Success; }
};

class SparseCholesky {
 public:
  SparseCholesky();
  ~SparseCholesky();
  SparseCholesky(const SparseCholesky&) = delete;
  SparseCholesky& operator=(const SparseCholesky&) = delete;

  /// Symbolic analysis of the pattern of `upper` (square, upper triangle, sorted).
  SolverStatus analyze(const CscMatrix& upper);
  /// Numeric factorization; the pattern must be the analyzed one.
  SolverStatus factorize(const CscMatrix& upper);
  /// x = A^-1 b with the last factorization.
  SolverStatus solve(const VecX& b, VecX& x) const;
  /// X = A^-1 B for several right-hand sides at once.
  SolverStatus solve(const MatX& B, MatX& X) const;

  bool analyzed() const;
  bool factorized() const;
  /// Nonzeros of the factor L, and the ordering CHOLMOD chose ("AMD", "METIS", ...).
  double factorNonZeros() const;
  std::string ordering() const;
  /// How many symbolic analyses ran (tests check it stays 1 across iterations).
  int analysisCount() const;

 private:
  SolverStatus solveRaw(const double* B, long rows, long cols, double* X) const;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace fgcal
