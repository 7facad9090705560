// The adapter that holds every cv::aruco call of fgcal (docs/toolchain.md, gotcha 3:
// OpenCV 4.7 moved ArUco into objdetect with a new API). Porting fgcal to
// OpenCV 4.7+ means rewriting aruco_adapter.cpp only; nothing outside it
// includes <opencv2/aruco*.hpp>. Private to the vision module.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "fgcal/vision/charuco_target.hpp"

namespace fgcal::vision::detail {

/// Opaque: OpenCV's dictionary, board and detector parameters for one target.
/// Read-only after construction, so one instance serves many threads.
struct ArucoBoard;

/// Throws VisionError (listing the valid names) on an unknown dictionary.
std::shared_ptr<const ArucoBoard> makeArucoBoard(const CharucoTarget& target);

const std::vector<std::string>& predefinedDictionaryNames();
/// Number of markers in a predefined dictionary (name must be valid).
int dictionarySize(const std::string& name);

struct MarkerSet {
  std::vector<int> ids;
  std::vector<std::vector<cv::Point2f>> corners;
};

/// Markers in an 8-bit grayscale image (OpenCV's pixel-corner convention).
MarkerSet detectMarkers(const ArucoBoard& board, const cv::Mat& gray);

/// ChArUco corners interpolated from the markers by local homographies (no
/// camera model: OpenCV's variant that uses one cannot take fisheye models).
/// Returns the corners as OpenCV 4.6 gives them (half-pixel biased).
void interpolateCorners(const ArucoBoard& board, const MarkerSet& markers, const cv::Mat& gray,
                        std::vector<cv::Point2f>* corners, std::vector<int>* ids);

/// OpenCV's board drawing: image of `size` with at least `margin` white pixels.
cv::Mat drawBoard(const ArucoBoard& board, cv::Size size, int margin);

/// For each ChArUco corner id, the (marker id, marker corner index) pairs of
/// the markers next to it, as OpenCV's board precomputes them.
std::vector<std::vector<std::pair<int, int>>> nearestMarkerCorners(const ArucoBoard& board);

/// The chessboard corners the OpenCV board object holds.
std::vector<cv::Point3f> boardCorners(const ArucoBoard& board);

}  // namespace fgcal::vision::detail
