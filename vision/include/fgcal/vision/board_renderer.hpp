// Renders the image a camera would see of a ChArUco board at T_cam_marker,
// for simulation and tests: every output pixel is supersampled, each sample's
// ray (cached per camera: the camera is fixed, only the pose changes) is
// intersected with the board plane z = 0 and looks up OpenCV's own drawing of
// the board (bilinear); optional corner (vertex) jitter, blur, brightness
// change and noise follow.
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "fgcal/core/se3.hpp"
#include "fgcal/vision/camera_model.hpp"
#include "fgcal/vision/charuco_target.hpp"

namespace fgcal::vision {

struct RenderOptions {
  int supersampling = 4;        ///< samples per pixel side (renderBoard only; BoardRenderer fixes it)
  double blur_sigma = 0.0;      ///< Gaussian blur std in pixels, 0 = none
  double noise_sigma = 0.0;     ///< additive Gaussian noise std in gray levels, 0 = none
  double gain = 1.0;            ///< brightness: I' = gain * I + offset (before noise)
  double offset = 0.0;
  std::uint64_t seed = 0;       ///< noise seed: same seed, same image
  double background = 128.0;    ///< gray level off the board
  double board_white = 230.0;   ///< gray levels of the printed board's white and black
  double board_black = 25.0;

  /// Corner (vertex) jitter, the paper's corner noise model: the printed board
  /// is displaced in its own plane by a smooth random field d whose values at
  /// the chessboard grid nodes (every square corner, border nodes included)
  /// are independent 2-D offsets corner_jitter_m * corner_jitter_shape * n,
  /// n ~ N(0, I), bilinear across each square (constant beyond the border).
  /// Rendering is an inverse warp (texture looked up at p - d(p)), so a corner
  /// node c is imaged where c + d(c) would be. Intensity noise alone moves the
  /// detected corners by ~0.03 px; this makes the corner noise a chosen value:
  /// corner_jitter_m = sigma_px * depth / f for a fronto-parallel board.
  /// 0 = off (the image is then exactly what it was without this feature).
  double corner_jitter_m = 0.0;
  /// Shape of the offset distribution in the board plane (board x, y); e.g.
  /// (f / z) J^-1 with J = d(pixel)/d(board XY) makes the pixel noise isotropic
  /// on a tilted board.
  Eigen::Matrix2d corner_jitter_shape = Eigen::Matrix2d::Identity();
  std::uint64_t jitter_seed = 0;  ///< same seed, same offsets
};

/// The jitter offsets (metres, board frame) at the grid nodes that `options`
/// gives: (squares_x + 1) * (squares_y + 1) entries, node (i, j) at board point
/// (i, j) * square_size stored at j * (squares_x + 1) + i. The ChArUco corner
/// `id` is node (id % (squares_x - 1) + 1, id / (squares_x - 1) + 1). All zero
/// when corner_jitter_m is 0.
std::vector<Eigen::Vector2d> cornerJitterOffsets(const CharucoTarget& target,
                                                 const RenderOptions& options);

class BoardRenderer {
 public:
  /// Precomputes one ray per sample (supersampling^2 per pixel) and draws the
  /// board texture at `texture_px_per_square` pixels per square with one
  /// square of white margin around the board (the board's quiet zone).
  BoardRenderer(const CameraModel& camera, const CharucoTarget& target, int supersampling = 4,
                int texture_px_per_square = 200);

  /// 8-bit grayscale image of camera.width() x camera.height(). Uses all cores.
  cv::Mat render(const SE3& T_cam_marker, const RenderOptions& options = {}) const;

  /// A board moving while the image is taken (rolling shutter, motion blur):
  /// image row v averages, with equal weights, the board at the
  /// `per_row` poses T_cam_marker[v * per_row + k], k < per_row, or at
  /// T_cam_marker[k] for every row when T_cam_marker holds just per_row poses.
  /// The options (blur, noise, corner jitter) apply once, to the whole image.
  /// One pose gives exactly render(T_cam_marker[0], options). Throws
  /// VisionError for per_row < 1 or another number of poses.
  cv::Mat renderMoving(const std::vector<SE3>& T_cam_marker, int per_row, const RenderOptions& options = {}) const;

  const CameraModel& camera() const { return camera_; }
  const CharucoTarget& target() const { return target_; }
  int supersampling() const { return ss_; }
  /// The board texture (board drawn by OpenCV plus the white margin).
  const cv::Mat& texture() const { return texture_; }

 private:
  CameraModel camera_;
  CharucoTarget target_;
  int ss_;
  int px_per_square_;
  int margin_px_;
  cv::Mat texture_;          // CV_8U
  std::vector<float> rays_;  // (x/z, y/z) per sample; NaN where unproject failed
  // Bounds (min x, max x, min y, max y) of the rays of each kTile x kTile block
  // of pixels: blocks whose rays cannot reach the board are filled with the
  // background without tracing (most of a typical view; same pixels either way).
  static constexpr int kTile = 16;
  int tiles_x_ = 0, tiles_y_ = 0;
  std::vector<float> tile_bounds_;
};

/// One-shot convenience: builds a BoardRenderer (options.supersampling) and renders.
cv::Mat renderBoard(const CameraModel& camera, const CharucoTarget& target,
                    const SE3& T_cam_marker, const RenderOptions& options = {});

}  // namespace fgcal::vision
