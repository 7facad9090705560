// Inverse-mapping renderer of a ChArUco board through a CameraModel.
#include "fgcal/vision/board_renderer.hpp"

#include <cmath>
#include <limits>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "fgcal/vision/vision_error.hpp"

namespace fgcal::vision {

BoardRenderer::BoardRenderer(const CameraModel& camera, const CharucoTarget& target,
                             int supersampling, int texture_px_per_square)
    : camera_(camera), target_(target), ss_(supersampling), px_per_square_(texture_px_per_square),
      margin_px_(texture_px_per_square) {
  target_.validate();
  if (ss_ < 1 || ss_ > 16)
    throw VisionError("RenderOptions.supersampling: expected 1..16, got " + std::to_string(ss_));
  if (px_per_square_ < 16)
    throw VisionError("texture_px_per_square: expected >= 16, got " +
                      std::to_string(px_per_square_));
  texture_ = drawTarget(target_, px_per_square_, margin_px_);

  const int W = camera_.width(), H = camera_.height();
  rays_.assign(static_cast<size_t>(W) * H * ss_ * ss_ * 2, std::numeric_limits<float>::quiet_NaN());
  cv::parallel_for_(cv::Range(0, H), [&](const cv::Range& range) {
    for (int v = range.start; v < range.end; ++v)
      for (int u = 0; u < W; ++u)
        for (int sy = 0; sy < ss_; ++sy)
          for (int sx = 0; sx < ss_; ++sx) {
            // Pixel centres at integer coordinates; samples evenly inside the pixel.
            const Vec2 uv(u + (sx + 0.5) / ss_ - 0.5, v + (sy + 0.5) / ss_ - 0.5);
            const auto ray = camera_.unproject(uv);
            const size_t k = ((static_cast<size_t>(v) * W + u) * ss_ * ss_ + sy * ss_ + sx) * 2;
            if (ray && ray->z() > 1e-6) {
              rays_[k] = static_cast<float>(ray->x() / ray->z());
              rays_[k + 1] = static_cast<float>(ray->y() / ray->z());
            }
          }
  });
}

cv::Mat BoardRenderer::render(const SE3& T_cam_marker, const RenderOptions& o) const {
  const int W = camera_.width(), H = camera_.height();
  cv::Mat img(H, W, CV_32F);

  // Ray (x, y, 1) from the camera centre, expressed in the marker frame.
  const Mat3 Rt = T_cam_marker.rotation().transpose();
  const Vec3 origin = -(Rt * T_cam_marker.translation());
  // Texture pixel-centre coordinates of board point (X, Y): margin + X / square * P - 0.5.
  const double scale = px_per_square_ / target_.square_size;
  const double shift = margin_px_ - 0.5;
  // Texture levels 0..255 map linearly to board_black..board_white.
  const double tex_gain = (o.board_white - o.board_black) / 255.0;
  const int tw = texture_.cols, th = texture_.rows;
  const int n_samples = ss_ * ss_;

  cv::parallel_for_(cv::Range(0, H), [&](const cv::Range& range) {
    for (int v = range.start; v < range.end; ++v) {
      float* row = img.ptr<float>(v);
      for (int u = 0; u < W; ++u) {
        const float* ray = &rays_[(static_cast<size_t>(v) * W + u) * n_samples * 2];
        double acc = 0.0;
        for (int s = 0; s < n_samples; ++s) {
          const double x = ray[2 * s], y = ray[2 * s + 1];
          double value = o.background;
          if (!std::isnan(x)) {
            const Vec3 d = Rt.col(0) * x + Rt.col(1) * y + Rt.col(2);
            const double lambda = d.z() != 0.0 ? -origin.z() / d.z() : -1.0;
            if (lambda > 0.0) {
              const double tx = (origin.x() + lambda * d.x()) * scale + shift;
              const double ty = (origin.y() + lambda * d.y()) * scale + shift;
              if (tx >= 0.0 && ty >= 0.0 && tx <= tw - 1 && ty <= th - 1) {
                const int x0 = std::min(static_cast<int>(tx), tw - 2);
                const int y0 = std::min(static_cast<int>(ty), th - 2);
                const double ax = tx - x0, ay = ty - y0;
                const uchar* t0 = texture_.ptr<uchar>(y0) + x0;
                const uchar* t1 = texture_.ptr<uchar>(y0 + 1) + x0;
                const double tex = (1 - ay) * ((1 - ax) * t0[0] + ax * t0[1]) +
                                   ay * ((1 - ax) * t1[0] + ax * t1[1]);
                value = o.board_black + tex_gain * tex;
              }
            }
          }
          acc += value;
        }
        row[u] = static_cast<float>(acc / n_samples);
      }
    }
  });

  if (o.blur_sigma > 0.0) cv::GaussianBlur(img, img, cv::Size(0, 0), o.blur_sigma);
  if (o.gain != 1.0 || o.offset != 0.0) img = img * o.gain + o.offset;
  if (o.noise_sigma > 0.0) {
    cv::Mat noise(H, W, CV_32F);
    cv::RNG rng(o.seed);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, o.noise_sigma);
    img += noise;
  }
  cv::Mat out;
  img.convertTo(out, CV_8U);  // rounds and saturates
  return out;
}

cv::Mat renderBoard(const CameraModel& camera, const CharucoTarget& target,
                    const SE3& T_cam_marker, const RenderOptions& options) {
  return BoardRenderer(camera, target, options.supersampling).render(T_cam_marker, options);
}

}  // namespace fgcal::vision
