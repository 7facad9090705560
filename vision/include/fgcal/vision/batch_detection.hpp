// Detection (and optionally pose) over many images on every core. Results
// come back in input order; an unreadable image or a rejected view is a
// per-image status, never an exception that stops the batch.
#pragma once

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "fgcal/vision/charuco_detector.hpp"
#include "fgcal/vision/pnp.hpp"

namespace fgcal::vision {

struct FrameResult {
  CharucoDetection detection;
  std::optional<PoseEstimate> pose;  ///< set when a camera was given and the detection is Ok
  std::string pose_error;            ///< why the pose failed, when it did
};

/// Produces image `index` (e.g. reads a file). An empty cv::Mat means
/// unreadable; a thrown exception is caught and recorded for that image.
using ImageLoader = std::function<cv::Mat(std::size_t index)>;

/// Detects (and, when `camera` is given, estimates the pose) for `count`
/// images on `threads` worker threads (0 = std::thread::hardware_concurrency()).
/// The loader and detector are called from several threads at once.
std::vector<FrameResult> processImages(const CharucoDetector& detector, std::size_t count,
                                       const ImageLoader& loader,
                                       const CameraModel* camera = nullptr,
                                       const PnpOptions& pnp = {}, int threads = 0);

/// The same over image files (read as grayscale); unreadable files get status
/// UnreadableImage with the path in the message.
std::vector<FrameResult> processFiles(const CharucoDetector& detector,
                                      const std::vector<std::string>& paths,
                                      const CameraModel* camera = nullptr,
                                      const PnpOptions& pnp = {}, int threads = 0);

}  // namespace fgcal::vision
