// The exceptions the kinematics module throws. Every message names what was
// being read (URDF file or chain), the cause, and what was expected, so that a
// calibration run can stop with exit code 2 and a sentence the user can act on.
#pragma once

#include <stdexcept>
#include <string>

namespace fgcal::kinematics {

/// Any error of the kinematics module: bad joint values, unknown joint names,
/// wrong vector sizes.
class KinematicsError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A robot description that cannot be used: file missing, XML malformed, not a
/// valid URDF, unknown link, no path between links, a joint type the chain
/// walker cannot handle, a zero joint axis.
class UrdfError : public KinematicsError {
 public:
  using KinematicsError::KinematicsError;
};

}  // namespace fgcal::kinematics
