// The bounded producer/consumer detection pool (detection_pool.hpp).
#include "bag/detection_pool.hpp"

#include <algorithm>
#include <chrono>

#include "fgcal/vision/image_header.hpp"

namespace fgcal::apps {

DetectionPool::DetectionPool(const vision::CharucoDetector& detector, int threads, OnResult on_result,
                             std::size_t capacity)
    : detector_(detector), on_result_(std::move(on_result)) {
  const unsigned n = threads > 0 ? static_cast<unsigned>(threads) : std::max(1u, std::thread::hardware_concurrency());
  capacity_ = capacity > 0 ? capacity : 2 * static_cast<std::size_t>(n);
  for (unsigned t = 0; t < n; ++t) threads_.emplace_back([this] { work(); });
}

DetectionPool::~DetectionPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    closing_ = true;
    queue_.clear();  // an exception ended the reading: drop what waits
  }
  not_empty_.notify_all();
  not_full_.notify_all();
  for (auto& t : threads_)
    if (t.joinable()) t.join();
}

std::size_t DetectionPool::submit(Decode decode, std::string unreadable) {
  std::unique_lock<std::mutex> lock(mutex_);
  not_full_.wait(lock, [&] { return queue_.size() < capacity_; });
  const std::size_t slot = submitted_++;
  queue_.push_back(Job{slot, std::move(decode), std::move(unreadable)});
  lock.unlock();
  not_empty_.notify_one();
  return slot;
}

StreamedDetection DetectionPool::run(Job& job) const {
  StreamedDetection r;
  const auto t0 = std::chrono::steady_clock::now();
  cv::Mat image;
  std::string error;
  try {
    image = job.decode();
  } catch (const vision::ImageSizeMismatch& e) {
    r.width = e.width();  // not decoded: the header's size, for the caller's size check
    r.height = e.height();
    error = e.what();
  } catch (const std::exception& e) {
    error = e.what();
  }
  job.decode = nullptr;  // frees the message's bytes before detection
  r.decode_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (image.empty()) {
    r.detection.status = vision::DetectionStatus::UnreadableImage;
    r.detection.message = error.empty() ? job.unreadable : job.unreadable + ": " + error;
    return r;
  }
  r.width = image.cols;
  r.height = image.rows;
  try {
    r.detection = detector_.detect(image);
  } catch (const std::exception& e) {
    r.detection.status = vision::DetectionStatus::UnreadableImage;
    r.detection.message = job.unreadable + ": " + e.what();
  }
  return r;
}

void DetectionPool::work() {
  for (;;) {
    Job job;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      not_empty_.wait(lock, [&] { return closing_ || !queue_.empty(); });
      if (queue_.empty()) return;  // closing and drained
      job = std::move(queue_.front());
      queue_.pop_front();
    }
    not_full_.notify_one();
    StreamedDetection r = run(job);
    try {
      on_result_(job.slot, std::move(r));
    } catch (...) {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!error_) error_ = std::current_exception();
    }
  }
}

void DetectionPool::finish() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    closing_ = true;
  }
  not_empty_.notify_all();
  for (auto& t : threads_) t.join();
  threads_.clear();
  if (error_) std::rethrow_exception(error_);
}

}  // namespace fgcal::apps
