// A minimal fork-join helper for the core's data-parallel loops: runs
// body(t) for t = 0 .. threads-1, t = 0 (and any part no thread could be
// started for) on the calling thread, and rethrows the first exception a
// part raised once all have joined.
#pragma once

#include <exception>
#include <mutex>
#include <system_error>
#include <thread>
#include <vector>

namespace fgcal::detail {

template <class Body>
void parallelRun(int threads, Body&& body) {
  if (threads <= 1) {
    body(0);
    return;
  }
  std::exception_ptr error;
  std::mutex error_mutex;
  auto guarded = [&](int t) {
    try {
      body(t);
    } catch (...) {
      std::lock_guard<std::mutex> lock(error_mutex);
      if (!error) error = std::current_exception();
    }
  };
  std::vector<std::thread> workers;
  workers.reserve(static_cast<std::size_t>(threads - 1));
  int t = 1;
  try {
    for (; t < threads; ++t) workers.emplace_back(guarded, t);
  } catch (const std::system_error&) {
    // No more threads to be had (a process or memory limit): this thread
    // does the parts that found none, after its own.
  }
  guarded(0);
  for (int rest = t; rest < threads; ++rest) guarded(rest);
  for (auto& w : workers) w.join();
  if (error) std::rethrow_exception(error);
}

/// [begin, end) of chunk t when n items are split into `chunks` near-equal parts.
inline std::pair<std::size_t, std::size_t> chunkRange(std::size_t n, int chunks, int t) {
  const std::size_t c = static_cast<std::size_t>(chunks), i = static_cast<std::size_t>(t);
  return {n * i / c, n * (i + 1) / c};
}

/// Threads worth using for `work` independent items (at least `grain` each).
inline int threadsFor(int requested, std::size_t work, std::size_t grain) {
  if (requested <= 1 || work < 2 * grain) return 1;
  const std::size_t most = work / grain;
  return static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(requested), most));
}

}  // namespace fgcal::detail
