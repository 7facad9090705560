// Shared by the tests of the linear machinery: calibration-shaped graphs
// (cameras, board poses, a mount, 3-dof points), dense references, and a
// factor with a fast path of its own.
#pragma once

#include <map>
#include <random>

#include <Eigen/Cholesky>
#include <catch2/catch.hpp>

#include "fgcal/core/factor_graph.hpp"
#include "fgcal/core/internal/linear_system.hpp"
#include "fgcal/core/internal/normal_equations.hpp"
#include "fgcal/factors/prior_factor.hpp"
#include "fgcal/factors/relative_pose_factor.hpp"

namespace fgcal::test {


inline CscMatrix upperFromDense(const MatX& A) {
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
inline MatX randomBlockSparseSpd(int nb, int bs, double p, std::mt19937& gen) {
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
inline double relativeMaxDifference(const std::vector<double>& a, const std::vector<double>& b) {
  REQUIRE(a.size() == b.size());
  double worst = 0.0, scale = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    worst = std::max(worst, std::abs(a[i] - b[i]));
    scale = std::max(scale, std::abs(b[i]));
  }
  return worst / scale;
}
inline VecX dampAndSolveDense(LinearSystem& sys, double factor) {
  for (LinearSystem::Index j = 0; j < sys.numColumns(); ++j) sys.hessianUpper().values[sys.hessianDiagonalPosition(j)] *= factor;
  const MatX Hu = MatX(sys.hessianUpper().eigen());
  const MatX H = MatX(Hu.selfadjointView<Eigen::Upper>());
  return H.llt().solve(-sys.gradient());
}
inline ArrowProblem makeArrowProblem(int cameras, int boards, unsigned seed) {
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
// Whether this CPU has AVX2 and FMA (then SchurSolver's Auto kernel must use them).
inline bool cpuHasAvx2Fma() {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
  return false;
#endif
}
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
inline ArrowProblem makeMixedProblem(int cameras, int points, unsigned seed, bool own_blocks = false) {
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

}  // namespace fgcal::test
