// Helpers of the simulator tests: the rig.yaml camera and board as the vision
// module's types, a camera folder's images in stamp order, the pose the
// images show (detection and PnP), and the check that a bad option is named.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <opencv2/imgcodecs.hpp>

#include "fgcal/apps/errors.hpp"
#include "fgcal/apps/rig_config.hpp"
#include "fgcal/apps/simulator.hpp"
#include "fgcal/vision/camera_model.hpp"
#include "fgcal/vision/charuco_detector.hpp"
#include "fgcal/vision/charuco_target.hpp"
#include "fgcal/vision/pnp.hpp"

namespace fgcal::apps::test {

inline vision::CameraModel cameraOf(const CameraConfig& c) {
  return vision::CameraModel::fromKalibr(c.camera_model, c.distortion_model,
                                         {c.intrinsics.begin(), c.intrinsics.end()}, c.distortion_coeffs,
                                         {c.resolution[0], c.resolution[1]});
}

inline vision::CharucoTarget targetOf(const TargetConfig& t) {
  vision::CharucoTarget target;
  target.squares_x = t.squares_x;
  target.squares_y = t.squares_y;
  target.square_size = t.square_size;
  target.marker_size = t.marker_size;
  target.dictionary = t.dictionary;
  return target;
}

inline std::vector<std::filesystem::path> imagesOf(const std::filesystem::path& folder) {
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(folder)) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return files;
}

inline int64_t stampOf(const std::filesystem::path& image) { return std::stoll(image.stem().string()); }

/// One image in which the board was detected: its stamp, the detection and
/// the board pose PnP gives with `camera`.
struct SeenBoard {
  int64_t stamp_ns = 0;
  vision::CharucoDetection detection;
  SE3 T_cam_marker;
};

inline std::vector<SeenBoard> seenBoards(const std::filesystem::path& folder, const vision::CameraModel& camera,
                                         const vision::CharucoTarget& target) {
  const vision::CharucoDetector detector(target);
  std::vector<SeenBoard> out;
  for (const auto& file : imagesOf(folder)) {
    const auto det = detector.detect(cv::imread(file.string(), cv::IMREAD_UNCHANGED));
    if (!det.ok()) continue;
    out.push_back({stampOf(file), det, vision::estimatePose(camera, det).T_cam_marker});
  }
  return out;
}

inline double rms(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x * x;
  return v.empty() ? 0.0 : std::sqrt(s / v.size());
}

/// `o` with one change applied, e.g. changed(o, [](auto& c) { c.frames = 0; }).
template <class Change>
SimulationOptions changed(SimulationOptions o, Change change) {
  change(o);
  return o;
}

/// simulateDataset(o) throws InputError (exit code 2) whose message names
/// `option` and contains `detail`.
inline void requireInputError(const SimulationOptions& o, const std::string& option, const std::string& detail = "") {
  try {
    simulateDataset(o);
    FAIL("expected InputError naming " << option);
  } catch (const InputError& e) {
    INFO(e.what());
    CHECK(std::string(e.what()).find(option) != std::string::npos);
    CHECK(std::string(e.what()).find(detail) != std::string::npos);
    CHECK(exitCodeFor(e) == 2);
  }
}

}  // namespace fgcal::apps::test
