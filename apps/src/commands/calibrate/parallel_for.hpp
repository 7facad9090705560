// fn(i) for every i < n, on `threads` threads (0: every core), each taking
// the next index as it is free.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <thread>
#include <vector>

namespace fgcal::apps {

template <class F>
void parallelFor(std::size_t n, int threads, F&& fn) {
  unsigned k = threads > 0 ? static_cast<unsigned>(threads) : std::max(1u, std::thread::hardware_concurrency());
  k = static_cast<unsigned>(std::min<std::size_t>(k, std::max<std::size_t>(n, 1)));
  std::atomic<std::size_t> next{0};
  auto work = [&] {
    for (std::size_t i = next++; i < n; i = next++) fn(i);
  };
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < k; ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
}

}  // namespace fgcal::apps
