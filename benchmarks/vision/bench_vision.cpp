// Images per second for ChArUco detection + PnP (with covariance) on rendered
// 640x480 and 1280x720 views of a 5x7 board, on one core and on all cores.
// "One core" = one worker and OpenCV's own parallel_for_ off
// (cv::setNumThreads(1)); "all cores" = processImages' pool with one worker
// per hardware thread, OpenCV's inner parallelism off so workers do not
// compete; "1 worker + OpenCV threads" shows what OpenCV's inner
// parallelism alone gives.
//
//   bench_vision [seconds_per_case=3]
#include <chrono>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <thread>

#include <opencv2/core/utility.hpp>

#include "fgcal/vision/batch_detection.hpp"
#include "fgcal/vision/board_renderer.hpp"

using namespace fgcal;
using namespace fgcal::vision;

namespace {

SE3 boardPose(const CharucoTarget& t, const Vec3& centre_cam, double roll, double pitch,
              double yaw) {
  const Vec3 c(0.5 * t.squares_x * t.square_size, 0.5 * t.squares_y * t.square_size, 0.0);
  const SO3 R = SO3::fromRpy(roll, pitch, yaw);
  return SE3(R, centre_cam - R.matrix() * c);
}

struct Case {
  const char* name;
  CameraModel camera;
};

double imagesPerSecond(const CharucoDetector& detector, const CameraModel& camera,
                       const std::vector<cv::Mat>& images, int workers, int cv_threads,
                       double seconds, int* ok_count, double* cpu_ms_per_image) {
  const int saved = cv::getNumThreads();
  cv::setNumThreads(cv_threads);
  const auto loader = [&](std::size_t i) { return images[i % images.size()]; };
  // Warm-up, then batches until the time budget is spent.
  processImages(detector, images.size(), loader, &camera, {}, workers);
  std::size_t done = 0;
  int ok = 0;
  const auto t0 = std::chrono::steady_clock::now();
  const std::clock_t c0 = std::clock();
  double elapsed = 0.0;
  do {
    const auto res = processImages(detector, 4 * images.size(), loader, &camera, {}, workers);
    for (const auto& r : res) ok += r.pose ? 1 : 0;
    done += res.size();
    elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  } while (elapsed < seconds);
  cv::setNumThreads(saved);
  // Process CPU time per image: independent of other load on the machine.
  *cpu_ms_per_image = 1e3 * static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC /
                      static_cast<double>(done);
  *ok_count = static_cast<int>(100.0 * ok / static_cast<double>(done));
  return static_cast<double>(done) / elapsed;
}

}  // namespace

int main(int argc, char** argv) {
  const double seconds = argc > 1 ? std::atof(argv[1]) : 3.0;
  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const CharucoTarget board{5, 7, 0.04, 0.03, "DICT_4X4_50"};
  const std::vector<Case> cases = {
      {"640x480", CameraModel(Projection::Pinhole, Distortion::RadTan, 500, 500, 319.5, 239.5,
                              {-0.28, 0.07, 1e-4, -2e-4}, 640, 480)},
      {"1280x720", CameraModel(Projection::Pinhole, Distortion::RadTan, 900, 900, 639.5, 359.5,
                               {-0.28, 0.07, 1e-4, -2e-4}, 1280, 720)},
  };
  std::printf("fgcal vision: ChArUco detection + PnP (5x7 board, DICT_4X4_50), %d hardware threads\n",
              cores);
  std::printf("%-10s %-28s %10s %12s %8s\n", "image", "mode", "images/s", "CPU ms/img", "posed %");
  for (const auto& c : cases) {
    // 16 views at 0.35 to 1.0 m, tilted up to ~35 deg, lightly blurred and noisy.
    const BoardRenderer renderer(c.camera, board, 2);
    std::vector<cv::Mat> images;
    for (int i = 0; i < 16; ++i) {
      RenderOptions o;
      o.blur_sigma = 0.5;
      o.noise_sigma = 2.0;
      o.seed = static_cast<std::uint64_t>(i);
      const double d = 0.35 + 0.04 * i;
      images.push_back(renderer.render(
          boardPose(board, Vec3(0.02 * ((i % 5) - 2), 0.015 * ((i % 3) - 1), d),
                    0.3 * std::sin(i), 0.3 * std::cos(1.7 * i), 0.4 * i),
          o));
    }
    const CharucoDetector detector(board);
    int ok = 0;
    double cpu = 0.0;
    double ips = imagesPerSecond(detector, c.camera, images, 1, 1, seconds, &ok, &cpu);
    std::printf("%-10s %-28s %10.1f %12.2f %8d\n", c.name, "one core", ips, cpu, ok);
    ips = imagesPerSecond(detector, c.camera, images, 1, cores, seconds, &ok, &cpu);
    std::printf("%-10s %-28s %10.1f %12.2f %8d\n", c.name, "1 worker + OpenCV threads", ips, cpu, ok);
    ips = imagesPerSecond(detector, c.camera, images, cores, 1, seconds, &ok, &cpu);
    char mode[64];
    std::snprintf(mode, sizeof(mode), "all cores (%d workers)", cores);
    std::printf("%-10s %-28s %10.1f %12.2f %8d\n", c.name, mode, ips, cpu, ok);
  }
  return 0;
}
