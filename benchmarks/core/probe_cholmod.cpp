// probe_cholmod: where fgcal's per-iteration time goes on the calibration
// graph, and what CHOLMOD and a hand-written Schur complement do with the same
// normal equations. A diagnostic for issue #2, not part of the CSV benchmark:
//   probe_cholmod M N
// prints the time of linearize(), formNormalEquations(), fgcal's
// SparseCholesky analyze/factorize/solve, and of CHOLMOD called directly with
// simplicial and supernodal factorizations, plus the fill (nnz of L) and flops.
#include <chrono>
#include <cstdio>
#include <cstdlib>

#include <Eigen/Cholesky>
#include <cholmod.h>

#include "calibration_problem.hpp"
#include "fgcal/core/linear_system.hpp"
#include "fgcal/core/sparse_cholesky.hpp"

using namespace fgcal;
using namespace fgcal::bench;
using Clock = std::chrono::steady_clock;
static double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

static cholmod_sparse view(const CscMatrix& A) {
  cholmod_sparse s{};
  s.nrow = static_cast<size_t>(A.rows);
  s.ncol = static_cast<size_t>(A.cols);
  s.nzmax = A.values.size();
  s.p = const_cast<CscMatrix::Index*>(A.colptr.data());
  s.i = const_cast<CscMatrix::Index*>(A.rowind.data());
  s.x = const_cast<double*>(A.values.data());
  s.stype = 1;
  s.itype = CHOLMOD_LONG;
  s.xtype = CHOLMOD_REAL;
  s.dtype = CHOLMOD_DOUBLE;
  s.sorted = 1;
  s.packed = 1;
  return s;
}

// CHOLMOD with fgcal's settings (final_ll) and a chosen supernodal strategy / ordering.
static void runCholmod(const char* name, const CscMatrix& H, const VecX& g, int supernodal, bool given_perm,
                       const std::vector<SuiteSparse_long>& perm) {
  cholmod_common c;
  cholmod_l_start(&c);
  c.print = 0;
  c.final_ll = 1;
  c.supernodal = supernodal;
  if (given_perm) {
    c.nmethods = 1;
    c.method[0].ordering = CHOLMOD_GIVEN;
    c.postorder = 1;
  }
  cholmod_sparse A = view(H);
  auto t0 = Clock::now();
  cholmod_factor* L = cholmod_l_analyze_p(&A, given_perm ? const_cast<SuiteSparse_long*>(perm.data()) : nullptr,
                                          nullptr, 0, &c);
  const double ta = since(t0);
  double tf = 1e300;
  for (int k = 0; k < 3; ++k) {
    t0 = Clock::now();
    cholmod_l_factorize(&A, L, &c);
    tf = std::min(tf, since(t0));
  }
  cholmod_dense b{};
  b.nrow = static_cast<size_t>(g.size());
  b.ncol = 1;
  b.nzmax = b.d = b.nrow;
  b.x = const_cast<double*>(g.data());
  b.xtype = CHOLMOD_REAL;
  b.dtype = CHOLMOD_DOUBLE;
  t0 = Clock::now();
  cholmod_dense* x = cholmod_l_solve(CHOLMOD_A, L, &b, &c);
  const double ts = since(t0);
  std::printf("  %-34s analyze %.3f s  factorize %.3f s  solve %.3f s  super=%d ordering=%d  lnz=%.3g  flops=%.3g  status=%d\n",
              name, ta, tf, ts, L->is_super, L->ordering, c.lnz, c.fl, c.status);
  cholmod_l_free_dense(&x, &c);
  cholmod_l_free_factor(&L, &c);
  cholmod_l_finish(&c);
}

int main(int argc, char** argv) {
  const int M = argc > 1 ? std::atoi(argv[1]) : 4;
  const int N = argc > 2 ? static_cast<int>(std::atof(argv[2])) : 10000;
  const CalibrationProblem p = makeCalibrationProblem({M, N, 0.6, 1});
  FactorGraph graph;
  Values values;
  buildFgcalProblem(p, graph, values);
  std::printf("M=%d N=%d factors=%zu\n", M, N, graph.size());

  auto t0 = Clock::now();
  LinearSystem sys(graph, values);
  std::printf("  LinearSystem construction           %.3f s  (J %lld x %lld nnz %zu, H nnz(upper) %zu)\n", since(t0),
              (long long)sys.numRows(), (long long)sys.numColumns(), sys.jacobian().nonZeros(),
              sys.hessianUpper().nonZeros());
  t0 = Clock::now();
  sys.linearize(values);
  std::printf("  linearize (evaluate+whiten+scatter)  %.3f s\n", since(t0));
  t0 = Clock::now();
  sys.formNormalEquations();
  std::printf("  formNormalEquations                  %.3f s\n", since(t0));
  t0 = Clock::now();
  const double c = sys.cost(values);
  std::printf("  cost (candidate evaluation)          %.3f s  (%.6g)\n", since(t0), c);
  VecX d = VecX::Constant(sys.numColumns(), 1e-6);
  t0 = Clock::now();
  const VecX Jd = sys.multiplyJacobian(d);
  std::printf("  multiplyJacobian                     %.3f s\n", since(t0));
  t0 = Clock::now();
  sys.retract(values, d);
  std::printf("  retract                              %.3f s\n", since(t0));

  const CscMatrix& H = sys.hessianUpper();
  SparseCholesky chol;
  t0 = Clock::now();
  chol.analyze(H);
  const double ta = since(t0);
  double tf = 1e300;
  for (int k = 0; k < 3; ++k) {
    t0 = Clock::now();
    const SolverStatus st = chol.factorize(H);
    tf = std::min(tf, since(t0));
    if (!st.ok()) std::printf("  factorize failed: %s\n", st.message.c_str());
  }
  VecX x;
  t0 = Clock::now();
  chol.solve(VecX(-sys.gradient()), x);
  std::printf("  fgcal SparseCholesky               analyze %.3f s  factorize %.3f s  solve %.3f s  ordering %s  nnz(L) %.3g\n",
              ta, tf, since(t0), chol.ordering().c_str(), chol.factorNonZeros());

  // Boards first, cameras last (columns: cameras were inserted first).
  std::vector<SuiteSparse_long> perm;
  for (Eigen::Index k = 6 * M; k < sys.numColumns(); ++k) perm.push_back(k);
  for (Eigen::Index k = 0; k < 6 * M; ++k) perm.push_back(k);
  runCholmod("CHOLMOD default (AUTO)", H, sys.gradient(), CHOLMOD_AUTO, false, perm);
  runCholmod("CHOLMOD simplicial", H, sys.gradient(), CHOLMOD_SIMPLICIAL, false, perm);
  runCholmod("CHOLMOD supernodal", H, sys.gradient(), CHOLMOD_SUPERNODAL, false, perm);
  runCholmod("CHOLMOD given boards-first, AUTO", H, sys.gradient(), CHOLMOD_AUTO, true, perm);
  runCholmod("CHOLMOD given boards-first, simpl.", H, sys.gradient(), CHOLMOD_SIMPLICIAL, true, perm);
  runCholmod("CHOLMOD given boards-first, super", H, sys.gradient(), CHOLMOD_SUPERNODAL, true, perm);

  // Hand-written Schur complement on the same H (upper CSC): eliminate each
  // board's 6x6 block, solve the dense 6M x 6M camera system, back-substitute.
  {
    const int nc = 6 * M;
    const auto& cp = H.colptr;
    const auto& ri = H.rowind;
    const auto& hv = H.values;
    t0 = Clock::now();
    Eigen::MatrixXd S = Eigen::MatrixXd::Zero(nc, nc);
    Eigen::VectorXd rhs = -sys.gradient().head(nc);
    Eigen::VectorXd gb = -sys.gradient();
    for (int j = 0; j < N; ++j) {
      const Eigen::Index c0 = nc + 6 * j;
      // Column c0+c of H: rows of cameras (< nc) then the board's own rows c0..c0+c.
      Eigen::Matrix<double, 6, 6> Hbb;
      Eigen::MatrixXd Hcb = Eigen::MatrixXd::Zero(nc, 6);
      for (int c = 0; c < 6; ++c)
        for (auto k = cp[c0 + c]; k < cp[c0 + c + 1]; ++k) {
          const auto r = ri[k];
          if (r < nc) Hcb(r, c) = hv[k];
          else { Hbb(r - c0, c) = hv[k]; Hbb(c, r - c0) = hv[k]; }
        }
      const Eigen::LLT<Eigen::Matrix<double, 6, 6>> llt(Hbb);
      const Eigen::MatrixXd HbbInvHbc = llt.solve(Hcb.transpose());
      S.noalias() -= Hcb * HbbInvHbc;
      rhs.noalias() -= Hcb * llt.solve(gb.segment<6>(c0));
    }
    for (int c = 0; c < nc; ++c)
      for (auto k = cp[c]; k < cp[c + 1]; ++k) { S(ri[k], c) += hv[k]; if (ri[k] != c) S(c, ri[k]) += hv[k]; }
    const VecX xc = S.llt().solve(rhs);
    const double ts = since(t0);
    std::printf("  naive Schur (dense Hcb per board)  eliminate+solve %.3f s  |x_cam - CHOLMOD x_cam| = %.2e\n", ts,
                (xc - x.head(nc)).norm());
  }
  return 0;
}
