// Renders the image a camera would see of a ChArUco board at T_cam_marker,
// for simulation and tests: every output pixel is supersampled, each sample's
// ray (cached per camera: the camera is fixed, only the pose changes) is
// intersected with the board plane z = 0 and looks up OpenCV's own drawing of
// the board (bilinear); optional blur, brightness change and noise follow.
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
};

class BoardRenderer {
 public:
  /// Precomputes one ray per sample (supersampling^2 per pixel) and draws the
  /// board texture at `texture_px_per_square` pixels per square with one
  /// square of white margin around the board (the board's quiet zone).
  BoardRenderer(const CameraModel& camera, const CharucoTarget& target, int supersampling = 4,
                int texture_px_per_square = 200);

  /// 8-bit grayscale image of camera.width() x camera.height(). Uses all cores.
  cv::Mat render(const SE3& T_cam_marker, const RenderOptions& options = {}) const;

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
};

/// One-shot convenience: builds a BoardRenderer (options.supersampling) and renders.
cv::Mat renderBoard(const CameraModel& camera, const CharucoTarget& target,
                    const SE3& T_cam_marker, const RenderOptions& options = {});

}  // namespace fgcal::vision
