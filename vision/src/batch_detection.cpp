// A small work-sharing pool: each worker takes the next image index from an
// atomic counter, so uneven images do not leave a core idle.
#include "fgcal/vision/batch_detection.hpp"

#include <algorithm>
#include <atomic>
#include <thread>

#include <opencv2/imgcodecs.hpp>

#include "fgcal/vision/image_header.hpp"

namespace fgcal::vision {

namespace {
FrameResult processOne(const CharucoDetector& detector, const cv::Mat& image,
                       const CameraModel* camera, const PnpOptions& pnp) {
  FrameResult r;
  r.detection = detector.detect(image);
  if (camera && r.detection.ok()) {
    try {
      r.pose = estimatePose(*camera, r.detection, pnp);
    } catch (const std::exception& e) {
      r.pose_error = e.what();
    }
  }
  return r;
}
}  // namespace

std::vector<FrameResult> processImages(const CharucoDetector& detector, std::size_t count,
                                       const ImageLoader& loader, const CameraModel* camera,
                                       const PnpOptions& pnp, int threads) {
  std::vector<FrameResult> results(count);
  unsigned n_threads = threads > 0 ? static_cast<unsigned>(threads)
                                   : std::max(1u, std::thread::hardware_concurrency());
  n_threads = static_cast<unsigned>(std::min<std::size_t>(n_threads, std::max<std::size_t>(count, 1)));
  std::atomic<std::size_t> next{0};
  auto work = [&] {
    for (std::size_t i = next++; i < count; i = next++) {
      cv::Mat image;
      std::string load_error;
      try {
        image = loader(i);
      } catch (const std::exception& e) {
        load_error = e.what();
      }
      if (image.empty()) {
        results[i].detection.status = DetectionStatus::UnreadableImage;
        results[i].detection.message =
            load_error.empty() ? "image " + std::to_string(i) + " could not be loaded" : load_error;
        continue;
      }
      results[i] = processOne(detector, image, camera, pnp);
    }
  };
  if (n_threads <= 1) {
    work();
  } else {
    std::vector<std::thread> pool;
    for (unsigned t = 0; t < n_threads; ++t) pool.emplace_back(work);
    for (auto& t : pool) t.join();
  }
  return results;
}

std::vector<FrameResult> processFiles(const CharucoDetector& detector,
                                      const std::vector<std::string>& paths,
                                      const CameraModel* camera, const PnpOptions& pnp,
                                      int threads) {
  auto results = processImages(
      detector, paths.size(),
      [&](std::size_t i) {
        cv::Mat img = readGrayChecked(paths[i], {});  // ImageSizeMismatch: a gigapixel header
        if (img.empty())
          throw std::runtime_error("cannot read image '" + paths[i] +
                                   "': missing file or not a format OpenCV can decode");
        return img;
      },
      camera, pnp, threads);
  for (std::size_t i = 0; i < paths.size(); ++i) {
    results[i].detection.source = paths[i];
    auto& d = results[i].detection;
    if (!d.ok() && d.status != DetectionStatus::UnreadableImage) d.message = paths[i] + ": " + d.message;
  }
  return results;
}

}  // namespace fgcal::vision
