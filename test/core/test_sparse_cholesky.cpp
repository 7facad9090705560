// SparseCholesky (CHOLMOD) against dense LLT on seeded random block-sparse SPD
// systems, and the status naming the column where it breaks down.
#include <random>

#include "fgcal/core/internal/sparse_cholesky.hpp"
#include "fgcal/core/internal/linear_system.hpp"
#include "fgcal/core/optimizer.hpp"
#include "fgcal_test/jacobian_check.hpp"
#include "linear_problems.hpp"

using namespace fgcal;
using namespace fgcal::test;

TEST_CASE("sparse Cholesky solve equals dense LLT on random block-sparse SPD systems") {
  std::mt19937 gen(2024);
  for (int trial = 0; trial < 20; ++trial) {
    const int nb = 3 + trial * 2, bs = 1 + trial % 6;
    const MatX A = randomBlockSparseSpd(nb, bs, 0.15, gen);
    VecX b(A.rows());
    for (Eigen::Index i = 0; i < b.size(); ++i) b[i] = std::normal_distribution<double>()(gen);
    const VecX x_dense = A.llt().solve(b);

    SparseCholesky chol;
    const CscMatrix U = upperFromDense(A);
    REQUIRE(chol.analyze(U).ok());
    REQUIRE(chol.factorize(U).ok());
    VecX x;
    REQUIRE(chol.solve(b, x).ok());
    INFO("trial " << trial << " n=" << A.rows() << " ordering " << chol.ordering());
    CHECK((x - x_dense).norm() <= 1e-9 * (1.0 + x_dense.norm()));

    // New values, same pattern: numeric factorization only, no new analysis.
    const MatX A2 = A + MatX::Identity(A.rows(), A.cols());
    const CscMatrix U2 = upperFromDense(A2);
    REQUIRE(U2.rowind == U.rowind);
    REQUIRE(chol.factorize(U2).ok());
    REQUIRE(chol.solve(b, x).ok());
    CHECK((x - A2.llt().solve(b)).norm() <= 1e-9 * (1.0 + x.norm()));
    CHECK(chol.analysisCount() == 1);
  }
}

TEST_CASE("a matrix that is not positive definite returns a status naming the column") {
  MatX A = MatX::Identity(6, 6) * 2.0;
  A(4, 4) = -1.0;
  SparseCholesky chol;
  const CscMatrix U = upperFromDense(A);
  REQUIRE(chol.analyze(U).ok());
  const SolverStatus st = chol.factorize(U);
  CHECK(st.code == SolverStatus::Code::NotPositiveDefinite);
  CHECK(st.failed_column == 4);
  VecX x;
  CHECK_FALSE(chol.solve(VecX::Ones(6), x).ok());  // no crash after a failed factorization

  // Positive semi-definite with a rank deficiency (an exactly zero pivot,
  // which CHOLMOD rejects), and the same up to 1e-14 on the second block's
  // diagonal (every pivot positive: the pivot ratio names it singular).
  for (double eps : {0.0, 1e-14}) {
    INFO("eps " << eps);
    MatX B = MatX::Zero(6, 6);
    B.topLeftCorner(3, 3) = MatX::Identity(3, 3);
    B.bottomRightCorner(3, 3) = (1.0 + eps) * MatX::Identity(3, 3);
    B.block(0, 3, 3, 3) = MatX::Identity(3, 3);
    B.block(3, 0, 3, 3) = MatX::Identity(3, 3);
    const CscMatrix UB = upperFromDense(B);
    SparseCholesky chol2;
    REQUIRE(chol2.analyze(UB).ok());
    const SolverStatus sb = chol2.factorize(UB);
    CHECK(sb.code == SolverStatus::Code::NotPositiveDefinite);
    CHECK(sb.failed_column >= 0);
    if (eps > 0.0) CHECK(sb.message.find("singular") != std::string::npos);
  }
}
