// PnP through our own camera models and the vertex-jitter covariance.
#include "fgcal/vision/pnp.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "fgcal/vision/vision_error.hpp"

namespace fgcal::vision {

using MatX6 = Eigen::Matrix<double, Eigen::Dynamic, 6>;

bool reprojection(const CameraModel& camera, const SE3& T, const std::vector<Vec3>& P,
                  const std::vector<Vec2>& uv, Eigen::VectorXd* r, MatX6* J) {
  const Eigen::Index n = static_cast<Eigen::Index>(P.size());
  if (r) r->resize(2 * n);
  if (J) J->resize(2 * n, 6);
  for (Eigen::Index i = 0; i < n; ++i) {
    Mat36 J_p_T;
    const Vec3 p = T.act(P[static_cast<size_t>(i)], J ? &J_p_T : nullptr);
    Mat23 J_uv_p;
    const auto proj = camera.project(p, J ? &J_uv_p : nullptr);
    if (!proj) return false;
    if (r) r->segment<2>(2 * i) = *proj - uv[static_cast<size_t>(i)];
    if (J) J->middleRows<2>(2 * i) = J_uv_p * J_p_T;
  }
  return true;
}

namespace {
void checkCorrespondences(const std::vector<Vec3>& P, const std::vector<Vec2>& uv) {
  if (P.size() != uv.size())
    throw VisionError("estimatePose: " + std::to_string(P.size()) + " board points but " +
                      std::to_string(uv.size()) + " pixels");
  if (P.size() < 4)
    throw VisionError("estimatePose: at least 4 corners needed, got " + std::to_string(P.size()));
}
}  // namespace

PoseEstimate refinePose(const CameraModel& camera, const SE3& initial, const std::vector<Vec3>& P,
                        const std::vector<Vec2>& uv, const PnpOptions& options) {
  checkCorrespondences(P, uv);
  PoseEstimate est;
  SE3 T = initial;
  Eigen::VectorXd r;
  MatX6 J;
  if (!reprojection(camera, T, P, uv, &r, &J))
    throw VisionError("estimatePose: initial pose puts board points behind the camera");
  double cost = r.squaredNorm();
  double lambda = 1e-6;
  int it = 0;
  for (; it < options.max_iterations; ++it) {
    const Mat6 H = J.transpose() * J;
    const Vec6 g = J.transpose() * r;
    bool improved = false;
    Vec6 step = Vec6::Zero();
    for (int tries = 0; tries < 10 && !improved; ++tries) {
      Mat6 A = H;
      A.diagonal() += lambda * H.diagonal().cwiseMax(1e-12);
      step = -A.ldlt().solve(g);
      const SE3 T_new = T.plus(step);
      Eigen::VectorXd r_new;
      if (reprojection(camera, T_new, P, uv, &r_new, nullptr) && r_new.squaredNorm() <= cost) {
        T = T_new;
        cost = r_new.squaredNorm();
        improved = true;
        lambda = std::max(lambda * 0.1, 1e-12);
      } else {
        lambda *= 10.0;
      }
    }
    if (!improved) {
      est.converged = true;  // no decrease possible: at the minimum to rounding
      break;
    }
    reprojection(camera, T, P, uv, &r, &J);
    if (step.norm() < 1e-12) {
      est.converged = true;
      ++it;
      break;
    }
  }
  est.iterations = it;
  const Eigen::Index n = static_cast<Eigen::Index>(P.size());
  est.T_cam_marker = T;
  est.JtJ = J.transpose() * J;
  est.rms_px = std::sqrt(cost / static_cast<double>(n));
  est.residual_sigma_px = n > 3 ? std::sqrt(cost / static_cast<double>(2 * n - 6)) : 0.0;
  switch (options.sigma_source) {
    case PnpOptions::SigmaSource::PixelSigma: est.sigma_px = options.pixel_sigma; break;
    case PnpOptions::SigmaSource::Residuals: est.sigma_px = est.residual_sigma_px; break;
    case PnpOptions::SigmaSource::Larger: est.sigma_px = std::max(options.pixel_sigma, est.residual_sigma_px); break;
  }
  est.covariance = est.sigma_px * est.sigma_px * est.JtJ.ldlt().solve(Mat6::Identity());
  est.residuals.resize(P.size());
  for (Eigen::Index i = 0; i < n; ++i) est.residuals[static_cast<size_t>(i)] = r.segment<2>(2 * i);
  return est;
}

PoseEstimate estimatePose(const CameraModel& camera, const std::vector<Vec3>& P,
                          const std::vector<Vec2>& uv, const PnpOptions& options) {
  checkCorrespondences(P, uv);
  // Initial pose: planar PnP (IPPE) on normalized, undistorted points, which
  // takes every distortion model through our own unproject().
  std::vector<cv::Point3d> obj;
  std::vector<cv::Point2d> img;
  bool planar = true;
  for (size_t i = 0; i < P.size(); ++i) {
    const auto ray = camera.unproject(uv[i]);
    if (!ray || ray->z() <= 1e-9) continue;
    obj.emplace_back(P[i].x(), P[i].y(), P[i].z());
    img.emplace_back(ray->x() / ray->z(), ray->y() / ray->z());
    planar = planar && std::abs(P[i].z()) < 1e-12;
  }
  if (obj.size() < 4)
    throw VisionError("estimatePose: fewer than 4 corners could be undistorted");
  cv::Mat rvec, tvec;
  bool ok = false;
  try {
    ok = cv::solvePnP(obj, img, cv::Mat::eye(3, 3, CV_64F), cv::noArray(), rvec, tvec, false,
                      planar ? cv::SOLVEPNP_IPPE : cv::SOLVEPNP_ITERATIVE);
  } catch (const cv::Exception& e) {
    throw VisionError(std::string("estimatePose: initial PnP failed: ") + e.what());
  }
  if (!ok) throw VisionError("estimatePose: initial PnP found no pose");
  cv::Mat Rcv;
  cv::Rodrigues(rvec, Rcv);
  Mat3 R;
  Vec3 t;
  cv::cv2eigen(Rcv, R);
  cv::cv2eigen(tvec, t);
  return refinePose(camera, SE3(SO3(R).normalized(), t), P, uv, options);
}

PoseEstimate estimatePose(const CameraModel& camera, const CharucoDetection& detection,
                          const PnpOptions& options) {
  if (!detection.ok())
    throw VisionError("estimatePose: detection is not usable (" + toString(detection.status) +
                      (detection.message.empty() ? "" : ": " + detection.message) + ")");
  return estimatePose(camera, detection.object_points, detection.corners, options);
}

}  // namespace fgcal::vision
