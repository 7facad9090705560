// The calibration report (fgcal/apps/report.hpp): the atomic folder write
// around the page (report_page.cpp), its plots (report_plots.cpp) and
// overlay pictures (report_overlay.cpp).
#include "fgcal/apps/report.hpp"

#include <stdio.h>  // renameat2
#include <fcntl.h>  // AT_FDCWD
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>

#include <opencv2/imgcodecs.hpp>

#include "fgcal/apps/errors.hpp"
#include "fgcal/vision/image_header.hpp"
#include "report/report_parts.hpp"

namespace fgcal::apps {

namespace {

namespace fs = std::filesystem;

bool isOurReport(const fs::path& dir) {
  std::error_code ec;
  if (fs::is_empty(dir, ec) && !ec) return true;
  std::ifstream in(dir / "index.html");
  std::string head(4096, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));
  return head.find(report::kGenerator) != std::string::npos;
}

void writeText(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  out.flush();
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

/// The report folder's final place, its parent and its name.
struct Target {
  fs::path final_dir, parent, name;
};
Target targetOf(const std::string& dir) {
  const fs::path target = fs::absolute(dir).lexically_normal();
  Target t;
  t.final_dir = target.filename().empty() ? target.parent_path() : target;
  t.parent = t.final_dir.parent_path();
  t.name = t.final_dir.filename();
  return t;
}

/// The overlays' images, by ReportOverlay::image_index: from the loader in one
/// call, or each read as a file. One that cannot be had is left out.
std::map<std::size_t, cv::Mat> loadOverlayImages(const ReportData& d, const ReportOptions& options) {
  std::map<std::size_t, cv::Mat> loaded;
  if (options.load_images) {
    std::vector<std::size_t> wanted;
    for (const ReportCamera& cam : d.cameras)
      for (const ReportOverlay& o : cam.overlays) wanted.push_back(o.image_index);
    try {
      loaded = options.load_images(wanted);
    } catch (const std::exception&) {
      // Every picture then says it could not be read; the report itself stands.
    }
    return loaded;
  }
  for (const ReportCamera& cam : d.cameras)
    for (const ReportOverlay& o : cam.overlays) {
      cv::Mat img;
      try {  // the size from the header first: a file of another size is not decoded
        img = vision::readColorChecked(o.image, {cam.resolution[0], cam.resolution[1]});
      } catch (const vision::ImageSizeMismatch&) {
      }
      if (!img.empty()) loaded[o.image_index] = std::move(img);
    }
  return loaded;
}

/// Draws every overlay into folder `tmp`; per camera and overlay, why it
/// could not be drawn (empty when it was).
std::vector<std::vector<std::string>> drawOverlays(const ReportData& d, const ReportOptions& options,
                                                   const fs::path& tmp) {
  const std::map<std::size_t, cv::Mat> loaded = loadOverlayImages(d, options);
  std::vector<std::vector<std::string>> errors(d.cameras.size());
  for (std::size_t c = 0; c < d.cameras.size(); ++c)
    for (std::size_t q = 0; q < d.cameras[c].overlays.size(); ++q) {
      const ReportOverlay& o = d.cameras[c].overlays[q];
      std::string error;
      try {  // a moved or unreadable image costs its picture only
        const auto it = loaded.find(o.image_index);
        if (it == loaded.end() || it->second.empty()) throw std::runtime_error("cannot read " + o.image);
        report::drawOverlay(o, it->second, (tmp / report::overlayFile(c, q)).string());
      } catch (const std::exception& e) {
        error = e.what();
      }
      errors[c].push_back(error);
    }
  return errors;
}

/// Moves the finished temporary folder into place: swapped in atomically
/// when an earlier report is there (which is then dropped), a plain rename
/// otherwise.
void commitFolder(const fs::path& tmp, const Target& t, const std::string& suffix) {
  if (!fs::exists(t.final_dir)) {
    fs::rename(tmp, t.final_dir);
    return;
  }
  if (::renameat2(AT_FDCWD, tmp.c_str(), AT_FDCWD, t.final_dir.c_str(), RENAME_EXCHANGE) == 0) {
    std::error_code ignored;
    fs::remove_all(tmp, ignored);  // now the earlier report
    return;
  }
  const fs::path old = t.parent / ("." + t.name.string() + ".old-" + suffix);
  fs::rename(t.final_dir, old);
  try {
    fs::rename(tmp, t.final_dir);
  } catch (...) {
    fs::rename(old, t.final_dir);
    throw;
  }
  std::error_code ignored;  // committed: a leftover old copy costs disk, not the report
  fs::remove_all(old, ignored);
}

}  // namespace

std::vector<std::string> reportPlotIds(const ReportData& data) {
  std::vector<std::string> ids = {"rig-top", "rig-side", "rig-front", "convergence"};
  for (std::size_t c = 0; c < data.cameras.size(); ++c)
    for (const char* p : {"coverage-", "reprojection-scatter-", "reprojection-histogram-", "residuals-time-"})
      ids.push_back(p + std::to_string(c));
  for (std::size_t k = 0; k < data.time_offset_sweeps.size(); ++k)
    ids.push_back("time-offset-sweep-" + std::to_string(report::sweepCamera(data, k)));
  return ids;
}

std::string formatReportHtml(const ReportData& data) { return report::pageHtml(data, {}); }

void checkReportFolder(const std::string& dir) {
  const Target t = targetOf(dir);
  if (!fs::is_directory(t.parent))
    throw InputError(dir, "--report", "the report's parent folder " + t.parent.string() + " does not exist; create it first");
  if (fs::exists(t.final_dir) && !fs::is_directory(t.final_dir))
    throw InputError(dir, "", "exists and is not a folder; the report needs a folder");
  if (fs::exists(t.final_dir) && !isOurReport(t.final_dir))
    throw InputError(dir, "",
                     "the folder exists and is not an fgcal report; it is left untouched (choose another report "
                     "folder)");
}

std::string writeReport(const ReportData& data, const std::string& dir, const ReportOptions& options) {
  checkReportFolder(dir);
  const Target t = targetOf(dir);
  static std::atomic<int> counter{0};
  const std::string suffix = std::to_string(::getpid()) + "-" + std::to_string(counter++);
  const fs::path tmp = t.parent / ("." + t.name.string() + ".tmp-" + suffix);
  try {
    fs::create_directory(tmp);
    fs::create_directory(tmp / "images");
    const auto overlay_errors = drawOverlays(data, options, tmp);
    writeText(tmp / "index.html", report::pageHtml(data, overlay_errors));
    if (options.before_commit) options.before_commit(tmp.string());
    commitFolder(tmp, t, suffix);
  } catch (...) {
    std::error_code ec;
    fs::remove_all(tmp, ec);
    throw;
  }
  return (t.final_dir / "index.html").string();
}

}  // namespace fgcal::apps
