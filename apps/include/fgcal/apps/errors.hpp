// The error contract of the fgcal command (docs/design.md, "Errors"): exit 0 on
// success, 1 when valid data cannot support a calibration (DataError), 2 on bad
// input or usage (InputError). An InputError always names the file, the field
// or line, and says what was expected and what was found, so that a robotics
// user can fix the input without reading our code.
#pragma once

#include <exception>
#include <stdexcept>
#include <string>

namespace fgcal::apps {

/// Bad input or usage: exit code 2. what() reads "FILE: LOCATION: DETAIL"
/// (empty parts left out), e.g.
/// "rig.yaml: cameras[cam1].distortion_coeffs: expected 4 numbers for
/// distortion_model radtan, got 5 (line 23)".
class InputError : public std::runtime_error {
 public:
  /// `file`: the file or folder concerned (as the user gave it); `location`: a
  /// field path such as "cameras[cam1].intrinsics" or "line 17" (may be empty);
  /// `detail`: what was expected and what was found.
  InputError(std::string file, std::string location, std::string detail);

  const std::string& file() const { return file_; }
  const std::string& location() const { return location_; }
  const std::string& detail() const { return detail_; }

 private:
  std::string file_, location_, detail_;
};

/// Valid input that cannot support a calibration (too few detections, no
/// convergence, ...): exit code 1. The message says why.
class DataError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Exit code for an exception that ended a command: 2 for InputError,
/// kinematics::UrdfError / KinematicsError (a robot description or joint name
/// the user supplied) and std::invalid_argument; 1 for DataError and for
/// anything else (docs/design.md allows only 0, 1 and 2; an unexpected exception is
/// reported as a failed calibration rather than a crash).
int exitCodeFor(const std::exception& e);

}  // namespace fgcal::apps
