// Detection as images stream in: one producer (the thread reading a bag)
// hands each image to a bounded queue, worker threads decode and detect it and
// keep only the detection. The queue bound keeps memory flat however long the
// bag is: the producer waits while the workers are behind.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "fgcal/vision/charuco_detector.hpp"

namespace fgcal::apps {

/// What a worker keeps of one image.
struct StreamedDetection {
  vision::CharucoDetection detection;
  int width = 0, height = 0;  ///< of the decoded image; 0 when it could not be decoded
  double decode_seconds = 0.0;
};

class DetectionPool {
 public:
  /// Produces the 8-bit grey image; runs on a worker. An empty cv::Mat or an
  /// exception makes the image UnreadableImage (the exception's text, or
  /// `unreadable` when empty, in the detection's message).
  using Decode = std::function<cv::Mat()>;

  /// `threads` workers (0: every core); at most `capacity` images wait in the
  /// queue (0: twice the workers). `on_detected` (may be empty) is called by
  /// a worker after each image.
  DetectionPool(const vision::CharucoDetector& detector, int threads, std::size_t capacity = 0,
                std::function<void()> on_detected = {});
  ~DetectionPool();
  DetectionPool(const DetectionPool&) = delete;
  DetectionPool& operator=(const DetectionPool&) = delete;

  /// Queues an image (blocks while the queue is full); returns its slot, the
  /// index of its result in finish(). `unreadable` names it in messages.
  std::size_t submit(Decode decode, std::string unreadable);
  /// Waits for every queued image; the results by slot. Call once.
  std::vector<StreamedDetection> finish();
  std::size_t workers() const { return threads_.size(); }

 private:
  struct Job {
    std::size_t slot;
    Decode decode;
    std::string unreadable;
  };
  void work();

  const vision::CharucoDetector& detector_;
  std::size_t capacity_;
  std::function<void()> on_detected_;
  std::mutex mutex_;
  std::condition_variable not_empty_, not_full_;
  std::deque<Job> queue_;
  bool closing_ = false;
  std::vector<StreamedDetection> results_;
  std::vector<std::thread> threads_;
};

}  // namespace fgcal::apps
