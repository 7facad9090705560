// The error contract (see errors.hpp).
#include "fgcal/apps/errors.hpp"

#include "fgcal/kinematics/errors.hpp"

namespace fgcal::apps {

namespace {
std::string compose(const std::string& file, const std::string& location, const std::string& detail) {
  std::string s = file;
  if (!location.empty()) s += (s.empty() ? "" : ": ") + location;
  if (!detail.empty()) s += (s.empty() ? "" : ": ") + detail;
  return s;
}
}  // namespace

InputError::InputError(std::string file, std::string location, std::string detail)
    : std::runtime_error(compose(file, location, detail)),
      file_(std::move(file)),
      location_(std::move(location)),
      detail_(std::move(detail)) {}

int exitCodeFor(const std::exception& e) {
  if (dynamic_cast<const InputError*>(&e)) return 2;
  if (dynamic_cast<const DataError*>(&e)) return 1;
  // A URDF or joint name the user supplied, or a value the user typed.
  if (dynamic_cast<const kinematics::KinematicsError*>(&e)) return 2;
  if (dynamic_cast<const std::invalid_argument*>(&e)) return 2;
  return 1;
}

}  // namespace fgcal::apps
