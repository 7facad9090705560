// The sparse machinery: CHOLMOD solve against dense LLT on seeded random
// block-sparse SPD systems, the not-positive-definite status, and the
// linearizer's J / H / g against a dense assembly from the factors.
#include <map>
#include <random>

#include <Eigen/Cholesky>

#include "fgcal/core/internal/linear_system.hpp"
#include "fgcal/core/optimizer.hpp"
#include "fgcal/core/internal/schur_solver.hpp"
#include "fgcal/core/internal/sparse_cholesky.hpp"
#include "fgcal/factors/prior_factor.hpp"
#include "fgcal/factors/relative_pose_factor.hpp"
#include "fgcal_test/jacobian_check.hpp"

using namespace fgcal;

namespace {

CscMatrix upperFromDense(const MatX& A) {
  CscMatrix m;
  m.rows = A.rows();
  m.cols = A.cols();
  m.colptr.push_back(0);
  for (Eigen::Index j = 0; j < A.cols(); ++j) {
    for (Eigen::Index i = 0; i <= j; ++i)
      if (A(i, j) != 0.0) {
        m.rowind.push_back(i);
        m.values.push_back(A(i, j));
      }
    m.colptr.push_back(static_cast<CscMatrix::Index>(m.values.size()));
  }
  return m;
}

// A random SPD matrix with nb blocks of size bs, each pair of blocks coupled
// with probability p.
MatX randomBlockSparseSpd(int nb, int bs, double p, std::mt19937& gen) {
  std::normal_distribution<double> n;
  std::uniform_real_distribution<double> u;
  const int dim = nb * bs;
  MatX J = MatX::Zero(3 * dim, dim);
  int row = 0;
  for (int b = 0; b < nb; ++b)
    for (int c = b; c < nb && row + bs <= J.rows(); ++c)
      if (c == b || u(gen) < p) {
        for (int i = 0; i < bs; ++i)
          for (int k = 0; k < bs; ++k) {
            J(row + i, b * bs + k) = n(gen);
            J(row + i, c * bs + k) = n(gen);
          }
        row += bs;
      }
  return J.transpose() * J + 1e-3 * MatX::Identity(dim, dim);
}

}  // namespace

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

TEST_CASE("linearization: J, H and g equal a dense assembly from the factors") {
  const auto pts = fgcal::test::se3TestPoints(31, 6);
  Values v;
  for (int i = 0; i < 5; ++i) v.insert(key('x', i), pts[i + 3]);
  v.insert(key('f', 0), pts[2]);  // held fixed
  FactorGraph g;
  const MatX S = [] {
    MatX A = MatX::Random(6, 6);
    return MatX(A * A.transpose() + MatX::Identity(6, 6));
  }();
  g.emplace<PriorFactorSE3>(key('x', 0), pts[1], NoiseModel::fromCovariance(S));
  for (int i = 0; i + 1 < 5; ++i)
    g.emplace<RelativePoseFactor>(key('x', i), key('x', i + 1), pts[i], NoiseModel::isotropic(6, 0.5));
  g.emplace<RelativePoseFactor>(key('x', 4), key('x', 0), pts[8], NoiseModel::isotropic(6, 0.2), huber(0.5));
  g.emplace<RelativePoseFactor>(key('f', 0), key('x', 2), pts[9], NoiseModel::isotropic(6, 0.3));

  LinearSystem sys(g, v, {key('f', 0)});
  REQUIRE(sys.numColumns() == 30);
  REQUIRE(sys.numRows() == 6 * static_cast<long>(g.size()));
  const double cost = sys.linearize(v);
  // H and g accumulated during linearization equal those recomputed from J.
  const std::vector<double> H_fused = sys.hessianUpper().values;
  const VecX g_fused = sys.gradient();
  sys.formNormalEquations();
  for (std::size_t i = 0; i < H_fused.size(); ++i)
    CHECK(H_fused[i] == Approx(sys.hessianUpper().values[i]).margin(1e-9));
  CHECK((g_fused - sys.gradient()).norm() < 1e-9 * (1.0 + g_fused.norm()));
  CHECK(cost == Approx(g.cost(v)).epsilon(1e-12));
  CHECK(sys.cost(v) == Approx(cost).epsilon(1e-12));

  // Dense assembly straight from Factor::error.
  MatX Jd = MatX::Zero(sys.numRows(), sys.numColumns());
  VecX rd(sys.numRows());
  int row = 0;
  for (std::size_t f = 0; f < g.size(); ++f) {
    std::vector<MatX> Js;
    const VecX r = g[f].error(v, &Js);
    const MatX& W = g[f].noiseModel().sqrtInformation();
    double scale = 1.0;
    if (g[f].robustKernel()) scale = std::sqrt(g[f].robustKernel()->weight((W * r).squaredNorm()));
    rd.segment(row, 6) = scale * W * r;
    for (std::size_t k = 0; k < g[f].keys().size(); ++k) {
      const auto col = sys.columnOf(g[f].keys()[k]);
      if (col >= 0) Jd.block(row, col, 6, 6) = scale * W * Js[k];
    }
    row += 6;
  }
  const MatX J = MatX(sys.jacobian().eigen());
  CHECK((J - Jd).norm() < 1e-12 * Jd.norm());
  CHECK((sys.residual() - rd).norm() < 1e-12 * rd.norm());
  const MatX H = MatX(sys.hessianUpper().eigen());
  const MatX Hd = Jd.transpose() * Jd;
  CHECK((MatX(H.triangularView<Eigen::Upper>()) - MatX(Hd.triangularView<Eigen::Upper>())).norm() <
        1e-11 * Hd.norm());
  CHECK(MatX(H.triangularView<Eigen::StrictlyLower>()).norm() == 0.0);
  const VecX x = VecX::LinSpaced(sys.numColumns(), -1.0, 1.0);
  CHECK((sys.multiplyJacobian(x) - Jd * x).norm() < 1e-12 * (Jd * x).norm());
  CHECK((sys.gradient() - Jd.transpose() * rd).norm() < 1e-11 * (Jd.transpose() * rd).norm());
  CHECK(sys.columnOf(key('f', 0)) == -1);
  CHECK(sys.keyOfColumn(13) == key('x', 2));
}

TEST_CASE("linearization rejects a factor on a variable without a value") {
  Values v;
  v.insert(key('x', 0), SE3());
  FactorGraph g;
  g.emplace<RelativePoseFactor>(key('x', 0), key('x', 9), SE3(), NoiseModel::isotropic(6, 1.0));
  CHECK_THROWS_WITH(LinearSystem(g, v), Catch::Contains("x9"));
}

namespace {
// A calibration-shaped graph: cameras c, board poses b with a prior each and a
// relative-pose factor per (camera, board) seen, a mount-like variable m tied
// to every board, and one camera-camera factor (a direct reduced neighbour).
struct ArrowProblem {
  FactorGraph graph;
  Values values;
};
// noise(s): a 6-vector of N(0, s^2) entries from a seeded generator.
struct SeededNoise {
  explicit SeededNoise(unsigned seed) : gen(seed) {}
  Vec6 operator()(double s) {
    Vec6 d;
    for (int i = 0; i < 6; ++i) d[i] = s * n(gen);
    return d;
  }
  std::mt19937 gen;
  std::normal_distribution<double> n;
};
// Scales H's diagonal by `factor` in place, as LM's damping would (so the
// system is not J^T J), and returns the dense solution of H x = -g.
// The largest |a_i - b_i| against the largest |b_i|: H's values compared entry by entry.
double relativeMaxDifference(const std::vector<double>& a, const std::vector<double>& b) {
  REQUIRE(a.size() == b.size());
  double worst = 0.0, scale = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    worst = std::max(worst, std::abs(a[i] - b[i]));
    scale = std::max(scale, std::abs(b[i]));
  }
  return worst / scale;
}
VecX dampAndSolveDense(LinearSystem& sys, double factor) {
  for (LinearSystem::Index j = 0; j < sys.numColumns(); ++j) sys.hessianUpper().values[sys.hessianDiagonalPosition(j)] *= factor;
  const MatX Hu = MatX(sys.hessianUpper().eigen());
  const MatX H = MatX(Hu.selfadjointView<Eigen::Upper>());
  return H.llt().solve(-sys.gradient());
}
ArrowProblem makeArrowProblem(int cameras, int boards, unsigned seed) {
  SeededNoise noise(seed);
  // Truth, measurements of it with small noise, an initial guess further off.
  std::map<Key, SE3> truth;
  ArrowProblem p;
  auto var = [&](Key k) {
    truth[k] = SE3::exp(noise(1.0));
    p.values.insert(k, truth[k].plus(noise(0.1)));
  };
  auto rel = [&](Key a, Key b, double sigma) {
    p.graph.emplace<RelativePoseFactor>(a, b, truth[a].between(truth[b]).plus(noise(sigma)),
                                        NoiseModel::isotropic(6, sigma));
  };
  for (int c = 0; c < cameras; ++c) var(key('c', c));
  var(key('m', 0));
  for (int b = 0; b < boards; ++b) {
    var(key('b', b));
    p.graph.emplace<PriorFactorSE3>(key('b', b), truth[key('b', b)].plus(noise(0.02)), NoiseModel::isotropic(6, 0.02));
    for (int c = 0; c < cameras; ++c)
      if ((b + c) % 3 != 0 || c == 0) rel(key('c', c), key('b', b), 0.01);
    if (b % 4 == 0) rel(key('m', 0), key('b', b), 0.03);
  }
  if (cameras > 1) rel(key('c', 0), key('c', cameras - 1), 0.05);
  return p;
}
}  // namespace

TEST_CASE("H and g from the factors' own blocks equal those formed through J") {
  // Without a stored J the linearizer takes the factors' fast paths; with
  // one it forms J. Full, diagonal and isotropic noise, robust kernels,
  // a fixed variable, and pairs whose H block is the factor's transposed
  // (the second key's columns first), in both column orders. Measurements
  // are 0.3-0.9 rad off, so every residual is non-zero and Log is smooth.
  const auto pts = fgcal::test::se3TestPoints(37, 6);
  Values v;
  for (int i = 0; i < 5; ++i) v.insert(key('x', i), pts[i + 3]);
  v.insert(key('f', 0), pts[2]);
  auto off = [&](Key a, Key b, int i) {
    Vec6 d;
    d << 0.3, -0.5, 0.4 + 0.1 * i, 0.2, -0.1, 0.3;
    return v.at<SE3>(a).between(v.at<SE3>(b)).plus(d);
  };
  FactorGraph g;
  MatX A(6, 6);
  for (int i = 0; i < 36; ++i) A(i % 6, i / 6) = std::sin(1.0 + 7.0 * i);
  const MatX S = A * A.transpose() + MatX::Identity(6, 6);
  Vec6 sigmas;
  sigmas << 0.1, 0.2, 0.3, 0.4, 0.5, 0.6;
  Vec6 d0;
  d0 << 0.5, 0.1, -0.2, 0.3, 0.2, 0.1;
  g.emplace<PriorFactorSE3>(key('x', 0), v.at<SE3>(key('x', 0)).plus(d0), NoiseModel::fromCovariance(S));
  g.emplace<PriorFactorSE3>(key('x', 3), v.at<SE3>(key('x', 3)).plus(-d0), NoiseModel::diagonal(sigmas), cauchy(0.3));
  for (int i = 0; i + 1 < 5; ++i)
    g.emplace<RelativePoseFactor>(key('x', i + 1), key('x', i), off(key('x', i + 1), key('x', i), i),
                                  NoiseModel::fromCovariance(S));
  g.emplace<RelativePoseFactor>(key('x', 4), key('x', 0), off(key('x', 4), key('x', 0), 5), NoiseModel::isotropic(6, 0.2),
                                huber(0.5));
  g.emplace<RelativePoseFactor>(key('f', 0), key('x', 2), off(key('f', 0), key('x', 2), 6), NoiseModel::isotropic(6, 0.3));
  g.emplace<RelativePoseFactor>(key('x', 1), key('f', 0), off(key('x', 1), key('f', 0), 7), NoiseModel::diagonal(sigmas));
  for (bool schur_order : {false, true}) {
    LinearSystemOptions with_j, without_j;
    with_j.order_for_schur = without_j.order_for_schur = schur_order;
    without_j.store_jacobian = false;
    LinearSystem a(g, v, {key('f', 0)}, with_j), b(g, v, {key('f', 0)}, without_j);
    const double ca = a.linearize(v), cb = b.linearize(v);
    REQUIRE(std::isfinite(ca));
    REQUIRE(a.gradient().allFinite());
    CHECK(cb == Approx(ca).epsilon(1e-13));
    CHECK(b.cost(v) == Approx(ca).epsilon(1e-13));
    CHECK(a.residual().size() == a.numRows());
    CHECK(b.residual().size() == 0);  // r is kept with J only
    CHECK((a.gradient() - b.gradient()).norm() <= 1e-11 * a.gradient().norm());
    const MatX Ha = MatX(a.hessianUpper().eigen()), Hb = MatX(b.hessianUpper().eigen());
    CHECK((Ha - Hb).norm() <= 1e-11 * Ha.norm());
  }
}

namespace {
// Whether this CPU has AVX2 and FMA (then SchurSolver's Auto kernel must use them).
bool cpuHasAvx2Fma() {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
  return false;
#endif
}
}  // namespace

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

namespace {
// A point p (R^3) seen from a pose T: r = T^-1 p - z. With T Exp(d), d = [w v],
// T^-1 p moves by hat(q) w - v (q = T^-1 p); with p + e, by R^T e.
class PointInFrameFactor : public TypedFactor<3, SE3, Vec3> {
 public:
  PointInFrameFactor(Key pose, Key point, const Vec3& measured, NoiseModel::Ptr noise)
      : TypedFactor({pose, point}, std::move(noise)), measured_(measured) {}
  Residual evaluateTyped(const SE3& T, const Vec3& p, Jacobian<SE3>* J_T, Jacobian<Vec3>* J_p) const override {
    const Vec3 q = T.inverse().act(p);
    if (J_T) {
      J_T->leftCols<3>() = hat(q);
      J_T->rightCols<3>() = -Mat3::Identity();
    }
    if (J_p) *J_p = T.rotation().matrix().transpose();
    return q - measured_;
  }

 private:
  Vec3 measured_;
};

// The same factor with a fast path of its own that hands the linearizer its
// H and g blocks, which puts 3x6 and 6x3 blocks through the linearizer's
// general-size scatter instead of the Jacobian path.
class PointInFrameOwnBlocks final : public PointInFrameFactor {
 public:
  PointInFrameOwnBlocks(Key pose, Key point, const Vec3& measured, NoiseModel::Ptr noise)
      : PointInFrameFactor(pose, point, measured, std::move(noise)) {
    static const FastPath path;
    internal::registerNormalEquations(typeid(PointInFrameOwnBlocks), path);
  }

 private:
  struct FastPath final : internal::NormalEquations {
    void whitened(const Factor& factor, const Variable* const* vars, double* r, double* const* g,
                  double* const* H) const override {
      const auto& f = static_cast<const PointInFrameOwnBlocks&>(factor);
      const SE3& T = static_cast<const TypedVariable<SE3>*>(vars[0])->value();
      const Vec3& p = static_cast<const TypedVariable<Vec3>*>(vars[1])->value();
      Jacobian<SE3> JT;
      Jacobian<Vec3> Jp;
      Eigen::Map<Vec3> rw(r);
      rw = f.evaluateTyped(T, p, g ? &JT : nullptr, g ? &Jp : nullptr);
      f.noiseModel().whitenResidual(r);
      if (!g) return;
      f.noiseModel().whitenJacobian(JT.data(), 6, 3);
      f.noiseModel().whitenJacobian(Jp.data(), 3, 3);
      Eigen::Map<Vec6> g_T(g[0]);
      Eigen::Map<Vec3> g_p(g[1]);
      Eigen::Map<Mat6> H_TT(H[0]);  // the pairs (0,0), (0,1), (1,1)
      Eigen::Map<Eigen::Matrix<double, 6, 3>> H_Tp(H[1]);
      Eigen::Map<Mat3> H_pp(H[2]);
      g_T = JT.transpose() * rw;
      g_p = Jp.transpose() * rw;
      H_TT = JT.transpose() * JT;
      H_Tp = JT.transpose() * Jp;
      H_pp = Jp.transpose() * Jp;
    }
  };
};

// Cameras (SE(3), a prior each) seeing 3-dof points, and a few 6-dof board
// poses: eliminated blocks of two sizes, which take the Schur solver's
// dynamic-size path instead of its fixed 6x6 one.
ArrowProblem makeMixedProblem(int cameras, int points, unsigned seed, bool own_blocks = false) {
  SeededNoise noise(seed);
  ArrowProblem p;
  std::vector<SE3> cams;
  for (int c = 0; c < cameras; ++c) {
    cams.push_back(SE3::exp(noise(1.0)));
    p.values.insert(key('c', c), cams.back().plus(noise(0.05)));
    p.graph.emplace<PriorFactorSE3>(key('c', c), cams.back().plus(noise(0.1)), NoiseModel::isotropic(6, 0.1));
  }
  for (int i = 0; i < points; ++i) {
    const Vec3 pt = 3.0 * noise(1.0).head<3>();
    p.values.insert(key('p', i), Vec3(pt + noise(0.1).head<3>()));
    for (int c = 0; c < cameras; ++c)
      if ((i + c) % 3 != 0 || c == 0)
      {
        const Vec3 z = cams[c].inverse().act(pt) + noise(0.01).head<3>();
        if (own_blocks)
          p.graph.emplace<PointInFrameOwnBlocks>(key('c', c), key('p', i), z, NoiseModel::isotropic(3, 0.01));
        else
          p.graph.emplace<PointInFrameFactor>(key('c', c), key('p', i), z, NoiseModel::isotropic(3, 0.01));
      }
  }
  for (int b = 0; b < 3; ++b) {
    const SE3 board = SE3::exp(noise(1.0));
    p.values.insert(key('b', b), board.plus(noise(0.1)));
    p.graph.emplace<PriorFactorSE3>(key('b', b), board.plus(noise(0.02)), NoiseModel::isotropic(6, 0.02));
    p.graph.emplace<RelativePoseFactor>(key('c', b % cameras), key('b', b),
                                        cams[b % cameras].between(board).plus(noise(0.01)),
                                        NoiseModel::isotropic(6, 0.01));
  }
  return p;
}
}  // namespace

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

TEST_CASE("factors' own blocks of 3 and 6 dof land in H and g as through J") {
  // The points' columns come first (eliminated), so every pose-point block
  // is the factor's transposed: the general-size scatter, plain and transposed,
  // and the 3x3 diagonal.
  const ArrowProblem p = makeMixedProblem(3, 20, 43, /*own_blocks=*/true);
  LinearSystemOptions with_j, without_j;
  with_j.order_for_schur = without_j.order_for_schur = true;
  without_j.store_jacobian = false;
  LinearSystem a(p.graph, p.values, {}, with_j), b(p.graph, p.values, {}, without_j);
  const double ca = a.linearize(p.values), cb = b.linearize(p.values);
  CHECK(cb == Approx(ca).epsilon(1e-13));
  CHECK((a.gradient() - b.gradient()).norm() <= 1e-11 * a.gradient().norm());
  const MatX Ha = MatX(a.hessianUpper().eigen()), Hb = MatX(b.hessianUpper().eigen());
  REQUIRE(Ha.norm() > 0.0);
  CHECK((Ha - Hb).norm() <= 1e-11 * Ha.norm());
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

TEST_CASE("threaded linearization and Schur elimination equal the single-threaded ones") {
  // Large enough that two threads are really used (checked below).
  const ArrowProblem p = makeArrowProblem(3, 5000, 5);
  LinearSystemOptions one, two;
  one.order_for_schur = two.order_for_schur = true;
  two.threads = 2;
  two.store_jacobian = false;
  LinearSystem s1(p.graph, p.values, {}, one), s2(p.graph, p.values, {}, two);
  const double c1 = s1.linearize(p.values), c2 = s2.linearize(p.values);
  REQUIRE(s1.lastLinearizeThreads() == 1);
  REQUIRE(s2.lastLinearizeThreads() == 2);  // else this would compare one thread with one
  CHECK(c2 == Approx(c1).epsilon(1e-13));
  // The cost alone (the optimizer's last step), on one and on two threads.
  CHECK(s1.cost(p.values) == Approx(c1).epsilon(1e-13));
  CHECK(s2.cost(p.values) == Approx(c1).epsilon(1e-13));
  CHECK_THROWS_AS(s2.cost(Values()), std::invalid_argument);
  CHECK(relativeMaxDifference(s2.hessianUpper().values, s1.hessianUpper().values) <= 1e-12);
  CHECK((s1.gradient() - s2.gradient()).norm() <= 1e-12 * s1.gradient().norm());

  // Without a stored J, what needs it says so instead of reading garbage.
  CHECK(s1.jacobian().nonZeros() > 0);
  CHECK(s2.jacobian().nonZeros() == 0);
  CHECK_THROWS_AS(s2.multiplyJacobian(VecX::Zero(s2.numColumns())), std::logic_error);
  CHECK_THROWS_AS(s2.formNormalEquations(), std::logic_error);

  SchurSolver e1(s1), e2(s2, 2);
  VecX x1, x2;
  REQUIRE(e1.solve(-s1.gradient(), x1).ok());
  REQUIRE(e2.solve(-s2.gradient(), x2).ok());
  CHECK((x1 - x2).norm() <= 1e-9 * (1.0 + x1.norm()));

  // The optimizer with two threads reaches the same estimate.
  OptimizerOptions o1, o2;
  o2.threads = 2;
  const OptimizerResult r1 = optimize(p.graph, p.values, o1), r2 = optimize(p.graph, p.values, o2);
  REQUIRE(r1.converged);
  REQUIRE(r2.converged);
  CHECK(r2.final_cost == Approx(r1.final_cost).epsilon(1e-9));
  for (Key k : {key('c', 0), key('c', 2), key('m', 0), key('b', 4999)})
    CHECK(r1.values.at<SE3>(k).minus(r2.values.at<SE3>(k)).norm() < 1e-8);
}

namespace {
// A prior that counts the pairs it evaluates, through PriorFactorSE3's own
// fast path.
class CountingPrior final : public Factor {
 public:
  CountingPrior(const PriorFactorSE3& inner, int* pairs, RobustKernel::Ptr robust = nullptr)
      : Factor(inner.keys(), inner.noiseModelPtr(), std::move(robust)), inner_(inner), pairs_(pairs) {
    static const FastPath path;
    internal::registerNormalEquations(typeid(CountingPrior), path);
  }
  void evaluate(const Variable* const* vars, double* r, double* const* J) const override { inner_.evaluate(vars, r, J); }

 private:
  struct FastPath final : internal::NormalEquations {
    static const internal::NormalEquations& prior() { return *internal::normalEquationsFor(typeid(PriorFactorSE3)); }
    void whitened(const Factor& f, const Variable* const* vars, double* r, double* const* g,
                  double* const* H) const override {
      prior().whitened(static_cast<const CountingPrior&>(f).inner_, vars, r, g, H);
    }
    bool pairs() const override { return true; }
    void whitenedPair(const Factor& a, const Factor& b, const Variable* const* vars_a, const Variable* const* vars_b,
                      double* r_a, double* const* g_a, double* const* H_a, double* r_b, double* const* g_b,
                      double* const* H_b) const override {
      const auto& ca = static_cast<const CountingPrior&>(a);
      prior().whitenedPair(ca.inner_, static_cast<const CountingPrior&>(b).inner_, vars_a, vars_b, r_a, g_a, H_a, r_b,
                           g_b, H_b);
      ++*ca.pairs_;
    }
  };
  PriorFactorSE3 inner_;
  int* pairs_;
};
}  // namespace

TEST_CASE("like factors evaluated in pairs give the H, g and cost of one by one") {
  // A calibration-shaped graph (each board's prior, then its views) near its
  // optimum, where the pairs' series apply; a Huber kernel on some views.
  ArrowProblem p = makeArrowProblem(3, 700, 11);
  const Values at = optimize(p.graph, p.values).values;
  // Each board's prior after its views: pairing the priors moves the next
  // board's prior ahead of that board's views, so the first write of its
  // block of H (which assigns) is the prior's in the order of evaluation.
  int pairs = 0;
  FactorGraph g;
  Factor::Ptr pending;
  for (std::size_t f = 0; f < p.graph.size(); ++f) {
    const Factor::Ptr& factor = p.graph.at(f);
    if (const auto* prior = dynamic_cast<const PriorFactorSE3*>(factor.get())) {
      if (pending) g.add(pending);
      // Every seventh prior with a Huber kernel (weights differ inside a pair).
      pending = std::make_shared<CountingPrior>(*prior, &pairs, f % 7 == 0 ? huber(0.01) : nullptr);
    } else {
      g.add(factor);
      if (f % 5 == 0) p.graph.at(f)->setRobustKernel(huber(0.02));
    }
  }
  g.add(pending);
  // Weak extra priors up to 4096 factors: the most that are paired here
  // (pair_max_factors below), and the fewest that two threads share.
  int priors = 700;
  for (int b = 0; g.size() < 4096; ++b, ++priors)
    g.emplace<CountingPrior>(
        PriorFactorSE3(key('b', b % 700), at.at<SE3>(key('b', b % 700)), NoiseModel::isotropic(6, 1.0)), &pairs);
  REQUIRE(g.size() == 4096);
  LinearSystemOptions paired, single, with_j;
  paired.order_for_schur = single.order_for_schur = with_j.order_for_schur = true;
  paired.store_jacobian = single.store_jacobian = false;
  paired.pair_max_factors = 4096;
  single.pair_factors = false;
  LinearSystem sp(g, at, {}, paired), ss(g, at, {}, single), sj(g, at, {}, with_j);
  // Relinearized after a linearization elsewhere: every block of H rewritten
  // in the pairs' order of evaluation.
  sp.linearize(p.values);
  pairs = 0;
  const double cp = sp.linearize(at);
  CHECK(pairs == priors / 2);  // in pairs although each board's views come between its prior and the next
  pairs = 0;
  const double cs = ss.linearize(at), cj = sj.linearize(at);
  CHECK(pairs == 0);  // pair_factors off, and never with a stored J
  CHECK(cp == Approx(cs).epsilon(1e-13));
  CHECK(cj == Approx(cs).epsilon(1e-13));
  CHECK(relativeMaxDifference(sp.hessianUpper().values, ss.hessianUpper().values) <= 1e-12);
  CHECK((sp.gradient() - ss.gradient()).norm() <= 1e-12 * ss.gradient().norm());
  // The cost alone takes the same pairs, to the same bits (the optimizer compares the two).
  pairs = 0;
  CHECK(sp.cost(at) == cp);
  CHECK(pairs == priors / 2);
  // Two threads split the schedule (a pair across the split goes singly).
  LinearSystemOptions two = paired;
  two.threads = 2;
  LinearSystem s2(g, at, {}, two);
  const double c2 = s2.linearize(at);
  REQUIRE(s2.lastLinearizeThreads() == 2);
  CHECK(relativeMaxDifference(s2.hessianUpper().values, ss.hessianUpper().values) <= 1e-12);
  CHECK((s2.gradient() - ss.gradient()).norm() <= 1e-12 * ss.gradient().norm());
  CHECK(c2 == Approx(cs).epsilon(1e-13));
  // A fixed camera (its slots have no columns), paired and not.
  {
    LinearSystem fp(g, at, {key('c', 1)}, paired), fs(g, at, {key('c', 1)}, single);
    pairs = 0;
    CHECK(fp.linearize(at) == Approx(fs.linearize(at)).epsilon(1e-13));
    CHECK(pairs == priors / 2);
    CHECK(relativeMaxDifference(fp.hessianUpper().values, fs.hessianUpper().values) <= 1e-12);
    CHECK((fp.gradient() - fs.gradient()).norm() <= 1e-12 * fs.gradient().norm());
  }
  // One factor more than pair_max_factors: no pairs; the default limit pairs it.
  {
    FactorGraph big = g;
    big.emplace<CountingPrior>(PriorFactorSE3(key('b', 0), at.at<SE3>(key('b', 0)), NoiseModel::isotropic(6, 1.0)),
                               &pairs);
    LinearSystem sb(big, at, {}, paired);
    pairs = 0;
    sb.linearize(at);
    sb.cost(at);
    CHECK(pairs == 0);
    LinearSystemOptions by_default;
    by_default.store_jacobian = false;
    REQUIRE(big.size() <= by_default.pair_max_factors);
    LinearSystem sd(big, at, {}, by_default);
    pairs = 0;
    sd.linearize(at);
    CHECK(pairs == (priors + 1) / 2);
  }
  // The optimizer (which pairs) reaches the optimum of the factors evaluated one by one.
  ss.linearize(p.values);
  const double g0 = ss.gradient().norm();
  const OptimizerResult r = optimize(g, p.values);
  REQUIRE(r.converged);
  ss.linearize(r.values);
  CHECK(ss.gradient().norm() <= 1e-6 * g0);
}

TEST_CASE("an exception thrown while evaluating on a worker thread reaches the caller") {
  struct Throwing final : TypedFactor<6, SE3> {
    using TypedFactor::TypedFactor;
    Residual evaluateTyped(const SE3& x, Jacobian<SE3>* J) const override {
      if (x.translation().x() > 1e6) throw std::runtime_error("bad factor");
      if (J) J->setIdentity();
      return x.log();
    }
  };
  FactorGraph g;
  Values v;
  for (int i = 0; i < 10000; ++i) {
    v.insert(key('x', i), SE3());
    g.emplace<Throwing>(std::vector<Key>{key('x', i)}, NoiseModel::isotropic(6, 1.0));
  }
  v.insertOrAssign(key('x', 9999), SE3(SO3(), Vec3(2e6, 0, 0)));  // on the second thread's half
  LinearSystemOptions two;
  two.threads = 2;
  LinearSystem sys(g, v, {}, two);
  CHECK_THROWS_WITH(sys.linearize(v), "bad factor");
  CHECK(sys.lastLinearizeThreads() == 2);
  CHECK_THROWS_WITH(sys.cost(v), "bad factor");
  two.threads = 0;
  CHECK_THROWS_AS(LinearSystem(g, v, {}, two), std::invalid_argument);
}

namespace {
// Linearizes at `values`, scribbles over H, linearizes at `moved` and
// compares H and g with J^T J and J^T r summed from a stored J into a cleared
// H (formNormalEquations) at `moved`.
void checkRelinearizationOverScribbledH(const FactorGraph& graph, const Values& values, const Values& moved,
                                        const std::vector<Key>& fixed, LinearSystemOptions o) {
  LinearSystem sys(graph, values, fixed, o);
  sys.linearize(values);
  for (double& h : sys.hessianValues()) h = 1e3 * h + 7.0;
  sys.linearize(moved);
  LinearSystemOptions with_j = o;
  with_j.store_jacobian = true;
  with_j.threads = 1;
  LinearSystem ref(graph, moved, fixed, with_j);
  ref.linearize(moved);
  ref.formNormalEquations();
  CHECK(relativeMaxDifference(sys.hessianValues(), ref.hessianValues()) <= 1e-12);
  CHECK((sys.gradient() - ref.gradient()).norm() <= 1e-12 * ref.gradient().norm());
}
Values movedBy(const Values& v, double d) {
  Values out = v;
  for (Key k : v.keys()) {
    if (v.variable(k).type() == typeid(SE3))
      out.insertOrAssign(k, v.at<SE3>(k).plus(Vec6::Constant(d)));
    else
      out.insertOrAssign(k, Vec3(v.at<Vec3>(k) + Vec3::Constant(d)));
  }
  return out;
}
}  // namespace

TEST_CASE("a second linearization rewrites every entry of H, whatever H held") {
  // On one thread each block of H is assigned by its first contribution and
  // added to by the others, without clearing H; on two threads H is cleared
  // and summed. Blocks with one contribution and with several (a repeated
  // factor, a prior beside relative poses), factors with their own blocks
  // and through J (the points), a robust kernel, a fixed variable, both
  // column orders, with and without a stored J.
  ArrowProblem p = makeArrowProblem(3, 9, 43);
  p.graph.emplace<RelativePoseFactor>(key('c', 1), key('b', 4), SE3::exp(Vec6::Constant(0.05)),
                                      NoiseModel::isotropic(6, 0.02));  // a second factor on one pair
  p.graph.emplace<RelativePoseFactor>(key('c', 2), key('b', 5), SE3::exp(Vec6::Constant(0.4)),
                                      NoiseModel::isotropic(6, 0.02), huber(0.1));
  ArrowProblem mixed = makeMixedProblem(3, 12, 47);
  mixed.graph.emplace<PriorFactorSE3>(key('c', 1), SE3::exp(Vec6::Constant(0.3)), NoiseModel::isotropic(6, 0.1),
                                      cauchy(0.2));
  for (bool schur_order : {false, true})
    for (bool store_j : {false, true}) {
      INFO("schur order " << schur_order << ", stored J " << store_j);
      LinearSystemOptions o;
      o.order_for_schur = schur_order;
      o.store_jacobian = store_j;
      checkRelinearizationOverScribbledH(p.graph, p.values, movedBy(p.values, 0.03), {}, o);
      checkRelinearizationOverScribbledH(mixed.graph, mixed.values, movedBy(mixed.values, 0.02), {key('c', 2)}, o);
    }
  // Two threads (enough factors that both are used).
  const ArrowProblem big = makeArrowProblem(3, 5000, 11);
  LinearSystemOptions two;
  two.order_for_schur = true;
  two.store_jacobian = false;
  two.threads = 2;
  LinearSystem probe(big.graph, big.values, {}, two);
  probe.linearize(big.values);
  REQUIRE(probe.lastLinearizeThreads() == 2);
  checkRelinearizationOverScribbledH(big.graph, big.values, movedBy(big.values, 0.01), {}, two);
}
