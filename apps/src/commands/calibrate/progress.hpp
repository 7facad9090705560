// Progress of the detection over many images, for a user watching a long run:
// on a terminal one line redrawn in place (a bar, images read and detected,
// the rate and the time left); when stderr is a file or a pipe, a plain line
// every ~10 % so that logs stay readable. Thread-safe: workers call detected().
#pragma once

#include <atomic>
#include <chrono>
#include <cstddef>
#include <iosfwd>
#include <mutex>

namespace fgcal::apps {

class Progress {
 public:
  /// `total`: the images expected (0 when unknown). `streaming`: images are
  /// read (from a bag) and detected at different times, so both counts show.
  Progress(std::ostream& log, std::size_t total, bool tty, bool streaming);
  /// True when `log` is std::cerr or std::cout and that stream is a terminal.
  static bool isTerminal(const std::ostream& log);

  void read();      ///< an image read and queued (streaming)
  void detected();  ///< an image done
  /// Ends the bar's line on a terminal (when the total was not reached).
  void finish();

 private:
  void draw(std::size_t done, bool last);

  std::ostream& log_;
  std::size_t total_;
  bool tty_, streaming_;
  std::atomic<std::size_t> read_{0}, done_{0};
  std::mutex mutex_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now(), last_ = start_;
  std::size_t next_line_ = 0;  ///< plain mode: the count of the next line
  bool open_line_ = false;     ///< a bar is drawn without its newline
};

}  // namespace fgcal::apps
