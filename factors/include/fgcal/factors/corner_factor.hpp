// The corner reprojection factor: one detected ChArUco corner u (pixels) of a
// camera, in the image taken at one instant, predicted from the camera pose
// X = T_base_cam, the board pose L = T_base_marker at that instant and the
// corner's point p in the board frame, through the camera model:
//   r = project(K, X^-1 L p) - u          (2 entries, pixels)
// Keys: X, L and, when the intrinsics are estimated, K: the camera's
// intrinsics vector [fx fy cx cy, distortion coefficients] in the layout of
// vision::CameraModel::intrinsicsVector, held as a fixed-size vector
// (Eigen::Matrix<double, n, 1>, n = 4 for distortion none, 8 for radtan and
// equidistant, 9 for radtan with k3; insertIntrinsics puts the right one in
// Values). Without K the camera's own intrinsics are used. Noise: the
// detector's pixel sigma, NoiseModel::isotropic(2, sigma).
//
//   graph.emplace<CornerFactor>(key('c', 0), key('b', j), camera, p, u, NoiseModel::isotropic(2, 0.5));
//
// A point at or behind the camera (z <= 1e-6 m) is projected as if it were
// 1e-6 m in front: a huge, finite residual that no step towards it survives.
#pragma once

#include <memory>

#include "fgcal/core/factor.hpp"
#include "fgcal/vision/camera_model.hpp"

namespace fgcal {

/// The prediction of one corner, for factors that form the board pose
/// another way (e.g. moved by a camera's time offset): r = project(K, X^-1 L
/// p) - u through `model`'s distortion with the intrinsics `K`
/// (model.intrinsicsSize() entries). Writes the Jacobians that are not null:
/// J_r_X and J_r_L (2 x 6, right perturbation, [w v]) and J_r_K (2 x
/// intrinsicsSize, column-major).
Eigen::Vector2d cornerResidual(const vision::CameraModel& model, const double* K, const SE3& X, const SE3& L,
                               const Vec3& p, const Eigen::Vector2d& u, Eigen::Matrix<double, 2, 6>* J_r_X,
                               Eigen::Matrix<double, 2, 6>* J_r_L, double* J_r_K);

class CornerFactor final : public Factor {
 public:
  /// Intrinsics held at `model`'s own. Keys: the camera pose, the board pose.
  CornerFactor(Key camera, Key board, std::shared_ptr<const vision::CameraModel> model, const Vec3& board_point,
               const Eigen::Vector2d& corner, NoiseModel::Ptr noise, RobustKernel::Ptr robust = nullptr);
  /// Intrinsics estimated: the variable `intrinsics` (insertIntrinsics) with
  /// `model`'s distortion model.
  CornerFactor(Key camera, Key board, Key intrinsics, std::shared_ptr<const vision::CameraModel> model,
               const Vec3& board_point, const Eigen::Vector2d& corner, NoiseModel::Ptr noise,
               RobustKernel::Ptr robust = nullptr);

  void evaluate(const Variable* const* vars, double* residual, double* const* jacobians) const override;

  bool estimatesIntrinsics() const { return keys().size() == 3; }
  const vision::CameraModel& model() const { return *model_; }
  const Vec3& boardPoint() const { return p_; }
  const Eigen::Vector2d& corner() const { return u_; }

  /// Inserts `model`'s intrinsics vector under `k` with the fixed size the
  /// factor expects.
  static void insertIntrinsics(Values& values, Key k, const vision::CameraModel& model);
  /// The intrinsics vector under `k` (any of the sizes above).
  static VecX intrinsicsAt(const Values& values, Key k);
  /// The entries of an intrinsics variable of `n` entries, without a copy;
  /// throws std::invalid_argument when `v` is not such a vector.
  static const double* intrinsicsData(const Variable* v, int n);

 private:
  std::shared_ptr<const vision::CameraModel> model_;
  Vec3 p_;
  Eigen::Vector2d u_;
};

}  // namespace fgcal
