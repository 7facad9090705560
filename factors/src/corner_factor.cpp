// CornerFactor: the projection chain and its Jacobians.
//   p_b = L p,  p_c = X^-1 p_b,  uv = project(K, p_c)
// With right perturbations: d p_c / d X = [hat(p_c)  -I] (X Exp(d) moves the
// camera, so the point moves the other way in its frame) and d p_c / d L =
// R_X^T [-R_L hat(p)  R_L].
#include "fgcal/factors/corner_factor.hpp"

#include <stdexcept>
#include <string>

namespace fgcal {

namespace {

template <int N>
using Vec = Eigen::Matrix<double, N, 1>;

const SE3& pose(const Variable* v) { return static_cast<const TypedVariable<SE3>*>(v)->value(); }

void checkNoise(const NoiseModel::Ptr& noise) {
  if (noise && noise->dim() != 2)
    throw std::invalid_argument("CornerFactor: expected a noise model of dimension 2 (pixels), got " +
                                std::to_string(noise->dim()));
}

}  // namespace

// The vector behind a variable of one of the three sizes; throws when the
// variable has another type (a graph built with the wrong value for the key).
const double* CornerFactor::intrinsicsData(const Variable* v, int n) {
  switch (n) {
    case 4:
      if (v->type() == typeid(Vec<4>)) return static_cast<const TypedVariable<Vec<4>>*>(v)->value().data();
      break;
    case 8:
      if (v->type() == typeid(Vec<8>)) return static_cast<const TypedVariable<Vec<8>>*>(v)->value().data();
      break;
    case 9:
      if (v->type() == typeid(Vec<9>)) return static_cast<const TypedVariable<Vec<9>>*>(v)->value().data();
      break;
    default: break;
  }
  throw std::invalid_argument("CornerFactor: the intrinsics variable is not a vector of " + std::to_string(n) +
                              " entries (insert it with CornerFactor::insertIntrinsics)");
}

Eigen::Vector2d cornerResidual(const vision::CameraModel& model, const double* K, const SE3& X, const SE3& L,
                               const Vec3& p, const Eigen::Vector2d& u, Eigen::Matrix<double, 2, 6>* J_r_X,
                               Eigen::Matrix<double, 2, 6>* J_r_L, double* J_r_K) {
  const Mat3& R_x = X.rotation();
  const Mat3& R_l = L.rotation();
  const Vec3 p_b = R_l * p + L.translation();
  Vec3 p_c = R_x.transpose() * (p_b - X.translation());
  // Behind the camera: projected from 1e-6 m in front (a huge residual); the
  // clamped depth has no derivative.
  const bool clamped = !(p_c.z() > 1e-6);
  if (clamped) p_c.z() = 1e-6;
  Eigen::Vector2d uv;
  vision::Mat23 J_uv_pc;
  const bool need = J_r_X || J_r_L;
  model.projectWith(K, p_c, &uv, need ? &J_uv_pc : nullptr, J_r_K);
  if (need && clamped) J_uv_pc.col(2).setZero();
  if (J_r_X) {
    J_r_X->leftCols<3>() = J_uv_pc * hat(p_c);
    J_r_X->rightCols<3>() = -J_uv_pc;
  }
  if (J_r_L) {
    const Eigen::Matrix<double, 2, 3> B = J_uv_pc * (R_x.transpose() * R_l);
    J_r_L->leftCols<3>() = -B * hat(p);
    J_r_L->rightCols<3>() = B;
  }
  return uv - u;
}

CornerFactor::CornerFactor(Key camera, Key board, std::shared_ptr<const vision::CameraModel> model,
                           const Vec3& board_point, const Eigen::Vector2d& corner, NoiseModel::Ptr noise,
                           RobustKernel::Ptr robust)
    : Factor({camera, board}, (checkNoise(noise), noise), std::move(robust)),
      model_(std::move(model)),
      p_(board_point),
      u_(corner) {
  if (!model_) throw std::invalid_argument("CornerFactor: no camera model");
}

CornerFactor::CornerFactor(Key camera, Key board, Key intrinsics, std::shared_ptr<const vision::CameraModel> model,
                           const Vec3& board_point, const Eigen::Vector2d& corner, NoiseModel::Ptr noise,
                           RobustKernel::Ptr robust)
    : Factor({camera, board, intrinsics}, (checkNoise(noise), noise), std::move(robust)),
      model_(std::move(model)),
      p_(board_point),
      u_(corner) {
  if (!model_) throw std::invalid_argument("CornerFactor: no camera model");
}

void CornerFactor::evaluate(const Variable* const* vars, double* residual, double* const* jacobians) const {
  const vision::CameraModel& m = *model_;
  const double* K = estimatesIntrinsics() ? intrinsicsData(vars[2], m.intrinsicsSize()) : m.intrinsicsData();
  Eigen::Matrix<double, 2, 6> J_X, J_L;
  const bool jx = jacobians && jacobians[0], jl = jacobians && jacobians[1];
  double* J_K = jacobians && estimatesIntrinsics() ? jacobians[2] : nullptr;
  const Eigen::Vector2d r =
      cornerResidual(m, K, pose(vars[0]), pose(vars[1]), p_, u_, jx ? &J_X : nullptr, jl ? &J_L : nullptr, J_K);
  residual[0] = r[0];
  residual[1] = r[1];
  if (jx) Eigen::Map<Eigen::Matrix<double, 2, 6>>{jacobians[0]} = J_X;
  if (jl) Eigen::Map<Eigen::Matrix<double, 2, 6>>{jacobians[1]} = J_L;
}

void CornerFactor::insertIntrinsics(Values& values, Key k, const vision::CameraModel& model) {
  const VecX v = model.intrinsicsVector();
  switch (v.size()) {
    case 4: values.insert(k, Vec<4>(v)); return;
    case 8: values.insert(k, Vec<8>(v)); return;
    case 9: values.insert(k, Vec<9>(v)); return;
    default: throw std::invalid_argument("CornerFactor: no intrinsics vector of " + std::to_string(v.size()) + " entries");
  }
}

VecX CornerFactor::intrinsicsAt(const Values& values, Key k) {
  const Variable& v = values.variable(k);
  return Eigen::Map<const VecX>(intrinsicsData(&v, v.dim()), v.dim());
}

}  // namespace fgcal
