// The detection progress display (progress.hpp).
#include "commands/calibrate/progress.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <ostream>
#include <sstream>
#include <string>

namespace fgcal::apps {

namespace {
double secondsSince(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

std::string duration(double s) {
  std::ostringstream o;
  if (s >= 3600) o << static_cast<long>(s / 3600) << " h " << static_cast<long>(std::fmod(s, 3600) / 60) << " min";
  else if (s >= 60) o << static_cast<long>(s / 60) << " min " << static_cast<long>(std::fmod(s, 60)) << " s";
  else o << static_cast<long>(std::ceil(s)) << " s";
  return o.str();
}
}  // namespace

Progress::Progress(std::ostream& log, std::size_t total, bool tty, bool streaming)
    : log_(log), total_(total), tty_(tty), streaming_(streaming) {
  next_line_ = std::max<std::size_t>(total_ / 10, 1);
}

bool Progress::isTerminal(const std::ostream& log) {
  return (&log == &std::cerr && isatty(STDERR_FILENO)) || (&log == &std::cout && isatty(STDOUT_FILENO));
}

void Progress::read() {
  ++read_;
  if (!tty_) return;
  std::lock_guard<std::mutex> lock(mutex_);
  if (secondsSince(last_) < 0.1) return;
  draw(done_.load(), false);
}

void Progress::detected() {
  const std::size_t done = ++done_;
  std::lock_guard<std::mutex> lock(mutex_);
  const bool last = total_ > 0 && done == total_;
  if (tty_) {
    if (!last && secondsSince(last_) < 0.1) return;
    draw(done, last);
    return;
  }
  // Plain lines: every ~10 % of the total (every 100 images when unknown).
  const std::size_t step = total_ > 0 ? std::max<std::size_t>(total_ / 10, 1) : 100;
  if (done % step != 0 && !last) return;
  if (streaming_)
    log_ << "  read " << read_.load() << ", detected " << done << (total_ ? "/" + std::to_string(total_) : "")
         << " images (" << std::fixed << std::setprecision(1) << done / std::max(secondsSince(start_), 1e-9)
         << " images/s)\n"
         << std::defaultfloat << std::flush;
  else
    log_ << "  detected " << done << "/" << total_ << " images\n" << std::flush;
}

void Progress::draw(std::size_t done, bool last) {
  last_ = std::chrono::steady_clock::now();
  const double elapsed = std::max(secondsSince(start_), 1e-9);
  const double rate = done / elapsed;
  std::ostringstream line;
  line << "\r  detecting ";
  if (total_ > 0) {
    const int width = 30, filled = static_cast<int>(width * std::min(done, total_) / total_);
    line << "[" << std::string(filled, '#') << std::string(width - filled, '.') << "] ";
  }
  if (streaming_) line << "read " << read_.load() << ", ";
  line << "detected " << done;
  if (total_ > 0) line << "/" << total_;
  line << ", " << std::fixed << std::setprecision(1) << rate << " images/s";
  if (total_ > 0 && !last && done > 0) line << ", " << duration((total_ - std::min(done, total_)) / rate) << " left";
  line << "   ";  // clears the tail of a longer previous line
  log_ << line.str() << (last ? "\n" : "") << std::flush;
  open_line_ = !last;
}

void Progress::finish() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (tty_ && open_line_) {
    draw(done_.load(), true);
  }
}

}  // namespace fgcal::apps
