// The report's overlay pictures (report_parts.hpp): detected and predicted
// corners over the part of the image around the board.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "report/report_parts.hpp"

namespace fgcal::apps::report {

namespace {

/// Pictures are scaled to this width, so that a pixel of error can be seen.
constexpr int kOverlayWidth = 720;

/// The board's box (detected and predicted corners) with a margin, at the
/// image's aspect ratio; the whole image when no corner is finite.
cv::Rect boardRegion(const ReportOverlay& o, const cv::Mat& img) {
  double x0 = img.cols, y0 = img.rows, x1 = 0, y1 = 0;
  for (const auto* pts : {&o.detected_px, &o.predicted_px})
    for (const auto& p : *pts)
      if (p.allFinite()) {
        x0 = std::min(x0, p.x()), y0 = std::min(y0, p.y()), x1 = std::max(x1, p.x()), y1 = std::max(y1, p.y());
      }
  const cv::Rect whole(0, 0, img.cols, img.rows);
  if (!(x1 > x0 && y1 > y0)) return whole;
  const double aspect = static_cast<double>(img.cols) / img.rows;
  double w = (x1 - x0) * 1.5 + 40.0, h = (y1 - y0) * 1.5 + 40.0;
  if (w / h < aspect) w = h * aspect; else h = w / aspect;
  w = std::min<double>(w, img.cols), h = std::min<double>(h, img.rows);
  const double cx = std::clamp(0.5 * (x0 + x1), w / 2, img.cols - w / 2);
  const double cy = std::clamp(0.5 * (y0 + y1), h / 2, img.rows - h / 2);
  return cv::Rect(static_cast<int>(cx - w / 2), static_cast<int>(cy - h / 2), static_cast<int>(w),
                  static_cast<int>(h)) &
         whole;
}

}  // namespace

void drawOverlay(const ReportOverlay& o, const cv::Mat& image, const std::string& path) {
  cv::Mat img;
  if (image.channels() == 1) cv::cvtColor(image, img, cv::COLOR_GRAY2BGR);
  else img = image.clone();
  const cv::Rect roi = boardRegion(o, img);
  const double scale = static_cast<double>(kOverlayWidth) / roi.width;
  cv::resize(img(roi), img, cv::Size(), scale, scale, scale > 1.0 ? cv::INTER_LINEAR : cv::INTER_AREA);
  const int r = std::max(4, static_cast<int>(std::lround(kOverlayWidth / 110.0)));
  const int thick = 2;
  auto pt = [&](const Eigen::Vector2d& p) {
    // Sub-pixel drawing: OpenCV's fixed-point shift of 4 bits.
    return cv::Point(static_cast<int>(std::lround((p.x() - roi.x) * scale * 16.0)),
                     static_cast<int>(std::lround((p.y() - roi.y) * scale * 16.0)));
  };
  for (const auto& p : o.detected_px)
    if (p.allFinite()) cv::circle(img, pt(p), r * 16, cv::Scalar(0, 200, 0), thick, cv::LINE_AA, 4);
  for (const auto& p : o.predicted_px) {
    if (!p.allFinite()) continue;
    const cv::Point c = pt(p), dx(r * 16, 0), dy(0, r * 16);
    cv::line(img, c - dx, c + dx, cv::Scalar(40, 40, 230), thick, cv::LINE_AA, 4);
    cv::line(img, c - dy, c + dy, cv::Scalar(40, 40, 230), thick, cv::LINE_AA, 4);
  }
  if (!cv::imwrite(path, img)) throw std::runtime_error("cannot write " + path);
}

}  // namespace fgcal::apps::report
