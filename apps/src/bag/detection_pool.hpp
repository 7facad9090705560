// Detection as images stream in: one producer (the thread reading a bag or
// listing a folder) hands each image to a bounded queue, worker threads decode
// and detect it and hand the detection to the caller as it comes out, so that
// the caller keeps only what it needs of it. The queue bound keeps memory flat
// however many images there are: the producer waits while the workers are
// behind.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "fgcal/vision/charuco_detector.hpp"

namespace fgcal::apps {

/// What a worker hands over of one image.
struct StreamedDetection {
  vision::CharucoDetection detection;
  /// Of the decoded image, or as its header declares when it was not decoded
  /// for its size; 0 when it could not be read.
  int width = 0, height = 0;
  double decode_seconds = 0.0;
};

class DetectionPool {
 public:
  /// Produces the 8-bit grey image; runs on a worker. An empty cv::Mat or an
  /// exception makes the image UnreadableImage (the exception's text, or
  /// `unreadable` when empty, in the detection's message). A
  /// vision::ImageSizeMismatch (the header's size is not the camera's, the
  /// image was not decoded) also gives the header's width and height, so
  /// that the caller counts it as a wrong image size.
  using Decode = std::function<cv::Mat()>;
  /// Takes one image's detection by its slot (the order of submit); called
  /// on the worker threads, several at once, as images finish.
  using OnResult = std::function<void(std::size_t slot, StreamedDetection&& result)>;

  /// `threads` workers (0: every core); at most `capacity` images wait in the
  /// queue (0: twice the workers).
  DetectionPool(const vision::CharucoDetector& detector, int threads, OnResult on_result, std::size_t capacity = 0);
  ~DetectionPool();
  DetectionPool(const DetectionPool&) = delete;
  DetectionPool& operator=(const DetectionPool&) = delete;

  /// Queues an image (blocks while the queue is full); returns its slot.
  /// `unreadable` names it in messages.
  std::size_t submit(Decode decode, std::string unreadable);
  /// Waits until every queued image was handed over. Call once. When
  /// on_result threw, rethrows the first exception.
  void finish();
  std::size_t workers() const { return threads_.size(); }

 private:
  struct Job {
    std::size_t slot;
    Decode decode;
    std::string unreadable;
  };
  void work();
  StreamedDetection run(Job& job) const;

  const vision::CharucoDetector& detector_;
  OnResult on_result_;
  std::size_t capacity_;
  std::mutex mutex_;
  std::condition_variable not_empty_, not_full_;
  std::deque<Job> queue_;
  bool closing_ = false;
  std::size_t submitted_ = 0;
  std::exception_ptr error_;
  std::vector<std::thread> threads_;
};

}  // namespace fgcal::apps
