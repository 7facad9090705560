// Pinhole projection with radtan / equidistant / no distortion, analytic
// Jacobians and Newton inversion. The formulas follow OpenCV's projectPoints
// and fisheye::projectPoints exactly, so the two agree to rounding error.
#include "fgcal/vision/camera_model.hpp"

#include <algorithm>
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
  params_[0] = fx_, params_[1] = fy_, params_[2] = cx_, params_[3] = cy_;
  for (size_t i = 0; i < n; ++i) params_[4 + i] = coeffs_[i];
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

namespace {

// Distortion of normalized coordinates with the coefficients k (ncoeff of
// them, the model's order); J_d_xy and J_d_k (2 x ncoeff, column-major) when
// not null. Radtan without a fifth coefficient has k3 = 0.
Vec2 distortWith(Distortion model, const double* k, int ncoeff, const Vec2& xy, Mat2* J_d_xy, double* J_d_k) {
  const double x = xy.x(), y = xy.y();
  switch (model) {
    case Distortion::None:
      if (J_d_xy) J_d_xy->setIdentity();
      return xy;
    case Distortion::RadTan: {
      const double k1 = k[0], k2 = k[1], p1 = k[2], p2 = k[3], k3 = ncoeff > 4 ? k[4] : 0.0;
      const double r2 = x * x + y * y;
      const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
      const double xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
      const double yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
      if (J_d_xy) {
        const double drad_dr2 = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2);
        const double drad_dx = 2.0 * x * drad_dr2, drad_dy = 2.0 * y * drad_dr2;
        (*J_d_xy)(0, 0) = radial + x * drad_dx + 2.0 * p1 * y + 6.0 * p2 * x;
        (*J_d_xy)(0, 1) = x * drad_dy + 2.0 * p1 * x + 2.0 * p2 * y;
        (*J_d_xy)(1, 0) = y * drad_dx + 2.0 * p1 * x + 2.0 * p2 * y;
        (*J_d_xy)(1, 1) = radial + y * drad_dy + 6.0 * p1 * y + 2.0 * p2 * x;
      }
      if (J_d_k) {
        const double r4 = r2 * r2;
        double* J = J_d_k;  // columns k1 k2 p1 p2 [k3], two rows each
        J[0] = x * r2, J[1] = y * r2;
        J[2] = x * r4, J[3] = y * r4;
        J[4] = 2.0 * x * y, J[5] = r2 + 2.0 * y * y;
        J[6] = r2 + 2.0 * x * x, J[7] = 2.0 * x * y;
        if (ncoeff > 4) J[8] = x * r4 * r2, J[9] = y * r4 * r2;
      }
      return Vec2(xd, yd);
    }
    case Distortion::Equidistant: {
      const double k1 = k[0], k2 = k[1], k3 = k[2], k4 = k[3];
      const double r = std::sqrt(x * x + y * y);
      if (r < 1e-10) {
        // theta_d / r -> 1 at the optical axis; the second-order term vanishes,
        // and so does theta^(2i+1) / r, the coefficients' effect.
        if (J_d_xy) J_d_xy->setIdentity();
        if (J_d_k) std::fill(J_d_k, J_d_k + 8, 0.0);
        return xy;
      }
      const double th = std::atan(r);
      const double t2 = th * th;
      const double poly = 1.0 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4)));
      const double thd = th * poly;
      const double scale = thd / r;
      if (J_d_xy) {
        const double dthd_dth = 1.0 + t2 * (3.0 * k1 + t2 * (5.0 * k2 + t2 * (7.0 * k3 + 9.0 * t2 * k4)));
        const double dth_dr = 1.0 / (1.0 + r * r);
        const double dscale_dr = (dthd_dth * dth_dr * r - thd) / (r * r);
        const Vec2 dr_dxy(x / r, y / r);
        *J_d_xy = scale * Mat2::Identity() + dscale_dr * xy * dr_dxy.transpose();
      }
      if (J_d_k) {
        // d(scale xy)/dk_i = xy theta^(2i+1) / r.
        double tp = th * t2 / r;
        for (int i = 0; i < 4; ++i, tp *= t2) {
          J_d_k[2 * i] = x * tp;
          J_d_k[2 * i + 1] = y * tp;
        }
      }
      return scale * xy;
    }
  }
  return xy;
}

}  // namespace

Vec2 CameraModel::distort(const Vec2& xy, Mat2* J) const {
  return distortWith(distortion_, params_ + 4, static_cast<int>(coeffs_.size()), xy, J, nullptr);
}

VecX CameraModel::intrinsicsVector() const {
  return Eigen::Map<const VecX>(params_, intrinsicsSize());
}

CameraModel CameraModel::withIntrinsics(const VecX& intrinsics) const {
  if (intrinsics.size() != intrinsicsSize())
    throw VisionError("intrinsics vector: expected " + std::to_string(intrinsicsSize()) +
                      " values [fx fy cx cy, distortion coefficients] for distortion model " +
                      toString(distortion_) + ", got " + std::to_string(intrinsics.size()));
  return CameraModel(projection_, distortion_, intrinsics[0], intrinsics[1], intrinsics[2], intrinsics[3],
                     std::vector<double>(intrinsics.data() + 4, intrinsics.data() + intrinsics.size()), width_,
                     height_);
}

bool CameraModel::projectWith(const double* in, const Vec3& p, Vec2* uv, Mat23* J_uv_p,
                              double* J_uv_in) const {
  if (!(p.z() > 1e-9)) return false;
  const int ncoeff = static_cast<int>(coeffs_.size());
  const double fx = in[0], fy = in[1];
  const double iz = 1.0 / p.z();
  const Vec2 xy(p.x() * iz, p.y() * iz);
  Mat2 J_d_xy;
  const Vec2 d = distortWith(distortion_, in + 4, ncoeff, xy, J_uv_p ? &J_d_xy : nullptr,
                             J_uv_in ? J_uv_in + 8 : nullptr);
  if (J_uv_p) {
    Mat23 J_xy_p;
    J_xy_p << iz, 0.0, -xy.x() * iz, 0.0, iz, -xy.y() * iz;
    Mat2 F = Mat2::Zero();
    F(0, 0) = fx;
    F(1, 1) = fy;
    *J_uv_p = F * J_d_xy * J_xy_p;
  }
  if (J_uv_in) {
    // fx, fy, cx, cy; the coefficients' columns (written by distortWith from
    // column 4 on) scaled by the focal lengths.
    const double head[8] = {d.x(), 0.0, 0.0, d.y(), 1.0, 0.0, 0.0, 1.0};
    std::copy(head, head + 8, J_uv_in);
    for (int i = 0; i < ncoeff; ++i) {
      J_uv_in[8 + 2 * i] *= fx;
      J_uv_in[9 + 2 * i] *= fy;
    }
  }
  *uv = Vec2(fx * d.x() + in[2], fy * d.y() + in[3]);
  return true;
}

std::optional<Vec2> CameraModel::undistort(const Vec2& xyd) const {
  switch (distortion_) {
    case Distortion::None:
      return xyd;
    case Distortion::Equidistant: {
      // Invert theta_d = theta (1 + k1 θ² + k2 θ⁴ + k3 θ⁶ + k4 θ⁸) by Newton in θ.
      const double rd = xyd.norm();
      if (rd < 1e-12) return xyd;
      const double* k = params_ + 4;
      const double k1 = k[0], k2 = k[1], k3 = k[2], k4 = k[3];
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
  Vec2 uv;
  if (!projectWith(params_, p, &uv, J_uv_p)) return std::nullopt;
  return uv;
}

std::optional<Vec3> CameraModel::unproject(const Vec2& uv) const {
  const Vec2 xyd((uv.x() - cx_) / fx_, (uv.y() - cy_) / fy_);
  const auto xy = undistort(xyd);
  if (!xy) return std::nullopt;
  return Vec3(xy->x(), xy->y(), 1.0).normalized();
}

}  // namespace fgcal::vision
