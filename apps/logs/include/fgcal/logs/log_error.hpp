// The one error type of the robot-log readers. Every message names the file,
// and where it can the topic and the message (its index in storage order, or
// its header stamp) or the byte offset, then says what was expected and what
// was found, e.g.
//   "run.bag: offset 1834231: chunk record declares 912334 bytes but only
//    4021 remain in the file (the bag was cut short?)".
// The calibration pipeline turns a LogError into its InputError (exit 2).
#pragma once

#include <stdexcept>
#include <string>

namespace fgcal::logs {

class LogError : public std::runtime_error {
 public:
  /// `file`: the bag file or folder; `where`: "topic /cam0/image_raw, message
  /// 17 (stamp 1700000000123456789)", "offset 4096", "table messages", ...
  /// (may be empty); `detail`: what was expected and what was found.
  LogError(std::string file, std::string where, std::string detail);

  const std::string& file() const { return file_; }
  const std::string& where() const { return where_; }
  const std::string& detail() const { return detail_; }

 private:
  std::string file_, where_, detail_;
};

}  // namespace fgcal::logs
