// Relative pose between two SE(3) variables: measured Z ~ A^-1 B,
// r = Log(Z^-1 A^-1 B). In the calibration, A = T_base_cam, B = T_base_marker
// and Z = T_cam_marker from PnP (the paper's fiducial factor).
#pragma once

#include "fgcal/core/factor.hpp"
#include "fgcal/factors/detail/whitened_log.hpp"

namespace fgcal {

class RelativePoseFactor final : public TypedFactor<6, SE3, SE3> {
 public:
  RelativePoseFactor(Key a, Key b, const SE3& measured, NoiseModel::Ptr noise, RobustKernel::Ptr robust = nullptr)
      : TypedFactor({a, b}, std::move(noise), std::move(robust)), measured_inverse_(measured.inverse()) {}

  Residual evaluateTyped(const SE3& A, const SE3& B, Jacobian<SE3>* J_r_A, Jacobian<SE3>* J_r_B) const override {
    const SE3 D = A.between(B);  // A^-1 B
    const SE3 E = measured_inverse_.compose(D);
    Mat6 Jlog;
    const bool need = J_r_A || J_r_B;
    const Vec6 r = E.log(need ? &Jlog : nullptr);
    // d/dB: D Exp(d) -> E Exp(d); d/dA: D <- Exp(-d) D = D Exp(-Ad(D^-1) d).
    if (J_r_B) *J_r_B = Jlog;
    if (J_r_A) *J_r_A = SE3::minusLogJacobianTimesInverseAdjoint(Jlog, D);
    return r;
  }
  /// H and g straight from the 6x6 block of the B side: with U = W Jlog and
  /// Ad = Ad(D^-1) (D = A^-1 B), so that J_A = -U Ad,
  ///   H_BB = U^T U,  H_AB = -Ad^T H_BB,  H_AA = Ad^T H_BB Ad,
  ///   g_B = U^T W r,  g_A = -Ad^T g_B,
  /// without whitening J_A or forming J_A^T J_A and J_A^T J_B from it.
  bool whitenedNormalEquations(const Variable* const* vars, double* r, double* const* g,
                               double* const* H) const override {
    const SE3& A = static_cast<const TypedVariable<SE3>*>(vars[0])->value();
    const SE3& B = static_cast<const TypedVariable<SE3>*>(vars[1])->value();
    const SE3 D = A.between(B);
    if (!detail::whitenedLogBlock(noiseModel(), measured_inverse_.compose(D), r, g ? g[1] : nullptr,
                                  g ? H[2] : nullptr))
      return true;
    // Ad(D^-1) = [[R^T 0] [-R^T t^ R^T]] (R, t of D), so Ad^T = [[R t^R] [0 R]]:
    // by 3x3 blocks, X = Ad^T H_BB is R times H_BB's row blocks plus a cross
    // product with t, and H_AA = X Ad is X's column blocks times R^T minus a
    // cross product: about 250 multiply-adds where two 6x6 products take 432.
    const Mat3& R = D.rotation();
    const Vec3& t = D.translation();
    const Eigen::Map<const Mat6> Hbb(H[2]);
    Mat36 Xt = R * Hbb.topRows<3>();
    const Mat36 Xb = R * Hbb.bottomRows<3>();
    for (int c = 0; c < 6; ++c) Xt.col(c) += t.cross(Xb.col(c));
    Eigen::Map<Mat6> Hab(H[1]);
    Hab.topRows<3>() = -Xt;
    Hab.bottomRows<3>() = -Xb;
    // H_AA = [[Z11 - Z12 t^, Z12] [., Z22]] with Z = X blockdiag(R^T, R^T);
    // row i of M t^ is (row i of M) x t. Symmetric: the lower block is Z12^T.
    const Mat3 Z11 = Xt.leftCols<3>() * R.transpose();
    const Mat3 Z12 = Xt.rightCols<3>() * R.transpose();
    Eigen::Map<Mat6> Haa(H[0]);
    for (int i = 0; i < 3; ++i) Haa.block<1, 3>(i, 0) = Z11.row(i) - Z12.row(i).cross(t.transpose());
    Haa.topRightCorner<3, 3>() = Z12;
    Haa.bottomLeftCorner<3, 3>() = Z12.transpose();
    Haa.bottomRightCorner<3, 3>().noalias() = Xb.rightCols<3>() * R.transpose();
    const Eigen::Map<const Vec6> gb(g[1]);
    const Vec3 Rg2 = R * gb.tail<3>();
    Eigen::Map<Vec6> ga(g[0]);
    ga.head<3>() = -(R * gb.head<3>() + t.cross(Rg2));
    ga.tail<3>() = -Rg2;
    return true;
  }
  SE3 measured() const { return measured_inverse_.inverse(); }

 private:
  SE3 measured_inverse_;
};

}  // namespace fgcal
