// The Schur complement solver against dense solves: calibration-shaped and
// mixed-size systems, damping, the statuses naming the failed variable, the
// AVX2 and baseline kernels, and whole optimizations against plain CHOLMOD.
#include <random>

#include "fgcal/core/internal/schur_solver.hpp"
#include "fgcal/core/internal/sparse_cholesky.hpp"
#include "fgcal/core/internal/linear_system.hpp"
#include "fgcal/core/optimizer.hpp"
#include "fgcal_test/jacobian_check.hpp"
#include "linear_problems.hpp"

using namespace fgcal;
using namespace fgcal::test;

TEST_CASE("the Schur complement solve equals the dense solve on a calibration-shaped system") {
  for (int cameras : {1, 3, 5}) {
    const ArrowProblem p = makeArrowProblem(cameras, 40, 17 + cameras);
    LinearSystem sys(p.graph, p.values, {}, /*order_for_schur=*/true);
    REQUIRE(sys.numEliminatedBlocks() == 40);  // every board pose
    CHECK(sys.columnOf(key('b', 0)) < sys.columnOf(key('c', 0)));
    sys.linearize(p.values);
    sys.formNormalEquations();
    const VecX x_dense = dampAndSolveDense(sys, 1.3);
    const VecX b = -sys.gradient();

    using RS = SchurSolver::ReducedSolve;
    using K = SchurSolver::Kernel;
    for (RS mode : {RS::Auto, RS::Dense, RS::Sparse})
    for (K kernel : {K::Auto, K::Baseline}) {
      INFO("cameras " << cameras << ", reduced solve " << static_cast<int>(mode) << ", kernel "
                      << static_cast<int>(kernel));
      SchurSolver schur(sys, 1, mode, kernel);
      CHECK(schur.usesAvx2() == (kernel == K::Auto && cpuHasAvx2Fma()));
      CHECK(schur.reducedSize() == 6 * (cameras + 1));
      CHECK(schur.reducedIsDense() == (mode != RS::Sparse));  // Auto: a small reduced system is dense
      VecX x;
      REQUIRE(schur.solve(b, x).ok());
      CHECK((x - x_dense).norm() <= 1e-8 * (1.0 + x_dense.norm()));
      REQUIRE(schur.solve(2.0 * b, x).ok());  // again: the sparse analysis is reused
      CHECK((x - 2.0 * x_dense).norm() <= 1e-8 * (1.0 + x_dense.norm()));
      CHECK(schur.analysisCount() == (mode == RS::Sparse ? 1 : 0));
    }
  }
}

TEST_CASE("the Schur solve names the reduced variable that is not positive definite, dense or sparse") {
  using RS = SchurSolver::ReducedSolve;
  for (RS mode : {RS::Dense, RS::Sparse}) {
    INFO("reduced solve " << static_cast<int>(mode));
    {  // a negative pivot in camera 1's fourth column
      const ArrowProblem p = makeArrowProblem(3, 12, 29);
      LinearSystem sys(p.graph, p.values, {}, /*order_for_schur=*/true);
      sys.linearize(p.values);
      const auto col = sys.columnOf(key('c', 1));
      REQUIRE(col >= sys.numEliminatedColumns());
      sys.hessianUpper().values[sys.hessianDiagonalPosition(col + 3)] = -1e6;
      SchurSolver schur(sys, 1, mode);
      VecX x;
      const SolverStatus st = schur.solve(-sys.gradient(), x);
      CHECK(st.code == SolverStatus::Code::NotPositiveDefinite);
      CHECK(st.failed_column == col + 3);
      CHECK(sys.keyOfColumn(st.failed_column) == key('c', 1));
    }
    {  // two poses tied only to each other: after eliminating one, the other's
       // reduced block is zero up to rounding (a gauge freedom)
      ArrowProblem p = makeArrowProblem(2, 12, 31);
      p.values.insert(key('u', 0), SE3::exp(Vec6::Constant(0.1)));
      p.values.insert(key('u', 1), SE3::exp(Vec6::Constant(0.2)));
      p.graph.emplace<RelativePoseFactor>(key('u', 0), key('u', 1), SE3::exp(Vec6::Constant(0.15)),
                                          NoiseModel::isotropic(6, 0.1));
      LinearSystem sys(p.graph, p.values, {}, /*order_for_schur=*/true);
      sys.linearize(p.values);
      const bool u0_eliminated = sys.columnOf(key('u', 0)) < sys.numEliminatedColumns();
      REQUIRE(u0_eliminated != (sys.columnOf(key('u', 1)) < sys.numEliminatedColumns()));
      SchurSolver schur(sys, 1, mode);
      VecX x;
      const SolverStatus st = schur.solve(-sys.gradient(), x);
      CHECK(st.code == SolverStatus::Code::NotPositiveDefinite);
      REQUIRE(st.failed_column >= 0);
      CHECK(sys.keyOfColumn(st.failed_column) == key('u', u0_eliminated ? 1 : 0));
    }
  }
  {  // Dense: a positive pivot at 1e-13 of its diagonal entry is singular, as in SparseCholesky.
    const ArrowProblem p = makeArrowProblem(3, 12, 37);
    LinearSystem sys(p.graph, p.values, {}, /*order_for_schur=*/true);
    sys.linearize(p.values);
    const auto ne = sys.numEliminatedColumns(), n = sys.numColumns(), j = n - 1;
    auto reduced = [&] {  // S = C - B^T A^-1 B, densely
      const MatX H = MatX(MatX(sys.hessianUpper().eigen()).selfadjointView<Eigen::Upper>());
      const MatX A = H.topLeftCorner(ne, ne), B = H.topRightCorner(ne, n - ne);
      return MatX(H.bottomRightCorner(n - ne, n - ne) - B.transpose() * A.llt().solve(B));
    };
    // The last pivot of S is S(j, j) minus a part that does not depend on H(j, j):
    // move H(j, j) by delta so that the pivot becomes eps times the new S(j, j).
    const MatX S = reduced();
    const double last = S.llt().matrixL()(n - ne - 1, n - ne - 1), p0 = last * last, sjj = S(n - ne - 1, n - ne - 1);
    const double eps = 1e-13, delta = (eps * sjj - p0) / (1.0 - eps);
    sys.hessianUpper().values[sys.hessianDiagonalPosition(j)] += delta;
    SchurSolver schur(sys, 1, SchurSolver::ReducedSolve::Dense);
    VecX x;
    const SolverStatus st = schur.solve(-sys.gradient(), x);
    CHECK(st.code == SolverStatus::Code::NotPositiveDefinite);
    CHECK(st.failed_column == j);
    CHECK(st.message.find("singular") != std::string::npos);
  }
}

TEST_CASE("Auto factors a large, sparse reduced system with CHOLMOD, a small full one densely") {
  // Eight cameras, each seeing only its own five board poses: the reduced
  // system (48 columns) is block diagonal, far from full.
  SeededNoise noise(53);
  FactorGraph g;
  Values v;
  for (int c = 0; c < 8; ++c) {
    const SE3 cam = SE3::exp(noise(1.0));
    v.insert(key('c', c), cam.plus(noise(0.05)));
    for (int i = 0; i < 5; ++i) {
      const int b = 5 * c + i;
      const SE3 board = SE3::exp(noise(1.0));
      v.insert(key('b', b), board.plus(noise(0.05)));
      g.emplace<PriorFactorSE3>(key('b', b), board.plus(noise(0.01)), NoiseModel::isotropic(6, 0.01));
      g.emplace<RelativePoseFactor>(key('c', c), key('b', b), cam.between(board).plus(noise(0.01)),
                                    NoiseModel::isotropic(6, 0.01));
    }
  }
  LinearSystem sys(g, v, {}, /*order_for_schur=*/true);
  REQUIRE(sys.numEliminatedBlocks() == 40);
  sys.linearize(v);
  const VecX x_dense = dampAndSolveDense(sys, 1.1);
  using RS = SchurSolver::ReducedSolve;
  SchurSolver automatic(sys), dense(sys, 1, RS::Dense);
  CHECK(automatic.reducedSize() == 48);
  CHECK_FALSE(automatic.reducedIsDense());
  VecX xa, xd;
  REQUIRE(automatic.solve(-sys.gradient(), xa).ok());
  REQUIRE(dense.solve(-sys.gradient(), xd).ok());
  CHECK((xa - x_dense).norm() <= 1e-8 * (1.0 + x_dense.norm()));
  CHECK((xd - x_dense).norm() <= 1e-8 * (1.0 + x_dense.norm()));
  CHECK(automatic.analysisCount() == 1);

  // A NaN in the reduced system is refused by the dense path, naming its column.
  const auto col = sys.columnOf(key('c', 3));
  sys.hessianUpper().values[sys.hessianDiagonalPosition(col + 1)] = std::nan("");
  const SolverStatus st = dense.solve(-sys.gradient(), xd);
  CHECK_FALSE(st.ok());
  CHECK(st.failed_column == col + 1);
  CHECK(st.message.find("NaN") != std::string::npos);
}

TEST_CASE("the Schur solve names the eliminated block that is not positive definite") {
  // 41 board poses: the 6x6 blocks are factored four at a time and the last
  // alone; a bad block is found in the first, second and fourth lane of a
  // group and as the last.
  const ArrowProblem p = makeArrowProblem(2, 41, 23);
  for (int bad : {4, 5, 7, 40}) {
    INFO("board " << bad);
    LinearSystem sys(p.graph, p.values, {}, /*order_for_schur=*/true);
    REQUIRE(sys.numEliminatedBlocks() == 41);
    sys.linearize(p.values);
    const auto col = sys.columnOf(key('b', bad));
    REQUIRE(col >= 0);
    sys.hessianUpper().values[sys.hessianDiagonalPosition(col + 2)] = -1.0;
    for (auto kernel : {SchurSolver::Kernel::Auto, SchurSolver::Kernel::Baseline}) {
      SchurSolver schur(sys, 1, SchurSolver::ReducedSolve::Auto, kernel);
      VecX x;
      const SolverStatus st = schur.solve(-sys.gradient(), x);
      CHECK(st.code == SolverStatus::Code::NotPositiveDefinite);
      CHECK(st.failed_column == col);
      CHECK(sys.keyOfColumn(st.failed_column) == key('b', bad));
    }
  }
}

TEST_CASE("an eliminated block's rounding-level pivot is refused by the pivot rule every path shares") {
  // A board pose's block whose last pivot is 1e-13 of its diagonal entry:
  // positive, yet singular by kSingularPivotRatio, in a lane of a four-block
  // group and alone, on both kernels, as DenseCholesky and CHOLMOD judge it.
  const ArrowProblem p = makeArrowProblem(2, 41, 29);
  for (int bad : {5, 40}) {
    INFO("board " << bad);
    LinearSystem sys(p.graph, p.values, {}, /*order_for_schur=*/true);
    sys.linearize(p.values);
    const auto col = sys.columnOf(key('b', bad));
    REQUIRE(col >= 0);
    REQUIRE(col < sys.numEliminatedColumns());
    const MatX H = MatX(MatX(sys.hessianUpper().eigen()).selfadjointView<Eigen::Upper>());
    const Mat6 A = H.block<6, 6>(col, col);
    const double l = Mat6(A.llt().matrixL())(5, 5), eps = 1e-13;
    const double delta = (eps * A(5, 5) - l * l) / (1.0 - eps);  // last pivot = eps (A55 + delta)
    sys.hessianUpper().values[sys.hessianDiagonalPosition(col + 5)] += delta;
    for (auto kernel : {SchurSolver::Kernel::Auto, SchurSolver::Kernel::Baseline}) {
      SchurSolver schur(sys, 1, SchurSolver::ReducedSolve::Auto, kernel);
      VecX x;
      const SolverStatus st = schur.solve(-sys.gradient(), x);
      CHECK(st.code == SolverStatus::Code::NotPositiveDefinite);
      CHECK(sys.keyOfColumn(st.failed_column) == key('b', bad));
    }
  }
}

TEST_CASE("the Schur solve with eliminated blocks of 3 and 6 dof equals the dense solve") {
  const ArrowProblem p = makeMixedProblem(3, 30, 41);
  for (std::size_t f = 0; f < p.graph.size(); ++f) {
    const auto bad = checkFactorJacobians(p.graph[f], p.values);
    INFO("factor " << f);
    CHECK(bad.empty());
  }
  LinearSystem sys(p.graph, p.values, {}, /*order_for_schur=*/true);
  REQUIRE(sys.numEliminatedBlocks() == 33);  // the points and the board poses
  REQUIRE(sys.numEliminatedColumns() == 30 * 3 + 3 * 6);
  sys.linearize(p.values);
  const VecX x_dense = dampAndSolveDense(sys, 1.2);
  const VecX b = -sys.gradient();
  SchurSolver schur(sys);
  CHECK(schur.reducedSize() == 18);
  VecX x;
  REQUIRE(schur.solve(b, x).ok());
  CHECK((x - x_dense).norm() <= 1e-8 * (1.0 + x_dense.norm()));
  REQUIRE(schur.solve(-b, x).ok());
  CHECK((x + x_dense).norm() <= 1e-8 * (1.0 + x_dense.norm()));

  // A point block that is not positive definite is named.
  const auto col = sys.columnOf(key('p', 7));
  REQUIRE(col >= 0);
  sys.hessianUpper().values[sys.hessianDiagonalPosition(col + 1)] = -1.0;
  const SolverStatus st = schur.solve(b, x);
  CHECK(st.code == SolverStatus::Code::NotPositiveDefinite);
  CHECK(st.failed_column == col);
  CHECK(sys.keyOfColumn(st.failed_column) == key('p', 7));

  // And the optimizer converges through this path to Cholesky's optimum.
  OptimizerOptions a, c;
  a.linear_solver = OptimizerOptions::LinearSolver::SchurComplement;
  c.linear_solver = OptimizerOptions::LinearSolver::SparseCholesky;
  a.relative_cost_tolerance = c.relative_cost_tolerance = 1e-14;
  const OptimizerResult ra = optimize(p.graph, p.values, a), rc = optimize(p.graph, p.values, c);
  REQUIRE(ra.converged);
  REQUIRE(rc.converged);
  CHECK(ra.linear_solver.find("Schur") != std::string::npos);
  CHECK(ra.final_cost == Approx(rc.final_cost).epsilon(1e-9));
  for (int i = 0; i < 30; i += 7) CHECK((ra.values.at<Vec3>(key('p', i)) - rc.values.at<Vec3>(key('p', i))).norm() < 1e-7);
}

TEST_CASE("optimizing with Schur and with plain sparse Cholesky gives the same estimate") {
  const ArrowProblem p = makeArrowProblem(4, 60, 99);
  OptimizerOptions a, b;
  a.linear_solver = OptimizerOptions::LinearSolver::SchurComplement;
  b.linear_solver = OptimizerOptions::LinearSolver::SparseCholesky;
  a.relative_cost_tolerance = b.relative_cost_tolerance = 1e-14;
  const OptimizerResult ra = optimize(p.graph, p.values, a), rb = optimize(p.graph, p.values, b);
  INFO(ra.linear_solver << " / " << rb.linear_solver);
  CHECK(ra.linear_solver.find("Schur") != std::string::npos);
  CHECK(rb.linear_solver.find("Cholesky") != std::string::npos);
  REQUIRE(ra.converged);
  REQUIRE(rb.converged);
  CHECK(ra.final_cost == Approx(rb.final_cost).epsilon(1e-9));
  for (Key k : p.values.keys()) CHECK(ra.values.at<SE3>(k).minus(rb.values.at<SE3>(k)).norm() < 1e-7);
  // Auto picks Schur on this shape.
  CHECK(optimize(p.graph, p.values).linear_solver.find("Schur") != std::string::npos);
}

TEST_CASE("the Schur solve damps the diagonal it reads as the optimizer damped H, and returns x^T D x") {
  // 61 board poses (a remainder after groups of four); points: the general path.
  for (int problem = 0; problem < 2; ++problem) {
    const bool six = problem == 0;
    INFO((six ? "6x6 blocks" : "points (3 dof) too: the general path"));
    const ArrowProblem q = six ? makeArrowProblem(3, 61, 31) : makeMixedProblem(3, 30, 41);
    LinearSystem sys(q.graph, q.values, {}, /*order_for_schur=*/true);
    sys.linearize(q.values);
    const VecX b = -sys.gradient();
    const std::vector<double> H0 = sys.hessianUpper().values;
    MatX H = MatX(MatX(sys.hessianUpper().eigen()).selfadjointView<Eigen::Upper>());
    // A clamp inside the range of H's diagonal: some entries below it, some above.
    const double lo = H.diagonal().minCoeff(), hi = H.diagonal().maxCoeff();
    SchurSolver::Damping damping;
    damping.lambda = 0.7;
    damping.min_diagonal = lo + 0.25 * (hi - lo);
    damping.max_diagonal = lo + 0.75 * (hi - lo);
    // Dense reference: H + lambda D, D = clamp(diag H).
    VecX D = H.diagonal().cwiseMax(damping.min_diagonal).cwiseMin(damping.max_diagonal);
    REQUIRE((H.diagonal().array() < damping.min_diagonal).any());
    REQUIRE((H.diagonal().array() > damping.max_diagonal).any());
    H.diagonal() += damping.lambda * D;
    const VecX x_dense = H.llt().solve(b);
    for (auto kernel : {SchurSolver::Kernel::Auto, SchurSolver::Kernel::Baseline})
      for (int threads : {1, 2}) {  // (too few blocks to share: one thread runs)
        SchurSolver schur(sys, threads, SchurSolver::ReducedSolve::Auto, kernel);
        VecX x;
        double xDx = -1.0;
        REQUIRE(schur.solve(b, x, damping, &xDx).ok());
        CHECK((x - x_dense).norm() <= 1e-9 * (1.0 + x_dense.norm()));
        CHECK(xDx == Approx(x.dot(D.cwiseProduct(x))).epsilon(1e-12));
        CHECK(sys.hessianUpper().values == H0);  // H itself untouched
        // lambda 0 with x^T D x asked for: the plain solve's bits.
        VecX x0, x1;
        REQUIRE(schur.solve(b, x0).ok());
        SchurSolver::Damping none = damping;
        none.lambda = 0.0;
        REQUIRE(schur.solve(b, x1, none, &xDx).ok());
        CHECK(x0 == x1);
        CHECK(xDx == Approx(x1.dot(D.cwiseProduct(x1))).epsilon(1e-12));
      }
    SchurSolver schur(sys);
    VecX x;
    for (double lambda : {-1.0, std::numeric_limits<double>::infinity(), std::numeric_limits<double>::quiet_NaN()}) {
      SchurSolver::Damping bad;
      bad.lambda = lambda;
      CHECK_THROWS_WITH(schur.solve(b, x, bad), Catch::Contains("lambda"));
    }
    SchurSolver::Damping bad;
    bad.min_diagonal = -1.0;
    CHECK_THROWS_WITH(schur.solve(b, x, bad), Catch::Contains("min_diagonal -1"));
    bad.min_diagonal = 2.0;
    bad.max_diagonal = 1.0;
    CHECK_THROWS_AS(schur.solve(b, x, bad), std::invalid_argument);
  }
  // 4101 board poses: two threads eliminate (from 4096 blocks), each with a
  // remainder after its groups of four; damped, against one thread.
  {
    const ArrowProblem q = makeArrowProblem(3, 4101, 37);
    LinearSystem sys(q.graph, q.values, {}, /*order_for_schur=*/true);
    sys.linearize(q.values);
    const VecX b = -sys.gradient();
    SchurSolver::Damping damping;
    damping.lambda = 0.3;
    for (auto kernel : {SchurSolver::Kernel::Auto, SchurSolver::Kernel::Baseline}) {
      SchurSolver one(sys, 1, SchurSolver::ReducedSolve::Auto, kernel),
          two(sys, 2, SchurSolver::ReducedSolve::Auto, kernel);
      VecX x1, x2, x_undamped;
      double d1 = 0.0, d2 = 0.0;
      REQUIRE(one.solve(b, x1, damping, &d1).ok());
      REQUIRE(two.solve(b, x2, damping, &d2).ok());
      REQUIRE(one.solve(b, x_undamped).ok());
      CHECK((x1 - x2).norm() <= 1e-10 * x1.norm());
      CHECK(d2 == Approx(d1).epsilon(1e-10));
      CHECK((x1 - x_undamped).norm() > 1e-3 * x1.norm());  // the damping took effect
    }
  }
  // A damped block that is not positive definite in a group of four is named (4-lane fallback).
  const ArrowProblem p = makeArrowProblem(2, 41, 23);
  LinearSystem sys(p.graph, p.values, {}, /*order_for_schur=*/true);
  sys.linearize(p.values);
  const auto col = sys.columnOf(key('b', 5));
  sys.hessianUpper().values[sys.hessianDiagonalPosition(col + 2)] = -1e9;  // lambda D cannot lift it
  SchurSolver::Damping damping;
  damping.lambda = 0.5;
  for (auto kernel : {SchurSolver::Kernel::Auto, SchurSolver::Kernel::Baseline}) {
    SchurSolver schur(sys, 1, SchurSolver::ReducedSolve::Auto, kernel);
    VecX x;
    const SolverStatus st = schur.solve(-sys.gradient(), x, damping);
    CHECK(st.code == SolverStatus::Code::NotPositiveDefinite);
    CHECK(st.failed_column == col);
  }
}

TEST_CASE("the AVX2 and the baseline elimination give the same step, one thread or two") {
  // Boards seen by several cameras (several links per eliminated block: the
  // pairs of S's blocks), and more boards than one thread takes.
  const ArrowProblem p = makeArrowProblem(4, 4200, 23);  // two threads from 4096 eliminated blocks
  LinearSystemOptions o;
  o.order_for_schur = true;
  o.store_jacobian = false;
  o.threads = 2;
  LinearSystem sys(p.graph, p.values, {}, o);
  sys.linearize(p.values);
  const VecX b = -sys.gradient();
  using K = SchurSolver::Kernel;
  if (!cpuHasAvx2Fma()) WARN("this CPU has no AVX2 and FMA: the AVX2 kernels are not exercised");
  SchurSolver base(sys, 1, SchurSolver::ReducedSolve::Auto, K::Baseline);
  REQUIRE_FALSE(base.usesAvx2());
  VecX x_base;
  REQUIRE(base.solve(b, x_base).ok());
  for (int threads : {1, 2}) {
    INFO(threads << " thread(s)");
    SchurSolver fast(sys, threads);
    CHECK(fast.usesAvx2() == cpuHasAvx2Fma());
    VecX x;
    REQUIRE(fast.solve(b, x).ok());
    CHECK((x - x_base).norm() <= 1e-9 * (1.0 + x_base.norm()));
    REQUIRE(fast.solve(b, x).ok());  // the workspaces are reused
    CHECK((x - x_base).norm() <= 1e-9 * (1.0 + x_base.norm()));
  }
}
