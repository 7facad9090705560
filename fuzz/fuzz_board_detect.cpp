// Fuzz target: ChArUco board detection on arbitrary image bytes, the way
// `fgcal calibrate` meets a corrupt or hostile image file: decode with OpenCV
// (PNG, JPEG, ... whatever imdecode recognises), then detect. Bytes that do
// not decode are also taken as a raw 8-bit image 48 pixels wide, so that the
// fuzzer reaches the detector itself and not only the decoders' checks.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "fgcal/vision/charuco_detector.hpp"
#include "fgcal/vision/pnp.hpp"
#include "fgcal/vision/vision_error.hpp"
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  // A few bytes of header may claim a gigapixel image: bound what the decoder
  // allocates (OpenCV reads this variable once, at its first decode).
  setenv("OPENCV_IO_MAX_IMAGE_PIXELS", "4194304", 1);
  cv::setNumThreads(1);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace fgcal::vision;
  static const CharucoDetector detector(CharucoTarget{5, 7, 0.04, 0.03, "DICT_4X4_50"});
  static const CameraModel camera =
      CameraModel::fromKalibr("pinhole", "radtan", {300, 300, 160, 120}, {0.01, -0.01, 0.0, 0.0}, {320, 240});
  if (size > 1 << 20) return 0;
  try {
    cv::Mat img;
    try {
      const cv::Mat buf(1, static_cast<int>(size), CV_8U, const_cast<uint8_t*>(data));
      if (size > 0) img = cv::imdecode(buf, cv::IMREAD_GRAYSCALE);
    } catch (const cv::Exception&) {
      img.release();  // OpenCV's decoders report some corrupt files by throwing: an unreadable image
    }
    if (img.empty() && size >= 48 * 8)
      img = cv::Mat(static_cast<int>(size / 48), 48, CV_8U, const_cast<uint8_t*>(data)).clone();
    if (img.empty()) return 0;
    if (img.total() > (1u << 22)) return 0;
    const CharucoDetection det = detector.detect(img);
    if (det.ok()) {
      // A detection the pipeline would use: corners and ids of one length, inside the image.
      if (det.corners.size() != det.ids.size() || det.corners.size() != det.object_points.size()) std::abort();
      for (const auto& c : det.corners)
        if (!(c.x() >= -1 && c.y() >= -1 && c.x() <= img.cols + 1 && c.y() <= img.rows + 1)) std::abort();
      // ... and the pose from it, as calibrate does (the camera is made up:
      // only crashes and non-finite covariances of converged poses matter here).
      PnpOptions pnp;
      pnp.sigma_source = PnpOptions::SigmaSource::Larger;
      const PoseEstimate pose = estimatePose(camera, det, pnp);
      if (pose.converged && !pose.covariance.allFinite()) std::abort();
    }
  } catch (const VisionError&) {
  } catch (const std::exception& e) {
    fgcal::fuzz::unexpected(e);
  }
  return 0;
}
