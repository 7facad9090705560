// Camera models with Kalibr's names: projection `pinhole` with distortion
// `radtan` [k1 k2 p1 p2] (an optional fifth k3, OpenCV's plumb_bob order),
// `equidistant` [k1 k2 k3 k4] (OpenCV's fisheye model) or `none`.
// project() maps a point in the camera frame to pixels (pixel centres at
// integer coordinates, as cv::projectPoints) with its Jacobian; unproject()
// maps a pixel back to a unit bearing. projectWith() does the same through
// intrinsics given as one vector [fx fy cx cy, distortion coefficients], with
// the Jacobian by those too, for estimating them (the corner factor).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "fgcal/core/types.hpp"

namespace fgcal::vision {

using Vec2 = Eigen::Vector2d;
using Mat2 = Eigen::Matrix2d;
using Mat23 = Eigen::Matrix<double, 2, 3>;
/// Room for the largest intrinsics vector (radtan with k3: 9 entries).
inline constexpr int kMaxIntrinsics = 9;

enum class Projection { Pinhole };
enum class Distortion { None, RadTan, Equidistant };

/// Kalibr's name of each model ("pinhole"; "none", "radtan", "equidistant").
std::string toString(Projection p);
std::string toString(Distortion d);
/// Parse Kalibr's names; throws VisionError listing the valid names.
Projection projectionFromString(const std::string& name);
Distortion distortionFromString(const std::string& name);

class CameraModel {
 public:
  CameraModel() = default;
  /// Checked construction: throws VisionError when the coefficient count does
  /// not fit the model (none 0, radtan 4 or 5, equidistant 4), a focal length
  /// is not positive or the resolution is not positive.
  CameraModel(Projection projection, Distortion distortion, double fx, double fy, double cx,
              double cy, std::vector<double> coeffs, int width, int height);

  /// From the rig.yaml / Kalibr fields: camera_model, distortion_model,
  /// intrinsics [fx fy cx cy], distortion_coeffs, resolution [w h].
  static CameraModel fromKalibr(const std::string& camera_model,
                                const std::string& distortion_model,
                                const std::vector<double>& intrinsics,
                                const std::vector<double>& distortion_coeffs,
                                const std::vector<int>& resolution);

  /// Pixel of a point in the camera frame; nullopt when the point is not in
  /// front of the camera (z <= 1e-9). J_uv_p receives d(uv)/d(p).
  std::optional<Vec2> project(const Vec3& p_cam, Mat23* J_uv_p = nullptr) const;

  /// Entries of the intrinsics vector: [fx fy cx cy] then the distortion
  /// coefficients in their rig.yaml order, so none 4, radtan 8 (9 with k3),
  /// equidistant 8.
  int intrinsicsSize() const { return 4 + static_cast<int>(coeffs_.size()); }
  /// [fx fy cx cy k...], the layout of projectWith's intrinsics.
  VecX intrinsicsVector() const;
  /// The same, intrinsicsSize() entries, without a copy.
  const double* intrinsicsData() const { return params_; }
  /// The same camera (model, resolution) with other intrinsics in that
  /// layout; throws VisionError when their count or values are invalid.
  CameraModel withIntrinsics(const VecX& intrinsics) const;

  /// Projection through `intrinsics` (intrinsicsSize() entries in the layout
  /// above) instead of this camera's own, this camera's distortion model.
  /// Writes the pixel to `uv`; J_uv_p (when not null) receives d(uv)/d(p)
  /// and J_uv_intrinsics (when not null) the 2 x intrinsicsSize() Jacobian
  /// d(uv)/d(intrinsics), column-major. Returns false (writing nothing) when
  /// the point is not in front of the camera. Allocates nothing.
  bool projectWith(const double* intrinsics, const Vec3& p_cam, Vec2* uv, Mat23* J_uv_p = nullptr,
                   double* J_uv_intrinsics = nullptr) const;

  /// Unit bearing of a pixel: iterative inversion of the distortion (Newton).
  /// nullopt when the inversion does not converge (far outside the valid
  /// field of view of a strongly distorted model).
  std::optional<Vec3> unproject(const Vec2& uv) const;

  /// Distortion of normalized coordinates (x/z, y/z) -> distorted normalized
  /// coordinates, with its 2x2 Jacobian.
  Vec2 distort(const Vec2& xy, Mat2* J_d_xy = nullptr) const;
  /// Inverse of distort(); nullopt when Newton does not converge.
  std::optional<Vec2> undistort(const Vec2& xy_distorted) const;

  Projection projection() const { return projection_; }
  Distortion distortion() const { return distortion_; }
  double fx() const { return fx_; }
  double fy() const { return fy_; }
  double cx() const { return cx_; }
  double cy() const { return cy_; }
  /// The coefficients as given (radtan 4 or 5, equidistant 4, none 0).
  const std::vector<double>& coeffs() const { return coeffs_; }
  int width() const { return width_; }
  int height() const { return height_; }
  /// 3x3 camera matrix K.
  Mat3 K() const;

 private:
  Projection projection_ = Projection::Pinhole;
  Distortion distortion_ = Distortion::None;
  double fx_ = 1.0, fy_ = 1.0, cx_ = 0.0, cy_ = 0.0;
  std::vector<double> coeffs_;
  // [fx fy cx cy k...] as projectWith takes them; coefficients past the
  // model's count stay 0 (radtan without k3: k3 = 0).
  double params_[kMaxIntrinsics] = {1, 1, 0, 0, 0, 0, 0, 0, 0};
  int width_ = 0, height_ = 0;
};

}  // namespace fgcal::vision
