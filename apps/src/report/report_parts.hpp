// The pieces of the calibration report (fgcal/apps/report.hpp), each in a
// file of its own: the plots (report_plots.cpp), the page around them
// (report_page.cpp), the overlay pictures (report_overlay.cpp); report.cpp
// writes the folder.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "fgcal/apps/report.hpp"

namespace fgcal::apps::report {

inline constexpr const char* kGenerator = "fgcal calibration report";
inline constexpr const char* kRed = "#d62728";
inline constexpr const char* kGrey = "#8c8c8c";

/// Camera colours; red is kept for rejected and predicted things.
std::string cameraColor(std::size_t c);
/// Fixed decimals; "–" for a non-finite value.
std::string fmt(double v, int precision);
double rad2deg(double r);

// ---- plots (report_plots.cpp) ----
/// Which way the rig is looked at.
enum class RigView {
  Top,    ///< from above: x forward, y left
  Side,   ///< from the robot's right: x forward, z up
  Front,  ///< from ahead, looking back: y left (on the viewer's right), z up
};
/// The rig in the base frame (m): its links, cameras and boards.
std::string rigPlot(const ReportData& d, RigView view);
std::string convergencePlot(const ReportData& d);
/// Every detected corner of camera c over its image frame (v downward, as
/// the image is shown): the used ones in its colour, the rejected ones red.
std::string coveragePlot(const ReportCamera& cam, std::size_t c);
std::string reprojectionScatter(const ReportCamera& cam, std::size_t c);
std::string reprojectionHistogram(const ReportCamera& cam, std::size_t c);
std::string residualsOverTime(const ReportCamera& cam, std::size_t c, double fiducial_gate);
/// The reprojection RMS against a camera's time offset swept around its
/// estimate; `c` is the camera's index (its colour and the plot's id).
std::string timeOffsetSweepPlot(const ReportTimeOffsetSweep& sweep, std::size_t c);
/// The index in d.cameras of the camera of sweep k.
std::size_t sweepCamera(const ReportData& d, std::size_t k);

// ---- the page (report_page.cpp) ----
/// The overlay picture of camera c, number q, relative to the report folder.
std::string overlayFile(std::size_t c, std::size_t q);
/// The page; overlay_errors[c][q], when not empty, replaces that picture by
/// why it could not be drawn.
std::string pageHtml(const ReportData& d, const std::vector<std::vector<std::string>>& overlay_errors);

// ---- overlay pictures (report_overlay.cpp) ----
/// Draws the detected (green circles) and predicted (red crosses) corners of
/// `o` over the part of `image` around the board (8-bit grey or BGR) and
/// writes the PNG `path`. Throws std::runtime_error when it cannot.
void drawOverlay(const ReportOverlay& o, const cv::Mat& image, const std::string& path);

}  // namespace fgcal::apps::report
