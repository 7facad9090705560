// Inverse-mapping renderer of a ChArUco board through a CameraModel.
#include "fgcal/vision/board_renderer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "fgcal/vision/vision_error.hpp"

namespace fgcal::vision {

namespace {

void checkPoses(std::size_t poses, int per_row, int H) {
  if (per_row < 1 ||
      (poses != static_cast<size_t>(per_row) && poses != static_cast<size_t>(per_row) * static_cast<size_t>(H)))
    throw VisionError("BoardRenderer::renderMoving: expected per_row >= 1 and per_row or per_row * height (" +
                      std::to_string(H) + ") poses, got " + std::to_string(poses) + " poses with " +
                      "per_row " + std::to_string(per_row));
}

/// Board point (X, Y) -> the texture point drawn there under corner jitter:
/// (X, Y) - d(X, Y), d interpolated bilinearly from the offsets at the grid
/// nodes of the square it falls in.
struct JitterWarp {
  JitterWarp(const std::vector<Eigen::Vector2d>& offsets, const CharucoTarget& t)
      : node_offsets(offsets), target(t), nodes_x(t.squares_x + 1), inv_square(1.0 / t.square_size) {}

  const std::vector<Eigen::Vector2d>& node_offsets;
  const CharucoTarget& target;
  const int nodes_x;
  const double inv_square;

  void operator()(double& X, double& Y) const {
    const double gx = X * inv_square, gy = Y * inv_square;
    const int i = std::clamp(static_cast<int>(std::floor(gx)), 0, target.squares_x - 1);
    const int j = std::clamp(static_cast<int>(std::floor(gy)), 0, target.squares_y - 1);
    const double ax = std::clamp(gx - i, 0.0, 1.0), ay = std::clamp(gy - j, 0.0, 1.0);
    const Eigen::Vector2d* n0 = &node_offsets[static_cast<size_t>(j) * nodes_x + i];
    const Eigen::Vector2d* n1 = n0 + nodes_x;
    const Eigen::Vector2d d = (1 - ay) * ((1 - ax) * n0[0] + ax * n0[1]) + ay * ((1 - ax) * n1[0] + ax * n1[1]);
    X -= d.x();
    Y -= d.y();
  }
};

/// Which kTile x kTile blocks of pixels can see the texture: those whose ray
/// bounds (`tile_bounds`: min x, max x, min y, max y per block) meet the
/// bounding box, on the normalized image plane, of the projections of the
/// texture's rectangle [x0, x1] x [y0, y1] (marker frame, z = 0) at every
/// pose. A texture partly behind the camera keeps every block.
std::vector<char> activeTiles(const std::vector<float>& tile_bounds, const std::vector<SE3>& T_cam_marker, double x0,
                              double x1, double y0, double y1) {
  std::vector<char> tile_active(tile_bounds.size() / 4, 1);
  double nx0 = std::numeric_limits<double>::infinity(), nx1 = -nx0, ny0 = nx0, ny1 = -nx0;
  bool in_front = true;
  for (const SE3& T : T_cam_marker)
    for (const Vec3& corner : {Vec3(x0, y0, 0), Vec3(x1, y0, 0), Vec3(x0, y1, 0), Vec3(x1, y1, 0)}) {
      const Vec3 p = T * corner;
      if (!(p.z() > 1e-6)) in_front = false;
      nx0 = std::min(nx0, p.x() / p.z());
      nx1 = std::max(nx1, p.x() / p.z());
      ny0 = std::min(ny0, p.y() / p.z());
      ny1 = std::max(ny1, p.y() / p.z());
    }
  if (in_front) {
    const double eps = 1e-4;  // float rays
    for (size_t t = 0; t < tile_active.size(); ++t) {
      const float* b = &tile_bounds[t * 4];
      tile_active[t] = b[1] >= nx0 - eps && b[0] <= nx1 + eps && b[3] >= ny0 - eps && b[2] <= ny1 + eps;
    }
  }
  return tile_active;
}

/// The rendered radiance as the camera records it: blur, gain and offset,
/// noise, then rounded and saturated to 8 bits.
cv::Mat finished(cv::Mat img, const RenderOptions& o) {
  const int H = img.rows, W = img.cols;
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

}  // namespace

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

  tiles_x_ = (W + kTile - 1) / kTile;
  tiles_y_ = (H + kTile - 1) / kTile;
  const float inf = std::numeric_limits<float>::infinity();
  tile_bounds_.assign(static_cast<size_t>(tiles_x_) * tiles_y_ * 4, 0.0f);
  for (int t = 0; t < tiles_x_ * tiles_y_; ++t) {
    float* b = &tile_bounds_[static_cast<size_t>(t) * 4];
    b[0] = b[2] = inf;
    b[1] = b[3] = -inf;
  }
  const int n_samples = ss_ * ss_;
  for (int v = 0; v < H; ++v)
    for (int u = 0; u < W; ++u) {
      float* b = &tile_bounds_[(static_cast<size_t>(v / kTile) * tiles_x_ + u / kTile) * 4];
      const float* ray = &rays_[(static_cast<size_t>(v) * W + u) * n_samples * 2];
      for (int k = 0; k < n_samples; ++k) {
        const float x = ray[2 * k], y = ray[2 * k + 1];
        if (std::isnan(x)) continue;
        b[0] = std::min(b[0], x);
        b[1] = std::max(b[1], x);
        b[2] = std::min(b[2], y);
        b[3] = std::max(b[3], y);
      }
    }
}

std::vector<Eigen::Vector2d> cornerJitterOffsets(const CharucoTarget& target, const RenderOptions& o) {
  const int nx = target.squares_x + 1, ny = target.squares_y + 1;
  std::vector<Eigen::Vector2d> d(static_cast<size_t>(nx) * ny, Eigen::Vector2d::Zero());
  if (!std::isfinite(o.corner_jitter_m) || o.corner_jitter_m < 0.0 || !o.corner_jitter_shape.allFinite())
    throw VisionError("RenderOptions.corner_jitter_m / corner_jitter_shape: expected finite values, the jitter >= 0");
  if (o.corner_jitter_m == 0.0) return d;
  // cv::RNG: the same stream on every platform, like the intensity noise.
  cv::RNG rng(o.jitter_seed);
  for (auto& v : d) {
    const double a = rng.gaussian(1.0);
    const double b = rng.gaussian(1.0);
    v = o.corner_jitter_m * (o.corner_jitter_shape * Eigen::Vector2d(a, b));
  }
  return d;
}

cv::Mat BoardRenderer::render(const SE3& T_cam_marker, const RenderOptions& o) const {
  return renderMoving({T_cam_marker}, 1, o);
}

cv::Mat BoardRenderer::renderMoving(const std::vector<SE3>& T_cam_marker, int per_row, const RenderOptions& o) const {
  const int W = camera_.width(), H = camera_.height();
  checkPoses(T_cam_marker.size(), per_row, H);
  const bool same_rows = T_cam_marker.size() == static_cast<size_t>(per_row);
  cv::Mat img(H, W, CV_32F);

  // Corner jitter: offsets at the grid nodes, interpolated bilinearly per square.
  const bool jitter = o.corner_jitter_m != 0.0;  // NaN and negative values reach the check
  const std::vector<Eigen::Vector2d> node_offsets =
      jitter ? cornerJitterOffsets(target_, o) : std::vector<Eigen::Vector2d>{};
  const JitterWarp warp(node_offsets, target_);
  // Per pose: the ray (x, y, 1) from the camera centre, expressed in the marker frame.
  std::vector<Mat3> Rts;
  std::vector<Vec3> origins;
  for (const SE3& T : T_cam_marker) {
    Rts.push_back(T.rotation().transpose());
    origins.push_back(-(Rts.back() * T.translation()));
  }
  // Texture pixel-centre coordinates of board point (X, Y): margin + X / square * P - 0.5.
  const double scale = px_per_square_ / target_.square_size;
  const double shift = margin_px_ - 0.5;
  // Texture levels 0..255 map linearly to board_black..board_white.
  const double tex_gain = (o.board_white - o.board_black) / 255.0;
  const int tw = texture_.cols, th = texture_.rows;
  const int n_samples = ss_ * ss_;

  // Blocks of pixels that can see the texture, grown by the largest jitter offset.
  double pad = 0.0;
  for (const auto& d : node_offsets) pad = std::max(pad, d.norm());
  const std::vector<char> tile_active =
      activeTiles(tile_bounds_, T_cam_marker, (0.0 - shift) / scale - pad, (tw - 1 - shift) / scale + pad,
                  (0.0 - shift) / scale - pad, (th - 1 - shift) / scale + pad);

  // The gray level that a sample's ray (x, y) sees of the board at one pose.
  auto sample = [&](const Mat3& Rt, const Vec3& origin, double x, double y) {
    if (std::isnan(x)) return o.background;
    const Vec3 d = Rt.col(0) * x + Rt.col(1) * y + Rt.col(2);
    const double lambda = d.z() != 0.0 ? -origin.z() / d.z() : -1.0;
    if (!(lambda > 0.0)) return o.background;
    double X = origin.x() + lambda * d.x(), Y = origin.y() + lambda * d.y();
    if (jitter) warp(X, Y);
    const double tx = X * scale + shift;
    const double ty = Y * scale + shift;
    if (!(tx >= 0.0 && ty >= 0.0 && tx <= tw - 1 && ty <= th - 1)) return o.background;
    const int x0 = std::min(static_cast<int>(tx), tw - 2);
    const int y0 = std::min(static_cast<int>(ty), th - 2);
    const double ax = tx - x0, ay = ty - y0;
    const uchar* t0 = texture_.ptr<uchar>(y0) + x0;
    const uchar* t1 = texture_.ptr<uchar>(y0 + 1) + x0;
    const double tex = (1 - ay) * ((1 - ax) * t0[0] + ax * t0[1]) + ay * ((1 - ax) * t1[0] + ax * t1[1]);
    return o.board_black + tex_gain * tex;
  };

  cv::parallel_for_(cv::Range(0, H), [&](const cv::Range& range) {
    for (int v = range.start; v < range.end; ++v) {
      float* row = img.ptr<float>(v);
      const char* active = &tile_active[static_cast<size_t>(v / kTile) * tiles_x_];
      const size_t first_pose = same_rows ? 0 : static_cast<size_t>(v) * per_row;
      const int n_values = n_samples * per_row;
      for (int u = 0; u < W; ++u) {
        const float* ray = &rays_[(static_cast<size_t>(v) * W + u) * n_samples * 2];
        double acc = 0.0;
        if (!active[u / kTile]) {  // the same sum a traced miss gives
          for (int s = 0; s < n_values; ++s) acc += o.background;
          row[u] = static_cast<float>(acc / n_values);
          continue;
        }
        for (int p = 0; p < per_row; ++p) {
          const size_t k = first_pose + static_cast<size_t>(p);
          for (int s = 0; s < n_samples; ++s) acc += sample(Rts[k], origins[k], ray[2 * s], ray[2 * s + 1]);
        }
        row[u] = static_cast<float>(acc / n_values);
      }
    }
  });

  return finished(img, o);
}

cv::Mat renderBoard(const CameraModel& camera, const CharucoTarget& target,
                    const SE3& T_cam_marker, const RenderOptions& options) {
  return BoardRenderer(camera, target, options.supersampling).render(T_cam_marker, options);
}

}  // namespace fgcal::vision
