// ChArUco detection: ArUco markers, then ChArUco corners interpolated with
// their ids, then sub-pixel refinement that removes OpenCV 4.6's half-pixel
// corner offset (docs/toolchain.md, gotcha 1), then the checks that make a view
// usable for PnP (enough corners, not all on one line). Corners come out in
// the pixel-centre convention of CameraModel::project and cv::projectPoints.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "fgcal/vision/camera_model.hpp"
#include "fgcal/vision/charuco_target.hpp"

namespace fgcal::vision {

namespace detail {
struct ArucoBoard;
struct MarkerSet;
}

enum class DetectionStatus {
  Ok,
  UnreadableImage,  ///< the file could not be read or the image is empty
  NoMarkers,        ///< zero markers (and so zero corners) detected
  TooFewCorners,    ///< fewer corners than DetectorOptions::min_corners
  Collinear,        ///< corners (nearly) on one line: PnP is degenerate
};
std::string toString(DetectionStatus s);

/// How the half-pixel bias of OpenCV 4.6's interpolated corners is removed.
enum class CornerRefinement {
  /// Re-run cv::cornerSubPix on the interpolated corners (default), on a
  /// lightly smoothed copy, with a window per corner that stays clear of the
  /// neighbouring markers. Rendered boards: mean offset < 0.001 px, RMS 0.03-0.04 px.
  CornerSubPix,
  SubtractHalfPixel,  ///< subtract 0.5 px in x and y (mean offset < 0.01 px, RMS 0.055 px)
  None,               ///< keep OpenCV 4.6's corners as they are (biased; for comparison)
};

struct DetectorOptions {
  int min_corners = 6;
  CornerRefinement refinement = CornerRefinement::CornerSubPix;
  /// cornerSubPix runs on a copy of the image smoothed with this Gaussian
  /// std (pixels). Sharp images otherwise pull corners towards pixel
  /// boundaries (pixel locking, up to 0.1 px on rendered boards); a symmetric
  /// blur keeps an X-junction where it is. 0 = refine on the image itself.
  double refine_blur_sigma = 1.0;
  /// Degenerate when the RMS distance of the corners' board positions from
  /// their best-fit line is below this fraction of a square.
  double collinear_fraction = 0.25;
};

struct CharucoDetection {
  DetectionStatus status = DetectionStatus::NoMarkers;
  std::string message;  ///< why it was rejected (empty when Ok); names the file when known
  std::string source;   ///< file path when detected from a file
  std::vector<int> marker_ids;
  std::vector<int> ids;              ///< ChArUco corner ids, increasing
  std::vector<Vec2> corners;         ///< pixels, pixel-centre convention
  std::vector<Vec3> object_points;   ///< board frame, same order as ids
  int width = 0, height = 0;
  bool ok() const { return status == DetectionStatus::Ok; }
};

class CharucoDetector {
 public:
  /// Validates the target (throws VisionError on bad fields / unknown dictionary).
  explicit CharucoDetector(CharucoTarget target, DetectorOptions options = {});

  /// Detection in an image (8-bit grayscale or BGR). Never throws on image
  /// content: a rejected view comes back with status and message.
  CharucoDetection detect(const cv::Mat& image) const;
  /// Reads the file (grayscale); an unreadable file gives status
  /// UnreadableImage and a message with the path.
  CharucoDetection detectFile(const std::string& path) const;

  const CharucoTarget& target() const { return target_; }
  const DetectorOptions& options() const { return options_; }

 private:
  void refineCorners(const cv::Mat& gray, const detail::MarkerSet& markers,
                     const std::vector<int>& ids, std::vector<cv::Point2f>* corners) const;

  CharucoTarget target_;
  DetectorOptions options_;
  std::shared_ptr<const detail::ArucoBoard> board_;
  std::vector<std::vector<std::pair<int, int>>> corner_markers_;  // per corner id
};

/// True when the board points lie (nearly) on one line: RMS distance from
/// their best-fit line below `fraction` * square_size.
bool cornersCollinear(const std::vector<Vec3>& object_points, double square_size, double fraction);

/// Reads an image as 8-bit grayscale; throws VisionError naming the path when
/// the file cannot be read.
cv::Mat readGrayImage(const std::string& path);

}  // namespace fgcal::vision
