// Shared by the SE(3) factors whose residual is Log(E): the whitened
// residual and, when asked, the normal-equation block of the side whose
// Jacobian is Jr^-1(Log E) itself, and, for E = C A^-1 B, the blocks of the
// other side from it.
#pragma once

#include "fgcal/core/internal/lie_series.hpp"
#include "fgcal/core/internal/noise_model_access.hpp"
#include "fgcal/core/noise_model.hpp"
#include "fgcal/core/se3.hpp"

namespace fgcal::detail {

// #pragma GCC unroll where the compiler knows it (GCC, Clang); nothing elsewhere.
#if defined(__GNUC__)
#define FGCAL_UNROLL(n) _Pragma(FGCAL_UNROLL_STR(GCC unroll n))
#define FGCAL_UNROLL_STR(x) #x
#else
#define FGCAL_UNROLL(n)
#endif

/// r <- W xi with xi = Log(E). When g is not null, also U = W Jr^-1(xi),
/// H = U^T U (6x6, column-major) and g = U^T r. Returns false when only r
/// was asked for. r is the same, to the bit, either way (the cost-only
/// evaluation and the linearization are compared by the optimizer).
///
/// W (6x6, read packed through internal::NoiseModelAccess) is upper triangular: row i
/// of U is the sum over k >= i of W(i, k) times row k of Jr^-1. U, H and g
/// are formed by rows of U held as three two-lane packets: Jr^-1 = [[J 0]
/// [K J]] has a zero block; H's column j is the sum over k of row k of U
/// times U(k, j), down to the diagonal, and H's lower triangle a copy of its
/// upper one (exactly symmetric).
inline bool whitenedLogBlock(const NoiseModel& noise, const SE3& E, double* r, double* g, double* H) {
  Vec6 xi;
  Mat3 J, K;
  detail::se3LogBlocks(E.rotation(), E.translation(), xi, g ? &J : nullptr, g ? &K : nullptr);
  Eigen::Map<Vec6> rw(r);
  rw = xi;
  noise.whitenResidual(r);
  if (!g) return false;
  using Access = internal::NoiseModelAccess;
  const double* W = Access::upperTriangle(noise);  // W(i, k), i <= k, at Access::upperIndex(i, k)
  using A2 = Eigen::Array2d;
  const A2 zero(0.0, 0.0);
  A2 row[6][3];  // rows of Jr^-1
  FGCAL_UNROLL(3)
  for (int k = 0; k < 3; ++k) {
    row[k][0] = A2(J(k, 0), J(k, 1));
    row[k][1] = A2(J(k, 2), 0.0);
    row[k][2] = zero;
    row[k + 3][0] = A2(K(k, 0), K(k, 1));
    row[k + 3][1] = A2(K(k, 2), J(k, 0));
    row[k + 3][2] = A2(J(k, 1), J(k, 2));
  }
  A2 U[6][3];
  FGCAL_UNROLL(6)
  for (int i = 0; i < 6; ++i) {
    A2 u0 = zero, u1 = zero, u2 = zero;
    FGCAL_UNROLL(6)
    for (int k = i; k < 6; ++k) {
      const A2 wik(W[Access::upperIndex(i, k)], W[Access::upperIndex(i, k)]);
      u0 += wik * row[k][0];
      u1 += wik * row[k][1];
      if (k >= 3) u2 += wik * row[k][2];
    }
    U[i][0] = u0, U[i][1] = u1, U[i][2] = u2;
  }
  // Column j's packets down to the diagonal only (rows 0 .. j, rounded up
  // to the packet), then the lower triangle mirrored from the upper.
  FGCAL_UNROLL(6)
  for (int j = 0; j < 6; ++j) {
    A2 h0 = zero, h1 = zero, h2 = zero;
    FGCAL_UNROLL(6)
    for (int k = 0; k < 6; ++k) {
      const double u = U[k][j / 2][j % 2];
      const A2 ukj(u, u);
      h0 += U[k][0] * ukj;
      if (j >= 2) h1 += U[k][1] * ukj;
      if (j >= 4) h2 += U[k][2] * ukj;
    }
    double* col = H + 6 * j;
    col[0] = h0[0], col[1] = h0[1];
    if (j >= 2) col[2] = h1[0], col[3] = h1[1];
    if (j >= 4) col[4] = h2[0], col[5] = h2[1];
  }
  FGCAL_UNROLL(6)
  for (int j = 0; j < 6; ++j)
    FGCAL_UNROLL(6)
    for (int i = j + 1; i < 6; ++i)
      if (i > (j | 1)) H[i + 6 * j] = H[j + 6 * i];  // (j, j + 1) for even j was computed in the packet
  A2 g0 = zero, g1 = zero, g2 = zero;
  FGCAL_UNROLL(6)
  for (int k = 0; k < 6; ++k) {
    const A2 rk(r[k], r[k]);
    g0 += U[k][0] * rk;
    g1 += U[k][1] * rk;
    g2 += U[k][2] * rk;
  }
  g[0] = g0[0], g[1] = g0[1], g[2] = g1[0], g[3] = g1[1], g[4] = g2[0], g[5] = g2[1];
  return true;
}

// The steps of whitenedLogBlockPair, forced inline into it: each is one
// stage of the same two-lane chain, and a call between stages would spill
// the lanes it carries.
#if defined(__GNUC__)
#define FGCAL_PAIR_STEP inline __attribute__((always_inline))
#else
#define FGCAL_PAIR_STEP inline
#endif
namespace pair_log {
using A2 = Eigen::Array2d;

// Log's rotation part w, theta^2, Jr^-1's coefficient d and, when with_q,
// Q's c1, c2, c3, for both lanes' rotations.
FGCAL_PAIR_STEP void rotationLog(const Mat3& Ra, const Mat3& Rb, bool with_q, A2* w, A2& t2, A2& d, A2& c1, A2& c2,
                                 A2& c3) {
  const auto R = [&](int i, int j) { return A2(Ra(i, j), Rb(i, j)); };
  // The quaternion at scale 4 qw: 1 + trace = 4 qw^2, vee(R - R^T) = 4 qw qv.
  const A2 tr1 = 1.0 + R(0, 0) + R(1, 1) + R(2, 2);
  const A2 q[3] = {R(2, 1) - R(1, 2), R(0, 2) - R(2, 0), R(1, 0) - R(0, 1)};
  const A2 n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2];
  const bool series = (tr1 > 3.0).all() && (n2 < 0.0025 * tr1 * tr1).all();
  if (series) {  // so3LogSeries, and the series of se3LogBlocks and se3Q, on both lanes
    const A2 k = detail::so3LogSeriesScale<A2>(1.0 / tr1, n2);
    FGCAL_UNROLL(3)
    for (int i = 0; i < 3; ++i) w[i] = k * q[i];
    t2 = k * k * n2;
    d = detail::so3InverseCoefficientSeries(t2);
    if (with_q) detail::se3QSeries(t2, c1, c2, c3);
    return;
  }
  // Each lane's as se3LogBlocks forms them (closed forms or series), then on both lanes.
  const Mat3* Rl[2] = {&Ra, &Rb};
  FGCAL_UNROLL(2)
  for (int l = 0; l < 2; ++l) {
    const detail::HalfAngleLog h = detail::so3LogHalfAngle(*Rl[l]);
    FGCAL_UNROLL(3)
    for (int i = 0; i < 3; ++i) w[i][l] = h.w[i];
    t2[l] = h.theta2;
    d[l] = detail::so3InverseCoefficient(h);
    if (with_q) detail::se3QCoefficients(h.theta2, h.theta, h.sin_theta, h.cos_theta, c1[l], c2[l], c3[l]);
  }
}

// J = Jr^-1(w)'s 3x3 block and K its lower-left one (Jr^-1 = [[J 0] [K J]]),
// column-major, from xi = (w, rho) and the coefficients.
FGCAL_PAIR_STEP void inverseRightJacobian(const A2* xi, const A2& t2, const A2& d, const A2& c1, const A2& c2,
                                          const A2& c3, A2* J, A2* K) {
  const A2* w = xi;
  // Jr^-1(w) = (1 - d t2) I + W/2 + d w w^T (W = hat(w)), column-major.
  FGCAL_UNROLL(3)
  for (int j = 0; j < 3; ++j)
    FGCAL_UNROLL(3)
    for (int i = 0; i < 3; ++i) J[i + 3 * j] = d * w[i] * w[j];
  const A2 dg = 1.0 - d * t2;
  J[0] += dg, J[4] += dg, J[8] += dg;
  J[1] += 0.5 * w[2], J[3] -= 0.5 * w[2];
  J[2] -= 0.5 * w[1], J[6] += 0.5 * w[1];
  J[5] += 0.5 * w[0], J[7] -= 0.5 * w[0];
  // se3Q(-w, -rho): the sign of w and rho cancels in the symmetric part and flips m.
  const A2* v = xi + 3;
  const A2 s = w[0] * v[0] + w[1] * v[1] + w[2] * v[2];
  const A2 mv = -(0.5 - c2 * t2), mw = -((2.0 * c2 - c1) * s);
  const A2 m[3] = {mv * v[0] + mw * w[0], mv * v[1] + mw * w[1], mv * v[2] + mw * w[2]};
  const A2 a = c3 * s, kd = 2.0 * c1 * s + a * t2;
  A2 Q[9];
  FGCAL_UNROLL(3)
  for (int j = 0; j < 3; ++j)
    FGCAL_UNROLL(3)
    for (int i = 0; i < 3; ++i) Q[i + 3 * j] = c1 * (v[i] * w[j] + w[i] * v[j]) + a * w[i] * w[j];
  Q[0] -= kd, Q[4] -= kd, Q[8] -= kd;
  Q[1] += m[2], Q[3] -= m[2];
  Q[2] -= m[1], Q[6] += m[1];
  Q[5] += m[0], Q[7] -= m[0];
  // K = -J (Q J).
  A2 QJ[9];
  FGCAL_UNROLL(3)
  for (int j = 0; j < 3; ++j)
    FGCAL_UNROLL(3)
    for (int i = 0; i < 3; ++i) QJ[i + 3 * j] = Q[i] * J[3 * j] + Q[i + 3] * J[1 + 3 * j] + Q[i + 6] * J[2 + 3 * j];
  FGCAL_UNROLL(3)
  for (int j = 0; j < 3; ++j)
    FGCAL_UNROLL(3)
    for (int i = 0; i < 3; ++i)
      K[i + 3 * j] = -(J[i] * QJ[3 * j] + J[i + 3] * QJ[1 + 3 * j] + J[i + 6] * QJ[2 + 3 * j]);
}

// U = W Jr^-1, g = U^T r and H = U^T U for both lanes (W(i, k) from Wik).
template <class WEntry>
FGCAL_PAIR_STEP void normalEquations(const WEntry& Wik, const A2* J, const A2* K, const A2* r, double* g_a,
                                     double* H_a, double* g_b, double* H_b) {
  // U = W Jr^-1 with Jr^-1 = [[J 0] [K J]], by rows (row i: W's row i on rows k >= i).
  const auto Jr = [&](int i, int j) -> A2 {
    if (i < 3) return j < 3 ? J[i + 3 * j] : A2::Zero();
    return j < 3 ? K[(i - 3) + 3 * j] : J[(i - 3) + 3 * (j - 3)];
  };
  A2 U[36];  // U[i + 6 j]
  FGCAL_UNROLL(6)
  for (int j = 0; j < 6; ++j)
    FGCAL_UNROLL(6)
    for (int i = 0; i < 6; ++i) {
      A2 acc = Wik(i, i) * Jr(i, j);
      FGCAL_UNROLL(6)
      for (int kk = i + 1; kk < 6; ++kk)
        if (!(kk < 3 && j >= 3)) acc += Wik(i, kk) * Jr(kk, j);  // Jr^-1's upper-right block is zero
      U[i + 6 * j] = acc;
    }
  FGCAL_UNROLL(6)
  for (int j = 0; j < 6; ++j) {
    A2 gj = U[6 * j] * r[0];
    FGCAL_UNROLL(6)
    for (int i = 1; i < 6; ++i) gj += U[i + 6 * j] * r[i];
    g_a[j] = gj[0];
    g_b[j] = gj[1];
    FGCAL_UNROLL(6)
    for (int i = 0; i <= j; ++i) {
      A2 h = U[6 * i] * U[6 * j];
      FGCAL_UNROLL(6)
      for (int kk = 1; kk < 6; ++kk) h += U[kk + 6 * i] * U[kk + 6 * j];
      H_a[i + 6 * j] = H_a[j + 6 * i] = h[0];
      H_b[i + 6 * j] = H_b[j + 6 * i] = h[1];
    }
  }
}
}  // namespace pair_log

/// whitenedLogBlock for two residuals at once, one in each lane of two-lane
/// packets: r_a = W_a Log(E_a) and r_b = W_b Log(E_b), and when g_a is not
/// null (then neither is g_b, H_a nor H_b) their U^T U and U^T r. The scalar
/// block is a chain of dependent operations (the quaternion, four series,
/// the 3x3 products of Jr^-1's lower block); two independent chains in the
/// lanes of one register run in the time of about one.
///
/// Where both rotations are small enough for the series (the scalar block's
/// shortcut: 1 + trace R > 3 and |vee(R - R^T)|^2 < 0.0025 (1 + trace R)^2,
/// angles below about 0.1 rad), the log and its coefficients are formed on
/// both lanes too; elsewhere each lane's log (atan2, sine and cosine, or its
/// series) is formed alone, as the scalar block does, and the rest on both
/// lanes. The results equal the scalar block's to rounding (the same
/// formulas, the operations in another order), and r does not depend on
/// whether g is given.
inline void whitenedLogBlockPair(const NoiseModel& noise_a, const SE3& E_a, const NoiseModel& noise_b, const SE3& E_b,
                                 double* r_a, double* g_a, double* H_a, double* r_b, double* g_b, double* H_b) {
  using A2 = Eigen::Array2d;
  // w, theta^2, Jr^-1's coefficient d and, when g is asked for, Q's c1, c2, c3.
  A2 w[3], t2, d, c1 = A2::Zero(), c2 = A2::Zero(), c3 = A2::Zero();
  pair_log::rotationLog(E_a.rotation(), E_b.rotation(), g_a != nullptr, w, t2, d, c1, c2, c3);
  // rho = t - w x t / 2 + d (w (w.t) - t2 t).
  const Vec3 &ta = E_a.translation(), &tb = E_b.translation();
  const A2 t[3] = {A2(ta[0], tb[0]), A2(ta[1], tb[1]), A2(ta[2], tb[2])};
  const A2 wt = w[0] * t[0] + w[1] * t[1] + w[2] * t[2];
  const A2 wxt[3] = {w[1] * t[2] - w[2] * t[1], w[2] * t[0] - w[0] * t[2], w[0] * t[1] - w[1] * t[0]};
  A2 xi[6];
  FGCAL_UNROLL(3)
  for (int i = 0; i < 3; ++i) {
    xi[i] = w[i];
    xi[i + 3] = t[i] - 0.5 * wxt[i] + d * (wt * w[i] - t2 * t[i]);
  }
  // r = W xi, W upper triangular (packed: W(i, k), i <= k, at Access::upperIndex(i, k)).
  using Access = internal::NoiseModelAccess;
  const double* Wa = Access::upperTriangle(noise_a);
  const double* Wb = Access::upperTriangle(noise_b);
  const auto Wik = [&](int i, int kk) { return A2(Wa[Access::upperIndex(i, kk)], Wb[Access::upperIndex(i, kk)]); };
  A2 r[6];
  FGCAL_UNROLL(6)
  for (int i = 0; i < 6; ++i) {
    A2 acc = Wik(i, i) * xi[i];
    FGCAL_UNROLL(6)
    for (int kk = i + 1; kk < 6; ++kk) acc += Wik(i, kk) * xi[kk];
    r[i] = acc;
    r_a[i] = acc[0];
    r_b[i] = acc[1];
  }
  if (!g_a) return;
  A2 J[9], K[9];
  pair_log::inverseRightJacobian(xi, t2, d, c1, c2, c3, J, K);
  pair_log::normalEquations(Wik, J, K, r, g_a, H_a, g_b, H_b);
}

/// For a residual Log(C D) with D = A^-1 B (C constant), the A side's blocks
/// from the B side's: J_B = Jr^-1 and J_A = -J_B Ad(D^-1), so with H_BB =
/// J_B^T J_B and g_B = J_B^T r,
///   H_AA = Ad^T H_BB Ad,  H_AB = -Ad^T H_BB (A's rows, B's columns),  g_A = -Ad^T g_B.
/// All 6x6 column-major (6-vectors for g).
///
/// Ad(D^-1) = [[R^T 0] [-R^T t^ R^T]] (R, t of D), so Ad^T = [[R t^R] [0 R]]:
/// by 3x3 blocks, X = Ad^T H_BB is R times H_BB's row blocks plus a cross
/// product with t, and H_AA = X Ad is X's column blocks times R^T minus a
/// cross product: about 250 multiply-adds where two 6x6 products take 432.
inline void inverseAdjointSide(const SE3& D, const double* H_BB, const double* g_B, double* H_AA, double* H_AB,
                               double* g_A) {
  const Mat3& R = D.rotation();
  const Vec3& t = D.translation();
  const Eigen::Map<const Mat6> Hbb(H_BB);
  Mat36 Xt = R * Hbb.topRows<3>();
  const Mat36 Xb = R * Hbb.bottomRows<3>();
  for (int c = 0; c < 6; ++c) Xt.col(c) += t.cross(Xb.col(c));
  Eigen::Map<Mat6> Hab(H_AB);
  Hab.topRows<3>() = -Xt;
  Hab.bottomRows<3>() = -Xb;
  // H_AA = [[Z11 - Z12 t^, Z12] [., Z22]] with Z = X blockdiag(R^T, R^T);
  // row i of M t^ is (row i of M) x t. Symmetric: the lower block is Z12^T.
  const Mat3 Z11 = Xt.leftCols<3>() * R.transpose();
  const Mat3 Z12 = Xt.rightCols<3>() * R.transpose();
  Eigen::Map<Mat6> Haa(H_AA);
  for (int i = 0; i < 3; ++i) Haa.block<1, 3>(i, 0) = Z11.row(i) - Z12.row(i).cross(t.transpose());
  Haa.topRightCorner<3, 3>() = Z12;
  Haa.bottomLeftCorner<3, 3>() = Z12.transpose();
  Haa.bottomRightCorner<3, 3>().noalias() = Xb.rightCols<3>() * R.transpose();
  const Eigen::Map<const Vec6> gb(g_B);
  const Vec3 Rg2 = R * gb.tail<3>();
  Eigen::Map<Vec6> ga(g_A);
  ga.head<3>() = -(R * gb.head<3>() + t.cross(Rg2));
  ga.tail<3>() = -Rg2;
}

#undef FGCAL_UNROLL
#undef FGCAL_UNROLL_STR

}  // namespace fgcal::detail
