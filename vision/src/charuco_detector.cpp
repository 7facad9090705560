// ChArUco detection on top of the aruco adapter: corner refinement that
// removes OpenCV 4.6's half-pixel bias, and the checks for usable views.
#include "fgcal/vision/charuco_detector.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include <Eigen/Eigenvalues>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "aruco_adapter.hpp"
#include "fgcal/vision/image_header.hpp"
#include "fgcal/vision/vision_error.hpp"

namespace fgcal::vision {

std::string toString(DetectionStatus s) {
  switch (s) {
    case DetectionStatus::Ok: return "ok";
    case DetectionStatus::UnreadableImage: return "unreadable image";
    case DetectionStatus::NoMarkers: return "no markers";
    case DetectionStatus::TooFewCorners: return "too few corners";
    case DetectionStatus::Collinear: return "collinear corners";
  }
  return "?";
}

namespace {

// Median marker side in pixels: the scale at which to refine corners.
double medianMarkerSide(const detail::MarkerSet& m) {
  std::vector<double> sides;
  for (const auto& c : m.corners)
    for (int k = 0; k < 4; ++k) {
      const cv::Point2f d = c[k] - c[(k + 1) % 4];
      sides.push_back(std::hypot(d.x, d.y));
    }
  if (sides.empty()) return 0.0;
  std::nth_element(sides.begin(), sides.begin() + static_cast<long>(sides.size() / 2), sides.end());
  return sides[sides.size() / 2];
}

}  // namespace

CharucoDetector::CharucoDetector(CharucoTarget target, DetectorOptions options)
    : target_(std::move(target)), options_(options) {
  target_.validate();
  if (options_.min_corners < 4)
    throw VisionError("DetectorOptions.min_corners: expected >= 4 (PnP needs 4 points), got " +
                      std::to_string(options_.min_corners));
  if (!(options_.refine_blur_sigma >= 0.0))
    throw VisionError("DetectorOptions.refine_blur_sigma: expected >= 0");
  board_ = detail::makeArucoBoard(target_);
  corner_markers_ = detail::nearestMarkerCorners(*board_);
}

bool cornersCollinear(const std::vector<Vec3>& P, double square_size, double fraction) {
  if (P.size() < 3) return true;
  const double n = static_cast<double>(P.size());
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& p : P) mean += p.head<2>();
  mean /= n;
  Eigen::Matrix2d C = Eigen::Matrix2d::Zero();
  for (const auto& p : P) {
    const Eigen::Vector2d d = p.head<2>() - mean;
    C += d * d.transpose();
  }
  C /= n;
  // Smallest eigenvalue = mean squared distance from the best-fit line.
  const double off_line =
      std::sqrt(std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(C).eigenvalues()(0)));
  return off_line < fraction * square_size;
}

void CharucoDetector::refineCorners(const cv::Mat& gray, const detail::MarkerSet& markers,
                                    const std::vector<int>& ids,
                                    std::vector<cv::Point2f>* corners) const {
  const double median_side = medianMarkerSide(markers);
  for (size_t i = 0; i < ids.size(); ++i) {
    cv::Point2f& c = (*corners)[i];
    // Window per corner: it must stay clear of the markers next to the
    // corner, whose edges would pull it (and the smoothing spreads them by
    // about 2 sigma). Under perspective this distance varies from corner to
    // corner, so it is measured on the detected marker corners.
    double d_min = std::numeric_limits<double>::infinity();
    if (ids[i] >= 0 && static_cast<size_t>(ids[i]) < corner_markers_.size()) {
      for (const auto& [marker_id, k] : corner_markers_[static_cast<size_t>(ids[i])]) {
        for (size_t m = 0; m < markers.ids.size(); ++m) {
          if (markers.ids[m] != marker_id) continue;
          const cv::Point2f d = markers.corners[m][static_cast<size_t>(k)] - c;
          d_min = std::min(d_min, static_cast<double>(std::hypot(d.x, d.y)));
        }
      }
    }
    if (!std::isfinite(d_min)) {
      d_min = median_side / target_.marker_size * 0.5 *
              (target_.square_size - target_.marker_size) * std::sqrt(2.0);
    }
    // Half-width of the window: clear of the markers, less the ~2 sigma by
    // which the smoothing spreads their edges. (A smaller sigma where the gap
    // is small was tried: no better on 60 rendered views.)
    const double clear = d_min / std::sqrt(2.0);
    const double sigma = options_.refine_blur_sigma;
    const bool smooth = options_.refine_blur_sigma > 0.0;
    const int half = std::clamp(
        static_cast<int>(std::floor(clear - (smooth ? 2.0 * sigma : 0.0))), 2, 12);
    // Smooth only a patch around the corner: a new buffer (gray may share the
    // caller's pixels) large enough for cornerSubPix to move its window.
    const int r = half + 8 + (smooth ? static_cast<int>(std::ceil(4.0 * sigma)) : 0);
    const cv::Rect roi = cv::Rect(static_cast<int>(std::lround(c.x)) - r,
                                  static_cast<int>(std::lround(c.y)) - r, 2 * r + 1, 2 * r + 1) &
                         cv::Rect(0, 0, gray.cols, gray.rows);
    if (roi.width < 2 * half + 5 || roi.height < 2 * half + 5) {
      // Too close to the image border to refine: remove the known offset only.
      c -= cv::Point2f(0.5f, 0.5f);
      continue;
    }
    cv::Mat patch;
    if (smooth) {
      cv::GaussianBlur(gray(roi), patch, cv::Size(0, 0), sigma);
    } else {
      patch = gray(roi);
    }
    std::vector<cv::Point2f> one{c - cv::Point2f(static_cast<float>(roi.x), static_cast<float>(roi.y))};
    cv::cornerSubPix(patch, one, cv::Size(half, half), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 100, 1e-4));
    const cv::Point2f refined = one[0] + cv::Point2f(static_cast<float>(roi.x), static_cast<float>(roi.y));
    // A corner that wanders off (e.g. a marker edge won) keeps the interpolated
    // position, without the known offset.
    const cv::Point2f moved = refined - c;
    if (std::hypot(moved.x, moved.y) > std::max(2.0, 0.5 * half)) {
      c -= cv::Point2f(0.5f, 0.5f);
    } else {
      c = refined;
    }
  }
}

cv::Mat readGrayImage(const std::string& path) {
  cv::Mat img = readGrayChecked(path, {});  // ImageSizeMismatch (a VisionError) for a header over the cap
  if (img.empty())
    throw VisionError("cannot read image '" + path +
                      "': missing file or not a format OpenCV can decode (expected PNG/JPEG)");
  return img;
}

CharucoDetection CharucoDetector::detectFile(const std::string& path) const {
  cv::Mat img;
  try {
    img = readGrayChecked(path, {});
  } catch (const ImageSizeMismatch& e) {
    CharucoDetection d;
    d.source = path;
    d.status = DetectionStatus::UnreadableImage;
    d.message = e.what();
    return d;
  }
  if (img.empty()) {
    CharucoDetection d;
    d.source = path;
    d.status = DetectionStatus::UnreadableImage;
    d.message = "cannot read image '" + path +
                "': missing file or not a format OpenCV can decode (expected PNG/JPEG)";
    return d;
  }
  CharucoDetection d = detect(img);
  d.source = path;
  if (!d.ok()) d.message = path + ": " + d.message;
  return d;
}


CharucoDetection CharucoDetector::detect(const cv::Mat& image) const {
  CharucoDetection out;
  if (image.empty()) {
    out.status = DetectionStatus::UnreadableImage;
    out.message = "empty image";
    return out;
  }
  cv::Mat gray;
  if (image.channels() == 3) {
    cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
  } else if (image.channels() == 4) {
    cv::cvtColor(image, gray, cv::COLOR_BGRA2GRAY);
  } else {
    gray = image;
  }
  if (gray.depth() != CV_8U) gray.convertTo(gray, CV_8U);
  out.width = gray.cols;
  out.height = gray.rows;

  const detail::MarkerSet markers = detail::detectMarkers(*board_, gray);
  out.marker_ids = markers.ids;
  if (markers.ids.empty()) {
    out.status = DetectionStatus::NoMarkers;
    out.message = "no ArUco markers of " + target_.dictionary + " detected";
    return out;
  }
  std::vector<cv::Point2f> corners;
  std::vector<int> ids;
  detail::interpolateCorners(*board_, markers, gray, &corners, &ids);

  if (!corners.empty()) {
    switch (options_.refinement) {
      case CornerRefinement::CornerSubPix:
        refineCorners(gray, markers, ids, &corners);
        break;
      case CornerRefinement::SubtractHalfPixel:
        for (auto& c : corners) c -= cv::Point2f(0.5f, 0.5f);
        break;
      case CornerRefinement::None:
        break;
    }
  }

  // Sort by id: callers and tests rely on increasing ids.
  std::vector<size_t> order(ids.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return ids[a] < ids[b]; });
  for (size_t i : order) {
    out.ids.push_back(ids[i]);
    out.corners.emplace_back(corners[i].x, corners[i].y);
    out.object_points.push_back(target_.cornerPosition(ids[i]));
  }

  const int n = static_cast<int>(out.ids.size());
  if (n < options_.min_corners) {
    out.status = DetectionStatus::TooFewCorners;
    out.message = std::to_string(n) + " ChArUco corners from " +
                  std::to_string(markers.ids.size()) + " markers; at least " +
                  std::to_string(options_.min_corners) + " needed";
    return out;
  }
  const bool collinear = cornersCollinear(out.object_points, target_.square_size, options_.collinear_fraction);
  if (collinear) {
    out.status = DetectionStatus::Collinear;
    out.message = std::to_string(n) + " ChArUco corners lie (nearly) on one line";
    return out;
  }
  out.status = DetectionStatus::Ok;
  return out;
}

}  // namespace fgcal::vision
