// Pinhole projection with radtan / equidistant / no distortion, analytic
// Jacobians and Newton inversion. The formulas follow OpenCV's projectPoints
// and fisheye::projectPoints exactly, so the two agree to rounding error.
#include "fgcal/vision/camera_model.hpp"

#include <cmath>
#include <sstream>

#include <Eigen/LU>

#include "fgcal/vision/vision_error.hpp"

namespace fgcal::vision {

std::string toString(Projection) { return "pinhole"; }

std::string toString(Distortion d) {
  switch (d) {
    case Distortion::None: return "none";
    case Distortion::RadTan: return "radtan";
    case Distortion::Equidistant: return "equidistant";
  }
  return "?";
}

Projection projectionFromString(const std::string& name) {
  if (name == "pinhole") return Projection::Pinhole;
  throw VisionError("camera_model: unknown camera model '" + name +
                    "'; expected one of: pinhole");
}

Distortion distortionFromString(const std::string& name) {
  if (name == "none") return Distortion::None;
  if (name == "radtan") return Distortion::RadTan;
  if (name == "equidistant") return Distortion::Equidistant;
  throw VisionError("distortion_model: unknown distortion model '" + name +
                    "'; expected one of: none, radtan, equidistant");
}

CameraModel::CameraModel(Projection projection, Distortion distortion, double fx, double fy,
                         double cx, double cy, std::vector<double> coeffs, int width, int height)
    : projection_(projection), distortion_(distortion), fx_(fx), fy_(fy), cx_(cx), cy_(cy),
      coeffs_(std::move(coeffs)), width_(width), height_(height) {
  const size_t n = coeffs_.size();
  const bool count_ok = (distortion_ == Distortion::None && n == 0) ||
                        (distortion_ == Distortion::RadTan && (n == 4 || n == 5)) ||
                        (distortion_ == Distortion::Equidistant && n == 4);
  if (!count_ok) {
    std::ostringstream s;
    s << "distortion_coeffs: distortion model '" << toString(distortion_) << "' expects "
      << (distortion_ == Distortion::None     ? "0 coefficients"
          : distortion_ == Distortion::RadTan ? "4 coefficients [k1 k2 p1 p2] (or 5 with k3)"
                                              : "4 coefficients [k1 k2 k3 k4]")
      << ", got " << n;
    throw VisionError(s.str());
  }
  for (double c : coeffs_)
    if (!std::isfinite(c)) throw VisionError("distortion_coeffs: holds NaN or inf");
  if (!(fx_ > 0.0) || !(fy_ > 0.0) || !std::isfinite(cx_) || !std::isfinite(cy_))
    throw VisionError("intrinsics: expected [fx fy cx cy] with fx, fy > 0 and finite cx, cy");
  if (width_ <= 0 || height_ <= 0)
    throw VisionError("resolution: expected [width height] with both > 0");
  for (size_t i = 0; i < n; ++i) k_[i] = coeffs_[i];
}

CameraModel CameraModel::fromKalibr(const std::string& camera_model,
                                    const std::string& distortion_model,
                                    const std::vector<double>& intrinsics,
                                    const std::vector<double>& distortion_coeffs,
                                    const std::vector<int>& resolution) {
  const Projection p = projectionFromString(camera_model);
  const Distortion d = distortionFromString(distortion_model);
  if (intrinsics.size() != 4)
    throw VisionError("intrinsics: expected 4 values [fx fy cx cy], got " +
                      std::to_string(intrinsics.size()));
  if (resolution.size() != 2)
    throw VisionError("resolution: expected 2 values [width height], got " +
                      std::to_string(resolution.size()));
  return CameraModel(p, d, intrinsics[0], intrinsics[1], intrinsics[2], intrinsics[3],
                     distortion_coeffs, resolution[0], resolution[1]);
}

Mat3 CameraModel::K() const {
  Mat3 K;
  K << fx_, 0, cx_, 0, fy_, cy_, 0, 0, 1;
  return K;
}

Vec2 CameraModel::distort(const Vec2& xy, Mat2* J) const {
  const double x = xy.x(), y = xy.y();
  switch (distortion_) {
    case Distortion::None:
      if (J) J->setIdentity();
      return xy;
    case Distortion::RadTan: {
      const double k1 = k_[0], k2 = k_[1], p1 = k_[2], p2 = k_[3], k3 = k_[4];
      const double r2 = x * x + y * y;
      const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
      const double xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
      const double yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
      if (J) {
        const double drad_dr2 = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2);
        const double drad_dx = 2.0 * x * drad_dr2, drad_dy = 2.0 * y * drad_dr2;
        (*J)(0, 0) = radial + x * drad_dx + 2.0 * p1 * y + 6.0 * p2 * x;
        (*J)(0, 1) = x * drad_dy + 2.0 * p1 * x + 2.0 * p2 * y;
        (*J)(1, 0) = y * drad_dx + 2.0 * p1 * x + 2.0 * p2 * y;
        (*J)(1, 1) = radial + y * drad_dy + 6.0 * p1 * y + 2.0 * p2 * x;
      }
      return Vec2(xd, yd);
    }
    case Distortion::Equidistant: {
      const double k1 = k_[0], k2 = k_[1], k3 = k_[2], k4 = k_[3];
      const double r = std::sqrt(x * x + y * y);
      if (r < 1e-10) {
        // theta_d / r -> 1 at the optical axis; the second-order term vanishes.
        if (J) J->setIdentity();
        return xy;
      }
      const double th = std::atan(r);
      const double t2 = th * th;
      const double poly = 1.0 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4)));
      const double thd = th * poly;
      const double scale = thd / r;
      if (J) {
        const double dthd_dth = 1.0 + t2 * (3.0 * k1 + t2 * (5.0 * k2 + t2 * (7.0 * k3 + 9.0 * t2 * k4)));
        const double dth_dr = 1.0 / (1.0 + r * r);
        const double dscale_dr = (dthd_dth * dth_dr * r - thd) / (r * r);
        const Vec2 dr_dxy(x / r, y / r);
        *J = scale * Mat2::Identity() + dscale_dr * xy * dr_dxy.transpose();
      }
      return scale * xy;
    }
  }
  return xy;
}

std::optional<Vec2> CameraModel::undistort(const Vec2& xyd) const {
  switch (distortion_) {
    case Distortion::None:
      return xyd;
    case Distortion::Equidistant: {
      // Invert theta_d = theta (1 + k1 θ² + k2 θ⁴ + k3 θ⁶ + k4 θ⁸) by Newton in θ.
      const double rd = xyd.norm();
      if (rd < 1e-12) return xyd;
      const double k1 = k_[0], k2 = k_[1], k3 = k_[2], k4 = k_[3];
      double th = rd;
      bool converged = false;
      for (int it = 0; it < 50; ++it) {
        const double t2 = th * th;
        const double f = th * (1.0 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4)))) - rd;
        const double df = 1.0 + t2 * (3.0 * k1 + t2 * (5.0 * k2 + t2 * (7.0 * k3 + 9.0 * t2 * k4)));
        if (!(std::abs(df) > 1e-12)) break;
        const double step = f / df;
        th -= step;
        if (std::abs(step) < 1e-15 * (1.0 + std::abs(th))) {
          converged = true;
          break;
        }
      }
      if (!converged || !(th >= 0.0) || th >= M_PI / 2.0) return std::nullopt;
      return xyd * (std::tan(th) / rd);
    }
    case Distortion::RadTan: {
      // Newton on distort(xy) = xyd, started at xyd. The result is accepted
      // only if the residual is tiny: past the maximum of the radial
      // polynomial no inverse exists and Newton stalls.
      Vec2 xy = xyd;
      for (int it = 0; it < 30; ++it) {
        Mat2 J;
        const Vec2 f = distort(xy, &J) - xyd;
        const double det = J.determinant();
        if (!(std::abs(det) > 1e-12)) return std::nullopt;
        const Vec2 step = J.inverse() * f;
        xy -= step;
        if (!xy.allFinite()) return std::nullopt;
        if (step.norm() < 1e-14 * (1.0 + xy.norm())) break;
      }
      // Past the fold of the radial polynomial a second root exists; only the
      // branch where the model is locally invertible (det J > 0) is the camera's.
      Mat2 J_end;
      if ((distort(xy, &J_end) - xyd).norm() < 1e-11 && J_end.determinant() > 0.0) return xy;
      return std::nullopt;
    }
  }
  return std::nullopt;
}

std::optional<Vec2> CameraModel::project(const Vec3& p, Mat23* J_uv_p) const {
  if (!(p.z() > 1e-9)) return std::nullopt;
  const double iz = 1.0 / p.z();
  const Vec2 xy(p.x() * iz, p.y() * iz);
  Mat2 J_d_xy;
  const Vec2 d = distort(xy, J_uv_p ? &J_d_xy : nullptr);
  if (J_uv_p) {
    Mat23 J_xy_p;
    J_xy_p << iz, 0.0, -xy.x() * iz, 0.0, iz, -xy.y() * iz;
    Mat2 F = Mat2::Zero();
    F(0, 0) = fx_;
    F(1, 1) = fy_;
    *J_uv_p = F * J_d_xy * J_xy_p;
  }
  return Vec2(fx_ * d.x() + cx_, fy_ * d.y() + cy_);
}

std::optional<Vec3> CameraModel::unproject(const Vec2& uv) const {
  const Vec2 xyd((uv.x() - cx_) / fx_, (uv.y() - cy_) / fy_);
  const auto xy = undistort(xyd);
  if (!xy) return std::nullopt;
  return Vec3(xy->x(), xy->y(), 1.0).normalized();
}

}  // namespace fgcal::vision
